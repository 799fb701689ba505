// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §5 (parallel solid synthesis, lazy subset synthesis) and §6.2 (coarse-level cache).
#include "synthesis/synthesize_solid.h"

#include "core/error.h"
#include "core/hash.h"
#include "core/parallel.h"
#include "synthesis/backend.h"
#include "synthesis/chunk_index.h"
#include "synthesis/coord_map.h"
#include "synthesis/cpu/solid_kernels.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/refine_solid.h"
#include "synthesis/solid_tiles.h"
#if TEXFAB_HAS_VULKAN
#include "synthesis/vulkan/solid_kernels.h"
#include "synthesis/vulkan/solid_level.h"
#endif

#include <algorithm>
#include <bitset>
#include <climits>
#include <cstdint>
#include <chrono>
#include <cmath>
#include <set>
#include <string>
#include <stdexcept>

namespace texfab::synthesis {

namespace {

using cpu::VolumeGrid;
using Clock = std::chrono::steady_clock;

constexpr int kBrickShift = 2;  // the cache holds 4^3 bricks (little padding around thin shells)
constexpr int kBrickSide = 1 << kBrickShift;

// The projections of a level laid out for the correction kernel.
struct Prepared {
  cpu::SolidKernelProjection projection2d, projection3d;
};

Prepared prepare(const SolidLevel& l) {
  return {cpu::prepareSolidProjection(l.projection2d.mean.data(), l.projection2d.basis.data(), l.projection2d.inputs,
                                      l.projection2d.dims, l.projection2d.divisor),
          cpu::prepareSolidProjection(l.projection3d.mean.data(), l.projection3d.basis.data(), l.projection3d.inputs,
                                      l.projection3d.dims, l.projection3d.divisor)};
}

cpu::SolidTables tablesOf(const SolidAnalysis& a, int li, const Prepared& prepared, const SolidSynthesisOptions& o) {
  const SolidLevel& l = a.levels[size_t(li)];
  cpu::SolidTables t;
  t.exemplarWidth = a.width;
  t.exemplarHeight = a.height;
  t.spacing = l.spacing;
  t.dims = l.dims;
  t.k2d = l.k2d;
  t.k2dStride = int(l.candidates2d[0].size() / (size_t(a.width) * size_t(a.height)));
  t.k3d = l.k3d;
  t.clampMargin = a.wrap == ExemplarWrap::Clamp ? l.valid.x0 : 0;
  for (int e = 0; e < 3; ++e) {
    // One image for the three axes: its per-pixel tables are identical; read one copy (cache).
    const size_t s = a.shared ? 0 : size_t(e);
    t.colors[e] = l.colors[s].data();
    t.candidates2d[e] = l.candidates2d[s].data();
    t.candidateDescriptors2d[e] = l.candidateDescriptors2d[s].data();
    t.triples[e] = l.triples[size_t(e)].data();
    t.descriptors3d[e] = l.descriptors3d[size_t(e)].data();
  }
  t.projection2d = &prepared.projection2d;
  t.projection3d = &prepared.projection3d;
  static_assert(sizeof(l.searchColors) == 3 * kSolidColorSums * sizeof(int16_t));
  if (o.matchColors) t.searchColors = l.searchColors[0].data();
  t.contrastGain16 = o.contrastGain16();
  return t;
}

cpu::SolidInit initOf(const SolidSynthesisOptions& o) {
  return {o.seed, int64_t(std::lrint(double(o.jitter) * 256.0)), o.offsetCells};
}


uint64_t ownerKey(const SolidAnalysis& a, const SolidSynthesisOptions& o) {
  Fnv1a h;
  h.add(a.key);
  h.add(o.seed);
  h.add(o.jitter);
  h.add(o.passes);
  h.add(o.interleave);
  h.add(o.matchColors);
  h.add(o.offsetCells);
  h.add(o.contrastGain16());
  return h.h;
}

// The engine works level by level over the whole request (Dong et al. §5.2): first the masks of
// every level, from the finest to the coarsest (the requested voxels, dilated exactly per
// sub-pass; their parents seed the level below, unless the coarse-level cache holds their final
// values, §6.2), then each level is synthesized once over its whole mask, coarsest first. Every
// voxel of a level is computed exactly once per request, as far as its mask says (no tile
// margins computed twice, no padding to whole cache bricks), which is what the per-sub-pass mask
// makes exact: each voxel's value is the same pure function of its position whatever the mask.
//
// A level lives in sparse 16^3 chunks of level voxels. Its synthesis sweeps the chunks' z-layers
// in a pipeline: correction step t of layer j runs once step t-1 of layers j-1..j+1 is done, and
// a step's values are dropped as soon as the next step of both neighbouring layers has read them,
// so the working memory is a few z-layers of chunks, not the level. Each correction gathers its
// chunk's values with a 2-voxel halo (the 3-neighborhood's radius) from its neighbours.

constexpr int kChunkShift = 4;
constexpr int kChunk = 1 << kChunkShift;  // 16
constexpr int kChunkVoxels = kChunk * kChunk * kChunk;
constexpr int kHalo = 2;                   // radius of the 61-voxel 3-neighborhood
constexpr int kGathered = kChunk + 2 * kHalo;
constexpr int kGatheredVoxels = kGathered * kGathered * kGathered;

using ChunkKey = GridKey;

template <int Shift = kChunkShift> inline int localIndex(int64_t x, int64_t y, int64_t z) {
  constexpr int64_t m = (1 << Shift) - 1;
  return int((((z & m) << Shift) + (y & m)) << Shift) + int(x & m);
}

// Dense chunks of (2^Shift)^3 voxels, N values of T per voxel, created on demand (filled with
// `fill`).
template <class T, int N, int Shift = kChunkShift> struct ChunkStore : ChunkIndex {
  static constexpr int kVoxels = 1 << (3 * Shift);
  T fill{};
  std::vector<std::unique_ptr<T[]>> chunks;

  uint32_t get(const ChunkKey& k) {
    const auto [slot, added] = insert(k);
    if (added) {
      chunks.emplace_back(new T[size_t(kVoxels) * N]);
      std::fill_n(chunks.back().get(), size_t(kVoxels) * N, fill);
    }
    return slot;
  }
  T* at(uint32_t slot) { return chunks[slot].get(); }
  const T* at(uint32_t slot) const { return chunks[slot].get(); }
  size_t bytes() const { return chunks.size() * size_t(kVoxels) * N * sizeof(T); }
  void release() {
    const T keep = fill;
    *this = ChunkStore{};
    fill = keep;
  }
};

// last[v] per voxel (-1 = not needed), see solid_kernels.h.
struct Mask : ChunkStore<int8_t, 1> {
  Mask() { fill = -1; }
};
// Final values (triples) of a coarse level where the finer level's upsampling reads them, in 8^3
// blocks: block k holds the parents of chunk k of the finer level.
constexpr int kBlockShift = kChunkShift - 1;
constexpr int kBlock = 1 << kBlockShift;
using Finals = ChunkStore<uint32_t, 3, kBlockShift>;

// One chunk's values after one step: triples and colours (solidColorKernel).
struct ChunkValues {
  std::unique_ptr<uint32_t[]> triples{new uint32_t[size_t(kChunkVoxels) * 3]};
  std::unique_ptr<int16_t[]> colors{new int16_t[size_t(kChunkVoxels) * 4]};
};

// Per-thread scratch of one correction: the chunk with its halo (not initialized: the masks
// guarantee that no value is read that was not written for this step).
struct Gathered {
  std::unique_ptr<int8_t[]> last{new int8_t[kGatheredVoxels]};
  std::unique_ptr<uint32_t[]> in{new uint32_t[size_t(kGatheredVoxels) * 3]}, out{new uint32_t[size_t(kGatheredVoxels) * 3]};
  std::unique_ptr<int16_t[]> inC{new int16_t[size_t(kGatheredVoxels) * 4]}, outC{new int16_t[size_t(kGatheredVoxels) * 4]};
};

// Along one axis, neighbour d in {-1, 0, 1} of a chunk: its voxels [from, from + n) (chunk-local)
// land at gathered positions [to, to + n).
struct Span1 {
  int from, to, n;
};
constexpr Span1 kSpans[3] = {{kChunk - kHalo, 0, kHalo}, {0, kHalo, kChunk}, {0, kHalo + kChunk, kHalo}};

template <class F> void forNeighbours(F&& f) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) f(dx, dy, dz);
}

