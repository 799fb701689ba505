// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §5 (parallel solid synthesis, lazy subset synthesis) and §6.2 (coarse-level cache).
#include "synthesis/synthesize_solid.h"

#include "render/error.h"
#include "render/parallel.h"
#include "synthesis/coord_map.h"
#include "synthesis/cpu/solid_kernels.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/hash.h"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <chrono>
#include <cmath>
#include <set>
#include <string>
#include <unordered_set>

namespace texfab::synthesis {

namespace {

using cpu::VolumeGrid;
using Clock = std::chrono::steady_clock;

constexpr int kTileShift = 7;   // requests are cut into 128^3 finest-level tiles
constexpr int kBrickShift = 2;  // the cache holds 4^3 bricks (little padding around thin shells)
constexpr int kBrickSide = 1 << kBrickShift;
constexpr int kRowGrain = 4;

// The projections of a level laid out for the correction kernel.
struct Prepared {
  cpu::SolidPairProjection pairs2d, pairs3d;
};

Prepared prepare(const SolidLevel& l) {
  return {cpu::prepareSolidProjection(l.projection2d.mean.data(), l.projection2d.basis.data(), l.projection2d.inputs,
                                      l.projection2d.dims, l.projection2d.divisor),
          cpu::prepareSolidProjection(l.projection3d.mean.data(), l.projection3d.basis.data(), l.projection3d.inputs,
                                      l.projection3d.dims, l.projection3d.divisor)};
}

cpu::SolidTables tablesOf(const SolidAnalysis& a, int li, const Prepared& prepared) {
  const SolidLevel& l = a.levels[size_t(li)];
  cpu::SolidTables t;
  t.exemplarWidth = a.width;
  t.exemplarHeight = a.height;
  t.spacing = l.spacing;
  t.dims = l.dims;
  t.k2d = l.k2d;
  t.k2dStride = int(l.candidates2d[0].size() / (size_t(a.width) * size_t(a.height)));
  t.k3d = l.k3d;
  for (int e = 0; e < 3; ++e) {
    // One image for the three axes: its per-pixel tables are identical; read one copy (cache).
    const size_t s = a.shared ? 0 : size_t(e);
    t.colors[e] = l.colors[s].data();
    t.candidates2d[e] = l.candidates2d[s].data();
    t.descriptors2d[e] = l.descriptors2d[s].data();
    t.candidateDescriptors2d[e] = l.candidateDescriptors2d[s].data();
    t.triples[e] = l.triples[size_t(e)].data();
    t.descriptors3d[e] = l.descriptors3d[size_t(e)].data();
  }
  t.mean2d = l.projection2d.mean.data();
  t.basis2d = l.projection2d.basis.data();
  t.divisor2d = l.projection2d.divisor;
  t.mean3d = l.projection3d.mean.data();
  t.basis3d = l.projection3d.basis.data();
  t.divisor3d = l.projection3d.divisor;
  t.pairs2d = &prepared.pairs2d;
  t.pairs3d = &prepared.pairs3d;
  return t;
}

size_t indexIn(const VolumeGrid& g, int64_t x, int64_t y, int64_t z) {
  return (size_t(z - g.z0) * size_t(g.ny) + size_t(y - g.y0)) * size_t(g.nx) + size_t(x - g.x0);
}

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

uint64_t ownerKey(const SolidAnalysis& a, const SolidSynthesisOptions& o) {
  Fnv1a h;
  h.add(a.key);
  h.add(o.seed);
  h.add(o.jitter);
  h.add(o.passes);
  h.add(o.interleave);
  return h.h;
}

// A grow-only scratch array, not initialized: every kernel writes a voxel before it reads it, and
// reusing the memory across tiles spares the page faults of fresh allocations.
template <class T> struct Buffer {
  std::unique_ptr<T[]> data;
  size_t capacity = 0;
  T* get(size_t size) {
    if (size > capacity) {
      data.reset(new T[size]);
      capacity = size;
    }
    return data.get();
  }
};

// Scratch memory of one level (compute and final of a level run nested inside those of the level
// below it, never inside their own).
struct Workspace {
  Buffer<int8_t> lastE, last;
  Buffer<uint32_t> cur, next, parent, values;
  Buffer<int16_t> curC, nextC;
  Buffer<uint8_t> pneed, touched, mneed;
};

struct Engine {
  const SolidAnalysis& a;
  const SolidSynthesisOptions& o;
  SolidLevelCache* cache;
  int threads;
  std::vector<SolidLevelStats>& stats;
  std::vector<std::unique_ptr<Prepared>> preparedLevels = std::vector<std::unique_ptr<Prepared>>(a.levels.size());
  std::vector<Workspace> ws = std::vector<Workspace>(a.levels.size());

