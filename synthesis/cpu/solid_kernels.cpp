// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §4.3 (candidate slab), §5.1 (initialization, jitter, upsampling, correction with the
//           two-step search), §5.2 (dependency masks).
#include "synthesis/cpu/solid_kernels.h"

#include "synthesis/coord_map.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/hash.h"
#include "synthesis/solid_analysis.h"

#include <array>
#include <atomic>
#include <bit>
#include <climits>
#include <cstring>
#include <stdexcept>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace texfab::synthesis::cpu {

namespace {

constexpr int kAxisU[3] = {1, 2, 0};  // as in solid_analysis.h: E_x (y, z), E_y (z, x), E_z (x, y)
constexpr int kAxisV[3] = {2, 0, 1};
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

// Projections of gathered int16 inputs (pairs), see SolidPairProjection. Integer arithmetic only:
// every variant below returns the same bytes.
inline void finishProjection(const int32_t* acc, const SolidPairProjection& p, int8_t* out) {
  for (int d = 0; d < p.dims; ++d) {
    const int32_t q = (acc[d] + p.offset[d]) >> p.shift;  // round half up, as SolidProjection
    out[d] = int8_t(q < -127 ? -127 : q > 127 ? 127 : q);
  }
}

void projectPortable(const int16_t* x, const SolidPairProjection& p, int8_t* out) {
  int32_t acc[SolidPairProjection::kLanes] = {};
  const int16_t* w = p.weights.data();
  for (int i = 0; i < p.pairs; ++i, w += 2 * SolidPairProjection::kLanes) {
    const int32_t a = x[2 * i], b = x[2 * i + 1];
    for (int d = 0; d < p.dims; ++d) acc[d] += int32_t(w[2 * d]) * a + int32_t(w[2 * d + 1]) * b;
  }
  finishProjection(acc, p, out);
}

#if defined(__x86_64__) || defined(__i386__)
#define TEXFAB_SOLID_X86 1
// SSE2 (every x86-64): 4 dimensions per register.
template <int G> void projectSseG(const int16_t* x, const SolidPairProjection& p, int8_t* out) {
  __m128i acc[G];
  for (int g = 0; g < G; ++g) acc[g] = _mm_setzero_si128();
  const int16_t* w = p.weights.data();
  for (int i = 0; i < p.pairs; ++i, w += 2 * SolidPairProjection::kLanes) {
    int32_t pair;
    std::memcpy(&pair, x + 2 * i, 4);
    const __m128i xb = _mm_set1_epi32(pair);
    for (int g = 0; g < G; ++g)
      acc[g] = _mm_add_epi32(acc[g], _mm_madd_epi16(xb, _mm_loadu_si128(reinterpret_cast<const __m128i*>(w + 8 * g))));
  }
  alignas(16) int32_t a[SolidPairProjection::kLanes];
  for (int g = 0; g < G; ++g) _mm_store_si128(reinterpret_cast<__m128i*>(a + 4 * g), acc[g]);
  finishProjection(a, p, out);
}
void projectSse(const int16_t* x, const SolidPairProjection& p, int8_t* out) {
  switch ((p.dims + 3) / 4) {
  case 1: return projectSseG<1>(x, p, out);
  case 2: return projectSseG<2>(x, p, out);
  case 3: return projectSseG<3>(x, p, out);
  default: return projectSseG<4>(x, p, out);
  }
}
// AVX2: 8 dimensions per register.
template <int G> __attribute__((target("avx2"))) void projectAvx2G(const int16_t* x, const SolidPairProjection& p, int8_t* out) {
  __m256i acc[G];
  for (int g = 0; g < G; ++g) acc[g] = _mm256_setzero_si256();
  const int16_t* w = p.weights.data();
  for (int i = 0; i < p.pairs; ++i, w += 2 * SolidPairProjection::kLanes) {
    int32_t pair;
    std::memcpy(&pair, x + 2 * i, 4);
    const __m256i xb = _mm256_set1_epi32(pair);
    for (int g = 0; g < G; ++g)
      acc[g] = _mm256_add_epi32(acc[g],
                                _mm256_madd_epi16(xb, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(w + 16 * g))));
  }
  alignas(32) int32_t a[SolidPairProjection::kLanes];
  for (int g = 0; g < G; ++g) _mm256_store_si256(reinterpret_cast<__m256i*>(a + 8 * g), acc[g]);
  finishProjection(a, p, out);
}
__attribute__((target("avx2"))) void projectAvx2(const int16_t* x, const SolidPairProjection& p, int8_t* out) {
  if (p.dims <= 8) projectAvx2G<1>(x, p, out);
  else projectAvx2G<2>(x, p, out);
}
#endif