struct Engine {
  const SolidAnalysis& a;
  const SolidSynthesisOptions& o;
  SolidLevelCache* cache;
  const Context& ctx;
  std::vector<SolidLevelStats>& stats;
  std::shared_ptr<vulkan::Device> device = deviceFor(ctx);  // null: the CPU
  std::vector<Mask> masks = std::vector<Mask>(a.levels.size());
  std::vector<Finals> finals = std::vector<Finals>(a.levels.size());
  size_t peakBytes = 0;  // masks + finals + step values held at once (diagnostics)

  int top() const { return int(a.levels.size()) - 1; }
  // Correction steps of level li (the finest may have its own number of passes).
  int steps(int li) const { return o.passesAt(li == top()) * o.subpasses(); }

  size_t storeBytes() const {
    size_t b = 0;
    for (const auto& m : masks) b += m.bytes();
    for (const auto& f : finals) b += f.bytes();
    return b;
  }

  bool inClass(int step, int64_t x, int64_t y, int64_t z) const {
    if (o.interleave == 1) return true;
    const int cls = (step - 1) % 8;
    return (x & 1) == (cls & 1) && (y & 1) == ((cls >> 1) & 1) && (z & 1) == ((cls >> 2) & 1);
  }

  // §5.2, exact per sub-pass, over the level's chunks: for t = T..1, every voxel of step t's
  // class with last >= t needs its 3-neighborhood after step t-1. Batch by batch, the chunks
  // holding such voxels are spread in parallel, each into its own gathered grid; the chunks the
  // grids reach are created (one thread: the store's index), then each chunk takes the maximum of
  // the grids reaching it (in parallel over the chunks written). Raising to t-1 < t never changes
  // which voxels are spread in step t, so the order of the batches does not matter.
  void dilate(int li) {
    Mask& m = masks[size_t(li)];
    constexpr size_t kBatch = 512;
    std::vector<int8_t> grids(kBatch * kGatheredVoxels);
    std::vector<uint32_t> reach(kBatch);  // per grid: bit (dz+1)*9 + (dy+1)*3 + dx+1 = it reaches that neighbour
    for (int t = steps(li); t >= 1; --t) {
      const std::vector<uint32_t> active = chunksHolding(m, t);  // chunks created in this step hold none
      for (size_t b = 0; b < active.size(); b += kBatch) {
        const int n = int(std::min(active.size() - b, kBatch));
        parallelFor(0, n, ctx, [&](int k0, int k1) {
          for (int k = k0; k < k1; ++k) {
            int8_t* g = grids.data() + size_t(k) * kGatheredVoxels;
            spread(m, active[b + size_t(k)], t, g);
            reach[size_t(k)] = reached(g);
          }
        });
        merge(m, std::span<const uint32_t>(active).subspan(b, size_t(n)), grids.data(), reach.data());
      }
    }
  }

  // The chunks of `m` holding a voxel with last >= t.
  std::vector<uint32_t> chunksHolding(const Mask& m, int t) const {
    std::vector<uint8_t> holds(m.size());
    parallelFor(0, int(m.size()), ctx, [&](int s0, int s1) {
      for (int s = s0; s < s1; ++s) {
        const int8_t* c = m.at(uint32_t(s));
        holds[size_t(s)] = std::any_of(c, c + kChunkVoxels, [&](int8_t v) { return v >= t; });
      }
    });
    std::vector<uint32_t> out;
    for (size_t s = 0; s < holds.size(); ++s)
      if (holds[s]) out.push_back(uint32_t(s));
    return out;
  }

  // Chunk `slot` with a halo, its voxels needed after step t spread to their 3-neighborhoods.
  void spread(const Mask& m, uint32_t slot, int t, int8_t* g) const {
    const int8_t* c = m.at(slot);
    const ChunkKey key = m.keys()[slot];
    std::fill_n(g, kGatheredVoxels, int8_t(-1));
    for (int z = 0; z < kChunk; ++z)
      for (int y = 0; y < kChunk; ++y)
        std::copy_n(c + (z * kChunk + y) * kChunk, kChunk, g + ((z + kHalo) * kGathered + y + kHalo) * kGathered + kHalo);
    const VolumeGrid grid{key[0] * kChunk - kHalo, key[1] * kChunk - kHalo, key[2] * kChunk - kHalo,
                          kGathered, kGathered, kGathered};
    cpu::solidDilateKernel(g, grid, o.interleave, t);
  }

