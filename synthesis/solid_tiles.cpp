// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/solid_tiles.h"

#include "core/error.h"
#include "core/files.h"
#include "core/hash.h"
#include "core/parallel.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/binary_io.h"
#include "synthesis/coord_map.h"
#include "synthesis/cpu/synthesis_kernels.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

namespace texfab::synthesis {

namespace fs = std::filesystem;

void SolidTileOptions::validate() const {
  if (tileSide < 8 || tileSide > 64 || !std::has_single_bit(uint32_t(tileSide)))
    throw Error("tile side must be 8, 16, 32 or 64, got " + std::to_string(tileSide));
  if (faceVariants != 2 && faceVariants != 3)
    throw Error("face variants must be 2 or 3, got " + std::to_string(faceVariants));
  if (arrangementCopies != 1 && arrangementCopies != 2)
    throw Error("arrangement copies must be 1 or 2, got " + std::to_string(arrangementCopies));
  if (iterations < 1 || iterations > 16 || finestIterations < 1 || finestIterations > 16)
    throw Error("tile iterations must be in [1, 16]");
  if (!(histogramWeight >= 0.0f && histogramWeight <= 16.0f))
    throw Error("histogram weight must be in [0, 16], got " + std::to_string(histogramWeight));
}

SolidTileLayout::SolidTileLayout(int n, int faceVariants)
    : side(n), shift(n > 0 ? std::countr_zero(uint32_t(n)) : 0), variants(faceVariants) {
  const size_t m = n > 0 ? size_t(n - 1) : 0, v = size_t(faceVariants);
  faces = 2 + 6 * m;
  interiors = faces + 3 * v * m * m;
  elements = interiors + v * v * v * v * v * v * m * m * m;
}

size_t SolidTileLayout::element(int x, int y, int z, uint32_t code) const {
  const size_t m = size_t(side - 1), tile = code & 1023u;
  const int local[3] = {x, y, z};
  const int zeros = (x == 0) + (y == 0) + (z == 0);
  if (zeros == 0)  // the interior of the tile of the cell's 6 face variants
    return interiors + ((tile * m + size_t(z - 1)) * m + size_t(y - 1)) * m + size_t(x - 1);
  if (zeros == 1) {  // a face, of the axis whose coordinate is 0: its start variant, digit 2a
    const int a = x == 0 ? 0 : y == 0 ? 1 : 2, b = (a + 1) % 3, c = (a + 2) % 3;
    size_t digit = tile;
    for (int i = 0; i < 2 * a; ++i) digit /= size_t(variants);
    const size_t face = size_t(a) * size_t(variants) + digit % size_t(variants);
    return faces + (face * m + size_t(local[c] - 1)) * m + size_t(local[b] - 1);
  }
  if (zeros == 2) {  // an edge, along the axis whose coordinate is not 0
    const int a = x != 0 ? 0 : y != 0 ? 1 : 2;
    const size_t edge = size_t(a) * 2 + ((code >> (10 + a)) & 1u);
    return 2 + edge * m + size_t(local[a] - 1);
  }
  return (code >> 13) & 1u;
}

namespace {

constexpr uint32_t kTilesMagic = 0x53544654;  // "TFTS"
constexpr uint32_t kTilesVersion = 3;
constexpr uint32_t kOptimizationSeed = 0x2545f491u;
constexpr uint32_t kArrangementPurpose = 0x41525247u;
constexpr uint32_t kPlacementPurpose = 0x504c4345u;
constexpr uint32_t kInitPurpose = 0x494e4954u;
constexpr uint32_t kSearchPurpose = 0x53524348u;
constexpr int kRadius = 2;  // 5x5 neighborhoods, as the analysis' descriptors
// Levels whose tiles would be narrower are skipped: their few interior voxels cannot differ from
// tile to tile, and every tile would inherit the same coarse structure, repeating with the tile
// period (GIMP patterns: shifted self-correlation at the period 0.3-0.7 with 4-voxel tiles at the
// coarsest level, 0.2-0.3 without; a start at 16 voxels lowers it further and loses fidelity).
constexpr int kMinTileSide = 8;

// The exemplar's u and v axes in the volume (solid_analysis.h: E_x in (y, z), E_y in (z, x), E_z
// in (x, y)).
constexpr int axisU(int e) { return (e + 1) % 3; }
constexpr int axisV(int e) { return (e + 2) % 3; }

// One exemplar at one level, as the optimization reads it.
struct ExemplarLevel {
  int w = 0, h = 0, spacing = 1, stride = 0, k = 0;
  bool wraps = true;
  ValidRegion valid;
  const uint8_t* rgb = nullptr;
  const uint32_t* candidates = nullptr;
  const int8_t* descriptors = nullptr;

