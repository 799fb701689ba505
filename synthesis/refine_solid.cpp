// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/refine_solid.h"

#include "core/parallel.h"
#include "synthesis/chunk_index.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdlib>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

namespace texfab::synthesis {
namespace {

// The refined region lives in sparse 8^3 chunks. Each voxel records the last pass whose vote it
// takes part in (0: Dong et al.'s triples only, -1: outside the region), and per axis the last pass
// whose search matches its slice across that axis (0: none). Every radius is less than 8, so a
// chunk's reads stay within its 27 neighbours.
constexpr int kShift = 3;
constexpr int kSide = 1 << kShift;
constexpr int kVoxels = kSide * kSide * kSide;
constexpr int kR = kRefineSearchRadius;
constexpr int kV = kRefineVoteRadius;
constexpr int kStride = kRefineSearchStride;
constexpr int kTaps = (2 * kR + 1) * (2 * kR + 1);
constexpr int kMaxSum = 3 * 255;  // colours at 3x the 8-bit scale: a voxel's is the sum of its three
constexpr uint64_t kWeightOne = uint64_t(1) << 40;  // weights < 2^31: 32 bits each
constexpr int kErrorFloor = 512;
static_assert(kR >= 1 && kR + 1 <= kSide && kV < kSide);  // dilations shift by less than a chunk
static_assert(kSide % kStride == 0 && kStride <= kV);       // every vote reads a searched window

int localIndex(int64_t x, int64_t y, int64_t z) {
  return int(((z & (kSide - 1)) * kSide + (y & (kSide - 1))) * kSide + (x & (kSide - 1)));
}

// Whether the window across axis q centred on chunk-local (x, y, z) is ever searched: both in-slice
// coordinates on the stride's grid (chunks start on it).
bool searches(int q, int x, int y, int z) {
  const int c[3] = {x, y, z};
  return c[(q + 1) % 3] % kStride == 0 && c[(q + 2) % 3] % kStride == 0;
}

class Grid {
public:
  size_t size() const { return chunks_.size(); }
  const GridKey& key(size_t slot) const { return chunks_.keys()[slot]; }
  int32_t find(const GridKey& k) const { return chunks_.find(k); }
  uint32_t get(const GridKey& k) {
    const auto [slot, added] = chunks_.insert(k);
    if (added) {
      pass.resize(size() * kVoxels, -1);
      searched.resize(size() * kVoxels);
    }
    return slot;
  }
  /// The voxel at index i of chunk `slot`, and the index (slot * kVoxels + i) of a voxel the grid
  /// holds.
  Voxel voxel(size_t slot, int i) const {
    const GridKey& k = key(slot);
    return {k[0] * kSide + (i & (kSide - 1)), k[1] * kSide + ((i >> kShift) & (kSide - 1)), k[2] * kSide + (i >> (2 * kShift))};
  }
  size_t index(const Voxel& v) const {
    return size_t(find({v.x >> kShift, v.y >> kShift, v.z >> kShift})) * kVoxels + size_t(localIndex(v.x, v.y, v.z));
  }
  /// The slots of a chunk's 27 neighbours, x fastest (-1: absent).
  std::array<int32_t, 27> neighbours(size_t slot) const {
    std::array<int32_t, 27> out{};
    const GridKey& k = key(slot);
    for (int dz = -1, i = 0; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx, ++i) out[size_t(i)] = find({k[0] + dx, k[1] + dy, k[2] + dz});
    return out;
  }