  // Which of the 27 chunks around a spread grid's centre hold a voxel of it that is needed.
  static uint32_t reached(const int8_t* g) {
    uint32_t bits = 0;
    int bit = 0;
    forNeighbours([&](int dx, int dy, int dz) {
      const Span1 &sx = kSpans[dx + 1], &sy = kSpans[dy + 1], &sz = kSpans[dz + 1];
      bool any = false;
      for (int z = 0; z < sz.n && !any; ++z)
        for (int y = 0; y < sy.n && !any; ++y) {
          const int8_t* row = g + ((sz.to + z) * kGathered + sy.to + y) * kGathered + sx.to;
          any = std::any_of(row, row + sx.n, [](int8_t v) { return v >= 0; });
        }
      bits |= uint32_t(any) << bit++;
    });
    return bits;
  }

  // The spread grids of the chunks `from` into the chunks they reach (created where missing).
  void merge(Mask& m, std::span<const uint32_t> from, const int8_t* grids, const uint32_t* reach) {
    struct Write {
      uint32_t to;       // chunk written
      uint32_t grid;     // index into `from`
      uint32_t neighbour;  // bit of `reach`
    };
    std::vector<Write> writes;
    for (size_t k = 0; k < from.size(); ++k) {
      const ChunkKey key = m.keys()[from[k]];  // by value: m.get() may move m.keys()
      int bit = 0;
      forNeighbours([&](int dx, int dy, int dz) {
        if (reach[k] >> bit & 1) writes.push_back({m.get({key[0] + dx, key[1] + dy, key[2] + dz}), uint32_t(k), uint32_t(bit)});
        ++bit;
      });
    }
    std::sort(writes.begin(), writes.end(), [](const Write& a, const Write& b) { return a.to < b.to; });
    std::vector<size_t> first;  // the writes of one chunk are [first[i], first[i + 1])
    for (size_t w = 0; w < writes.size(); ++w)
      if (w == 0 || writes[w].to != writes[w - 1].to) first.push_back(w);
    first.push_back(writes.size());
    parallelFor(0, int(first.size()) - 1, ctx, [&](int i0, int i1) {
      for (int i = i0; i < i1; ++i)
        for (size_t w = first[size_t(i)]; w < first[size_t(i) + 1]; ++w) {
          const Write& wr = writes[w];
          const int dx = int(wr.neighbour % 3) - 1, dy = int(wr.neighbour / 3 % 3) - 1, dz = int(wr.neighbour / 9) - 1;
          const Span1 &sx = kSpans[dx + 1], &sy = kSpans[dy + 1], &sz = kSpans[dz + 1];
          const int8_t* g = grids + size_t(wr.grid) * kGatheredVoxels;
          int8_t* d = m.at(wr.to);
          for (int z = 0; z < sz.n; ++z)
            for (int y = 0; y < sy.n; ++y) {
              const int8_t* row = g + ((sz.to + z) * kGathered + sy.to + y) * kGathered + sx.to;
              int8_t* to = d + ((sz.from + z) * kChunk + sy.from + y) * kChunk + sx.from;
              for (int x = 0; x < sx.n; ++x) to[x] = std::max(to[x], row[x]);
            }
        }
    });
  }

  // The voxels of level li whose final values level li+1 upsamples from (the parents of its
  // mask): read from the cache where it has them, else seeds of level li's mask (with
  // Fill::WholeBricks, every voxel of a brick the cache lacks in part). The parents of each child
  // chunk fill one octant of one chunk of level li; which are needed is found in parallel, the
  // cache is asked in one thread (it is not thread-safe, and its order of use decides what it
  // evicts), and the values and seeds are written in parallel (octants and blocks are disjoint).
  void seedFromChild(int li) {
    const Mask& child = masks[size_t(li) + 1];
    Mask& m = masks[size_t(li)];
    Finals& f = finals[size_t(li)];
    const auto T = int8_t(steps(li));
    const int n = int(child.size());
    std::vector<std::bitset<512>> need(static_cast<size_t>(n));  // per child chunk: its parents, (z * 8 + y) * 8 + x
    parallelFor(0, n, ctx, [&](int s0, int s1) {
      for (int s = s0; s < s1; ++s) {
        const int8_t* c = child.at(uint32_t(s));
        for (int z = 0; z < kChunk; ++z)
          for (int y = 0; y < kChunk; ++y)
            for (int x = 0; x < kChunk; ++x)
              if (c[(z * kChunk + y) * kChunk + x] >= 0) need[size_t(s)].set(size_t(((z >> 1) * 8 + (y >> 1)) * 8 + (x >> 1)));
      }
    });
    // Per 4^3 brick of an octant, bit (z * 4 + y) * 4 + x: the parents read from the cache, and
    // those seeded.
    struct Octant {
      uint32_t child;     // chunk of level li+1
      uint32_t block;     // its parents' block in `f`
      int32_t mask = -1;  // the chunk of `m` holding its seeds, if it has any
      std::array<std::shared_ptr<const SolidLevelCache::Brick>, 8> bricks;
      std::array<uint64_t, 8> cached{}, seeded{};
    };
    const bool wholeBricks = cache && cache->fill() == SolidLevelCache::Fill::WholeBricks;
    std::vector<Octant> octants;
    for (int s = 0; s < n; ++s) {
      if (need[size_t(s)].none()) continue;
      const ChunkKey key = child.keys()[size_t(s)];
      Octant oc{uint32_t(s), f.get(key), -1, {}, {}, {}};
      for (int b = 0; b < 8; ++b) {
        const uint64_t needed = brickNeed(need[size_t(s)], b & 1, b >> 1 & 1, b >> 2);
        if (!needed) continue;
        if (cache) oc.bricks[size_t(b)] = cache->find({li, key[0] * 2 + (b & 1), key[1] * 2 + (b >> 1 & 1), key[2] * 2 + (b >> 2)});
        const uint64_t valid = oc.bricks[size_t(b)] ? oc.bricks[size_t(b)]->valid : 0;
        oc.cached[size_t(b)] = needed & valid;
        oc.seeded[size_t(b)] = (wholeBricks ? ~uint64_t(0) : needed) & ~valid;
      }
      if (std::any_of(oc.seeded.begin(), oc.seeded.end(), [](uint64_t bits) { return bits != 0; }))
        oc.mask = int32_t(m.get({cpu::floorShift(key[0], 1), cpu::floorShift(key[1], 1), cpu::floorShift(key[2], 1)}));
      octants.push_back(std::move(oc));
    }
    parallelFor(0, int(octants.size()), ctx, [&](int i0, int i1) {
      for (int i = i0; i < i1; ++i) {
        const Octant& oc = octants[size_t(i)];
        const ChunkKey key = child.keys()[oc.child];
        uint32_t* fv = f.at(oc.block);
        int8_t* mv = oc.mask >= 0 ? m.at(uint32_t(oc.mask)) : nullptr;
        for (int b = 0; b < 8; ++b)
          for (int inBrick = 0; inBrick < 64; ++inBrick) {
            const bool cached = oc.cached[size_t(b)] >> inBrick & 1, seeded = oc.seeded[size_t(b)] >> inBrick & 1;
            if (!cached && !seeded) continue;
            const int x = (b & 1) * 4 + (inBrick & 3), y = (b >> 1 & 1) * 4 + (inBrick >> 2 & 3), z = (b >> 2) * 4 + (inBrick >> 4);
            if (cached) std::copy_n(oc.bricks[size_t(b)]->values.data() + inBrick * 3, 3, fv + ((z * 8 + y) * 8 + x) * 3);
            else mv[localIndex(key[0] * kBlock + x, key[1] * kBlock + y, key[2] * kBlock + z)] = T;
          }
      }
    });
  }

