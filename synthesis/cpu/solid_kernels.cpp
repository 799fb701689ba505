// SPDX-License-Identifier: GPL-3.0-or-later
// The solid kernels, portable: plain scalar C++, one voxel at a time. This file is the
// specification that the x86 batches (solid_kernels_x86.cpp) and the GLSL compute shaders
// (synthesis/vulkan/shaders/solid_*.comp) follow, bit for bit.
//
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §4.3 (candidate slab), §5.1 (initialization, jitter, upsampling, correction with the
//           two-step search), §5.2 (dependency masks).
#include "synthesis/cpu/solid_kernels.h"

#include "core/hash.h"
#include "synthesis/coord_map.h"
#include "synthesis/cpu/solid_search.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/solid_analysis.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace texfab::synthesis::cpu {

namespace {

constexpr int kSlabThickness = kSolidNeighborhoodSide;

struct CrossLayout {
  int64_t linear[kSolidCrossVoxels];  // buffer index offsets of the cross
  int plane[3][25];                   // cross index of plane e's (u, v) offsets, v outer
};

CrossLayout layoutFor(const VolumeGrid& g) {
  // The planes' cross indices do not depend on the grid: found once.
  static const auto planes = [] {
    std::array<std::array<int, 25>, 3> p{};
    const auto& cross = solidCrossOffsets();
    for (int e = 0; e < 3; ++e) {
      int k = 0;
      for (int j = -2; j <= 2; ++j)
        for (int i = -2; i <= 2; ++i) {
          int o[3] = {0, 0, 0};
          o[kAxisU[e]] += i;
          o[kAxisV[e]] += j;
          for (int c = 0; c < kSolidCrossVoxels; ++c)
            if (cross[size_t(c)][0] == o[0] && cross[size_t(c)][1] == o[1] && cross[size_t(c)][2] == o[2])
              p[size_t(e)][size_t(k)] = c;
          ++k;
        }
    }
    for (int k = 0; k < 25; ++k)
      if (p[2][size_t(k)] != k) throw std::logic_error("solid kernels: E_z's plane must lead the 3-neighborhood");
    return p;
  }();
  CrossLayout l{};
  const auto& cross = solidCrossOffsets();
  for (int i = 0; i < kSolidCrossVoxels; ++i)
    l.linear[i] = (int64_t(cross[size_t(i)][2]) * g.ny + cross[size_t(i)][1]) * g.nx + cross[size_t(i)][0];
  for (int e = 0; e < 3; ++e)
    for (int k = 0; k < 25; ++k) l.plane[e][k] = planes[size_t(e)][size_t(k)];
  return l;
}

// Coordinates a few taps outside [0, m) (|offset| <= m): one compare instead of a division.
inline int64_t wrapNear(int64_t a, int64_t m) {
  if (a < 0) a += m;
  else if (a >= m) a -= m;
  return (a >= 0 && a < m) ? a : floorMod(a, m);
}

inline uint32_t wrapCoord(int64_t u, int64_t v, int w, int h) {
  return packCoord(uint32_t(wrapNear(u, w)), uint32_t(wrapNear(v, h)));
}

// ---- Initialization (§5.1) ----

// The random warp at level position q, added to disp (1/256 voxel): a sum of compactly supported
// bumps on two hashed grids.
void warp(const int64_t q[3], uint32_t seed, int64_t jitter256, int64_t disp[3]) {
  constexpr int kCells[2] = {4, 8};              // warp grids, voxels
  constexpr int64_t kAmplitude[2] = {384, 256};  // x jitter/256: stronger at the small scale (§5.1)
  for (int octave = 0; octave < 2; ++octave) {
    const int cell = kCells[octave];
    const int64_t amp = jitter256 * kAmplitude[octave] / 256;
    const int64_t radius2 = int64_t(cell * 256) * (cell * 256);
    int64_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = q[a] >= 0 ? q[a] / cell : -((-q[a] + cell - 1) / cell);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int32_t cc[3] = {int32_t(c[0] + dx), int32_t(c[1] + dy), int32_t(c[2] + dz)};
          // One hash per bump: its centre (3 x 10 bits inside the cell), a second for its
          // direction (3 x 9 bits, each component in [-256, 256)).
          const uint32_t hc = voxelHash(seed, uint32_t(octave), cc[0], cc[1], cc[2], 0);
          const uint32_t hd = pcgHash(hc);
          int64_t r2 = 0;
          int64_t dir[3];
          for (int a = 0; a < 3; ++a) {
            const int64_t frac = (hc >> (10 * a)) & 0x3ffu;
            const int64_t centre = int64_t(cc[a]) * cell * 256 + ((frac * cell * 256) >> 10);
            const int64_t d = q[a] * 256 - centre;
            r2 += d * d;
            dir[a] = int64_t((hd >> (9 * a)) & 0x1ffu) - 256;
          }
          if (r2 >= radius2) continue;
          const int64_t s = (radius2 - r2) * 65536 / radius2;
          const int64_t weight = (s * s) >> 16;
          for (int a = 0; a < 3; ++a) disp[a] += (amp * dir[a] * weight) >> 24;
        }
  }
}

// The hashed offset of the cell of side `cell` holding p: exemplar pixels (u, v) and slab layers.
void cellOffset(const int64_t p[3], uint32_t seed, int cell, const SolidTables& t, int64_t offset[3]) {
  int32_t c[3];
  for (int a = 0; a < 3; ++a) c[a] = int32_t((p[a] - floorMod(p[a], cell)) / cell);
  const uint32_t hu = voxelHash(seed, 2, c[0], c[1], c[2], 0), hv = pcgHash(hu), hz = pcgHash(hv);
  offset[0] = int64_t(hu % uint32_t(t.exemplarWidth));
  offset[1] = int64_t(hv % uint32_t(t.exemplarHeight));
  offset[2] = int64_t(hz % uint32_t(kSlabThickness));
}

// The slab (§4.3) at warped position p, shifted by `offset`: the E_z pixel under (x, y), thickened
// along z by its best candidate's E_x and E_y neighborhoods (E_x's v axis and E_y's u axis are z).
void slabTriple(const int64_t p[3], const int64_t offset[3], const SolidTables& t, uint32_t* out) {
  const int w = t.exemplarWidth, h = t.exemplarHeight, m = t.clampMargin;
  const uint32_t pixel = wrapCoord(p[0] * t.spacing + offset[0], p[1] * t.spacing + offset[1], w, h);
  const int64_t dz = floorMod(p[2] + offset[2], kSlabThickness) - kSlabThickness / 2;
  const uint32_t* best = t.triples[2] + (size_t(coordV(pixel)) * size_t(w) + coordU(pixel)) * kSolidMaxCandidates * 3;
  auto layer = [&](int64_t c, int side) {
    return uint32_t(m > 0 ? reflectInto(c, m, side - 1 - m) : floorMod(c, side));
  };
  out[0] = packCoord(coordU(best[0]), layer(int64_t(coordV(best[0])) + dz * t.spacing, h));
  out[1] = packCoord(layer(int64_t(coordU(best[1])) + dz * t.spacing, w), coordV(best[1]));
  out[2] = best[2];  // the pixel itself, or (clamp) its reflection into the valid region
}

std::atomic<SolidSimd> gSimd{SolidSimd::Avx2};

// ---- Correction: the two-step search of §5.1, one voxel at a time (see solid_search.h) ----

// q_d = clamp((sum_j w[d][j] x_j + offset[d]) >> shift, +-127) for the prepared weights.
void project(const int16_t* x, const SolidKernelProjection& p, int8_t* out) {
  constexpr int kChunk = SolidKernelProjection::kChunk;
  int32_t sum[SolidKernelProjection::kLanes] = {};
  const int16_t* w = p.weights.data();
  for (int c = 0; c < p.lanes; c += kChunk)
    for (int d = 0; d < p.rows; ++d, w += kChunk)
      for (int i = 0; i < kChunk; ++i) sum[d] += int32_t(w[i]) * int32_t(x[c + i]);
  finishProjection(sum, p, out);
}

int32_t ssd(const int8_t* a, const int8_t* b, int n) {
  int32_t s = 0;
  for (int i = 0; i < n; ++i) {
    const int32_t d = int32_t(a[i]) - int32_t(b[i]);
    s += d * d;
  }
  return s;
}

// The targets: the projected 3-neighborhood and its three projected planes.
void projectTargets(VoxelSearch& s, const int16_t* inColors, const Correction& c, const SolidTables& t,
                    Neighborhood& n) {
  gatherNeighborhood(s, inColors, c, n);
  project(n.cross, *t.projection3d, s.target3d);
  project(n.planes[0], *t.projection2d, s.target2d[0]);
  project(n.planes[1], *t.projection2d, s.target2d[1]);
  project(n.cross, *t.projection2d, s.target2d[2]);  // layoutFor checks that E_z's plane leads
}

// Step 1 in direction e: the pixel (v * w + u) of the best of the k2d candidates of its 9 pixels.
uint32_t nearest2d(const VoxelSearch& s, const SolidTables& t, int e) {
  uint64_t best = UINT64_MAX;
  for (int n = 0; n < 9; ++n) {
    const size_t slot = size_t(s.bases[e][n]) * size_t(t.k2dStride);
    const uint32_t* cand = t.candidates2d[e] + slot;
    const int8_t* descriptors = t.candidateDescriptors2d[e] + slot * kSolid2dDims;
    for (int k = 0; k < t.k2d; ++k)
      best = std::min(best, searchKey(ssd(s.target2d[e], descriptors + size_t(k) * kSolid2dDims, kSolid2dDims), cand[k]));
  }
  return coordV(uint32_t(best)) * uint32_t(t.exemplarWidth) + coordU(uint32_t(best));
}

void correctVoxel(VoxelSearch& s, const uint32_t* in, const int16_t* inColors, const Correction& c,
                  const SolidTables& t, Neighborhood& n) {
  findBases(s, in, c.bases);
  projectTargets(s, inColors, c, t, n);
  for (int e = 0; e < 3; ++e) s.pixels[e] = nearest2d(s, t, e);
  s.triple = tripleOf(t, s.pixels, nearest3d(s, t, ssd));
}

} // namespace