using ProjectFn = void (*)(const int16_t*, const SolidPairProjection&, int8_t*);

std::atomic<bool> gAllowSimd{true};

ProjectFn projectFor() {
#ifdef TEXFAB_SOLID_X86
  if (!gAllowSimd.load(std::memory_order_relaxed)) return projectPortable;
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2 ? projectAvx2 : projectSse;
#else
  return projectPortable;
#endif
}

inline void colorOf(const SolidTables& t, const uint32_t* s, int16_t* out) {
  int32_t c[3] = {0, 0, 0};
  for (int e = 0; e < 3; ++e) {
    const uint8_t* p = t.colors[e] + (size_t(coordV(s[e])) * size_t(t.exemplarWidth) + coordU(s[e])) * 3;
    for (int ch = 0; ch < 3; ++ch) c[ch] += 2 * p[ch];
  }
  for (int ch = 0; ch < 3; ++ch) out[ch] = int16_t(c[ch]);
  out[3] = 0;
}

template <int N> inline int32_t ssdN(const int8_t* a, const int8_t* b) {
  int32_t s = 0;
  for (int i = 0; i < N; ++i) {
    const int32_t d = int32_t(a[i]) - int32_t(b[i]);
    s += d * d;
  }
  return s;
}

#if defined(__SSE4_1__)
// SSD of 8 int8 against a target already widened to int16.
inline int32_t ssd8(__m128i target, const int8_t* b) {
  int64_t raw;
  std::memcpy(&raw, b, 8);
  const __m128i d = _mm_sub_epi16(_mm_cvtepi8_epi16(_mm_cvtsi64_si128(raw)), target);
  __m128i m = _mm_madd_epi16(d, d);
  m = _mm_add_epi32(m, _mm_shuffle_epi32(m, _MM_SHUFFLE(1, 0, 3, 2)));
  m = _mm_add_epi32(m, _mm_shuffle_epi32(m, _MM_SHUFFLE(2, 3, 0, 1)));
  return _mm_cvtsi128_si32(m);
}
inline __m128i widen8(const int8_t* a) {
  int64_t raw;
  std::memcpy(&raw, a, 8);
  return _mm_cvtepi8_epi16(_mm_cvtsi64_si128(raw));
}
#endif

inline int32_t ssd(const int8_t* a, const int8_t* b, int n) {
#if defined(__SSE4_1__)
  if (n >= 8) {
    int32_t s = ssd8(widen8(a), b);
    for (int i = 8; i < n; ++i) {
      const int32_t d = int32_t(a[i]) - int32_t(b[i]);
      s += d * d;
    }
    return s;
  }
#endif
  if (n == 8) return ssdN<8>(a, b);
  if (n == 12) return ssdN<12>(a, b);
  int32_t s = 0;
  for (int i = 0; i < n; ++i) {
    const int32_t d = int32_t(a[i]) - int32_t(b[i]);
    s += d * d;
  }
  return s;
}