  std::vector<int8_t> pass;                     // size() * kVoxels
  std::vector<std::array<int8_t, 3>> searched;  // size() * kVoxels

private:
  ChunkIndex chunks_;
};

// Index of the voxel at chunk-local (x, y, z), each in [-kSide, 2 kSide), through the chunk's
// neighbours; -1 when its chunk is absent.
int64_t voxelAt(const std::array<int32_t, 27>& nb, int x, int y, int z) {
  const int32_t slot = nb[size_t(((z >> kShift) + 1) * 9 + ((y >> kShift) + 1) * 3 + (x >> kShift) + 1)];
  return slot < 0 ? -1 : int64_t(slot) * kVoxels + localIndex(x, y, z);
}

// A chunk's voxels as bits: bit y * kSide + x of word z.
using Bits = std::array<uint64_t, kSide>;
static_assert(kSide * kSide == 64);

bool any(const Bits& b) {
  return std::any_of(b.begin(), b.end(), [](uint64_t w) { return w != 0; });
}

// The bits of a chunk moved by t voxels along `axis` (0 < |t| < kSide): those that stay in the
// chunk, and those that land in its neighbour on that side.
std::pair<Bits, Bits> shifted(const Bits& b, int axis, int t) {
  constexpr uint64_t kEveryRow = 0x0101010101010101ull;
  const int s = std::abs(t);
  Bits stay{}, spill{};
  for (int z = 0; z < kSide; ++z) {
    const uint64_t w = b[size_t(z)];
    if (axis == 0) {  // within each row's byte
      const uint64_t low = ((uint64_t(1) << s) - 1) * kEveryRow, high = ~(((uint64_t(1) << (kSide - s)) - 1) * kEveryRow);
      stay[size_t(z)] = t > 0 ? (w << s) & ~low : (w >> s) & ~high;
      spill[size_t(z)] = t > 0 ? (w >> (kSide - s)) & low : (w << (kSide - s)) & high;
    } else if (axis == 1) {  // whole rows
      stay[size_t(z)] = t > 0 ? w << (kSide * s) : w >> (kSide * s);
      spill[size_t(z)] = t > 0 ? w >> (64 - kSide * s) : w << (64 - kSide * s);
    } else {  // whole words
      const int to = z + t;
      (to >= 0 && to < kSide ? stay[size_t(to)] : spill[size_t(to < 0 ? to + kSide : to - kSide)]) = w;
    }
  }
  return {stay, spill};
}

// The voxels of the grid where `pred(index)` holds, as bits.
template <class Pred> std::vector<Bits> maskWhere(const Grid& g, Pred&& pred) {
  std::vector<Bits> mark(g.size());
  for (size_t slot = 0; slot < g.size(); ++slot)
    for (int i = 0; i < kVoxels; ++i)
      if (pred(slot * kVoxels + size_t(i))) mark[slot][size_t(i >> 6)] |= uint64_t(1) << (i & 63);
  return mark;
}

// `mark` dilated by `radius` along every axis but `across` (the slices across that axis): one-axis
// dilations of the chunks' bits. Chunks the dilation reaches join the grid.
void dilate(Grid& g, std::vector<Bits>& mark, int radius, int across) {
  for (int axis = 0; axis < 3; ++axis) {
    if (axis == across) continue;
    std::vector<Bits> next(mark.size());
    const size_t chunks = mark.size();  // chunks added below only receive
    for (size_t slot = 0; slot < chunks; ++slot) {
      if (!any(mark[slot])) continue;
      Bits stay = mark[slot];
      std::array<Bits, 2> spill{};  // to the neighbour below, above
      for (int t = -radius; t <= radius; ++t) {
        if (t == 0) continue;
        const auto [in, out] = shifted(mark[slot], axis, t);
        for (int z = 0; z < kSide; ++z) stay[size_t(z)] |= in[size_t(z)], spill[t > 0][size_t(z)] |= out[size_t(z)];
      }
      for (int z = 0; z < kSide; ++z) next[slot][size_t(z)] |= stay[size_t(z)];
      for (int side = 0; side < 2; ++side) {
        if (!any(spill[size_t(side)])) continue;
        GridKey key = g.key(slot);
        key[size_t(axis)] += side ? 1 : -1;
        const size_t neighbour = g.get(key);
        if (neighbour >= next.size()) next.resize(g.size()), mark.resize(g.size());
        for (int z = 0; z < kSide; ++z) next[neighbour][size_t(z)] |= spill[size_t(side)][size_t(z)];
      }
    }
    mark = std::move(next);
  }
  mark.resize(g.size());
}

// fn(index) for every voxel of `mark`.
template <class Fn> void forEachBit(const std::vector<Bits>& mark, Fn&& fn) {
  for (size_t slot = 0; slot < mark.size(); ++slot)
    for (int z = 0; z < kSide; ++z)
      for (uint64_t w = mark[slot][size_t(z)]; w != 0; w &= w - 1)
        fn(slot * kVoxels + size_t(z) * 64 + size_t(std::countr_zero(w)));
}

// The region of each pass, from the requested voxels (their vote: pass `passes`) down. The vote of
// pass p at a voxel reads the axis-q matches of its neighbours within kV in its slice across q, so
// axis q is searched at pass p there, where searches() allows; each such search reads the colours
// within kR in the same slice, whose voxels therefore take part in the vote of pass p - 1 (0: Dong
// et al.'s triples).
void markRegion(Grid& g, int passes) {
  std::array<Bits, 3> searchable{};  // per axis, the chunk voxels searches() allows
  for (int q = 0; q < 3; ++q)
    for (int i = 0; i < kVoxels; ++i)
      if (searches(q, i & (kSide - 1), (i >> kShift) & (kSide - 1), i >> (2 * kShift)))
        searchable[size_t(q)][size_t(i >> 6)] |= uint64_t(1) << (i & 63);
  for (int p = passes; p >= 1; --p) {
    const std::vector<Bits> votes = maskWhere(g, [&](size_t i) { return g.pass[i] >= p; });
    std::vector<Bits> reads;
    for (int q = 0; q < 3; ++q) {
      std::vector<Bits> search = votes;
      dilate(g, search, kV, q);
      for (Bits& b : search)
        for (int z = 0; z < kSide; ++z) b[size_t(z)] &= searchable[size_t(q)][size_t(z)];
      forEachBit(search, [&](size_t i) { g.searched[i][size_t(q)] = std::max(g.searched[i][size_t(q)], int8_t(p)); });
      dilate(g, search, kR, q);
      reads.resize(g.size());
      for (size_t slot = 0; slot < search.size(); ++slot)
        for (int z = 0; z < kSide; ++z) reads[slot][size_t(z)] |= search[slot][size_t(z)];
    }
    forEachBit(reads, [&](size_t i) { g.pass[i] = std::max(g.pass[i], int8_t(p - 1)); });
  }
}

// One exemplar at the finest level, as the passes read it: colours padded by kR (wrapped or
// mirrored as the analysis reads them), four values per pixel (3x the 8-bit colour, then 0, so that
// a window's row is contiguous and vectorizes), 2-D candidates, the coordinates a triple may hold.
struct Exemplar {
  int width = 0, height = 0, pitch = 0;
  ExemplarWrap wrap = ExemplarWrap::Tile;
  ValidRegion valid;
  std::vector<int16_t> padded;  // (width + 2 kR) x (height + 2 kR) x 4
  const uint32_t* candidates = nullptr;
  int k = 0;