  // The needed parents in brick (bx, by, bz) of a child chunk's octant, bit (z * 4 + y) * 4 + x
  // (as SolidLevelCache::Brick::valid).
  static uint64_t brickNeed(const std::bitset<512>& need, int bx, int by, int bz) {
    uint64_t bits = 0;
    for (int z = 0; z < kBrickSide; ++z)
      for (int y = 0; y < kBrickSide; ++y)
        for (int x = 0; x < kBrickSide; ++x)
          if (need[size_t(((bz * 4 + z) * 8 + by * 4 + y) * 8 + bx * 4 + x)])
            bits |= uint64_t(1) << ((z * kBrickSide + y) * kBrickSide + x);
    return bits;
  }

  // Final values of level li < top computed in this request go to the cache, per 4^3 brick
  // (only the voxels computed: `valid`).
  void fillCache(int li) {
    const Mask& m = masks[size_t(li)];
    const Finals& f = finals[size_t(li)];
    const auto T = int8_t(steps(li));
    for (size_t s = 0; s < m.size(); ++s) {
      const int8_t* c = m.at(uint32_t(s));
      const ChunkKey key = m.keys()[s];
      for (int bz = 0; bz < kChunk; bz += kBrickSide)
        for (int by = 0; by < kChunk; by += kBrickSide)
          for (int bx = 0; bx < kChunk; bx += kBrickSide) {
            uint64_t valid = 0;
            for (int z = 0; z < kBrickSide; ++z)
              for (int y = 0; y < kBrickSide; ++y)
                for (int x = 0; x < kBrickSide; ++x)
                  if (c[((bz + z) * kChunk + by + y) * kChunk + bx + x] == T)
                    valid |= uint64_t(1) << ((z * kBrickSide + y) * kBrickSide + x);
            if (!valid) continue;
            const int64_t b0[3] = {key[0] * kChunk + bx, key[1] * kChunk + by, key[2] * kChunk + bz};
            const int32_t fs = f.find({b0[0] >> kBlockShift, b0[1] >> kBlockShift, b0[2] >> kBlockShift});
            if (fs < 0) throw std::logic_error("lazy solid synthesis: final values missing");
            const uint32_t* fv = f.at(uint32_t(fs));
            auto brick = std::make_shared<SolidLevelCache::Brick>();
            brick->values.assign(size_t(kBrickSide) * kBrickSide * kBrickSide * 3, 0);
            brick->valid = valid;
            for (int z = 0; z < kBrickSide; ++z)
              for (int y = 0; y < kBrickSide; ++y)
                for (int x = 0; x < kBrickSide; ++x)
                  std::copy_n(fv + localIndex<kBlockShift>(b0[0] + x, b0[1] + y, b0[2] + z) * 3, 3,
                              brick->values.data() + ((z * kBrickSide + y) * kBrickSide + x) * 3);
            cache->insert({li, key[0] * (kChunk / kBrickSide) + bx / kBrickSide, key[1] * (kChunk / kBrickSide) + by / kBrickSide,
                           key[2] * (kChunk / kBrickSide) + bz / kBrickSide},
                          std::move(brick));
          }
    }
  }

  // Step 0 of one chunk: initialization (coarsest level) or upsampling, then colours.
  void start(int li, uint32_t slot, const cpu::SolidTables& tables, ChunkValues& out) {
    const Mask& m = masks[size_t(li)];
    const ChunkKey key = m.keys()[slot];
    const int8_t* last = m.at(slot);
    const VolumeGrid grid{key[0] * kChunk, key[1] * kChunk, key[2] * kChunk, kChunk, kChunk, kChunk};
    if (li == 0) {
      cpu::solidInitKernel(out.triples.get(), last, grid, tables, initOf(o), 0, grid.rows());
    } else {
      const Finals& f = finals[size_t(li) - 1];
      const int32_t ps = f.find(key);  // the block of this chunk's parents
      if (ps < 0) throw std::logic_error("lazy solid synthesis: parent values missing");
      const VolumeGrid pg{key[0] * kBlock, key[1] * kBlock, key[2] * kBlock, kBlock, kBlock, kBlock};
      cpu::solidUpsampleKernel(f.at(uint32_t(ps)), pg, out.triples.get(), last, grid, tables.spacing, a.width, a.height, 0, grid.rows());
    }
    cpu::solidColorKernel(out.triples.get(), out.colors.get(), last, 0, grid, tables, 0, grid.rows());
  }