  ExemplarLevel(const SolidAnalysis& a, const SolidLevel& l, int e)
      : w(a.width), h(a.height), spacing(l.spacing), wraps(a.wrap == ExemplarWrap::Tile), valid(l.valid),
        rgb(l.colors[size_t(e)].data()), candidates(l.candidates2d[size_t(e)].data()),
        descriptors(l.descriptors2d[size_t(e)].data()) {
    stride = int(l.candidates2d[size_t(e)].size() / (size_t(w) * size_t(h)));
    k = std::min(l.k2d, stride);
  }
  size_t pixel(uint32_t c) const { return size_t(coordV(c)) * size_t(w) + coordU(c); }
  // c moved by (du, dv) pixels: wrapped, or (non-toroidal) false when it leaves the valid region.
  bool shift(uint32_t c, int64_t du, int64_t dv, uint32_t& out) const {
    const int64_t u = int64_t(coordU(c)) + du, v = int64_t(coordV(c)) + dv;
    if (wraps) {
      out = packCoord(uint32_t(cpu::floorMod(u, w)), uint32_t(cpu::floorMod(v, h)));
      return true;
    }
    if (!valid.contains(u, v)) return false;
    out = packCoord(uint32_t(u), uint32_t(v));
    return true;
  }
  // The colour at c moved by (du, dv): wrapped, or mirrored into the exemplar.
  const uint8_t* colorAt(uint32_t c, int64_t du, int64_t dv) const {
    int64_t u = int64_t(coordU(c)) + du, v = int64_t(coordV(c)) + dv;
    if (wraps) {
      u = cpu::floorMod(u, w);
      v = cpu::floorMod(v, h);
    } else {
      u = cpu::reflectInto(u, 0, w - 1);
      v = cpu::reflectInto(v, 0, h - 1);
    }
    return rgb + (size_t(v) * size_t(w) + size_t(u)) * 3;
  }
  // A child coordinate at the next finer level (spacing `child`), bit 0 or 1 as
  // cpu::upsampleKernel; bit -1: one step before the parent.
  uint32_t upsample(uint32_t c, int bitU, int bitV, int child) const {
    if (wraps)
      return packCoord(uint32_t(cpu::floorMod(int64_t(coordU(c)) + child * bitU, w)),
                       uint32_t(cpu::floorMod(int64_t(coordV(c)) + child * bitV, h)));
    auto axis = [&](int64_t x, int bit, int lo, int hi) {
      int64_t b = std::min<int64_t>(x, hi - child);
      if (b < lo) b = lo;
      return uint32_t(std::clamp<int64_t>(b + int64_t(child) * bit, lo, hi));
    };
    return packCoord(axis(coordU(c), bitU, valid.x0, valid.x1), axis(coordV(c), bitV, valid.y0, valid.y1));
  }
};

// A periodic arrangement of cells^3 tiles (cells = V^2 or 2 V^2) in which every tile of the set
// appears equally often (once or 8 times): along each axis a face variants follow a de Bruijn
// sequence (0011, or 001021122: every ordered pair of variants, a tile's two faces, once per
// period) shifted by s_a. The shifts are triangular in a permutation (a, b, c) of the axes (s_a a
// function of the cell's b and c, s_b of its c, s_c a constant), so the cell -> tile map stays
// onto, and they are drawn anew per salt so that tiles meet different neighbours. Edge and corner
// variants are plain hashes of the cell.
struct Arrangement {
  int cells = 0, side = 0;
  std::vector<uint32_t> element;  // side^3, x fastest