  const int16_t* colour3(int u, int v) const { return &padded[(size_t(v + kR) * size_t(pitch) + size_t(u + kR)) * 4]; }
  // The coordinate (u, v) moved by (du, dv): wrapped, or false when it leaves the valid region.
  bool moved(uint32_t c, int du, int dv, uint32_t& out) const {
    int u = int(coordU(c)) + du, v = int(coordV(c)) + dv;
    if (wrap == ExemplarWrap::Tile) {
      u = (u + width) % width, v = (v + height) % height;
    } else if (!valid.contains(u, v)) {
      return false;
    }
    out = packCoord(uint32_t(u), uint32_t(v));
    return true;
  }
};

Exemplar exemplarOf(const SolidAnalysis& a, int e) {
  const SolidLevel& level = a.levels.back();
  Exemplar x;
  x.width = a.width, x.height = a.height, x.pitch = a.width + 2 * kR, x.wrap = a.wrap, x.valid = level.valid;
  x.padded.resize(size_t(x.pitch) * size_t(a.height + 2 * kR) * 4);
  const std::vector<uint8_t>& c = level.colors[size_t(e)];
  for (int v = -kR; v < a.height + kR; ++v)
    for (int u = -kR; u < a.width + kR; ++u) {
      const size_t from = (size_t(foldIndex(v, a.height, a.wrap)) * size_t(a.width) + size_t(foldIndex(u, a.width, a.wrap))) * 3;
      for (int ch = 0; ch < 3; ++ch)
        x.padded[(size_t(v + kR) * size_t(x.pitch) + size_t(u + kR)) * 4 + size_t(ch)] = int16_t(3 * c[from + size_t(ch)]);
    }
  x.k = int(level.candidates2d[size_t(e)].size() / (size_t(a.width) * size_t(a.height)));
  x.candidates = level.candidates2d[size_t(e)].data();
  return x;
}

// A voxel's state between passes: its triple and colour (sum of its three 8-bit colours).
struct State {
  std::vector<uint32_t> triples;  // 3 per voxel
  std::vector<int16_t> colours;   // 3 per voxel
  explicit State(size_t voxels) : triples(voxels * 3), colours(voxels * 3) {}
};

// The search's result per voxel and axis: the match's centre and its vote weight,
// kWeightOne / (error + kErrorFloor).
struct Matches {
  std::vector<uint32_t> coords;   // 3 per voxel
  std::vector<uint32_t> weights;  // 3 per voxel
  explicit Matches(size_t voxels) : coords(voxels * 3), weights(voxels * 3) {}
};

void setColour(State& s, size_t i, const std::array<Exemplar, 3>& ex) {
  for (int c = 0; c < 3; ++c) {
    int sum = 0;
    for (int q = 0; q < 3; ++q) {
      const uint32_t t = s.triples[i * 3 + size_t(q)];
      sum += ex[size_t(q)].colour3(int(coordU(t)), int(coordV(t)))[c];
    }
    s.colours[i * 3 + size_t(c)] = int16_t(sum / 3);
  }
}

// Local offset of slice tap (a, b) across axis q: u along axis (q + 1) % 3, v along (q + 2) % 3
// (the orientation of solid_analysis.h).
std::array<int, 3> sliceOffset(int q, int a, int b) {
  std::array<int, 3> d{};
  d[size_t((q + 1) % 3)] = a;
  d[size_t((q + 2) % 3)] = b;
  return d;
}

class Refiner {
public:
  Refiner(const SolidAnalysis& a, Grid& g) : g_(g), ex_{exemplarOf(a, 0), exemplarOf(a, 1), exemplarOf(a, 2)} {}