  int top() const { return int(a.levels.size()) - 1; }
  int stepsAt(int) const { return o.passes * o.subpasses(); }

  const Prepared& prepared(int li) {
    auto& p = preparedLevels[size_t(li)];
    if (!p) p = std::make_unique<Prepared>(prepare(a.levels[size_t(li)]));
    return *p;
  }

  // Writes into `out` (3 words per voxel of `box`) the values after the last sub-pass of level li
  // where `need`; leaves the other voxels unspecified.
  void final(int li, const VolumeGrid& box, const uint8_t* need, uint32_t* out) {
    if (!cache || li == top()) return compute(li, box, need, out);
    Workspace& w = ws[size_t(li)];
    // The bricks `box` touches where needed, as a dense grid of brick slots (no per-voxel lookup).
    const int64_t bx0 = cpu::floorShift(box.x0, kBrickShift), by0 = cpu::floorShift(box.y0, kBrickShift),
                  bz0 = cpu::floorShift(box.z0, kBrickShift);
    const VolumeGrid bg{bx0, by0, bz0, int(cpu::floorShift(box.x0 + box.nx - 1, kBrickShift) - bx0 + 1),
                        int(cpu::floorShift(box.y0 + box.ny - 1, kBrickShift) - by0 + 1),
                        int(cpu::floorShift(box.z0 + box.nz - 1, kBrickShift) - bz0 + 1)};
    auto slotOf = [&](int x, int y, int z) {  // buffer voxel of `box` -> brick slot of `bg`
      return indexIn(bg, cpu::floorShift(box.x0 + x, kBrickShift), cpu::floorShift(box.y0 + y, kBrickShift),
                     cpu::floorShift(box.z0 + z, kBrickShift));
    };
    uint8_t* touched = w.touched.get(bg.size());
    std::fill_n(touched, bg.size(), uint8_t(0));
    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y) {
        const uint8_t* row = need + (size_t(z) * box.ny + size_t(y)) * box.nx;
        for (int x = 0; x < box.nx; ++x)
          if (row[x]) touched[slotOf(x, y, z)] = 1;
      }
    std::vector<std::shared_ptr<const SolidLevelCache::Brick>> bricks(bg.size());
    std::vector<size_t> missing;
    auto brickOrigin = [&](size_t i, int64_t b[3]) {
      b[0] = (bg.x0 + int64_t(i % size_t(bg.nx))) * kBrickSide;
      b[1] = (bg.y0 + int64_t(i / size_t(bg.nx) % size_t(bg.ny))) * kBrickSide;
      b[2] = (bg.z0 + int64_t(i / (size_t(bg.nx) * size_t(bg.ny)))) * kBrickSide;
    };
    for (size_t i = 0; i < bg.size(); ++i) {
      if (!touched[i]) continue;
      int64_t b[3];
      brickOrigin(i, b);
      bricks[i] = cache->find({li, b[0] / kBrickSide, b[1] / kBrickSide, b[2] / kBrickSide});
      if (!bricks[i]) missing.push_back(i);
    }
    if (!missing.empty()) {
      int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
      for (size_t i : missing) {
        int64_t b[3];
        brickOrigin(i, b);
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], b[k]);
          hi[k] = std::max(hi[k], b[k] + kBrickSide);
        }
      }
      const VolumeGrid mbox{lo[0], lo[1], lo[2], int(hi[0] - lo[0]), int(hi[1] - lo[1]), int(hi[2] - lo[2])};
      uint8_t* mneed = w.mneed.get(mbox.size());
      std::fill_n(mneed, mbox.size(), uint8_t(0));
      for (size_t i : missing) {
        int64_t b[3];
        brickOrigin(i, b);
        for (int z = 0; z < kBrickSide; ++z)
          for (int y = 0; y < kBrickSide; ++y)
            std::fill_n(mneed + indexIn(mbox, b[0], b[1] + y, b[2] + z), kBrickSide, uint8_t(1));
      }
      uint32_t* values = w.values.get(mbox.size() * 3);
      compute(li, mbox, mneed, values);
      for (size_t i : missing) {
        int64_t b[3];
        brickOrigin(i, b);
        auto brick = std::make_shared<SolidLevelCache::Brick>();
        brick->values.resize(size_t(kBrickSide) * kBrickSide * kBrickSide * 3);
        for (int z = 0; z < kBrickSide; ++z)
          for (int y = 0; y < kBrickSide; ++y)
            std::copy_n(values + indexIn(mbox, b[0], b[1] + y, b[2] + z) * 3, kBrickSide * 3,
                        brick->values.begin() + std::ptrdiff_t((size_t(z) * kBrickSide + size_t(y)) * kBrickSide * 3));
        cache->insert({li, b[0] / kBrickSide, b[1] / kBrickSide, b[2] / kBrickSide}, brick);
        bricks[i] = std::move(brick);
      }
    }
    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y)
        for (int x = 0; x < box.nx; ++x) {
          const size_t v = (size_t(z) * box.ny + size_t(y)) * box.nx + size_t(x);
          if (!need[v]) continue;
          const int64_t q[3] = {box.x0 + x, box.y0 + y, box.z0 + z};
          const SolidLevelCache::Brick& brick = *bricks[slotOf(x, y, z)];
          const size_t from = ((size_t(cpu::floorMod(q[2], kBrickSide)) * kBrickSide + size_t(cpu::floorMod(q[1], kBrickSide))) *
                                   kBrickSide +
                               size_t(cpu::floorMod(q[0], kBrickSide))) *
                              3;
          std::copy_n(brick.values.data() + from, 3, out + v * 3);
        }
  }

  void compute(int li, const VolumeGrid& box, const uint8_t* need, uint32_t* out) {
    auto started = Clock::now();
    Workspace& w = ws[size_t(li)];
    const int steps = stepsAt(li);
    // §5.2, exact per sub-pass: last[v] = the last step after which v's value is needed.
    const int margin = 2 * steps;
    const VolumeGrid e{box.x0 - margin, box.y0 - margin, box.z0 - margin, box.nx + 2 * margin, box.ny + 2 * margin,
                       box.nz + 2 * margin};
    int8_t* lastE = w.lastE.get(e.size());
    std::fill_n(lastE, e.size(), int8_t(-1));
    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y) {
        const uint8_t* row = need + (size_t(z) * box.ny + size_t(y)) * box.nx;
        int8_t* to = lastE + indexIn(e, box.x0, box.y0 + y, box.z0 + z);
        for (int x = 0; x < box.nx; ++x)
          if (row[x]) to[x] = int8_t(steps);
      }
    for (int t = steps; t >= 1; --t)
      parallelFor(0, e.rows(), threads, [&](int r0, int r1) { cpu::solidDilateKernel(lastE, e, o.interleave, t, r0, r1); },
                  kRowGrain);

    // The level's working box: the bounding box of the chain.
    int lo[3] = {e.nx, e.ny, e.nz}, hi[3] = {-1, -1, -1};
    for (int z = 0; z < e.nz; ++z)
      for (int y = 0; y < e.ny; ++y) {
        const int8_t* row = lastE + (size_t(z) * e.ny + size_t(y)) * e.nx;
        for (int x = 0; x < e.nx; ++x)
          if (row[x] >= 0) {
            lo[0] = std::min(lo[0], x), hi[0] = std::max(hi[0], x);
            lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
            lo[2] = std::min(lo[2], z), hi[2] = std::max(hi[2], z);
          }
      }
    if (hi[0] < 0) return;  // nothing needed
    const VolumeGrid g{e.x0 + lo[0], e.y0 + lo[1], e.z0 + lo[2], hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
    int8_t* last = w.last.get(g.size());
    int64_t voxels = 0;
    for (int z = 0; z < g.nz; ++z)
      for (int y = 0; y < g.ny; ++y) {
        const int8_t* from = lastE + indexIn(e, g.x0, g.y0 + y, g.z0 + z);
        int8_t* to = last + (size_t(z) * g.ny + size_t(y)) * g.nx;
        std::copy_n(from, g.nx, to);
        for (int x = 0; x < g.nx; ++x) voxels += to[x] >= 0;
      }

    const cpu::SolidTables tables = tablesOf(a, li, prepared(li));
    uint32_t* cur = w.cur.get(g.size() * 3);
    if (li == 0) {
      const auto jitter256 = int64_t(std::lrint(double(o.jitter) * 256.0));
      parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
        cpu::solidInitKernel(cur, last, g, tables, o.seed, jitter256, r0, r1);
      }, kRowGrain);
    } else {
      const VolumeGrid pg{cpu::floorShift(g.x0, 1), cpu::floorShift(g.y0, 1), cpu::floorShift(g.z0, 1),
                          int(cpu::floorShift(g.x0 + g.nx - 1, 1) - cpu::floorShift(g.x0, 1) + 1),
                          int(cpu::floorShift(g.y0 + g.ny - 1, 1) - cpu::floorShift(g.y0, 1) + 1),
                          int(cpu::floorShift(g.z0 + g.nz - 1, 1) - cpu::floorShift(g.z0, 1) + 1)};
      uint8_t* pneed = w.pneed.get(pg.size());
      std::fill_n(pneed, pg.size(), uint8_t(0));
      for (int z = 0; z < g.nz; ++z)
        for (int y = 0; y < g.ny; ++y) {
          const int8_t* row = last + (size_t(z) * g.ny + size_t(y)) * g.nx;
          uint8_t* prow = pneed + indexIn(pg, pg.x0, cpu::floorShift(g.y0 + y, 1), cpu::floorShift(g.z0 + z, 1));
          for (int x = 0; x < g.nx; ++x)
            if (row[x] >= 0) prow[cpu::floorShift(g.x0 + x, 1) - pg.x0] = 1;
        }
      stats[size_t(li)].seconds += since(started);
      uint32_t* parent = w.parent.get(pg.size() * 3);
      final(li - 1, pg, pneed, parent);
      started = Clock::now();
      parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
        cpu::solidUpsampleKernel(parent, pg, cur, last, g, tables.spacing, a.width, a.height, r0, r1);
      }, kRowGrain);
    }

    // The colour buffer of the level (the correction kernel reads colours, not triples).
    int16_t* curC = w.curC.get(g.size() * 4);
    parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
      cpu::solidColorKernel(cur, curC, last, 0, g, tables, r0, r1);
    }, kRowGrain);
    uint32_t* next = w.next.get(g.size() * 3);
    int16_t* nextC = w.nextC.get(g.size() * 4);
    for (int t = 1; t <= steps; ++t) {
      parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
        cpu::solidCorrectKernel(cur, curC, next, nextC, last, g, tables, o.interleave, t, r0, r1);
      }, kRowGrain);
      if (o.interleave == 1) {
        // Jacobi: every voxel still needed (last >= t) was just written; the others are never
        // read again.
        std::swap(cur, next);
        std::swap(curC, nextC);
      } else {
        parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
          cpu::solidCommitKernel(next, nextC, cur, curC, last, g, o.interleave, t, r0, r1);
        }, kRowGrain);
      }
    }
    const int subpasses = o.subpasses();
    int64_t corrections = 0;
    for (size_t v = 0; v < g.size(); ++v) corrections += last[v] > 0 ? (last[v] + subpasses - 1) / subpasses : 0;

    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y)
        for (int x = 0; x < box.nx; ++x) {
          const size_t v = (size_t(z) * box.ny + size_t(y)) * box.nx + size_t(x);
          if (need[v]) std::copy_n(cur + indexIn(g, box.x0 + x, box.y0 + y, box.z0 + z) * 3, 3, out + v * 3);
        }
    SolidLevelStats& s = stats[size_t(li)];
    s.voxels += voxels;
    s.corrections += corrections;
    s.seconds += since(started);
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
  if (interleave != 1 && interleave != 2)
    throw Error("interleave must be 1 (one sub-pass per pass) or 2 (8 sub-passes), got " + std::to_string(interleave));
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
  if (bricks_.count(key)) return;
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