  Arrangement(const SolidTileLayout& layout, int copies, uint32_t salt, const Context& ctx)
      : cells(layout.variants * layout.variants * copies), side(cells * layout.side),
        element(size_t(side) * side * side) {
    // De Bruijn sequences: every ordered pair of variants once per period.
    const std::array<int, 9> sequence = layout.variants == 2 ? std::array<int, 9>{0, 0, 1, 1} :
                                                               std::array<int, 9>{0, 0, 1, 0, 2, 1, 1, 2, 2};
    const int period = layout.variants * layout.variants;
    const uint32_t order = voxelHash(kOptimizationSeed, salt, 0, 0, 0, kArrangementPurpose + 16) % 6;
    const int a = int(order / 2), b = (a + 1 + int(order % 2)) % 3, c = 3 - a - b;
    int rank[3];
    rank[a] = 0;
    rank[b] = 1;
    rank[c] = 2;
    const int by[3] = {b, c, -1}, bz[3] = {c, -1, -1};  // what each rank's shift depends on
    auto shift = [&](int axis, const int64_t* cell) {
      const int r = rank[axis];
      const int32_t u = by[r] < 0 ? 0 : int32_t(cpu::floorMod(cell[by[r]], cells));
      const int32_t v = bz[r] < 0 ? 0 : int32_t(cpu::floorMod(cell[bz[r]], cells));
      return int64_t(voxelHash(kOptimizationSeed, salt, u, v, r, kArrangementPurpose + 8) % uint32_t(cells));
    };
    auto variant = [&](int kind, int64_t x, int64_t y, int64_t z) {
      const int64_t cell[3] = {x, y, z};
      if (kind < 3) return uint32_t(sequence[size_t(cpu::floorMod(cell[kind] + shift(kind, cell), period))]);
      return voxelHash(kOptimizationSeed, salt, int32_t(cpu::floorMod(x, cells)), int32_t(cpu::floorMod(y, cells)),
                       int32_t(cpu::floorMod(z, cells)), kArrangementPurpose + uint32_t(kind)) & 1u;
    };
    parallelFor(0, side, ctx, [&](int z0, int z1) {
      for (int z = z0; z < z1; ++z)
        for (int y = 0; y < side; ++y)
          for (int x = 0; x < side; ++x)
            element[index(x, y, z)] = uint32_t(layout.element(x, y, z, variant));
    });
  }
  size_t index(int x, int y, int z) const { return (size_t(z) * side + size_t(y)) * side + size_t(x); }
  size_t voxels() const { return element.size(); }
};

// The optimization state of one level: per storage element, a triple and the voted colour (6x
// 8-bit units, the scale of the projection inputs).
struct LevelState {
  SolidTileLayout layout;
  std::vector<Triple> triples;
  std::vector<std::array<int16_t, 3>> colors;
};

std::array<int16_t, 3> meanColor(const std::array<ExemplarLevel, 3>& ex, const Triple& t) {
  std::array<int16_t, 3> c{};
  for (int ch = 0; ch < 3; ++ch) {
    int sum = 0;
    for (int e = 0; e < 3; ++e) sum += ex[size_t(e)].rgb[ex[size_t(e)].pixel(t[size_t(e)]) * 3 + size_t(ch)];
    c[size_t(ch)] = int16_t(2 * sum);  // 6 * sum / 3
  }
  return c;
}

// One search-and-vote iteration (Kopf et al. §3, Chen & Wang's position histogram) over one
// arrangement; returns the mean best distance.
class Iteration {
public:
  Iteration(const SolidLevel& level, const std::array<ExemplarLevel, 3>& ex, const Arrangement& arr, uint32_t salt,
            float penaltyScale, const Context& ctx)
      : level_(level), ex_(ex), arr_(arr), salt_(salt), penaltyScale_(penaltyScale), ctx_(ctx) {}

  double run(LevelState& state) {
    gather(state);
    countUsage();
    search();
    vote();
    matchHistograms();
    reduce(state);
    double sum = 0;
    for (int32_t d : distance_) sum += double(d);
    return sum / double(distance_.size());
  }

private:
  size_t neighbor(int x, int y, int z, int e, int64_t du, int64_t dv) const {
    int p[3] = {x, y, z};
    p[axisU(e)] = int(cpu::floorMod(p[axisU(e)] + du, arr_.side));
    p[axisV(e)] = int(cpu::floorMod(p[axisV(e)] + dv, arr_.side));
    return arr_.index(p[0], p[1], p[2]);
  }

  void gather(const LevelState& state) {
    const size_t n = arr_.voxels();
    colors_.resize(n);
    triples_.resize(n);
    for (size_t v = 0; v < n; ++v) {
      colors_[v] = state.colors[arr_.element[v]];
      triples_[v] = state.triples[arr_.element[v]];
    }
  }