  void search(int pass, const State& s, Matches& m, const Context& ctx) const {
    forEachVoxel(pass - 1, ctx, [&](const std::array<int32_t, 27>& nb, int x, int y, int z, size_t at) {
      for (int q = 0; q < 3; ++q)
        if (g_.searched[at][size_t(q)] >= pass) searchAxis(nb, x, y, z, q, s, m, at);
    });
  }

  void vote(int pass, const Matches& m, State& s, const Context& ctx) const {
    forEachVoxel(pass, ctx, [&](const std::array<int32_t, 27>& nb, int x, int y, int z, size_t at) {
      voteAt(nb, x, y, z, m, s, at);
    });
  }

  const std::array<Exemplar, 3>& exemplars() const { return ex_; }

private:
  // fn(chunk's neighbours, chunk-local x, y, z, index) for every voxel of pass >= `pass`, chunks in
  // parallel.
  template <class Fn> void forEachVoxel(int pass, const Context& ctx, Fn&& fn) const {
    parallelFor(0, int(g_.size()), ctx, [&](int s0, int s1) {
      for (int slot = s0; slot < s1; ++slot) {
        const auto nb = g_.neighbours(size_t(slot));
        for (int i = 0; i < kVoxels; ++i) {
          const size_t at = size_t(slot) * kVoxels + size_t(i);
          if (g_.pass[at] >= pass) fn(nb, i & (kSide - 1), (i >> kShift) & (kSide - 1), i >> (2 * kShift), at);
        }
      }
    });
  }

