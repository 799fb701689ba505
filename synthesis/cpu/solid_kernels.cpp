// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §4.3 (candidate slab), §5.1 (initialization, jitter, upsampling, correction with the
//           two-step search), §5.2 (dependency masks).
#include "synthesis/cpu/solid_kernels.h"

#include "synthesis/coord_map.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/hash.h"
#include "synthesis/solid_analysis.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

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

// Projections of gathered colour records, see SolidKernelProjection. Integer arithmetic only: both
// variants return the same bytes (a sum of int32 products does not depend on its order).
inline int8_t clampProjected(int32_t sum, int32_t offset, int shift) {
  const int32_t q = (sum + offset) >> shift;  // round half up, as SolidProjection
  return int8_t(q < -127 ? -127 : q > 127 ? 127 : q);
}

inline void finishProjection(const int32_t* sum, const SolidKernelProjection& p, int8_t* out) {
  for (int d = 0; d < SolidKernelProjection::kLanes; ++d) out[d] = clampProjected(sum[d], p.offset[d], p.shift);
}

void projectPortable(const int16_t* x, const SolidKernelProjection& p, int8_t* out) {
  constexpr int kChunk = SolidKernelProjection::kChunk;
  int32_t sum[SolidKernelProjection::kLanes] = {};
  const int16_t* w = p.weights.data();
  for (int c = 0; c < p.lanes; c += kChunk)
    for (int d = 0; d < p.rows; ++d, w += kChunk)
      for (int i = 0; i < kChunk; ++i) sum[d] += int32_t(w[i]) * int32_t(x[c + i]);
  finishProjection(sum, p, out);
}

#if defined(__x86_64__) || defined(__i386__)
#define TEXFAB_SOLID_X86 1
// SIMD: one accumulator register per dimension, so each chunk of 16 input lanes is loaded once
// and multiplied by every dimension's weights (stored chunk by chunk, read in order).

// SSE2 (every x86-64): a chunk in two registers.
template <int Rows> void projectSseRows(const int16_t* x, const SolidKernelProjection& p, int8_t* out) {
  __m128i acc[Rows];
  for (int d = 0; d < Rows; ++d) acc[d] = _mm_setzero_si128();
  const int16_t* w = p.weights.data();
  for (int c = 0; c < p.lanes; c += SolidKernelProjection::kChunk) {
    const __m128i x0 = _mm_load_si128(reinterpret_cast<const __m128i*>(x + c));
    const __m128i x1 = _mm_load_si128(reinterpret_cast<const __m128i*>(x + c + 8));
    for (int d = 0; d < Rows; ++d, w += SolidKernelProjection::kChunk) {
      const __m128i m0 = _mm_madd_epi16(x0, _mm_loadu_si128(reinterpret_cast<const __m128i*>(w)));
      const __m128i m1 = _mm_madd_epi16(x1, _mm_loadu_si128(reinterpret_cast<const __m128i*>(w + 8)));
      acc[d] = _mm_add_epi32(acc[d], _mm_add_epi32(m0, m1));
    }
  }
  alignas(16) int32_t parts[Rows][4];
  int32_t sum[SolidKernelProjection::kLanes] = {};
  for (int d = 0; d < Rows; ++d) {
    _mm_store_si128(reinterpret_cast<__m128i*>(parts[d]), acc[d]);
    sum[d] = parts[d][0] + parts[d][1] + parts[d][2] + parts[d][3];
  }
  finishProjection(sum, p, out);
}

void projectSse(const int16_t* x, const SolidKernelProjection& p, int8_t* out) {
  switch (p.rows) {
  case 4: return projectSseRows<4>(x, p, out);
  case 8: return projectSseRows<8>(x, p, out);
  case 12: return projectSseRows<12>(x, p, out);
  default: return projectSseRows<16>(x, p, out);
  }
}

// AVX2: a chunk in one register. The horizontal sums of 4 accumulators:
__attribute__((target("avx2"))) inline __m128i sum4(const __m256i* a) {
  const __m256i h = _mm256_hadd_epi32(_mm256_hadd_epi32(a[0], a[1]), _mm256_hadd_epi32(a[2], a[3]));  // low | high halves
  return _mm_add_epi32(_mm256_castsi256_si128(h), _mm256_extracti128_si256(h, 1));
}

// The horizontal sums of `rows` accumulators (4 or 8), zero past them.
__attribute__((target("avx2"))) inline __m256i sum8(const __m256i* a, int rows) {
  const __m256i low = _mm256_zextsi128_si256(sum4(a));
  return rows > 4 ? _mm256_inserti128_si256(low, sum4(a + 4), 1) : low;
}