  void countUsage() {
    for (int e = 0; e < 3; ++e) {
      auto& u = usage_[size_t(e)];
      u.assign(size_t(ex_[size_t(e)].w) * size_t(ex_[size_t(e)].h), 0);
      for (const Triple& t : triples_) ++u[ex_[size_t(e)].pixel(t[size_t(e)])];
    }
    const ValidRegion& r = ex_[0].valid;
    const double pixels = double(r.x1 - r.x0 + 1) * double(r.y1 - r.y0 + 1);
    share_ = float(double(arr_.voxels()) / pixels);
  }

  // Best match of every voxel's three slice neighborhoods among its k-coherence candidates.
  void search() {
    const size_t n = arr_.voxels();
    match_.resize(n * 3);
    distance_.resize(n * 3);
    const int side = arr_.side;
    parallelFor(0, side, ctx_, [&](int z0, int z1) {
      int32_t values[75];
      int8_t target[kSolid2dDims];
      for (int z = z0; z < z1; ++z)
        for (int y = 0; y < side; ++y)
          for (int x = 0; x < side; ++x)
            for (int e = 0; e < 3; ++e) {
              int32_t* out = values;
              for (int j = -kRadius; j <= kRadius; ++j)
                for (int i = -kRadius; i <= kRadius; ++i) {
                  const auto& c = colors_[neighbor(x, y, z, e, i, j)];
                  for (int ch = 0; ch < 3; ++ch) *out++ = c[size_t(ch)];
                }
              level_.projection2d.project(values, target);
              const size_t v = arr_.index(x, y, z);
              bestCandidate(x, y, z, e, target, match_[v * 3 + size_t(e)], distance_[v * 3 + size_t(e)]);
            }
    });
  }

  // PatchMatch-style search (Barnes et al. 2009) over k-coherence candidates: the coherent
  // candidates of the 3x3 neighbours, then random positions around the best at halving radii, so
  // that the search leaves a region it has collapsed into; costs include the position histogram.
  void bestCandidate(int x, int y, int z, int e, const int8_t* target, uint32_t& best, int32_t& bestDistance) const {
    const ExemplarLevel& ex = ex_[size_t(e)];
    const auto& usage = usage_[size_t(e)];
    float bestCost = 0;
    bool found = false;
    auto consider = [&](uint32_t c) {
      const size_t p = ex.pixel(c);
      const int8_t* d = ex.descriptors + p * kSolid2dDims;
      int32_t dist = 0;
      for (int t = 0; t < kSolid2dDims; ++t) {
        const int32_t diff = int32_t(d[t]) - int32_t(target[t]);
        dist += diff * diff;
      }
      const float excess = float(usage[p]) / share_ - 1.0f;
      const float cost = float(dist) + (excess > 0.0f ? penaltyScale_ * excess : 0.0f);
      if (!found || cost < bestCost || (cost == bestCost && c < best)) {
        found = true;
        bestCost = cost;
        best = c;
        bestDistance = dist;
      }
    };
    for (int j = -1; j <= 1; ++j)
      for (int i = -1; i <= 1; ++i) {
        uint32_t base;
        if (!ex.shift(triples_[neighbor(x, y, z, e, i, j)][size_t(e)], -int64_t(i) * ex.spacing,
                      -int64_t(j) * ex.spacing, base))
          continue;
        const uint32_t* cands = ex.candidates + ex.pixel(base) * size_t(ex.stride);
        for (int m = 0; m < ex.k; ++m) consider(cands[m]);
      }
    if (!found) consider(triples_[arr_.index(x, y, z)][size_t(e)]);
    const ValidRegion& r = ex.valid;
    int radius = std::max(r.x1 - r.x0, r.y1 - r.y0) + 1;
    for (int t = 0; radius >= 1; ++t, radius /= 2) {
      const uint32_t h = voxelHash(kOptimizationSeed, salt_, x, y, z, kSearchPurpose + uint32_t(e * 16 + t));
      const int64_t du = int64_t(h & 0xffffu) % (2 * radius + 1) - radius;
      const int64_t dv = int64_t(h >> 16) % (2 * radius + 1) - radius;
      uint32_t c;
      if (ex.shift(best, du, dv, c)) consider(c);
    }
  }

  // Each voxel's colour: the IRLS-weighted mean of what the neighborhoods covering it voted.
  void vote() {
    votedColors_.resize(arr_.voxels());
    const int side = arr_.side;
    parallelFor(0, side, ctx_, [&](int z0, int z1) {
      for (int z = z0; z < z1; ++z)
        for (int y = 0; y < side; ++y)
          for (int x = 0; x < side; ++x) voteVoxel(x, y, z);
    });
  }