  // Correction step t >= 1 of one chunk, from step t-1 of it and its neighbours. Only the box of
  // the voxels needed after step t (last >= t) is corrected and written, and only that box with
  // its halo is gathered: thin requests (a cut, a shell) fill a few layers of a chunk.
  void correct(int li, uint32_t slot, int t, const std::vector<int32_t>& before, std::vector<ChunkValues>& pool,
               const cpu::SolidTables& tables, Gathered& g, ChunkValues& out) {
    const Mask& m = masks[size_t(li)];
    const ChunkKey key = m.keys()[slot];
    const int8_t* last = m.at(slot);
    int lo[3] = {kChunk, kChunk, kChunk}, hi[3] = {0, 0, 0};  // chunk-local box [lo, hi)
    for (int z = 0; z < kChunk; ++z)
      for (int y = 0; y < kChunk; ++y)
        for (int x = 0; x < kChunk; ++x)
          if (last[(z * kChunk + y) * kChunk + x] >= t) {
            const int p[3] = {x, y, z};
            for (int a = 0; a < 3; ++a) {
              lo[a] = std::min(lo[a], p[a]);
              hi[a] = std::max(hi[a], p[a] + 1);
            }
          }
    if (lo[0] >= hi[0]) return;  // (a chunk is only scheduled when it holds such a voxel)
    std::fill_n(g.last.get(), kGatheredVoxels, int8_t(-1));
    for (int z = lo[2]; z < hi[2]; ++z)
      for (int y = lo[1]; y < hi[1]; ++y)
        std::copy_n(last + (z * kChunk + y) * kChunk + lo[0], hi[0] - lo[0],
                    g.last.get() + ((z + kHalo) * kGathered + y + kHalo) * kGathered + kHalo + lo[0]);
    // The box with its halo, in gathered coordinates: [lo, hi + 2 halo).
    forNeighbours([&](int dx, int dy, int dz) {
      const int32_t ns = m.find({key[0] + dx, key[1] + dy, key[2] + dz});
      if (ns < 0 || before[size_t(ns)] < 0) return;  // none of its voxels is read at this step
      const ChunkValues& src = pool[size_t(before[size_t(ns)])];
      const int d[3] = {dx, dy, dz};
      int from[3], to[3], n[3];
      for (int a = 0; a < 3; ++a) {
        const Span1& s = kSpans[d[a] + 1];
        const int b = std::max(s.to, lo[a]), e = std::min(s.to + s.n, hi[a] + 2 * kHalo);
        if (b >= e) return;
        from[a] = s.from + b - s.to;
        to[a] = b;
        n[a] = e - b;
      }
      for (int z = 0; z < n[2]; ++z)
        for (int y = 0; y < n[1]; ++y) {
          const size_t f = size_t(((from[2] + z) * kChunk + from[1] + y) * kChunk + from[0]);
          const size_t o = size_t(((to[2] + z) * kGathered + to[1] + y) * kGathered + to[0]);
          std::copy_n(src.triples.get() + f * 3, size_t(n[0]) * 3, g.in.get() + o * 3);
          std::copy_n(src.colors.get() + f * 4, size_t(n[0]) * 4, g.inC.get() + o * 4);
        }
    });
    const VolumeGrid grid{key[0] * kChunk - kHalo, key[1] * kChunk - kHalo, key[2] * kChunk - kHalo,
                          kGathered, kGathered, kGathered};
    for (int z = lo[2] + kHalo; z < hi[2] + kHalo; ++z)
      cpu::solidCorrectKernel(g.in.get(), g.inC.get(), g.out.get(), g.outC.get(), g.last.get(), grid, tables, o.interleave,
                              t, z * kGathered + lo[1] + kHalo, z * kGathered + hi[1] + kHalo);
    for (int z = lo[2]; z < hi[2]; ++z)
      for (int y = lo[1]; y < hi[1]; ++y)
        for (int x = lo[0]; x < hi[0]; ++x) {
          const size_t v = size_t((z * kChunk + y) * kChunk + x);
          if (last[v] < t) continue;
          const size_t gv = size_t(((z + kHalo) * kGathered + y + kHalo) * kGathered + x + kHalo);
          const bool corrected = inClass(t, key[0] * kChunk + x, key[1] * kChunk + y, key[2] * kChunk + z);
          std::copy_n((corrected ? g.out.get() : g.in.get()) + gv * 3, 3, out.triples.get() + v * 3);
          std::copy_n((corrected ? g.outC.get() : g.inC.get()) + gv * 4, 4, out.colors.get() + v * 4);
        }
  }

  // The final values of chunk `slot` of level li: to emit at the finest level; above it, its seeds
  // (last = T: the voxels whose final values level li+1 reads) into the store block of each 8^3
  // block holding one.
  template <class Emit> void finishChunk(int li, uint32_t slot, const uint32_t* triples, const Emit& emit) {
    if (li == top()) return emit(slot, triples);
    const Mask& m = masks[size_t(li)];
    const ChunkKey key = m.keys()[slot];
    const int8_t* last = m.at(slot);
    const auto T = int8_t(steps(li));
    for (int bz = 0; bz < kChunk; bz += kBlock)
      for (int by = 0; by < kChunk; by += kBlock)
        for (int bx = 0; bx < kChunk; bx += kBlock) {
          uint32_t* fv = nullptr;
          for (int z = 0; z < kBlock; ++z)
            for (int y = 0; y < kBlock; ++y)
              for (int x = 0; x < kBlock; ++x) {
                const int v = ((bz + z) * kChunk + by + y) * kChunk + bx + x;
                if (last[v] != T) continue;
                if (!fv) {
                  const int32_t fs = finals[size_t(li)].find({(key[0] * kChunk + bx) >> kBlockShift,
                                                              (key[1] * kChunk + by) >> kBlockShift,
                                                              (key[2] * kChunk + bz) >> kBlockShift});
                  if (fs < 0) throw std::logic_error("lazy solid synthesis: final block missing");
                  fv = finals[size_t(li)].at(uint32_t(fs));
                }
                std::copy_n(triples + v * 3, 3, fv + ((z * kBlock + y) * kBlock + x) * 3);
              }
        }
  }

  // Synthesizes level li over its whole mask (on the device when there is one); emit(slot,
  // triples) receives the final values of each chunk of the finest level.
  template <class Emit> void synthesizeLevel(int li, const Emit& emit) {
    const auto started = Clock::now();
    const Mask& m = masks[size_t(li)];
    const size_t n = m.size();
    std::vector<int8_t> maxLast(n, -1);
    int64_t voxels = 0, corrections = 0;
    const int subpasses = o.subpasses();
    for (size_t s = 0; s < n; ++s) {
      const int8_t* c = m.at(uint32_t(s));
      for (int v = 0; v < kChunkVoxels; ++v) {
        maxLast[s] = std::max(maxLast[s], c[v]);
        voxels += c[v] >= 0;
        corrections += c[v] > 0 ? (c[v] + subpasses - 1) / subpasses : 0;
      }
    }
#if TEXFAB_HAS_VULKAN
    if (device) synthesizeLevelOnDevice(li, emit);
    else
#endif
      synthesizeLevelOnCpu(li, maxLast, emit);
    if (cache && li < top()) fillCache(li);
    SolidLevelStats& st = stats[size_t(li)];
    st.voxels += voxels;
    st.corrections += corrections;
    st.seconds += secondsSince(started);
  }

#if TEXFAB_HAS_VULKAN
  template <class Emit> void synthesizeLevelOnDevice(int li, const Emit& emit) {
    const Mask& m = masks[size_t(li)];
    vulkan::SolidLevelInput level;
    level.chunks = &m;
    level.last = [&](uint32_t slot) { return m.at(slot); };
    if (li > 0)
      level.parents = [&](uint32_t slot) -> const uint32_t* {
        const int32_t ps = finals[size_t(li) - 1].find(m.keys()[slot]);  // the block of this chunk's parents
        if (ps < 0) throw std::logic_error("lazy solid synthesis: parent values missing");
        return finals[size_t(li) - 1].at(uint32_t(ps));
      };
    if (a.key) {  // the tables are a function of the analysis, the level and the colour rule
      Fnv1a h;
      h.add(a.key);
      h.add(li);
      h.add(o.matchColors);
      level.tablesKey = h.h;
    }
    level.steps = steps(li);
    level.interleave = o.interleave;
    level.init = initOf(o);
    vulkan::synthesizeSolidLevel(*device, tablesOf(a, li, prepared(li), o), level,
                                 [&](uint32_t slot, const uint32_t* triples) { finishChunk(li, slot, triples, emit); },
                                 ctx);
  }
#endif