// (sum + offset) >> shift clamped to +-127, as 8 int8.
__attribute__((target("avx2"))) inline void finish8(__m256i sum, const int32_t* offset, __m128i shift, int8_t* out) {
  __m256i q = _mm256_add_epi32(sum, _mm256_load_si256(reinterpret_cast<const __m256i*>(offset)));
  q = _mm256_sra_epi32(q, shift);
  q = _mm256_max_epi32(_mm256_min_epi32(q, _mm256_set1_epi32(127)), _mm256_set1_epi32(-127));
  const __m256i b = _mm256_packs_epi16(_mm256_packs_epi32(q, q), q);  // per half: q0-q3 as int8 first
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out),
                   _mm_unpacklo_epi32(_mm256_castsi256_si128(b), _mm256_extracti128_si256(b, 1)));
}

template <int Rows>
__attribute__((target("avx2"))) inline void projectAvx2(const int16_t* x, const SolidKernelProjection& p, int8_t* out) {
  __m256i acc[Rows];
  for (int d = 0; d < Rows; ++d) acc[d] = _mm256_setzero_si256();
  const int16_t* w = p.weights.data();
  for (int c = 0; c < p.lanes; c += SolidKernelProjection::kChunk) {
    const __m256i xc = _mm256_load_si256(reinterpret_cast<const __m256i*>(x + c));
    for (int d = 0; d < Rows; ++d, w += SolidKernelProjection::kChunk)
      acc[d] = _mm256_add_epi32(acc[d], _mm256_madd_epi16(xc, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(w))));
  }
  const __m128i shift = _mm_cvtsi32_si128(p.shift);
  finish8(sum8(acc, std::min(Rows, 8)), p.offset, shift, out);
  if constexpr (Rows > 8) finish8(sum8(acc + 8, Rows - 8), p.offset + 8, shift, out + 8);
  else std::memset(out + 8, 0, 8);
}
#endif

using ProjectFn = void (*)(const int16_t* x, const SolidKernelProjection& p, int8_t* out);

std::atomic<bool> gAllowSimd{true};