  void voteVoxel(int x, int y, int z) {
    float sum[3] = {0, 0, 0}, weights = 0;
    for (int e = 0; e < 3; ++e) {
      const ExemplarLevel& ex = ex_[size_t(e)];
      for (int j = -kRadius; j <= kRadius; ++j)
        for (int i = -kRadius; i <= kRadius; ++i) {
          const size_t q = neighbor(x, y, z, e, -i, -j) * 3 + size_t(e);
          const float w = 1.0f / (1.0f + std::sqrt(float(distance_[q])));
          const uint8_t* c = ex.colorAt(match_[q], int64_t(i) * ex.spacing, int64_t(j) * ex.spacing);
          for (int ch = 0; ch < 3; ++ch) sum[ch] += w * float(c[ch]);
          weights += w;
        }
    }
    std::array<int16_t, 3>& color = votedColors_[arr_.index(x, y, z)];
    for (int ch = 0; ch < 3; ++ch) color[size_t(ch)] = int16_t(std::floor(6.0f * sum[ch] / weights + 0.5f));
  }

  // Kopf et al. §3.3, as a transfer: each channel of the voted colours mapped onto the exemplar's
  // distribution at this level (a voted colour averages disagreeing votes and regresses to the
  // mean; the search would then prefer the exemplar's flat regions).
  void matchHistograms() {
    constexpr int kValues = 6 * 255 + 1;
    for (int ch = 0; ch < 3; ++ch) {
      std::vector<int64_t> source(kValues, 0), target(256, 0);
      for (const auto& c : votedColors_) ++source[size_t(std::clamp<int>(c[size_t(ch)], 0, kValues - 1))];
      for (int e = 0; e < 3; ++e) {
        const ExemplarLevel& ex = ex_[size_t(e)];
        for (int v = ex.valid.y0; v <= ex.valid.y1; ++v)
          for (int u = ex.valid.x0; u <= ex.valid.x1; ++u)
            ++target[ex.rgb[(size_t(v) * size_t(ex.w) + size_t(u)) * 3 + size_t(ch)]];
      }
      int64_t sourceTotal = 0, targetTotal = 0;
      for (int64_t c : source) sourceTotal += c;
      for (int64_t c : target) targetTotal += c;
      std::vector<int16_t> map(kValues, 0);
      int64_t below = 0, targetBelow = 0;
      int bin = 0;
      for (int value = 0; value < kValues; ++value) {
        // the target value at quantile (below + count / 2) / sourceTotal, in 1/6 units
        const int64_t q = (2 * below + source[size_t(value)]) * targetTotal;  // times 2 * sourceTotal
        while (bin < 255 && 2 * sourceTotal * (targetBelow + target[size_t(bin)]) <= q)
          targetBelow += target[size_t(bin++)];
        const int64_t inBin = target[size_t(bin)] > 0 ? q - 2 * sourceTotal * targetBelow : 0;
        const int64_t span = 2 * sourceTotal * std::max<int64_t>(1, target[size_t(bin)]);
        map[size_t(value)] = int16_t(std::clamp<int64_t>(6 * bin - 3 + (6 * inBin + span / 2) / span, 0, kValues - 1));
        below += source[size_t(value)];
      }
      for (auto& c : votedColors_) c[size_t(ch)] = map[size_t(std::clamp<int>(c[size_t(ch)], 0, kValues - 1))];
    }
  }

  // Each storage element takes the voted colour and the best matches (the centres of its three
  // neighborhoods' matches) of the occurrence whose neighborhoods matched best (the first of
  // equals): a face shared by many tiles keeps the values of one context instead of a blend of
  // all, which would flatten it.
  void reduce(LevelState& state) const {
    std::vector<int64_t> best(state.colors.size(), -1);
    for (size_t v = 0; v < arr_.voxels(); ++v) {
      const uint32_t el = arr_.element[v];
      const int64_t error = int64_t(distance_[v * 3]) + distance_[v * 3 + 1] + distance_[v * 3 + 2];
      if (best[el] >= 0 && error >= best[el]) continue;
      best[el] = error;
      state.colors[el] = votedColors_[v];
      state.triples[el] = {match_[v * 3], match_[v * 3 + 1], match_[v * 3 + 2]};
    }
  }