  // The CPU pipelines the level's z-layers of chunks: step t of layer j runs once step t-1 of
  // layers j-1..j+1 is done, and a step's values are dropped as soon as the next step of both
  // neighbouring layers has read them.
  template <class Emit> void synthesizeLevelOnCpu(int li, const std::vector<int8_t>& maxLast, const Emit& emit) {
    const Mask& m = masks[size_t(li)];
    const int T = steps(li);
    const size_t n = m.size();
    // Chunks in z-layers (then y, x: neighbours close in memory).
    std::vector<uint32_t> order(n);
    for (size_t s = 0; s < n; ++s) order[s] = uint32_t(s);
    std::sort(order.begin(), order.end(), [&](uint32_t p, uint32_t q) {
      const ChunkKey &kp = m.keys()[p], &kq = m.keys()[q];
      return std::tie(kp[2], kp[1], kp[0]) < std::tie(kq[2], kq[1], kq[0]);
    });
    std::vector<std::pair<size_t, size_t>> layers;
    for (size_t b = 0; b < n;) {
      size_t e = b + 1;
      while (e < n && m.keys()[order[e]][2] == m.keys()[order[b]][2]) ++e;
      layers.push_back({b, e});
      b = e;
    }
    const cpu::SolidTables tables = tablesOf(a, li, prepared(li), o);
    std::vector<ChunkValues> pool;
    std::vector<int32_t> freeList;
    std::vector<std::vector<int32_t>> bufferOf(size_t(T) + 1, std::vector<int32_t>(n, -1));
    auto release = [&](int step, size_t layer) {
      for (size_t k = layers[layer].first; k < layers[layer].second; ++k) {
        int32_t& b = bufferOf[size_t(step)][order[k]];
        if (b >= 0) freeList.push_back(b);
        b = -1;
      }
    };
    const int L = int(layers.size());
    for (int i = 0; i < L + T; ++i) {
      for (int t = 0; t <= T; ++t) {
        const int j = i - t;
        if (j < 0 || j >= L) continue;
        const auto [b, e] = layers[size_t(j)];
        for (size_t k = b; k < e; ++k) {
          const uint32_t slot = order[k];
          if (maxLast[slot] < t) continue;
          if (freeList.empty()) {
            freeList.push_back(int32_t(pool.size()));
            pool.emplace_back();
          }
          bufferOf[size_t(t)][slot] = freeList.back();
          freeList.pop_back();
        }
        peakBytes = std::max(peakBytes, storeBytes() + pool.size() * sizeof(uint32_t) * kChunkVoxels * 5);
        parallelFor(int(b), int(e), ctx, [&](int k0, int k1) {
          thread_local std::unique_ptr<Gathered> scratch;
          if (!scratch) scratch = std::make_unique<Gathered>();
          for (int k = k0; k < k1; ++k) {
            const uint32_t slot = order[size_t(k)];
            const int32_t ob = bufferOf[size_t(t)][slot];
            if (ob < 0) continue;
            ChunkValues& out = pool[size_t(ob)];
            if (t == 0) start(li, slot, tables, out);
            else correct(li, slot, t, bufferOf[size_t(t) - 1], pool, tables, *scratch, out);
            if (t == T) finishChunk(li, slot, out.triples.get(), emit);
          }
        });
        if (t == T) release(T, size_t(j));
      }
      // Step t-1 of layer j was read by step t of layers j-1, j, j+1; the last of them just ran.
      for (int t = 1; t <= T; ++t) {
        const int j = i - t - 1;
        if (j >= 0 && j < L) release(t - 1, size_t(j));
      }
    }
  }

  std::vector<std::unique_ptr<Prepared>> preparedLevels = std::vector<std::unique_ptr<Prepared>>(a.levels.size());
  const Prepared& prepared(int li) {
    auto& p = preparedLevels[size_t(li)];
    if (!p) p = std::make_unique<Prepared>(prepare(a.levels[size_t(li)]));
    return *p;
  }

  // masks[top] holds the request (last = T); emit as in synthesizeLevel.
  template <class Emit> void run(const Emit& emit) {
    Stage maskStage(ctx, "masks");
    for (int li = top(); li >= 0; --li) {
      const auto started = Clock::now();
      if (li < top()) seedFromChild(li);
      dilate(li);
      stats[size_t(li)].seconds += secondsSince(started);
      peakBytes = std::max(peakBytes, storeBytes());
    }
    maskStage.finish();
    for (int li = 0; li <= top(); ++li) {
      Stage levelStage(ctx, "level " + std::to_string(li + 1) + "/" + std::to_string(top() + 1));
      if (masks[size_t(li)].size()) synthesizeLevel(li, emit);
      const SolidLevelStats& st = stats[size_t(li)];
      levelStage.finish(std::to_string(st.voxels) + " voxels, " + std::to_string(st.corrections) + " corrections");
      masks[size_t(li)].release();
      if (li > 0) finals[size_t(li) - 1].release();
    }
  }
};

void validatePosition(int64_t x, int64_t y, int64_t z) {
  if (std::abs(x) > kMaxSolidPosition || std::abs(y) > kMaxSolidPosition || std::abs(z) > kMaxSolidPosition)
    throw Error("voxel position (" + std::to_string(x) + ", " + std::to_string(y) + ", " + std::to_string(z) +
                ") is out of range (|x|, |y|, |z| <= 2^30)");
}

std::vector<SolidLevelStats> emptyStats(const SolidAnalysis& a) {
  std::vector<SolidLevelStats> s(a.levels.size());
  for (size_t i = 0; i < s.size(); ++i) s[i].stackLevel = a.levels[i].stackLevel;
  return s;
}

void prepare(const SolidAnalysis& a, const SolidSynthesisOptions& o, SolidLevelCache* cache) {
  o.validate();
  if (a.levels.empty()) throw Error("solid analysis is empty");
  if (cache) cache->bind(ownerKey(a, o));
}

} // namespace