// A voxel's colour as the search sees it: the sum of its three exemplar colours, scaled (6x the
// mean) or through the level's colour transfer.
inline void colorOf(const SolidTables& t, const uint32_t* s, int16_t* out) {
  int32_t c[3] = {0, 0, 0};
  for (int e = 0; e < 3; ++e) {
    const uint8_t* p = t.colors[e] + (size_t(coordV(s[e])) * size_t(t.exemplarWidth) + coordU(s[e])) * 3;
    for (int ch = 0; ch < 3; ++ch) c[ch] += p[ch];
  }
  for (int ch = 0; ch < 3; ++ch)
    out[ch] = t.searchColors ? t.searchColors[ch * kSolidColorSums + c[ch]] : int16_t(2 * c[ch]);
  out[3] = 0;
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

// ---- Correction: the two-step search of §5.1, over batches of voxels ----
//
// A voxel's search reads table lines scattered over megabytes (the 2-D candidates of its 27
// pixels, the 3-D candidates of 3, its new triple), far beyond L2. The kernel therefore searches
// a batch of voxels phase by phase: 1. step 1's pixels; 2. the targets (projections); 3. step 1;
// 4. step 2; 5. the new triples. A phase requests, for the whole batch, the lines that a later
// phase reads (prefetches), so that their misses overlap. Phases 1-4 come in variants that give
// the same bytes: portable, and AVX2.
//
// Both steps minimize a key (SSD << 32 | tie-break) over their candidates. SSDs of int8
// descriptors are below 2^31 (at most 16 * 254^2), so keys order as the pairs (SSD, tie-break),
// as unsigned or as signed 64-bit integers. Step 1's tie-break is the candidate's packed
// coordinate; step 2's is its rank e * kSolidMaxCandidates + k, so that the earliest of equally
// near candidates wins. Either way a candidate seen twice cannot change the minimum: step 1 need
// not skip pixels reached from two neighbours, and SIMD groups are padded with repeats.

constexpr int kBatch = 32;

// One voxel's search, carried from phase to phase.
struct VoxelSearch {
  size_t voxel;
  uint32_t bases[3][9];  // step 1's pixels (v * w + u) per direction, see BaseLayout
  alignas(16) int8_t target3d[SolidKernelProjection::kLanes];
  alignas(16) int8_t target2d[3][SolidKernelProjection::kLanes];
  uint32_t pixels[3];    // step 1's winners (v * w + u)
  const uint32_t* triple;  // step 2's winner
};

// Where step 1's 27 pixels come from: C(S[v + P d] - d) for the 3x3 plane neighbours d of each
// direction e (§5.1), as the offset of S_e[v + P d] in `in` from the voxel's first coordinate and
// -d h_l mod w (resp. h), so that each wraps with one compare (coordinates are below w and h).
struct BaseLayout {
  int32_t taps[27];
  uint32_t du[27], dv[27];
  uint32_t w = 0, h = 0;
};

// Projection inputs: colour records' 3 channels side by side, in projection order (a record is
// copied whole, 4 int16, the next one overwriting the 4th), then padding to whole chunks (zero
// weights; zero-initialized so that it stays finite).
constexpr int kCrossLanes = (3 * kSolidCrossVoxels + 1 + 15) / 16 * 16;
constexpr int kPlaneLanes = (3 * 25 + 1 + 15) / 16 * 16;
struct Neighborhood {
  alignas(32) int16_t cross[kCrossLanes] = {};      // the 3-neighborhood; E_z's plane is its first 25 voxels
  alignas(32) int16_t planes[2][kPlaneLanes] = {};  // E_x's and E_y's planes
};

// What a correction call derives from the grid and the tables, once.
struct Correction {
  int64_t cross[kSolidCrossVoxels];  // offsets of the 3-neighborhood's colour records (int16)
  int64_t planes[2][25];             // the same for E_x's and E_y's planes
  BaseLayout bases;

  Correction(const VolumeGrid& g, const SolidTables& t) {
    if (t.projection3d->lanes > kCrossLanes || t.projection2d->lanes > kPlaneLanes || t.projection2d->dims != kSolid2dDims)
      throw std::logic_error("solid correction: projections of other neighbourhoods");
    const CrossLayout l = layoutFor(g);
    for (int i = 0; i < kSolidCrossVoxels; ++i) cross[i] = l.linear[i] * 4;
    for (int e = 0; e < 2; ++e)
      for (int k = 0; k < 25; ++k) planes[e][k] = cross[l.plane[e][k]];
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
};

// A hint (CPU only): the lines of [p, p + bytes) are read soon; bytes <= 64, two lines at most.
// Always inlined, as the helpers below that use it: GCC deems a function that only prefetches
// free of effects and drops its calls.
[[gnu::always_inline]] inline void prefetchShort(const void* p, size_t bytes) {
  __builtin_prefetch(p);
  __builtin_prefetch(static_cast<const char*>(p) + bytes - 1);
}

// The same for any span.
[[gnu::always_inline]] inline void prefetch(const void* p, size_t bytes) {
  const char* c = static_cast<const char*>(p);
  for (; bytes > 64; bytes -= 64, c += 64) __builtin_prefetch(c);
  prefetchShort(c, bytes);
}

// Phase 1, both variants: a request for the 2-D candidates of step 1's pixels, their first lines
// only (a pixel's k2d candidates seldom span two; measured, more requests cost more than they save).
[[gnu::always_inline]] inline void requestCandidates2d(const VoxelSearch& s, const SolidTables& t) {
  for (int e = 0; e < 3; ++e)
    for (int n = 0; n < 9; ++n) {
      const size_t slot = size_t(s.bases[e][n]) * size_t(t.k2dStride);
      __builtin_prefetch(t.candidateDescriptors2d[e] + slot * kSolid2dDims);
      __builtin_prefetch(t.candidates2d[e] + slot);
    }
}

// Phase 2, both variants: the current 3-neighborhood (2 x the sum of each voxel's three exemplar
// colours, the colour buffer's records) and its E_x and E_y planes.
inline void gatherNeighborhood(const VoxelSearch& s, const int16_t* inColors, const Correction& c, Neighborhood& n) {
  const int16_t* centre = inColors + s.voxel * 4;
#pragma GCC unroll 61
  for (int i = 0; i < kSolidCrossVoxels; ++i) std::memcpy(n.cross + 3 * i, centre + c.cross[i], 8);
  for (int e = 0; e < 2; ++e)
#pragma GCC unroll 25
    for (int k = 0; k < 25; ++k) std::memcpy(n.planes[e] + 3 * k, centre + c.planes[e][k], 8);
}

// Phase 3, both variants: step 1's winner in direction e, and a request for its 3-D candidates'
// descriptors.
[[gnu::always_inline]] inline void keepStep1(VoxelSearch& s, int e, uint32_t best, const SolidTables& t) {
  const uint32_t pixel = coordV(best) * uint32_t(t.exemplarWidth) + coordU(best);
  s.pixels[e] = pixel;
  prefetch(t.descriptors3d[e] + size_t(pixel) * kSolidMaxCandidates * size_t(t.dims), size_t(t.k3d) * size_t(t.dims));
}

// Phase 4, both variants: step 2's winner, and a request for it.
[[gnu::always_inline]] inline void keepStep2(VoxelSearch& s, const uint32_t* triple) {
  s.triple = triple;
  prefetchShort(triple, 3 * sizeof(uint32_t));
}

// Phase 5: the voxel's new triple and its colour.
inline void writeTriple(const VoxelSearch& s, const SolidTables& t, uint32_t* out, int16_t* outColors) {
  for (int e = 0; e < 3; ++e) out[s.voxel * 3 + size_t(e)] = s.triple[e];
  colorOf(t, s.triple, outColors + s.voxel * 4);
}

// Step 2's winner, from the tie-break of its key.
inline const uint32_t* tripleOf(const SolidTables& t, const uint32_t* pixels, uint32_t rank) {
  const uint32_t e = rank / kSolidMaxCandidates, k = rank % kSolidMaxCandidates;
  return t.triples[e] + (size_t(pixels[e]) * kSolidMaxCandidates + k) * 3;
}

// The phases of one variant, each over a batch.
struct Variant {
  void (*findBases)(VoxelSearch* batch, int count, const uint32_t* in, const Correction& c, const SolidTables& t);
  void (*projectTargets)(VoxelSearch* batch, int count, const int16_t* inColors, const Correction& c,
                         const SolidTables& t, Neighborhood& n);
  void (*searchStep1)(VoxelSearch* batch, int count, const SolidTables& t);
  void (*searchStep2)(VoxelSearch* batch, int count, const SolidTables& t);
};

// -- Portable variant --

inline uint64_t searchKey(int32_t ssd, uint32_t tie) { return uint64_t(uint32_t(ssd)) << 32 | tie; }

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
  int32_t s = 0;
  int i = 0;
#if defined(__SSE4_1__)
  if (n >= 8) {
    s = ssd8(widen8(a), b);
    i = 8;
  }
#endif
  for (; i < n; ++i) {
    const int32_t d = int32_t(a[i]) - int32_t(b[i]);
    s += d * d;
  }
  return s;
}

void findBasesPortable(VoxelSearch* batch, int count, const uint32_t* in, const Correction& c, const SolidTables& t) {
  const BaseLayout& b = c.bases;
  for (int i = 0; i < count; ++i) {
    const uint32_t* at = in + batch[i].voxel * 3;
    uint32_t* bases = &batch[i].bases[0][0];
    for (int n = 0; n < 27; ++n) {
      const uint32_t q = at[b.taps[n]];
      const uint32_t u = coordU(q) + b.du[n], v = coordV(q) + b.dv[n];
      bases[n] = (v >= b.h ? v - b.h : v) * b.w + (u >= b.w ? u - b.w : u);
    }
    requestCandidates2d(batch[i], t);
  }
}

template <ProjectFn Project>
void projectTargets(VoxelSearch* batch, int count, const int16_t* inColors, const Correction& c, const SolidTables& t,
                    Neighborhood& n) {
  for (int i = 0; i < count; ++i) {
    VoxelSearch& s = batch[i];
    gatherNeighborhood(s, inColors, c, n);
    Project(n.cross, *t.projection3d, s.target3d);
    Project(n.planes[0], *t.projection2d, s.target2d[0]);
    Project(n.planes[1], *t.projection2d, s.target2d[1]);
    Project(n.cross, *t.projection2d, s.target2d[2]);  // layoutFor checks that E_z's plane leads
  }
}

// Step 1 in direction e: the packed coordinate of the best of the k2d candidates of each pixel.
uint32_t nearest2dPortable(const int8_t* target, const uint32_t* pixels, const SolidTables& t, int e) {
  uint64_t best = UINT64_MAX;
  for (int n = 0; n < 9; ++n) {
    const size_t slot = size_t(pixels[n]) * size_t(t.k2dStride);
    const uint32_t* cand = t.candidates2d[e] + slot;
    const int8_t* descriptors = t.candidateDescriptors2d[e] + slot * kSolid2dDims;
    for (int k = 0; k < t.k2d; ++k)
      best = std::min(best, searchKey(ssd(target, descriptors + size_t(k) * kSolid2dDims, kSolid2dDims), cand[k]));
  }
  return uint32_t(best);
}

void searchStep1Portable(VoxelSearch* batch, int count, const SolidTables& t) {
  for (int i = 0; i < count; ++i)
    for (int e = 0; e < 3; ++e) keepStep1(batch[i], e, nearest2dPortable(batch[i].target2d[e], batch[i].bases[e], t, e), t);
}

// Step 2: the best of the k3d 3-D candidates of the three pixels.
void searchStep2Portable(VoxelSearch* batch, int count, const SolidTables& t) {
  for (int i = 0; i < count; ++i) {
    VoxelSearch& s = batch[i];
    uint64_t best = UINT64_MAX;
    for (int e = 0; e < 3; ++e) {
      const int8_t* descriptors = t.descriptors3d[e] + size_t(s.pixels[e]) * kSolidMaxCandidates * size_t(t.dims);
      for (int k = 0; k < t.k3d; ++k)
        best = std::min(best, searchKey(ssd(s.target3d, descriptors + size_t(k) * size_t(t.dims), t.dims),
                                        uint32_t(e * kSolidMaxCandidates + k)));
    }
    keepStep2(s, tripleOf(t, s.pixels, uint32_t(best)));
  }
}

#ifdef TEXFAB_SOLID_X86
// -- AVX2 variant --
//
// Step 1's pixels 8 per gather. The searches compare 8 keys per group of registers, as int64.
// Candidates are staged first (descriptors as loaded, 16 bytes per entry, and their
// tie-breaks), then the groups run without branches.

__attribute__((target("avx2"))) void findBasesAvx2(VoxelSearch* batch, int count, const uint32_t* in,
                                                  const Correction& c, const SolidTables& t) {
  const BaseLayout& b = c.bases;
  const __m256i w = _mm256_set1_epi32(int(b.w)), h = _mm256_set1_epi32(int(b.h));
  const __m256i wMax = _mm256_set1_epi32(int(b.w) - 1), hMax = _mm256_set1_epi32(int(b.h) - 1);
  for (int i = 0; i < count; ++i) {
    const uint32_t* at = in + batch[i].voxel * 3;
    uint32_t* bases = &batch[i].bases[0][0];
    for (const int first : {0, 8, 16, 19}) {  // 27 = 3 x 8 + 3: the last group overlaps the one before
      const __m256i q = _mm256_i32gather_epi32(reinterpret_cast<const int*>(at),
                                               _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b.taps + first)), 4);
      __m256i u = _mm256_add_epi32(_mm256_and_si256(q, _mm256_set1_epi32(0xffff)),
                                   _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b.du + first)));
      __m256i v = _mm256_add_epi32(_mm256_srli_epi32(q, 16),
                                   _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b.dv + first)));
      u = _mm256_sub_epi32(u, _mm256_and_si256(_mm256_cmpgt_epi32(u, wMax), w));  // values < 2^17: signed compares
      v = _mm256_sub_epi32(v, _mm256_and_si256(_mm256_cmpgt_epi32(v, hMax), h));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(bases + first), _mm256_add_epi32(_mm256_mullo_epi32(v, w), u));
    }
    requestCandidates2d(batch[i], t);
  }
}