Correction::Correction(const VolumeGrid& g, const SolidTables& t) {
  if (t.projection3d->lanes > kCrossLanes || t.projection2d->lanes > kPlaneLanes || t.projection2d->dims != kSolid2dDims)
    throw std::logic_error("solid correction: projections of other neighbourhoods");
  const CrossLayout l = layoutFor(g);
  for (int i = 0; i < kSolidCrossVoxels; ++i) cross[i] = l.linear[i] * 4;
  for (int e = 0; e < 2; ++e)
    for (int k = 0; k < 25; ++k) planes[e][k] = cross[l.plane[e][k]];
  contrastGain16 = t.contrastGain16;
  bases.w = uint32_t(t.exemplarWidth);
  bases.h = uint32_t(t.exemplarHeight);
  for (int e = 0; e < 3; ++e)
    for (int j = -1; j <= 1; ++j)
      for (int i = -1; i <= 1; ++i) {
        const int n = e * 9 + (j + 1) * 3 + i + 1;
        bases.taps[n] = int32_t(l.linear[l.plane[e][(j + 2) * 5 + i + 2]] * 3 + e);
        bases.du[n] = uint32_t(floorMod(-int64_t(i) * t.spacing, t.exemplarWidth));
        bases.dv[n] = uint32_t(floorMod(-int64_t(j) * t.spacing, t.exemplarHeight));
      }
}