void SolidSynthesisOptions::validate() const {
  if (!(jitter >= 0.0f && jitter <= 4.0f)) throw Error("jitter must be in [0, 4], got " + std::to_string(jitter));
  if (passes < 0 || passes > 4) throw Error("passes must be in [0, 4], got " + std::to_string(passes));
  if (finestPasses < 0 || finestPasses > 4)
    throw Error("finest-level passes must be in [0, 4], got " + std::to_string(finestPasses));
  if (interleave != 1 && interleave != 2)
    throw Error("interleave must be 1 (one sub-pass per pass) or 2 (8 sub-passes), got " + std::to_string(interleave));
  if (offsetCells < 0 || offsetCells > 1024)
    throw Error("offset cells must be in [0, 1024], got " + std::to_string(offsetCells));
  if (!(contrastGain >= 1.0f && contrastGain <= 4.0f))
    throw Error("contrast gain must be in [1, 4], got " + std::to_string(contrastGain));
  if (refinePasses < 0 || refinePasses > 4)
    throw Error("refinement passes must be in [0, 4], got " + std::to_string(refinePasses));
}

double synthesizeSolidMemoryBytes(int64_t voxels, int refinePasses) {
  return double(voxels) * 40.0 + refineSolidMemoryBytes(voxels, refinePasses);
}

void addLevelStats(std::vector<SolidLevelStats>& total, const SolidSynthesisResult& r) {
  if (total.empty()) {
    total = r.levels;
    return;
  }
  for (size_t i = 0; i < r.levels.size() && i < total.size(); ++i) {
    total[i].voxels += r.levels[i].voxels;
    total[i].corrections += r.levels[i].corrections;
    total[i].seconds += r.levels[i].seconds;
  }
}

int64_t SolidSynthesisResult::voxelsSynthesized() const {
  int64_t n = 0;
  for (const auto& l : levels) n += l.voxels;
  return n;
}

void SolidLevelCache::clear() {
  order_.clear();
  bricks_.clear();
  bytes_ = 0;
}

void SolidLevelCache::bind(uint64_t owner) {
  if (owner != owner_) clear();
  owner_ = owner;
}

std::shared_ptr<const SolidLevelCache::Brick> SolidLevelCache::find(const Key& key) {
  auto it = bricks_.find(key);
  if (it == bricks_.end()) {
    ++misses_;
    return nullptr;
  }
  ++hits_;
  order_.splice(order_.begin(), order_, it->second.second);
  return it->second.first;
}

void SolidLevelCache::insert(const Key& key, std::shared_ptr<const Brick> brick) {
  const auto found = bricks_.find(key);
  if (found != bricks_.end()) {
    // Merge: the brick's values are final values, the same whoever computed them.
    const Brick& old = *found->second.first;
    const uint64_t added = brick->valid & ~old.valid;
    if (added) {
      auto merged = std::make_shared<Brick>(old);
      for (int i = 0; i < 64; ++i)
        if (added >> i & 1) std::copy_n(brick->values.data() + i * 3, 3, merged->values.data() + i * 3);
      merged->valid |= added;
      found->second.first = std::move(merged);
    }
    order_.splice(order_.begin(), order_, found->second.second);
    return;
  }
  const size_t size = brick->values.size() * sizeof(uint32_t);
  order_.push_front(key);
  bricks_[key] = {std::move(brick), order_.begin()};
  bytes_ += size;
  while (bytes_ > maxBytes_ && order_.size() > 1) {
    auto it = bricks_.find(order_.back());
    bytes_ -= it->second.first->values.size() * sizeof(uint32_t);
    bricks_.erase(it);
    order_.pop_back();
  }
}

const char* toString(SolidMethod method) { return method == SolidMethod::Tiles ? "tiles" : "lazy"; }

SolidSynthesisResult synthesizeSolid(const SolidAnalysis& a, std::span<const Voxel> voxels,
                                     const SolidSynthesisOptions& o, SolidLevelCache* cache, const Context& ctx) {
  for (const Voxel& v : voxels) validatePosition(v.x, v.y, v.z);
  if (o.method == SolidMethod::Tiles) {
    SolidSynthesisResult result;
    result.triples.resize(voxels.size());
#if TEXFAB_HAS_VULKAN
    if (const auto device = deviceFor(ctx))
      vulkan::evaluateSolidTiles(*device, requireTiles(a), o.seed, voxels, result.triples, ctx);
    else
#endif
      evaluateSolidTiles(requireTiles(a), o.seed, voxels, result.triples, ctx);
    result.distinctVoxels = int64_t(voxels.size());
    return result;
  }
  prepare(a, o, cache);
  SolidSynthesisResult result;
  result.levels = emptyStats(a);
  result.triples.resize(voxels.size());
  if (voxels.empty()) return result;
  if (o.refinePasses > 0) return refineSolid(a, voxels, o, cache, ctx);
  Engine engine{a, o, cache, ctx, result.levels};
  Mask& mask = engine.masks[size_t(engine.top())];
  const auto T = int8_t(engine.steps(engine.top()));
  // The requested voxels, grouped by finest chunk (counting sort).
  std::vector<uint32_t> slotOf(voxels.size());
  ChunkKey lastKey{};
  uint32_t slot = 0;
  for (size_t i = 0; i < voxels.size(); ++i) {
    const Voxel& v = voxels[i];
    const ChunkKey key{v.x >> kChunkShift, v.y >> kChunkShift, v.z >> kChunkShift};
    if (i == 0 || key != lastKey) slot = mask.get(key);  // neighbouring requests share chunks
    lastKey = key;
    int8_t& last = mask.at(slot)[localIndex(v.x, v.y, v.z)];
    result.distinctVoxels += last != T;
    last = T;
    slotOf[i] = slot;
  }
  std::vector<size_t> first(mask.size() + 1, 0);
  for (uint32_t s : slotOf) ++first[s + 1];
  for (size_t s = 0; s < mask.size(); ++s) first[s + 1] += first[s];
  std::vector<size_t> members(voxels.size());
  {
    std::vector<size_t> fill(first.begin(), first.end() - 1);
    for (size_t i = 0; i < voxels.size(); ++i) members[fill[slotOf[i]]++] = i;
  }
  slotOf = {};
  const size_t seeded = mask.size();
  engine.run([&](uint32_t slot, const uint32_t* values) {
    if (slot >= seeded) return;
    for (size_t k = first[slot]; k < first[slot + 1]; ++k) {
      const size_t i = members[k];
      const uint32_t* v = values + localIndex(voxels[i].x, voxels[i].y, voxels[i].z) * 3;
      result.triples[i] = {v[0], v[1], v[2]};
    }
  });
  return result;
}