// The projections with Rows3d accumulators for the 3-D one (its dimensions rounded up to 4) and 8
// for the 2-D ones.
template <int Rows3d>
__attribute__((target("avx2"))) void projectTargetsAvx2(VoxelSearch* batch, int count, const int16_t* inColors,
                                                       const Correction& c, const SolidTables& t, Neighborhood& n) {
  for (int i = 0; i < count; ++i) {
    VoxelSearch& s = batch[i];
    gatherNeighborhood(s, inColors, c, n);
    projectAvx2<Rows3d>(n.cross, *t.projection3d, s.target3d);
    projectAvx2<kSolid2dDims>(n.planes[0], *t.projection2d, s.target2d[0]);
    projectAvx2<kSolid2dDims>(n.planes[1], *t.projection2d, s.target2d[1]);
    projectAvx2<kSolid2dDims>(n.cross, *t.projection2d, s.target2d[2]);  // layoutFor checks that E_z's plane leads
  }
}

__attribute__((target("avx2"))) inline __m256i min64(__m256i a, __m256i b) {
  return _mm256_blendv_epi8(a, b, _mm256_cmpgt_epi64(a, b));
}

// The least of `best` and the keys of 8 SSDs, their tie-breaks in the same lane order.
__attribute__((target("avx2"))) inline __m256i minKey(__m256i best, __m256i ssd, __m256i ties) {
  return min64(best, min64(_mm256_unpacklo_epi32(ties, ssd), _mm256_unpackhi_epi32(ties, ssd)));
}