SolidSynthesisResult synthesizeSolid(const SolidAnalysis& a, std::span<const Voxel> voxels,
                                     const SolidSynthesisOptions& o, SolidLevelCache* cache, int threads) {
  prepare(a, o, cache);
  for (const Voxel& v : voxels) validatePosition(v.x, v.y, v.z);
  SolidSynthesisResult result;
  result.levels = emptyStats(a);
  result.triples.resize(voxels.size());
  std::map<std::array<int64_t, 3>, std::vector<size_t>> tiles;
  for (size_t i = 0; i < voxels.size(); ++i)
    tiles[{cpu::floorShift(voxels[i].x, kTileShift), cpu::floorShift(voxels[i].y, kTileShift),
           cpu::floorShift(voxels[i].z, kTileShift)}]
        .push_back(i);
  // Several tiles share coarse levels: without a cache of the caller's, one for this request.
  SolidLevelCache local(SIZE_MAX);
  Engine engine{a, o, cache ? cache : tiles.size() > 1 ? &local : nullptr, threads, result.levels};
  Buffer<uint8_t> needBuffer;
  Buffer<uint32_t> valueBuffer;
  for (const auto& [tile, members] : tiles) {
    int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
    for (size_t i : members) {
      const int64_t p[3] = {voxels[i].x, voxels[i].y, voxels[i].z};
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], p[k]);
        hi[k] = std::max(hi[k], p[k]);
      }
    }
    const VolumeGrid box{lo[0], lo[1], lo[2], int(hi[0] - lo[0] + 1), int(hi[1] - lo[1] + 1), int(hi[2] - lo[2] + 1)};
    uint8_t* need = needBuffer.get(box.size());
    std::fill_n(need, box.size(), uint8_t(0));
    for (size_t i : members) need[indexIn(box, voxels[i].x, voxels[i].y, voxels[i].z)] = 1;
    uint32_t* values = valueBuffer.get(box.size() * 3);
    engine.final(engine.top(), box, need, values);
    for (size_t i : members) {
      const size_t v = indexIn(box, voxels[i].x, voxels[i].y, voxels[i].z) * 3;
      result.triples[i] = {values[v], values[v + 1], values[v + 2]};
    }
  }
  return result;
}