// The sub-pass class of step t and the row's first voxel of that class; false if the row has none.
// interleave 2: 8 classes (x, y, z parities); interleave 1: every voxel in every step.
inline bool classRow(const VolumeGrid& g, int interleave, int step, int row, int& y, int& z, int& firstX) {
  y = row % g.ny;
  z = row / g.ny;
  if (interleave == 1) {
    firstX = 0;
    return true;
  }
  const int cls = (step - 1) % 8;
  if (floorMod(g.y0 + y, 2) != ((cls >> 1) & 1) || floorMod(g.z0 + z, 2) != ((cls >> 2) & 1)) return false;
  firstX = int(floorMod((cls & 1) - g.x0, 2));
  return true;
}

} // namespace

void solidDilateKernel(int8_t* last, const VolumeGrid& g, int interleave, int step, int rowBegin, int rowEnd) {
  const CrossLayout l = layoutFor(g);
  const auto target = int8_t(step - 1);
  for (int r = rowBegin; r < rowEnd; ++r) {
    int y, z, x0;
    if (!classRow(g, interleave, step, r, y, z, x0)) continue;
    if (y < 2 || z < 2 || y >= g.ny - 2 || z >= g.nz - 2) continue;
    for (int x = x0; x < g.nx; x += interleave) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (std::atomic_ref<int8_t>(last[v]).load(std::memory_order_relaxed) < step) continue;
      if (x < 2 || x >= g.nx - 2) continue;
      for (int i = 0; i < kSolidCrossVoxels; ++i) {
        std::atomic_ref<int8_t> w(last[int64_t(v) + l.linear[i]]);
        if (w.load(std::memory_order_relaxed) < target) w.store(target, std::memory_order_relaxed);
      }
    }
  }
}

