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
constexpr int kBrickShift = 3;  // the cache holds 8^3 bricks
constexpr int kBrickSide = 1 << kBrickShift;
constexpr int kRowGrain = 4;

cpu::SolidTables tablesOf(const SolidAnalysis& a, int li) {
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

struct Engine {
  const SolidAnalysis& a;
  const SolidSynthesisOptions& o;
  SolidLevelCache* cache;
  int threads;
  int steps;
  std::vector<SolidLevelStats>& stats;

  int top() const { return int(a.levels.size()) - 1; }

  // Values (3 words per voxel of `box`) after the last sub-pass of level li, valid where `need`.
  std::vector<uint32_t> final(int li, const VolumeGrid& box, const std::vector<uint8_t>& need) {
    if (!cache || li == top()) return compute(li, box, need);
    std::vector<SolidLevelCache::Key> keys;
    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y)
        for (int x = 0; x < box.nx; ++x)
          if (need[(size_t(z) * box.ny + size_t(y)) * box.nx + size_t(x)])
            keys.emplace_back(li, cpu::floorShift(box.x0 + x, kBrickShift), cpu::floorShift(box.y0 + y, kBrickShift),
                              cpu::floorShift(box.z0 + z, kBrickShift));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    std::map<SolidLevelCache::Key, std::shared_ptr<const SolidLevelCache::Brick>> bricks;
    std::vector<SolidLevelCache::Key> missing;
    for (const auto& k : keys) {
      auto b = cache->find(k);
      if (b) bricks[k] = std::move(b);
      else missing.push_back(k);
    }
    if (!missing.empty()) {
      int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
      for (const auto& [l, bx, by, bz] : missing) {
        const int64_t b[3] = {bx, by, bz};
        for (int i = 0; i < 3; ++i) {
          lo[i] = std::min(lo[i], b[i] * kBrickSide);
          hi[i] = std::max(hi[i], b[i] * kBrickSide + kBrickSide);
        }
      }
      const VolumeGrid mbox{lo[0], lo[1], lo[2], int(hi[0] - lo[0]), int(hi[1] - lo[1]), int(hi[2] - lo[2])};
      std::vector<uint8_t> mneed(mbox.size(), 0);
      for (const auto& [l, bx, by, bz] : missing)
        for (int z = 0; z < kBrickSide; ++z)
          for (int y = 0; y < kBrickSide; ++y)
            for (int x = 0; x < kBrickSide; ++x)
              mneed[indexIn(mbox, bx * kBrickSide + x, by * kBrickSide + y, bz * kBrickSide + z)] = 1;
      const std::vector<uint32_t> values = compute(li, mbox, mneed);
      for (const auto& k : missing) {
        const auto& [l, bx, by, bz] = k;
        auto brick = std::make_shared<SolidLevelCache::Brick>();
        brick->values.resize(size_t(kBrickSide) * kBrickSide * kBrickSide * 3);
        for (int z = 0; z < kBrickSide; ++z)
          for (int y = 0; y < kBrickSide; ++y)
            for (int x = 0; x < kBrickSide; ++x) {
              const size_t from = indexIn(mbox, bx * kBrickSide + x, by * kBrickSide + y, bz * kBrickSide + z) * 3;
              const size_t to = ((size_t(z) * kBrickSide + size_t(y)) * kBrickSide + size_t(x)) * 3;
              std::copy_n(values.begin() + std::ptrdiff_t(from), 3, brick->values.begin() + std::ptrdiff_t(to));
            }
        cache->insert(k, brick);
        bricks[k] = std::move(brick);
      }
    }
    std::vector<uint32_t> out(box.size() * 3, 0);
    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y)
        for (int x = 0; x < box.nx; ++x) {
          const size_t v = (size_t(z) * box.ny + size_t(y)) * box.nx + size_t(x);
          if (!need[v]) continue;
          const int64_t q[3] = {box.x0 + x, box.y0 + y, box.z0 + z};
          const auto& brick = bricks.at({li, cpu::floorShift(q[0], kBrickShift), cpu::floorShift(q[1], kBrickShift),
                                         cpu::floorShift(q[2], kBrickShift)});
          const size_t from = ((size_t(cpu::floorMod(q[2], kBrickSide)) * kBrickSide + size_t(cpu::floorMod(q[1], kBrickSide))) *
                                   kBrickSide +
                               size_t(cpu::floorMod(q[0], kBrickSide))) *
                              3;
          std::copy_n(brick->values.begin() + std::ptrdiff_t(from), 3, out.begin() + std::ptrdiff_t(v * 3));
        }
    return out;
  }

  std::vector<uint32_t> compute(int li, const VolumeGrid& box, const std::vector<uint8_t>& need) {
    auto started = Clock::now();
    // §5.2, exact per sub-pass: last[v] = the last step after which v's value is needed.
    const int margin = 2 * steps;
    const VolumeGrid e{box.x0 - margin, box.y0 - margin, box.z0 - margin, box.nx + 2 * margin, box.ny + 2 * margin,
                       box.nz + 2 * margin};
    std::vector<int8_t> lastE(e.size(), -1);
    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y)
        for (int x = 0; x < box.nx; ++x)
          if (need[(size_t(z) * box.ny + size_t(y)) * box.nx + size_t(x)])
            lastE[indexIn(e, box.x0 + x, box.y0 + y, box.z0 + z)] = int8_t(steps);
    for (int t = steps; t >= 1; --t)
      parallelFor(0, e.rows(), threads, [&](int r0, int r1) { cpu::solidDilateKernel(lastE.data(), e, o.interleave, t, r0, r1); },
                  kRowGrain);

    // The level's working box: the bounding box of the chain.
    int lo[3] = {e.nx, e.ny, e.nz}, hi[3] = {-1, -1, -1};
    for (int z = 0; z < e.nz; ++z)
      for (int y = 0; y < e.ny; ++y) {
        const int8_t* row = &lastE[(size_t(z) * e.ny + size_t(y)) * e.nx];
        for (int x = 0; x < e.nx; ++x)
          if (row[x] >= 0) {
            lo[0] = std::min(lo[0], x), hi[0] = std::max(hi[0], x);
            lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
            lo[2] = std::min(lo[2], z), hi[2] = std::max(hi[2], z);
          }
      }
    std::vector<uint32_t> out(box.size() * 3, 0);
    if (hi[0] < 0) return out;  // nothing needed
    const VolumeGrid g{e.x0 + lo[0], e.y0 + lo[1], e.z0 + lo[2], hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
    std::vector<int8_t> last(g.size());
    int64_t voxels = 0;
    for (int z = 0; z < g.nz; ++z)
      for (int y = 0; y < g.ny; ++y) {
        const int8_t* from = &lastE[indexIn(e, g.x0, g.y0 + y, g.z0 + z)];
        int8_t* to = &last[(size_t(z) * g.ny + size_t(y)) * g.nx];
        std::copy_n(from, g.nx, to);
        for (int x = 0; x < g.nx; ++x) voxels += to[x] >= 0;
      }
    lastE.clear();
    lastE.shrink_to_fit();

    const cpu::SolidTables tables = tablesOf(a, li);
    std::vector<uint32_t> cur(g.size() * 3, 0);
    if (li == 0) {
      const auto jitter256 = int64_t(std::lrint(double(o.jitter) * 256.0));
      parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
        cpu::solidInitKernel(cur.data(), last.data(), g, tables, o.seed, jitter256, r0, r1);
      }, kRowGrain);
    } else {
      const VolumeGrid pg{cpu::floorShift(g.x0, 1), cpu::floorShift(g.y0, 1), cpu::floorShift(g.z0, 1),
                          int(cpu::floorShift(g.x0 + g.nx - 1, 1) - cpu::floorShift(g.x0, 1) + 1),
                          int(cpu::floorShift(g.y0 + g.ny - 1, 1) - cpu::floorShift(g.y0, 1) + 1),
                          int(cpu::floorShift(g.z0 + g.nz - 1, 1) - cpu::floorShift(g.z0, 1) + 1)};
      std::vector<uint8_t> pneed(pg.size(), 0);
      for (int z = 0; z < g.nz; ++z)
        for (int y = 0; y < g.ny; ++y)
          for (int x = 0; x < g.nx; ++x)
            if (last[(size_t(z) * g.ny + size_t(y)) * g.nx + size_t(x)] >= 0)
              pneed[indexIn(pg, cpu::floorShift(g.x0 + x, 1), cpu::floorShift(g.y0 + y, 1),
                            cpu::floorShift(g.z0 + z, 1))] = 1;
      stats[size_t(li)].seconds += since(started);
      const std::vector<uint32_t> parent = final(li - 1, pg, pneed);
      started = Clock::now();
      parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
        cpu::solidUpsampleKernel(parent.data(), pg, cur.data(), last.data(), g, tables.spacing, a.width, a.height, r0,
                                 r1);
      }, kRowGrain);
    }

    std::vector<uint32_t> next(cur.size());
    int64_t corrections = 0;
    for (int t = 1; t <= steps; ++t) {
      parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
        cpu::solidCorrectKernel(cur.data(), next.data(), last.data(), g, tables, o.interleave, t, r0, r1);
      }, kRowGrain);
      parallelFor(0, g.rows(), threads, [&](int r0, int r1) {
        cpu::solidCommitKernel(next.data(), cur.data(), last.data(), g, o.interleave, t, r0, r1);
      }, kRowGrain);
    }
    const int subpasses = o.subpasses();
    for (int8_t l : last) corrections += l > 0 ? (l + subpasses - 1) / subpasses : 0;  // passes (approx.)

    for (int z = 0; z < box.nz; ++z)
      for (int y = 0; y < box.ny; ++y)
        for (int x = 0; x < box.nx; ++x) {
          const size_t v = (size_t(z) * box.ny + size_t(y)) * box.nx + size_t(x);
          if (!need[v]) continue;
          std::copy_n(cur.begin() + std::ptrdiff_t(indexIn(g, box.x0 + x, box.y0 + y, box.z0 + z) * 3), 3,
                      out.begin() + std::ptrdiff_t(v * 3));
        }
    SolidLevelStats& s = stats[size_t(li)];
    s.voxels += voxels;
    s.corrections += corrections;
    s.seconds += since(started);
    return out;
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
  Engine engine{a, o, cache, threads, o.passes * o.subpasses(), result.levels};

  std::map<std::array<int64_t, 3>, std::vector<size_t>> tiles;
  for (size_t i = 0; i < voxels.size(); ++i)
    tiles[{cpu::floorShift(voxels[i].x, kTileShift), cpu::floorShift(voxels[i].y, kTileShift),
           cpu::floorShift(voxels[i].z, kTileShift)}]
        .push_back(i);
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
    std::vector<uint8_t> need(box.size(), 0);
    for (size_t i : members) need[indexIn(box, voxels[i].x, voxels[i].y, voxels[i].z)] = 1;
    const std::vector<uint32_t> values = engine.final(engine.top(), box, need);
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
  Engine engine{a, o, cache, threads, o.passes * o.subpasses(), result.levels};
  const int64_t side = int64_t(1) << kTileShift;
  auto tileStart = [&](int64_t p) { return cpu::floorShift(p, kTileShift) * side; };
  for (int64_t tz = tileStart(box.z); tz < box.z + box.nz; tz += side)
    for (int64_t ty = tileStart(box.y); ty < box.y + box.ny; ty += side)
      for (int64_t tx = tileStart(box.x); tx < box.x + box.nx; tx += side) {
        const int64_t x0 = std::max(tx, box.x), y0 = std::max(ty, box.y), z0 = std::max(tz, box.z);
        const int64_t x1 = std::min(tx + side, box.x + box.nx), y1 = std::min(ty + side, box.y + box.ny),
                      z1 = std::min(tz + side, box.z + box.nz);
        const VolumeGrid sub{x0, y0, z0, int(x1 - x0), int(y1 - y0), int(z1 - z0)};
        const std::vector<uint8_t> need(sub.size(), 1);
        const std::vector<uint32_t> values = engine.final(engine.top(), sub, need);
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