  const SolidLevel& level_;
  const std::array<ExemplarLevel, 3>& ex_;
  const Arrangement& arr_;
  uint32_t salt_ = 0;
  float penaltyScale_ = 0;
  const Context& ctx_;
  float share_ = 1;
  std::array<std::vector<int32_t>, 3> usage_;
  std::vector<std::array<int16_t, 3>> colors_, votedColors_;
  std::vector<Triple> triples_;
  std::vector<uint32_t> match_;
  std::vector<int32_t> distance_;
};

std::array<ExemplarLevel, 3> exemplarLevels(const SolidAnalysis& a, const SolidLevel& l) {
  return {ExemplarLevel(a, l, 0), ExemplarLevel(a, l, 1), ExemplarLevel(a, l, 2)};
}

// A random 3-D candidate of the analysis' coarsest level for every element, whatever level the
// optimization starts at: its crossbars agree at the largest scale the analysis has (the start
// level's own candidates, measured on five patterns: fidelity within 2 %, the lattice higher on
// two and lower on one). Colours: that level's mean of three.
LevelState initialState(const SolidAnalysis& a, const SolidTileLayout& layout) {
  const SolidLevel& level = a.levels.front();
  const auto ex = exemplarLevels(a, level);
  LevelState s{layout, {}, {}};
  s.triples.resize(s.layout.elements);
  s.colors.resize(s.layout.elements);
  const uint32_t pixels = uint32_t(a.width * a.height);
  for (size_t el = 0; el < s.layout.elements; ++el) {
    const uint32_t h = voxelHash(kOptimizationSeed, 0, int32_t(el), int32_t(el >> 31), 0, kInitPurpose);
    const uint32_t* t = &level.triples[0][(size_t(h % pixels) * kSolidMaxCandidates) * 3];
    s.triples[el] = {t[0], t[1], t[2]};
    s.colors[el] = meanColor(ex, s.triples[el]);
  }
  return s;
}

// The next finer level: each element takes its parent's triple moved by its sub-voxel offset
// (coordinate inheritance, as lazy synthesis upsamples), read through one arrangement that both
// levels share. At the finest level, a tile's last voxel along an axis takes the next cell's face
// one step back instead, as its first two take their own face, so that the face continues into
// both of its sides: from its own parent, the step the optimization leaves where a tile meets the
// next face, passed on from level to level, stays on the face planes as a seam. (At coarser
// levels too, the face's content would reach several voxels into every tile that shares it: a
// stronger lattice.)
LevelState upsample(const SolidAnalysis& a, const LevelState& parent, int childLevel, int copies, const Context& ctx) {
  const SolidLevel& level = a.levels[size_t(childLevel)];
  const auto ex = exemplarLevels(a, level);
  LevelState child{SolidTileLayout(parent.layout.side * 2, parent.layout.variants), {}, {}};
  const uint32_t salt = 0x10000u + uint32_t(childLevel);
  const Arrangement up(parent.layout, copies, salt, ctx), down(child.layout, copies, salt, ctx);
  child.triples.resize(child.layout.elements);
  child.colors.resize(child.layout.elements);
  std::vector<uint8_t> set(child.layout.elements, 0);
  const int n = child.layout.side;
  const bool finest = childLevel + 1 == int(a.levels.size());
  for (int z = 0; z < down.side; ++z)
    for (int y = 0; y < down.side; ++y)
      for (int x = 0; x < down.side; ++x) {
        const uint32_t el = down.element[down.index(x, y, z)];
        if (set[el]) continue;
        set[el] = 1;
        const int at[3] = {x, y, z};
        int from[3], bits[3];
        for (int d = 0; d < 3; ++d) {
          const bool last = finest && (at[d] & (n - 1)) == n - 1;
          from[d] = last ? (at[d] + 1) / 2 % up.side : at[d] / 2;
          bits[d] = last ? -1 : at[d] & 1;
        }
        const Triple& p = parent.triples[up.element[up.index(from[0], from[1], from[2])]];
        for (int e = 0; e < 3; ++e)
          child.triples[el][size_t(e)] =
              ex[size_t(e)].upsample(p[size_t(e)], bits[axisU(e)], bits[axisV(e)], level.spacing);
      }
  LevelState fallback = initialState(a, child.layout);  // elements no arrangement showed (rare)
  for (size_t el = 0; el < child.layout.elements; ++el) {
    if (!set[el]) child.triples[el] = fallback.triples[el];
    child.colors[el] = meanColor(ex, child.triples[el]);
  }
  return child;
}

} // namespace

double solidTilesCpuSeconds(const SolidTileOptions& o) {
  const double finest = std::pow(double(o.faceVariants * o.faceVariants * o.arrangementCopies * o.tileSide), 3.0);
  return finest * 6e-6 * (o.finestIterations + o.iterations / 7.0);  // measured: ~6 us per voxel and iteration
}

uint64_t solidTilesKey(const SolidAnalysis& a, const SolidTileOptions& o) {
  Fnv1a hash;
  hash.add(kTilesMagic);
  hash.add(kTilesVersion);
  hash.add(a.key);
  hash.add(o.tileSide);
  hash.add(o.faceVariants);
  hash.add(o.arrangementCopies);
  hash.add(o.iterations);
  hash.add(o.finestIterations);
  hash.add(o.histogramWeight);
  return hash.h;
}

SolidTileSet buildSolidTiles(const SolidAnalysis& a, const SolidTileOptions& o, const Context& ctx) {
  o.validate();
  const auto started = std::chrono::steady_clock::now();
  const int levels = int(a.levels.size());
  const int side = o.tileSide;
  int first = 0;  // the coarsest level whose tiles are kMinTileSide voxels wide or more
  while (first + 1 < levels && (side >> (levels - 1 - first)) < kMinTileSide) ++first;
  reportEstimate(ctx, solidTilesCpuSeconds(o), "the solid tile set");
  LevelState state = initialState(a, SolidTileLayout(side >> (levels - 1 - first), o.faceVariants));
  for (int l = first; l < levels; ++l) {
    Stage stage(ctx, "tiles level " + std::to_string(l - first + 1) + "/" + std::to_string(levels - first));
    if (l > first) state = upsample(a, state, l, o.arrangementCopies, stage.inner());
    const SolidLevel& level = a.levels[size_t(l)];
    const auto ex = exemplarLevels(a, level);
    const int iterations = l + 1 == levels ? o.finestIterations : o.iterations;
    double spread = 0;  // the mean squared norm of the level's (centred) descriptors
    for (int8_t d : level.descriptors2d[0]) spread += double(d) * double(d);
    spread /= double(level.descriptors2d[0].size() / kSolid2dDims);
    const float penaltyScale = float(spread * o.histogramWeight);
    double meanDistance = 0;
    for (int it = 0; it < iterations; ++it) {
      const uint32_t salt = uint32_t(l * 64 + it);
      const Arrangement arr(state.layout, o.arrangementCopies, salt, stage.inner());
      meanDistance = Iteration(level, ex, arr, salt, penaltyScale, stage.inner()).run(state);
      stage.advance(it + 1, iterations);
    }
    char detail[96];
    std::snprintf(detail, sizeof detail, "%d^3 voxels per tile, mean best distance %.1f", state.layout.side,
                  meanDistance);
    stage.finish(detail);
  }
  SolidTileSet tiles;
  tiles.width = a.width;
  tiles.height = a.height;
  tiles.layout = state.layout;
  tiles.elements = std::move(state.triples);
  tiles.key = solidTilesKey(a, o);
  tiles.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return tiles;
}

// ---- evaluation ----

namespace {

struct Placement {
  uint32_t seed;
  uint32_t variants;
  uint32_t operator()(int kind, int64_t x, int64_t y, int64_t z) const {
    const uint32_t h = voxelHash(seed, kPlacementPurpose, int32_t(x), int32_t(y), int32_t(z), uint32_t(kind));
    return kind < 3 ? h % variants : h & 1u;
  }
};

} // namespace

Triple SolidTileReader::operator()(int64_t x, int64_t y, int64_t z) {
  const SolidTileLayout& layout = tiles_.layout;
  const int64_t c[3] = {x >> layout.shift, y >> layout.shift, z >> layout.shift};
  if (c[0] != cell_[0] || c[1] != cell_[1] || c[2] != cell_[2]) {
    std::copy_n(c, 3, cell_);
    bits_ = layout.cellCode(c[0], c[1], c[2], Placement{seed_, uint32_t(layout.variants)});
  }
  const int64_t mask = layout.side - 1;
  return tiles_.elements[layout.element(int(x & mask), int(y & mask), int(z & mask), bits_)];
}

const SolidTileSet& requireTiles(const SolidAnalysis& analysis) {
  if (!analysis.tiles) throw Error("the solid tiles method needs the analysis' tile set (buildSolidTilesCached)");
  return *analysis.tiles;
}

void evaluateSolidTiles(const SolidTileSet& tiles, uint32_t seed, std::span<const Voxel> voxels, std::span<Triple> out,
                        const Context& ctx) {
  if (out.size() != voxels.size()) throw Error("evaluateSolidTiles: one output per voxel");
  const int count = int(std::min<size_t>(voxels.size(), size_t(1) << 30));
  parallelFor(0, count, ctx, [&](int begin, int end) {
    SolidTileReader read(tiles, seed);
    for (int i = begin; i < end; ++i) {
      const Voxel& v = voxels[size_t(i)];
      out[size_t(i)] = read(v.x, v.y, v.z);
    }
  }, 4096);
}

void evaluateSolidTilesBox(const SolidTileSet& tiles, uint32_t seed, const VoxelBox& box, std::span<Triple> out,
                           const Context& ctx) {
  if (int64_t(out.size()) != box.count()) throw Error("evaluateSolidTilesBox: one output per voxel");
  const SolidTileLayout& layout = tiles.layout;
  const Placement placement{seed, uint32_t(layout.variants)};
  const int mask = layout.side - 1;
  parallelFor(0, box.nz, ctx, [&](int z0, int z1) {
    for (int z = z0; z < z1; ++z)
      for (int y = 0; y < box.ny; ++y) {
        Triple* row = &out[(size_t(z) * size_t(box.ny) + size_t(y)) * size_t(box.nx)];
        const int64_t vy = box.y + y, vz = box.z + z;
        // One cell's run of the row at a time: SolidTileReader's per-voxel cell check makes a box
        // about 40 % slower.
        for (int x = 0; x < box.nx;) {
          const int64_t vx = box.x + x;
          const uint32_t bits = layout.cellCode(vx >> layout.shift, vy >> layout.shift, vz >> layout.shift, placement);
          const int run = std::min<int>(box.nx - x, layout.side - int(vx & mask));
          for (int i = 0; i < run; ++i, ++x)
            row[x] = tiles.elements[layout.element(int((vx + i) & mask), int(vy & mask), int(vz & mask), bits)];
        }
      }
  });
}

// ---- the on-disk cache ----

void writeSolidTiles(const SolidTileSet& t, const fs::path& path) {
  writeFileAtomically(path, [&](std::ostream& out) {
    BinaryWriter w{out};
    w.value(kTilesMagic);
    w.value(kTilesVersion);
    w.value(t.key);
    w.value(t.width);
    w.value(t.height);
    w.value(t.layout.side);
    w.value(t.layout.variants);
    w.value(t.seconds);
    w.vec(t.elements);
  });
}

std::optional<SolidTileSet> readSolidTiles(const fs::path& path, uint64_t expectedKey) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  BinaryReader r{in};
  uint32_t magic = 0, version = 0;
  int side = 0, variants = 0;
  SolidTileSet t;
  r.value(magic);
  r.value(version);
  r.value(t.key);
  r.value(t.width);
  r.value(t.height);
  r.value(side);
  r.value(variants);
  r.value(t.seconds);
  if (!r.ok || magic != kTilesMagic || version != kTilesVersion || t.key != expectedKey || side < 2 || side > 64 ||
      (variants != 2 && variants != 3) ||
      t.width < 1 || t.height < 1 || t.width > 65535 || t.height > 65535)
    return std::nullopt;
  t.layout = SolidTileLayout(side, variants);
  r.vec(t.elements, t.layout.elements);
  if (!r.ok || in.peek() != std::ifstream::traits_type::eof()) return std::nullopt;
  for (const Triple& triple : t.elements)
    for (uint32_t c : triple)
      if (coordU(c) >= uint32_t(t.width) || coordV(c) >= uint32_t(t.height)) return std::nullopt;
  return t;
}

SolidTileSet buildSolidTilesCached(const SolidAnalysis& a, const SolidTileOptions& o, const fs::path& cacheDir,
                                   const Context& ctx, bool* fromCache) {
  o.validate();
  return loadOrCompute(cacheDir, solidTilesKey(a, o), ".tiles", readSolidTiles,
                       [&] { return buildSolidTiles(a, o, ctx); }, writeSolidTiles, fromCache, ctx);
}

} // namespace texfab::synthesis