  void searchAxis(const std::array<int32_t, 27>& nb, int x, int y, int z, int q, const State& s, Matches& m,
                  size_t at) const {
    const Exemplar& e = ex_[size_t(q)];
    // Targets: the slice window's colours, their contrast raised around the window's mean.
    constexpr int kRow = (2 * kR + 1) * 4;
    std::array<int16_t, kTaps * 4> target{};
    std::array<int64_t, kTaps> voxel{};
    int32_t mean[3] = {0, 0, 0};
    for (int b = -kR, t = 0; b <= kR; ++b)
      for (int a = -kR; a <= kR; ++a, ++t) {
        const auto d = sliceOffset(q, a, b);
        voxel[size_t(t)] = voxelAt(nb, x + d[0], y + d[1], z + d[2]);
        for (int c = 0; c < 3; ++c) mean[c] += s.colours[size_t(voxel[size_t(t)]) * 3 + size_t(c)];
      }
    for (int& v : mean) v = (v + kTaps / 2) / kTaps;
    for (int t = 0; t < kTaps; ++t)
      for (int c = 0; c < 3; ++c) {
        const int v = s.colours[size_t(voxel[size_t(t)]) * 3 + size_t(c)];
        target[size_t(t * 4 + c)] = int16_t(std::clamp(mean[c] + (((v - mean[c]) * kRefineGain16) >> 4), 0, kMaxSum));
      }
    // Candidates: the 2-D candidates of the voxel's and its four slice neighbours' coordinates,
    // shifted back (the 3x3 neighbours cost 1.4x for the same figures).
    int32_t best = std::numeric_limits<int32_t>::max();
    uint32_t bestCoord = s.triples[at * 3 + size_t(q)];
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        if (di != 0 && dj != 0) continue;
        const auto d = sliceOffset(q, di, dj);
        const uint32_t c = s.triples[size_t(voxelAt(nb, x + d[0], y + d[1], z + d[2])) * 3 + size_t(q)];
        const uint32_t* set = e.candidates + (size_t(coordV(c)) * size_t(e.width) + coordU(c)) * size_t(e.k);
        for (int k = 0; k < e.k; ++k) {
          uint32_t centre;
          if (!e.moved(set[k], -di, -dj, centre)) continue;
          const int u = int(coordU(centre)), v = int(coordV(centre));
          int32_t ssd = 0;
          for (int b = -kR; b <= kR; ++b) {
            const int16_t* p = e.colour3(u - kR, v + b);
            const int16_t* t = &target[size_t((b + kR) * kRow)];
            for (int i = 0; i < kRow; ++i) {
              const auto diff = int16_t(t[i] - p[i]);  // |diff| <= 765: int16 products (pmaddwd)
              ssd += int32_t(diff) * diff;
            }
          }
          if (ssd < best) best = ssd, bestCoord = centre;
        }
      }
    m.coords[at * 3 + size_t(q)] = bestCoord;
    m.weights[at * 3 + size_t(q)] = uint32_t(kWeightOne / (uint64_t(best) + kErrorFloor));
  }

  void voteAt(const std::array<int32_t, 27>& nb, int x, int y, int z, const Matches& m, State& s, size_t at) const {
    // Predictions: each slice neighbour's match, shifted back to this voxel.
    struct Prediction {
      uint32_t coord;
      const int16_t* colour;
    };
    constexpr int kPerAxis = (2 * kV + 1) * (2 * kV + 1);
    std::array<std::array<Prediction, kPerAxis>, 3> predictions;
    std::array<int, 3> count{};
    uint64_t sum[3] = {0, 0, 0}, total = 0;
    for (int q = 0; q < 3; ++q) {
      const Exemplar& e = ex_[size_t(q)];
      for (int b = -kV; b <= kV; ++b)
        for (int a = -kV; a <= kV; ++a) {
          const auto d = sliceOffset(q, a, b);
          if (!searches(q, (x + d[0]) & (kSide - 1), (y + d[1]) & (kSide - 1), (z + d[2]) & (kSide - 1))) continue;
          const size_t w = size_t(voxelAt(nb, x + d[0], y + d[1], z + d[2]));
          const uint64_t weight = m.weights[w * 3 + size_t(q)];
          // A searched window weighs at least 2^40 / (2^31 + 512); 0 is one never searched.
          if (weight == 0) throw std::logic_error("refinement: a vote read a window that was not searched");
          uint32_t p;
          if (!e.moved(m.coords[w * 3 + size_t(q)], -a, -b, p)) continue;
          const int16_t* colour = e.colour3(int(coordU(p)), int(coordV(p)));
          for (int c = 0; c < 3; ++c) sum[c] += weight * uint64_t(colour[c]);
          total += weight;
          predictions[size_t(q)][size_t(count[size_t(q)]++)] = {p, colour};
        }
    }
    if (total == 0) return;  // every prediction left the valid region: the voxel keeps its triple
    int mean[3];
    for (int c = 0; c < 3; ++c) mean[c] = int((sum[c] + total / 2) / total);
    // Each exemplar's coordinate: its prediction nearest the weighted mean (the first of equals).
    for (int q = 0; q < 3; ++q) {
      int bestDistance = std::numeric_limits<int>::max();
      for (int k = 0; k < count[size_t(q)]; ++k) {
        const Prediction& p = predictions[size_t(q)][size_t(k)];
        int distance = 0;
        for (int c = 0; c < 3; ++c) distance += (p.colour[c] - mean[c]) * (p.colour[c] - mean[c]);
        if (distance < bestDistance) bestDistance = distance, s.triples[at * 3 + size_t(q)] = p.coord;
      }
    }
    setColour(s, at, ex_);
  }