__attribute__((target("avx2"))) inline uint64_t horizontalMin64(__m256i a) {
  a = min64(a, _mm256_permute4x64_epi64(a, _MM_SHUFFLE(1, 0, 3, 2)));
  a = min64(a, _mm256_shuffle_epi32(a, _MM_SHUFFLE(1, 0, 3, 2)));
  return uint64_t(_mm256_extract_epi64(a, 0));
}

// Candidates staged for the groups: descriptors as loaded, 16 bytes per entry.
template <int Entries> struct Staged {
  __m128i descriptors[Entries];

  // Repeats the last descriptor up to a whole group; returns the padded count.
  int padDescriptors(int count, int group) {
    for (; count % group; ++count) descriptors[count] = descriptors[count - 1];
    return count;
  }
};

// 8-dim descriptors two at a time: an entry is a pair (A, B) of candidates, 16 int16 once widened;
// its tie-breaks are one word, A | B << 32, so that the 4 words of a group are read as written
// (a 32-byte read of 4 fresh stores would wait for them to retire).
struct Pairs : Staged<9 * 4 + 3> {  // step 1: 9 pixels x ceil(8 / 2) pairs, padded to a group of 4
  static constexpr int kGroup = 4;
  uint64_t ties[9 * 4 + 3];

  void stage(int i, const int8_t* a, const int8_t* b) {
    const __m128d d = _mm_loadh_pd(_mm_castsi128_pd(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(a))),
                                   reinterpret_cast<const double*>(b));
    descriptors[i] = _mm_castpd_si128(d);
  }
  int padTies(int count) {
    for (int i = count; i % kGroup; ++i) ties[i] = ties[count - 1];
    return (count + kGroup - 1) / kGroup * kGroup;
  }
  int pad(int count) {
    padTies(count);
    return padDescriptors(count, kGroup);
  }
};