void solidInitKernel(uint32_t* out, const int8_t* last, const VolumeGrid& g, const SolidTables& t, uint32_t seed,
                     int64_t jitter256, int rowBegin, int rowEnd) {
  const int w = t.exemplarWidth, h = t.exemplarHeight;
  constexpr int kCells[2] = {4, 8};          // warp grids, voxels
  constexpr int64_t kAmplitude[2] = {384, 256};  // x jitter/256: stronger at the small scale (§5.1)
  for (int r = rowBegin; r < rowEnd; ++r) {
    const int y = r % g.ny, z = r / g.ny;
    for (int x = 0; x < g.nx; ++x) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (last[v] < 0) continue;
      const int64_t q[3] = {g.x0 + x, g.y0 + y, g.z0 + z};
      int64_t disp[3] = {0, 0, 0};  // 1/256 voxel
      if (jitter256 > 0)
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
      int64_t p[3];
      for (int a = 0; a < 3; ++a) p[a] = q[a] + ((disp[a] + 128) >> 8);
      // The slab: E_z pixel under (x, y), thickened along z by its best candidate's E_x and E_y
      // neighborhoods (E_x's v axis and E_y's u axis are z).
      const uint32_t pixel = wrapCoord(p[0] * t.spacing, p[1] * t.spacing, w, h);
      const int64_t dz = floorMod(p[2], kSlabThickness) - kSlabThickness / 2;
      const uint32_t* best = t.triples[2] + (size_t(coordV(pixel)) * size_t(w) + coordU(pixel)) * kSolidMaxCandidates * 3;
      uint32_t* o = out + v * 3;
      o[0] = wrapCoord(coordU(best[0]), int64_t(coordV(best[0])) + dz * t.spacing, w, h);
      o[1] = wrapCoord(int64_t(coordU(best[1])) + dz * t.spacing, coordV(best[1]), w, h);
      o[2] = pixel;
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

SolidPairProjection prepareSolidProjection(const int32_t* mean, const int16_t* basis, int inputs, int dims,
                                           int32_t divisor) {
  SolidPairProjection p;
  p.dims = dims;
  p.pairs = (inputs + 1) / 2;
  p.shift = std::countr_zero(uint32_t(divisor));
  p.weights.assign(size_t(p.pairs) * SolidPairProjection::kLanes * 2, 0);
  for (int d = 0; d < dims; ++d) {
    int64_t centre = 0;
    for (int j = 0; j < inputs; ++j) {
      const int16_t b = basis[size_t(d) * size_t(inputs) + size_t(j)];
      p.weights[(size_t(j / 2) * SolidPairProjection::kLanes + size_t(d)) * 2 + size_t(j & 1)] = b;
      centre += int64_t(b) * mean[j];
    }
    p.offset[d] = int32_t((divisor >> 1) - centre);
  }
  return p;
}

void solidAllowSimd(bool allow) { gAllowSimd.store(allow, std::memory_order_relaxed); }

void solidColorKernel(const uint32_t* triples, int16_t* colors, const int8_t* last, int minLast, const VolumeGrid& g,
                      const SolidTables& t, int rowBegin, int rowEnd) {
  for (size_t v = size_t(rowBegin) * size_t(g.nx); v < size_t(rowEnd) * size_t(g.nx); ++v)
    if (last[v] >= minLast) colorOf(t, triples + v * 3, colors + v * 4);
}

void solidCorrectKernel(const uint32_t* in, const int16_t* inColors, uint32_t* out, int16_t* outColors,
                        const int8_t* last, const VolumeGrid& g, const SolidTables& t, int interleave, int step,
                        int rowBegin, int rowEnd) {
  const CrossLayout l = layoutFor(g);
  const ProjectFn project = projectFor();
  const int w = t.exemplarWidth, h = t.exemplarHeight;
  for (int r = rowBegin; r < rowEnd; ++r) {
    int y, z, x0;
    if (!classRow(g, interleave, step, r, y, z, x0)) continue;
    for (int x = x0; x < g.nx; x += interleave) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (last[v] < step) continue;

      // The 2-D candidate pixels of the 3x3 plane neighbors (C(S[v + P d] - d), §5.1): found
      // first, so that their table lines are fetched while the projections run (a CPU-only hint).
      uint32_t bases[3][9];
      for (int e = 0; e < 3; ++e)
        for (int j = -1; j <= 1; ++j)
          for (int i = -1; i <= 1; ++i) {
            const uint32_t s = in[(int64_t(v) + l.linear[l.plane[e][(j + 2) * 5 + (i + 2)]]) * 3 + e];
            const uint32_t base = wrapCoord(int64_t(coordU(s)) - i * t.spacing, int64_t(coordV(s)) - j * t.spacing, w, h);
            bases[e][(j + 1) * 3 + (i + 1)] = base;
#if defined(__GNUC__)
            const size_t slot = (size_t(coordV(base)) * size_t(w) + coordU(base)) * size_t(t.k2dStride);
            __builtin_prefetch(t.candidateDescriptors2d[e] + slot * kSolid2dDims);
            __builtin_prefetch(t.candidates2d[e] + slot);
#endif
          }
      // The current 3-neighborhood (2 x the sum of each voxel's three exemplar colours, from the
      // colour buffer), in projection order: 61 voxels x 3 channels, then a zero; and the three
      // 5x5 planes. Each voxel's 4 int16 are copied whole; the next voxel overwrites the 4th.
      alignas(32) int16_t cross[kSolidCrossVoxels * 3 + 5];
      alignas(32) int16_t planes[3][25 * 3 + 5];
      for (int i = 0; i < kSolidCrossVoxels; ++i)
        std::memcpy(cross + 3 * i, inColors + (int64_t(v) + l.linear[i]) * 4, 8);
      // E_z's plane is the cross's first 25 voxels (layoutFor checks it); input 75 has weight 0.
      for (int e = 0; e < 2; ++e) {
        for (int k = 0; k < 25; ++k) std::memcpy(planes[e] + 3 * k, cross + 3 * l.plane[e][k], 6);
        planes[e][75] = 0;
      }
      int8_t target3d[SolidPairProjection::kLanes];
      project(cross, *t.pairs3d, target3d);

      // Step 1: the best 2-D candidate in each direction.
      uint32_t bestPixel[3];
      for (int e = 0; e < 3; ++e) {
        int8_t target2d[SolidPairProjection::kLanes];
        project(e == 2 ? cross : planes[e], *t.pairs2d, target2d);
#if defined(__SSE4_1__)
        const __m128i wideTarget = widen8(target2d);
#endif
        int32_t best = INT32_MAX;
        uint32_t bestC = 0;
        uint32_t seen[9];  // coherent neighbors often point at the same pixel: visit it once
        int seenCount = 0;
        for (int n = 0; n < 9; ++n) {
          const uint32_t base = bases[e][n];
          bool visited = false;
          for (int k = 0; k < seenCount && !visited; ++k) visited = seen[k] == base;
          if (visited) continue;
          seen[seenCount++] = base;
          const size_t slot = (size_t(coordV(base)) * size_t(w) + coordU(base)) * size_t(t.k2dStride);
          const uint32_t* cand = t.candidates2d[e] + slot;
          const int8_t* candDescriptors = t.candidateDescriptors2d[e] + slot * kSolid2dDims;
          for (int k = 0; k < t.k2d; ++k) {
            const uint32_t p = cand[k];
#if defined(__SSE4_1__)
            const int32_t d = ssd8(wideTarget, candDescriptors + size_t(k) * kSolid2dDims);
#else
            const int32_t d = ssdN<kSolid2dDims>(target2d, candDescriptors + size_t(k) * kSolid2dDims);
#endif
            if (d < best || (d == best && p < bestC)) {  // order-independent minimum of (d, p)
              best = d;
              bestC = p;
            }
          }
        }
        bestPixel[e] = bestC;
#if defined(__GNUC__)
        const size_t first = (size_t(coordV(bestC)) * size_t(w) + coordU(bestC)) * kSolidMaxCandidates;
        for (int k = 0; k < t.k3d * t.dims; k += 64) __builtin_prefetch(t.descriptors3d[e] + first * size_t(t.dims) + size_t(k));
        __builtin_prefetch(t.triples[e] + first * 3);
#endif
      }

      // Step 2: the best 3-D candidate of those three pixels.
      int32_t best = INT32_MAX;
      const uint32_t* bestTriple = nullptr;
      for (int e = 0; e < 3; ++e) {
        const size_t p = size_t(coordV(bestPixel[e])) * size_t(w) + coordU(bestPixel[e]);
        for (int k = 0; k < t.k3d; ++k) {
          const size_t slot = p * kSolidMaxCandidates + size_t(k);
          const int32_t d = ssd(target3d, t.descriptors3d[e] + slot * size_t(t.dims), t.dims);
          if (d < best) {
            best = d;
            bestTriple = t.triples[e] + slot * 3;
          }
        }
      }
      for (int e = 0; e < 3; ++e) out[v * 3 + size_t(e)] = bestTriple[e];
      colorOf(t, bestTriple, outColors + v * 4);
    }
  }
}

void solidCommitKernel(const uint32_t* from, const int16_t* fromColors, uint32_t* to, int16_t* toColors,
                       const int8_t* last, const VolumeGrid& g, int interleave, int step, int rowBegin, int rowEnd) {
  for (int r = rowBegin; r < rowEnd; ++r) {
    int y, z, x0;
    if (!classRow(g, interleave, step, r, y, z, x0)) continue;
    for (int x = x0; x < g.nx; x += interleave) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (last[v] < step) continue;
      for (int e = 0; e < 3; ++e) to[v * 3 + size_t(e)] = from[v * 3 + size_t(e)];
      std::memcpy(toColors + v * 4, fromColors + v * 4, 8);
    }
  }
}

} // namespace texfab::synthesis::cpu