void solidDilateKernel(int8_t* last, const VolumeGrid& g, int interleave, int step) {
  // The 61-voxel cross is three 5x5 planes through the voxel: (x, y), (z, x) and (y, z). Per row
  // of active voxels, its activity widened by 2 along x raises the 5 rows of the (x, y) plane and
  // the 4 other rows of the (z, x) plane; the activity itself raises the 16 rows of the (y, z)
  // plane off the axes. Raising to step-1 < step never changes which voxels are active.
  const auto target = int8_t(step - 1);
  const int nx = g.nx;
  std::vector<uint8_t> active(static_cast<size_t>(nx)), widened(static_cast<size_t>(nx));
  auto raise = [&](int y, int z, const uint8_t* mask) {
    int8_t* row = last + (size_t(z) * size_t(g.ny) + size_t(y)) * size_t(nx);
    for (int x = 0; x < nx; ++x) row[x] = std::max(row[x], mask[x] ? target : std::numeric_limits<int8_t>::min());
  };
  for (int r = 0; r < g.rows(); ++r) {
    int y, z, x0;
    if (!classRow(g, interleave, step, r, y, z, x0)) continue;
    if (y < 2 || z < 2 || y >= g.ny - 2 || z >= g.nz - 2) continue;
    const int8_t* row = last + size_t(r) * size_t(nx);
    std::fill(active.begin(), active.end(), uint8_t(0));
    bool any = false;
    for (int x = x0; x < nx - 2; x += interleave)
      if (x >= 2 && row[x] >= step) active[size_t(x)] = 1, any = true;
    if (!any) continue;
    for (int x = 0; x < nx; ++x) {
      uint8_t w = 0;
      for (int d = std::max(0, x - 2); d <= std::min(nx - 1, x + 2); ++d) w |= active[size_t(d)];
      widened[size_t(x)] = w;
    }
    for (int d = -2; d <= 2; ++d) raise(y + d, z, widened.data());
    for (int d : {-2, -1, 1, 2}) raise(y, z + d, widened.data());
    for (int dz : {-2, -1, 1, 2})
      for (int dy : {-2, -1, 1, 2}) raise(y + dy, z + dz, active.data());
  }
}

void solidInitKernel(uint32_t* out, const int8_t* last, const VolumeGrid& g, const SolidTables& t, const SolidInit& init,
                     int rowBegin, int rowEnd) {
  for (int r = rowBegin; r < rowEnd; ++r) {
    const int y = r % g.ny, z = r / g.ny;
    for (int x = 0; x < g.nx; ++x) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (last[v] < 0) continue;
      const int64_t q[3] = {g.x0 + x, g.y0 + y, g.z0 + z};
      int64_t disp[3] = {0, 0, 0};  // 1/256 voxel
      if (init.jitter256 > 0) warp(q, init.seed, init.jitter256, disp);
      int64_t p[3], offset[3] = {0, 0, 0};
      for (int a = 0; a < 3; ++a) p[a] = q[a] + ((disp[a] + 128) >> 8);
      if (init.offsetCells > 0) cellOffset(p, init.seed, init.offsetCells, t, offset);
      slabTriple(p, offset, t, out + v * 3);
    }
  }
}