inline uint64_t pairTie(uint32_t a, uint32_t b) { return a | uint64_t(b) << 32; }

// SSDs of 4 pairs, in the order of their tie-breaks: A0 B0 A1 B1 | A2 B2 A3 B3.
__attribute__((target("avx2"))) inline __m256i ssdPairs(__m256i target, const __m128i* pairs) {
  __m256i m[4];
  for (int i = 0; i < 4; ++i) {
    const __m256i d = _mm256_sub_epi16(_mm256_cvtepi8_epi16(pairs[i]), target);
    m[i] = _mm256_madd_epi16(d, d);  // A's 4 partial sums | B's
  }
  const __m256i s = _mm256_hadd_epi32(_mm256_hadd_epi32(m[0], m[1]), _mm256_hadd_epi32(m[2], m[3]));  // A0-A3 | B0-B3
  return _mm256_permutevar8x32_epi32(s, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7));
}

// The least key of `count` (padded) pairs against an 8-dim target.
__attribute__((target("avx2"))) inline uint64_t minPairKey(const Pairs& p, int count, const int8_t* target) {
  const __m256i wide =
      _mm256_broadcastsi128_si256(_mm_cvtepi8_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(target))));
  __m256i best = _mm256_set1_epi64x(INT64_MAX);
  for (int i = 0; i < count; i += Pairs::kGroup) {
    const __m256i ties = _mm256_set_epi64x(int64_t(p.ties[i + 3]), int64_t(p.ties[i + 2]), int64_t(p.ties[i + 1]),
                                           int64_t(p.ties[i]));
    best = minKey(best, ssdPairs(wide, p.descriptors + i), ties);
  }
  return horizontalMin64(best);
}

// Step 1 with P = ceil(k2d / 2) pairs per pixel; a lone last candidate (odd k2d) pairs with itself.
template <int P>
__attribute__((target("avx2"))) void searchStep1Avx2(VoxelSearch* batch, int count, const SolidTables& t) {
  const int last = t.k2d - 1;
  for (int i = 0; i < count; ++i)
    for (int e = 0; e < 3; ++e) {
      Pairs p;
      for (int n = 0; n < 9; ++n) {
        const size_t slot = size_t(batch[i].bases[e][n]) * size_t(t.k2dStride);
        const uint32_t* cand = t.candidates2d[e] + slot;
        const int8_t* descriptors = t.candidateDescriptors2d[e] + slot * kSolid2dDims;
        for (int j = 0; j < P; ++j) {
          const int a = 2 * j, b = std::min(a + 1, last);
          p.stage(n * P + j, descriptors + a * kSolid2dDims, descriptors + b * kSolid2dDims);
          p.ties[n * P + j] = pairTie(cand[a], cand[b]);
        }
      }
      keepStep1(batch[i], e, uint32_t(minPairKey(p, p.pad(9 * P), batch[i].target2d[e])), t);
    }
}