  Grid& g_;
  std::array<Exemplar, 3> ex_;
};

// Refines one slab of a request: every requested voxel's region at once.
SolidSynthesisResult refineSlab(const SolidAnalysis& a, std::span<const Voxel> voxels,
                                const SolidSynthesisOptions& options, SolidLevelCache* cache, const Context& ctx) {
  const int passes = options.refinePasses;
  Stage regionStage(ctx, "refinement region");
  Grid g;
  for (const Voxel& v : voxels)
    g.pass[g.get({v.x >> kShift, v.y >> kShift, v.z >> kShift}) * kVoxels + size_t(localIndex(v.x, v.y, v.z))] =
        int8_t(passes);
  markRegion(g, passes);

  // Dong et al.'s triples of the whole region, listed in the grid's order.
  std::vector<Voxel> region;
  for (size_t slot = 0; slot < g.size(); ++slot)
    for (int i = 0; i < kVoxels; ++i)
      if (g.pass[slot * kVoxels + size_t(i)] >= 0) region.push_back(g.voxel(slot, i));
  regionStage.finish(std::to_string(region.size()) + " voxels for " + std::to_string(voxels.size()) + " requested");
  SolidSynthesisOptions dong = options;
  dong.refinePasses = 0;
  SolidSynthesisResult result = synthesizeSolid(a, region, dong, cache, ctx);

  Stage stage(ctx, "refinement");
  Refiner refiner(a, g);
  State state(g.size() * kVoxels);
  for (size_t at = 0, r = 0; at < g.pass.size(); ++at)
    if (g.pass[at] >= 0) {
      std::copy_n(result.triples[r++].begin(), 3, &state.triples[at * 3]);
      setColour(state, at, refiner.exemplars());
    }
  region = {};
  result.triples = {};
  Matches matches(g.size() * kVoxels);
  for (int p = 1; p <= passes; ++p) {
    refiner.search(p, state, matches, ctx);
    refiner.vote(p, matches, state, ctx);
    stage.advance(p, passes);
  }

  result.triples.resize(voxels.size());
  result.distinctVoxels = 0;
  for (size_t i = 0; i < voxels.size(); ++i) {
    const Voxel& v = voxels[i];
    const size_t at = g.index(v);
    std::copy_n(&state.triples[at * 3], 3, result.triples[i].begin());
    // The first request of a voxel marks it (one above the last pass).
    result.distinctVoxels += g.pass[at] == int8_t(passes);
    g.pass[at] = int8_t(passes + 1);
  }
  stage.finish(std::to_string(passes) + " passes over " + std::to_string(result.voxelsSynthesized()) + " voxels");
  return result;
}

// Slabs are at least 4 margins thick, so that the margins add at most half the work.
int64_t minSlabDepth(int passes) { return 4 * refineMargin(passes); }

} // namespace

double refineSolidMemoryBytes(int64_t voxels, int passes) {
  if (passes < 1) return 0;
  // A slab holds up to a quarter slab more than kRefineSlabVoxels, and the end of a layer.
  return double(std::min<int64_t>(voxels, kRefineSlabVoxels * 3 / 2)) * 140.0 * (1 + 2 * refineMargin(passes));
}