SolidSynthesisResult synthesizeSolidBox(const SolidAnalysis& a, const VoxelBox& box, const SolidSynthesisOptions& o,
                                        SolidLevelCache* cache, int threads) {
  prepare(a, o, cache);
  if (box.nx < 1 || box.ny < 1 || box.nz < 1)
    throw Error("voxel box " + std::to_string(box.nx) + "x" + std::to_string(box.ny) + "x" + std::to_string(box.nz) +
                " is empty");
  validatePosition(box.x, box.y, box.z);
  validatePosition(box.x + box.nx - 1, box.y + box.ny - 1, box.z + box.nz - 1);
  SolidSynthesisResult result;
  result.levels = emptyStats(a);
  result.triples.resize(size_t(box.count()));
  const int64_t side = int64_t(1) << kTileShift;
  auto tileStart = [&](int64_t p) { return cpu::floorShift(p, kTileShift) * side; };
  const bool oneTile = tileStart(box.x) == tileStart(box.x + box.nx - 1) && tileStart(box.y) == tileStart(box.y + box.ny - 1) &&
                       tileStart(box.z) == tileStart(box.z + box.nz - 1);
  SolidLevelCache local(SIZE_MAX);
  Engine engine{a, o, cache ? cache : oneTile ? nullptr : &local, threads, result.levels};
  Buffer<uint8_t> needBuffer;
  Buffer<uint32_t> valueBuffer;
  for (int64_t tz = tileStart(box.z); tz < box.z + box.nz; tz += side)
    for (int64_t ty = tileStart(box.y); ty < box.y + box.ny; ty += side)
      for (int64_t tx = tileStart(box.x); tx < box.x + box.nx; tx += side) {
        const int64_t x0 = std::max(tx, box.x), y0 = std::max(ty, box.y), z0 = std::max(tz, box.z);
        const int64_t x1 = std::min(tx + side, box.x + box.nx), y1 = std::min(ty + side, box.y + box.ny),
                      z1 = std::min(tz + side, box.z + box.nz);
        const VolumeGrid sub{x0, y0, z0, int(x1 - x0), int(y1 - y0), int(z1 - z0)};
        uint8_t* need = needBuffer.get(sub.size());
        std::fill_n(need, sub.size(), uint8_t(1));
        uint32_t* values = valueBuffer.get(sub.size() * 3);
        engine.final(engine.top(), sub, need, values);
        for (int z = 0; z < sub.nz; ++z)
          for (int y = 0; y < sub.ny; ++y)
            for (int x = 0; x < sub.nx; ++x) {
              const size_t from = ((size_t(z) * sub.ny + size_t(y)) * sub.nx + size_t(x)) * 3;
              const size_t to = (size_t(sub.z0 + z - box.z) * size_t(box.ny) + size_t(sub.y0 + y - box.y)) *
                                    size_t(box.nx) +
                                size_t(sub.x0 + x - box.x);
              result.triples[to] = {values[from], values[from + 1], values[from + 2]};
            }
      }
  return result;
}