// Step 2 with 8 dimensions (the finest level): pairs, as step 1; the ranks are the same for every
// voxel.
__attribute__((target("avx2"))) void searchStep2Avx2Pairs(VoxelSearch* batch, int count, const SolidTables& t) {
  const int last = t.k3d - 1;
  Pairs p;
  int staged = 0;
  for (int e = 0; e < 3; ++e)
    for (int a = 0; a <= last; a += 2) {
      const uint32_t rank = uint32_t(e * kSolidMaxCandidates + a);
      p.ties[staged++] = pairTie(rank, a < last ? rank + 1 : rank);
    }
  const int padded = p.padTies(staged);
  for (int i = 0; i < count; ++i) {
    VoxelSearch& s = batch[i];
    for (int e = 0, n = 0; e < 3; ++e) {
      const int8_t* descriptors = t.descriptors3d[e] + size_t(s.pixels[e]) * kSolidMaxCandidates * kSolid2dDims;
      for (int a = 0; a <= last; a += 2, ++n)
        p.stage(n, descriptors + a * kSolid2dDims, descriptors + std::min(a + 1, last) * kSolid2dDims);
    }
    p.padDescriptors(staged, Pairs::kGroup);
    keepStep2(s, tripleOf(t, s.pixels, uint32_t(minPairKey(p, padded, s.target3d))));
  }
}

// Step 2 with 9 to 16 dimensions: one candidate per entry, widened to 16 int16, the lanes past
// dims masked.
struct Singles : Staged<3 * kSolidMaxCandidates + 7> {
  static constexpr int kGroup = 8;
  alignas(32) uint32_t ranks[3 * kSolidMaxCandidates + 7];
};