SolidSynthesisResult refineSolid(const SolidAnalysis& a, std::span<const Voxel> voxels,
                                 const SolidSynthesisOptions& options, SolidLevelCache* cache, const Context& ctx,
                                 int64_t slabVoxels) {
  if (options.refinePasses < 1) throw Error("refineSolid needs at least one pass");
  if (int64_t(voxels.size()) <= slabVoxels) return refineSlab(a, voxels, options, cache, ctx);
  // The requests ordered along the axis of their largest extent (the index, below 2^32, in the low
  // bits: stable), cut into slabs between layers across it.
  std::array<int64_t, 3> low{}, high{};
  low.fill(std::numeric_limits<int64_t>::max()), high.fill(std::numeric_limits<int64_t>::min());
  for (const Voxel& v : voxels)
    for (int c = 0; c < 3; ++c) {
      low[size_t(c)] = std::min(low[size_t(c)], v[c]);
      high[size_t(c)] = std::max(high[size_t(c)], v[c]);
    }
  int axis = 2;
  for (int c = 1; c >= 0; --c)
    if (high[size_t(c)] - low[size_t(c)] > high[size_t(axis)] - low[size_t(axis)]) axis = c;
  std::vector<uint64_t> order(voxels.size());
  for (size_t i = 0; i < voxels.size(); ++i) order[i] = uint64_t(voxels[i][axis] + kMaxSolidPosition) << 32 | i;
  std::sort(order.begin(), order.end());
  auto layer = [&](size_t k) { return int64_t(order[k] >> 32); };
  auto fills = [&](size_t b, size_t e) {  // the slab [b, e) needs no more (the rest: at least a quarter slab)
    return int64_t(e - b) >= slabVoxels && layer(e) >= layer(b) + minSlabDepth(options.refinePasses) &&
           layer(e) != layer(e - 1) && int64_t(order.size() - e) >= slabVoxels / 4;
  };
  std::vector<size_t> cuts{0};
  for (size_t e = 0; e < order.size(); cuts.push_back(e))
    while (e < order.size() && !fills(cuts.back(), e)) ++e;
  SolidSynthesisResult result;
  result.triples.resize(voxels.size());
  std::vector<Voxel> part;
  for (size_t s = 0; s + 1 < cuts.size(); ++s) {
    const size_t b = cuts[s], e = cuts[s + 1];
    Stage stage(ctx, "refinement slab " + std::to_string(s + 1) + "/" + std::to_string(cuts.size() - 1));
    part.clear();
    for (size_t k = b; k < e; ++k) part.push_back(voxels[uint32_t(order[k])]);
    SolidSynthesisResult slab = refineSlab(a, part, options, cache, stage.inner());
    for (size_t k = b; k < e; ++k) result.triples[uint32_t(order[k])] = slab.triples[k - b];
    addLevelStats(result.levels, slab);
    result.distinctVoxels += slab.distinctVoxels;  // a voxel's requests share a layer, so a slab
    stage.finish(std::to_string(e - b) + " requested voxels");
  }
  return result;
}

SolidSynthesisResult refineSolidBox(const SolidAnalysis& a, const VoxelBox& box, const SolidSynthesisOptions& options,
                                    SolidLevelCache* cache, const Context& ctx, int64_t slabVoxels) {
  if (options.refinePasses < 1) throw Error("refineSolid needs at least one pass");
  const int64_t slice = int64_t(box.nx) * box.ny;
  const int64_t thick = std::max<int64_t>(slabVoxels / slice, minSlabDepth(options.refinePasses));
  const int depth = int(std::min<int64_t>(thick, box.nz));
  const int slabs = (box.nz + depth - 1) / depth;
  std::vector<Voxel> voxels;
  auto layers = [&](int z0, int nz) {  // the voxels of layers [z0, z0 + nz), in the box's order
    voxels.clear();
    for (int z = z0; z < z0 + nz; ++z)
      for (int y = 0; y < box.ny; ++y)
        for (int x = 0; x < box.nx; ++x) voxels.push_back({box.x + x, box.y + y, box.z + z});
    return std::span<const Voxel>(voxels);
  };
  if (slabs == 1) return refineSlab(a, layers(0, box.nz), options, cache, ctx);
  SolidSynthesisResult result;
  result.triples.resize(size_t(box.count()));
  for (int z0 = 0; z0 < box.nz; z0 += depth) {
    const int nz = std::min(depth, box.nz - z0);
    Stage stage(ctx, "refinement slab " + std::to_string(z0 / depth + 1) + "/" + std::to_string(slabs));
    const SolidSynthesisResult part = refineSlab(a, layers(z0, nz), options, cache, stage.inner());
    std::copy(part.triples.begin(), part.triples.end(), result.triples.begin() + z0 * slice);
    addLevelStats(result.levels, part);
    stage.finish(std::to_string(nz) + " layers");
  }
  result.distinctVoxels = box.count();
  return result;
}

} // namespace texfab::synthesis