void solidUpsampleKernel(const uint32_t* parent, const VolumeGrid& pg, uint32_t* out, const int8_t* last,
                         const VolumeGrid& g, int spacing, int w, int h, int rowBegin, int rowEnd) {
  for (int r = rowBegin; r < rowEnd; ++r) {
    const int y = r % g.ny, z = r / g.ny;
    for (int x = 0; x < g.nx; ++x) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (last[v] < 0) continue;
      const int64_t q[3] = {g.x0 + x, g.y0 + y, g.z0 + z};
      const size_t pv = (size_t(floorShift(q[2], 1) - pg.z0) * size_t(pg.ny) + size_t(floorShift(q[1], 1) - pg.y0)) *
                            size_t(pg.nx) +
                        size_t(floorShift(q[0], 1) - pg.x0);
      for (int e = 0; e < 3; ++e) {
        const uint32_t s = parent[pv * 3 + size_t(e)];
        out[v * 3 + size_t(e)] = wrapCoord(int64_t(coordU(s)) + spacing * (q[kAxisU[e]] & 1),
                                           int64_t(coordV(s)) + spacing * (q[kAxisV[e]] & 1), w, h);
      }
    }
  }
}

SolidKernelProjection prepareSolidProjection(const int32_t* mean, const int16_t* basis, int inputs, int dims,
                                           int32_t divisor) {
  if (dims < 1 || dims > SolidKernelProjection::kLanes)
    throw std::invalid_argument("prepareSolidProjection: 1 to 16 dimensions");
  constexpr int kChunk = SolidKernelProjection::kChunk;
  SolidKernelProjection p;
  p.dims = dims;
  p.rows = (dims + 3) / 4 * 4;
  p.lanes = (inputs + kChunk - 1) / kChunk * kChunk;
  p.shift = std::countr_zero(uint32_t(divisor));
  p.weights.assign(size_t(p.lanes) * size_t(p.rows), 0);
  for (int d = 0; d < dims; ++d) {
    int64_t centre = 0;
    for (int j = 0; j < inputs; ++j) {
      const int16_t b = basis[size_t(d) * size_t(inputs) + size_t(j)];
      p.weights[(size_t(j / kChunk) * size_t(p.rows) + size_t(d)) * kChunk + size_t(j % kChunk)] = b;
      centre += int64_t(b) * mean[j];
    }
    p.offset[d] = int32_t((divisor >> 1) - centre);
  }
  return p;
}

void solidLimitSimd(SolidSimd limit) { gSimd.store(limit, std::memory_order_relaxed); }

void solidColorKernel(const uint32_t* triples, int16_t* colors, const int8_t* last, int minLast, const VolumeGrid& g,
                      const SolidTables& t, int rowBegin, int rowEnd) {
  for (size_t v = size_t(rowBegin) * size_t(g.nx); v < size_t(rowEnd) * size_t(g.nx); ++v)
    if (last[v] >= minLast) colorOf(t, triples + v * 3, colors + v * 4);
}

void solidCorrectKernel(const uint32_t* in, const int16_t* inColors, uint32_t* out, int16_t* outColors,
                        const int8_t* last, const VolumeGrid& g, const SolidTables& t, int interleave, int step,
                        int rowBegin, int rowEnd) {
  const SolidSimd simd = gSimd.load(std::memory_order_relaxed);
  if (solidCorrectX86(in, inColors, out, outColors, last, g, t, interleave, step, rowBegin, rowEnd, simd)) return;
  const Correction c(g, t);
  Neighborhood n;
  forEachCorrected(last, g, interleave, step, rowBegin, rowEnd, [&](size_t v) {
    VoxelSearch s{};
    s.voxel = v;
    correctVoxel(s, in, inColors, c, t, n);
    writeTriple(s, t, out, outColors);
  });
}

void solidCommitKernel(const uint32_t* from, const int16_t* fromColors, uint32_t* to, int16_t* toColors,
                       const int8_t* last, const VolumeGrid& g, int interleave, int step, int rowBegin, int rowEnd) {
  forEachCorrected(last, g, interleave, step, rowBegin, rowEnd, [&](size_t v) {
    for (int e = 0; e < 3; ++e) to[v * 3 + size_t(e)] = from[v * 3 + size_t(e)];
    std::memcpy(toColors + v * 4, fromColors + v * 4, 8);
  });
}

} // namespace texfab::synthesis::cpu