// A 3-D descriptor in the low bytes of a register. One near the end of its pixel's block (12 *
// dims bytes) is read from the 16 bytes before its end and shifted down (dims > 8: they lie in
// the block): nothing past the table is read.
__attribute__((target("avx2"))) inline __m128i loadDescriptor3d(const int8_t* d, int k, int dims) {
  if (k * dims + 16 <= kSolidMaxCandidates * dims) return _mm_loadu_si128(reinterpret_cast<const __m128i*>(d));
  static constexpr int8_t kShiftDown[32] = {0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11, 12, 13, 14, 15,
                                            -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
  const __m128i tail = _mm_loadu_si128(reinterpret_cast<const __m128i*>(d + dims - 16));
  return _mm_shuffle_epi8(tail, _mm_loadu_si128(reinterpret_cast<const __m128i*>(kShiftDown + 16 - dims)));
}

// SSDs of 8 candidates: c0-c3 | c4-c7.
__attribute__((target("avx2"))) inline __m256i ssdSingles(__m256i target, __m256i used, const __m128i* singles) {
  __m256i m[8];
  for (int i = 0; i < 8; ++i) {
    const __m256i d = _mm256_and_si256(_mm256_sub_epi16(_mm256_cvtepi8_epi16(singles[i]), target), used);
    m[i] = _mm256_madd_epi16(d, d);
  }
  const __m256i a = _mm256_hadd_epi32(_mm256_hadd_epi32(m[0], m[1]), _mm256_hadd_epi32(m[2], m[3]));  // c0-c3 halves
  const __m256i b = _mm256_hadd_epi32(_mm256_hadd_epi32(m[4], m[5]), _mm256_hadd_epi32(m[6], m[7]));  // c4-c7 halves
  return _mm256_add_epi32(_mm256_permute2x128_si256(a, b, 0x20), _mm256_permute2x128_si256(a, b, 0x31));
}

__attribute__((target("avx2"))) void searchStep2Avx2Singles(VoxelSearch* batch, int count, const SolidTables& t) {
  const int dims = t.dims;
  const __m256i used = _mm256_cmpgt_epi16(_mm256_set1_epi16(int16_t(dims)),
                                          _mm256_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
  Singles c;
  int staged = 0;
  for (int e = 0; e < 3; ++e)
    for (int k = 0; k < t.k3d; ++k) c.ranks[staged++] = uint32_t(e * kSolidMaxCandidates + k);
  int padded = staged;
  for (; padded % Singles::kGroup; ++padded) c.ranks[padded] = c.ranks[staged - 1];
  for (int i = 0; i < count; ++i) {
    VoxelSearch& s = batch[i];
    for (int e = 0, n = 0; e < 3; ++e) {
      const int8_t* descriptors = t.descriptors3d[e] + size_t(s.pixels[e]) * kSolidMaxCandidates * size_t(dims);
      for (int k = 0; k < t.k3d; ++k, ++n) c.descriptors[n] = loadDescriptor3d(descriptors + k * dims, k, dims);
    }
    c.padDescriptors(staged, Singles::kGroup);
    const __m256i wide = _mm256_cvtepi8_epi16(_mm_load_si128(reinterpret_cast<const __m128i*>(s.target3d)));
    __m256i best = _mm256_set1_epi64x(INT64_MAX);
    for (int j = 0; j < padded; j += Singles::kGroup)
      best = minKey(best, ssdSingles(wide, used, c.descriptors + j),
                    _mm256_load_si256(reinterpret_cast<const __m256i*>(c.ranks + j)));
    keepStep2(s, tripleOf(t, s.pixels, uint32_t(horizontalMin64(best))));
  }
}
#endif

// AVX2 where the CPU has it; else the portable phases, with SSE2 projections on x86.
Variant variantFor(const SolidTables& t) {
  const bool simd = gAllowSimd.load(std::memory_order_relaxed);
#ifdef TEXFAB_SOLID_X86
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (simd && avx2) {
    static constexpr decltype(Variant::searchStep1) kStep1[4] = {searchStep1Avx2<1>, searchStep1Avx2<2>,
                                                                 searchStep1Avx2<3>, searchStep1Avx2<4>};
    static constexpr decltype(Variant::projectTargets) kProject[4] = {projectTargetsAvx2<4>, projectTargetsAvx2<8>,
                                                                        projectTargetsAvx2<12>, projectTargetsAvx2<16>};
    return {findBasesAvx2, kProject[t.projection3d->rows / 4 - 1], kStep1[(t.k2d - 1) / 2],
            t.dims == kSolid2dDims ? searchStep2Avx2Pairs
            : t.dims > kSolid2dDims ? searchStep2Avx2Singles
                                    : searchStep2Portable};
  }
  if (simd) return {findBasesPortable, projectTargets<projectSse>, searchStep1Portable, searchStep2Portable};
#else
  (void)t, (void)simd;
#endif
  return {findBasesPortable, projectTargets<projectPortable>, searchStep1Portable, searchStep2Portable};
}

} // namespace

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

void solidAllowSimd(bool allow) { gAllowSimd.store(allow, std::memory_order_relaxed); }

void solidColorKernel(const uint32_t* triples, int16_t* colors, const int8_t* last, int minLast, const VolumeGrid& g,
                      const SolidTables& t, int rowBegin, int rowEnd) {
  for (size_t v = size_t(rowBegin) * size_t(g.nx); v < size_t(rowEnd) * size_t(g.nx); ++v)
    if (last[v] >= minLast) colorOf(t, triples + v * 3, colors + v * 4);
}

void solidCorrectKernel(const uint32_t* in, const int16_t* inColors, uint32_t* out, int16_t* outColors,
                        const int8_t* last, const VolumeGrid& g, const SolidTables& t, int interleave, int step,
                        int rowBegin, int rowEnd) {
  const Correction c(g, t);
  const Variant variant = variantFor(t);
  Neighborhood n;
  VoxelSearch batch[kBatch];
  int count = 0;
  const auto correctBatch = [&] {
    variant.findBases(batch, count, in, c, t);
    variant.projectTargets(batch, count, inColors, c, t, n);
    variant.searchStep1(batch, count, t);
    variant.searchStep2(batch, count, t);
    for (int i = 0; i < count; ++i) writeTriple(batch[i], t, out, outColors);
    count = 0;
  };
  for (int r = rowBegin; r < rowEnd; ++r) {
    int y, z, x0;
    if (!classRow(g, interleave, step, r, y, z, x0)) continue;
    for (int x = x0; x < g.nx; x += interleave) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (last[v] < step) continue;
      batch[count++].voxel = v;
      if (count == kBatch) correctBatch();
    }
  }
  correctBatch();
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