int solidColorChannels(const Image& ex, const Image& ey, const Image& ez) {
  return (ex.channels >= 3 || ey.channels >= 3 || ez.channels >= 3) ? 3 : 1;
}

void solidColors(std::span<const Triple> triples, const Image& ex, const Image& ey, const Image& ez,
                 std::vector<float>& out) {
  const int channels = solidColorChannels(ex, ey, ez);
  const Image* images[3] = {&ex, &ey, &ez};
  const size_t start = out.size();
  out.resize(start + triples.size() * size_t(channels));
  for (size_t i = 0; i < triples.size(); ++i)
    for (int c = 0; c < channels; ++c) {
      float sum = 0;
      for (int e = 0; e < 3; ++e) {
        const Image& im = *images[e];
        sum += im.at(int(coordU(triples[i][size_t(e)])), int(coordV(triples[i][size_t(e)])), im.channels >= 3 ? c : 0);
      }
      out[start + i * size_t(channels) + size_t(c)] = sum / 3.0f;
    }
}

DependencyChain dependencyChainSize(const SolidAnalysis& a, const SolidSynthesisOptions& o) {
  DependencyChain chain;
  const Voxel origin{};
  const SolidSynthesisResult r = synthesizeSolid(a, std::span<const Voxel>(&origin, 1), o, nullptr, 1);
  for (const auto& l : r.levels) chain.exactPerLevel.push_back(l.voxels);
  chain.exact = r.voxelsSynthesized();

  // The paper's count: per level, the mask dilated by the 3-neighborhood once per pass, then
  // downsampled to the parent level; the sum of the levels' masks.
  const auto& cross = solidCrossOffsets();
  std::set<std::array<int64_t, 3>> mask{{0, 0, 0}};
  for (size_t level = 0; level < a.levels.size(); ++level) {
    for (int p = 0; p < o.passes; ++p) {
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