SolidSynthesisResult synthesizeSolidBox(const SolidAnalysis& a, const VoxelBox& box, const SolidSynthesisOptions& o,
                                        SolidLevelCache* cache, const Context& ctx) {
  if (box.nx < 1 || box.ny < 1 || box.nz < 1)
    throw Error("voxel box " + std::to_string(box.nx) + "x" + std::to_string(box.ny) + "x" + std::to_string(box.nz) +
                " is empty");
  validatePosition(box.x, box.y, box.z);
  validatePosition(box.x + box.nx - 1, box.y + box.ny - 1, box.z + box.nz - 1);
  if (o.method == SolidMethod::Tiles) {
    SolidSynthesisResult result;
    result.triples.resize(size_t(box.count()));
#if TEXFAB_HAS_VULKAN
    if (const auto device = deviceFor(ctx))
      vulkan::evaluateSolidTilesBox(*device, requireTiles(a), o.seed, box, result.triples, ctx);
    else
#endif
      evaluateSolidTilesBox(requireTiles(a), o.seed, box, result.triples, ctx);
    result.distinctVoxels = box.count();
    return result;
  }
  prepare(a, o, cache);
  if (o.refinePasses > 0) return refineSolidBox(a, box, o, cache, ctx);
  SolidSynthesisResult result;
  result.levels = emptyStats(a);
  result.triples.resize(size_t(box.count()));
  Engine engine{a, o, cache, ctx, result.levels};
  Mask& mask = engine.masks[size_t(engine.top())];
  const auto T = int8_t(engine.steps(engine.top()));
  const int64_t lo[3] = {box.x, box.y, box.z}, hi[3] = {box.x + box.nx, box.y + box.ny, box.z + box.nz};
  // The part of chunk `key` inside the box, in level coordinates: [b, e) per axis.
  auto clip = [&](const ChunkKey& key, int64_t b[3], int64_t e[3]) {
    for (int k = 0; k < 3; ++k) {
      b[k] = std::max(lo[k], key[size_t(k)] * kChunk);
      e[k] = std::min(hi[k], key[size_t(k)] * kChunk + kChunk);
    }
  };
  for (int64_t cz = box.z >> kChunkShift; cz <= (hi[2] - 1) >> kChunkShift; ++cz)
    for (int64_t cy = box.y >> kChunkShift; cy <= (hi[1] - 1) >> kChunkShift; ++cy)
      for (int64_t cx = box.x >> kChunkShift; cx <= (hi[0] - 1) >> kChunkShift; ++cx) {
        const ChunkKey key{cx, cy, cz};
        int8_t* last = mask.at(mask.get(key));
        int64_t b[3], e[3];
        clip(key, b, e);
        for (int64_t z = b[2]; z < e[2]; ++z)
          for (int64_t y = b[1]; y < e[1]; ++y) std::fill_n(last + localIndex(b[0], y, z), e[0] - b[0], T);
      }
  result.distinctVoxels = box.count();
  const size_t seeded = mask.size();
  engine.run([&](uint32_t slot, const uint32_t* values) {
    if (slot >= seeded) return;
    int64_t b[3], e[3];
    clip(mask.keys()[slot], b, e);
    for (int64_t z = b[2]; z < e[2]; ++z)
      for (int64_t y = b[1]; y < e[1]; ++y)
        for (int64_t x = b[0]; x < e[0]; ++x) {
          const uint32_t* v = values + localIndex(x, y, z) * 3;
          result.triples[size_t(((z - box.z) * box.ny + (y - box.y)) * box.nx + (x - box.x))] = {v[0], v[1], v[2]};
        }
  });
  return result;
}

int solidColorChannels(const Image& ex, const Image& ey, const Image& ez) {
  return (ex.channels >= 3 || ey.channels >= 3 || ez.channels >= 3) ? 3 : 1;
}

Image solidColorView(const Image& image, int channels) {
  if (image.channels == channels) return image;
  Image out(image.width, image.height, channels, image.format);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < channels; ++c) out.at(x, y, c) = image.at(x, y, image.channels >= 3 ? c : 0);
  return out;
}

void solidColor(const Triple& triple, const Image& ex, const Image& ey, const Image& ez, float* out) {
  const int channels = solidColorChannels(ex, ey, ez);
  const Image* images[3] = {&ex, &ey, &ez};
  for (int c = 0; c < channels; ++c) {
    float sum = 0;
    for (int e = 0; e < 3; ++e) {
      const Image& im = *images[e];
      sum += im.at(int(coordU(triple[size_t(e)])), int(coordV(triple[size_t(e)])), im.channels >= 3 ? c : 0);
    }
    out[c] = sum / 3.0f;
  }
}

void solidColors(std::span<const Triple> triples, const Image& ex, const Image& ey, const Image& ez,
                 std::vector<float>& out) {
  const size_t channels = size_t(solidColorChannels(ex, ey, ez)), start = out.size();
  out.resize(start + triples.size() * channels);
  for (size_t i = 0; i < triples.size(); ++i) solidColor(triples[i], ex, ey, ez, &out[start + i * channels]);
}

DependencyChain dependencyChainSize(const SolidAnalysis& a, const SolidSynthesisOptions& o) {
  DependencyChain chain;
  const Voxel origin{};
  const SolidSynthesisResult r = synthesizeSolid(a, std::span<const Voxel>(&origin, 1), o, nullptr, Context{.threads = 1});
  for (const auto& l : r.levels) chain.exactPerLevel.push_back(l.voxels);
  chain.exact = r.voxelsSynthesized();

  // The paper's count: per level, the mask dilated by the 3-neighborhood once per pass, then
  // downsampled to the parent level; the sum of the levels' masks.
  const auto& cross = solidCrossOffsets();
  std::set<std::array<int64_t, 3>> mask{{0, 0, 0}};
  for (size_t level = 0; level < a.levels.size(); ++level) {
    for (int p = 0; p < o.passesAt(level == 0); ++p) {  // level 0 of this loop is the finest
      std::set<std::array<int64_t, 3>> grown;
      for (const auto& v : mask)
        for (const auto& c : cross) grown.insert({v[0] + c[0], v[1] + c[1], v[2] + c[2]});
      mask.swap(grown);
    }
    chain.perPassDilation += int64_t(mask.size());
    std::set<std::array<int64_t, 3>> parent;
    for (const auto& v : mask) parent.insert({cpu::floorShift(v[0], 1), cpu::floorShift(v[1], 1), cpu::floorShift(v[2], 1)});
    mask.swap(parent);
  }
  return chain;
}

} // namespace texfab::synthesis
