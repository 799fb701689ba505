// SPDX-License-Identifier: GPL-3.0-or-later
// The x86 batches of the solid correction kernel: the search of solid_kernels.cpp (the portable
// specification) over batches of voxels, phase by phase, with SSE (every x86-64) or AVX2 (where
// the CPU has it). Same integers, same bytes as the portable kernel.
//
// A voxel's search reads table lines scattered over megabytes (the 2-D candidates of its 27
// pixels, the 3-D candidates of 3, its new triple), far beyond L2. A batch is therefore searched
// phase by phase: 1. step 1's pixels; 2. the targets (projections); 3. step 1; 4. step 2; 5. the
// new triples. A phase requests, for the whole batch, the lines that a later phase reads
// (prefetches), so that their misses overlap.
#include "synthesis/cpu/solid_search.h"

#if defined(__x86_64__) || defined(__i386__)

#include <immintrin.h>

#include <algorithm>
#include <climits>

namespace texfab::synthesis::cpu {

namespace {

constexpr int kBatch = 32;

// -- Projections --
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

// The phases of one variant, each over a batch.
struct Variant {
  void (*findBases)(VoxelSearch* batch, int count, const uint32_t* in, const Correction& c, const SolidTables& t);
  void (*projectTargets)(VoxelSearch* batch, int count, const int16_t* inColors, const Correction& c,
                         const SolidTables& t, Neighborhood& n);
  void (*searchStep1)(VoxelSearch* batch, int count, const SolidTables& t);
  void (*searchStep2)(VoxelSearch* batch, int count, const SolidTables& t);
};

// -- SSE variant: the portable searches with SSE projections and distances --

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

void findBasesSse(VoxelSearch* batch, int count, const uint32_t* in, const Correction& c, const SolidTables& t) {
  for (int i = 0; i < count; ++i) {
    findBases(batch[i], in, c.bases);
    requestCandidates2d(batch[i], t);
  }
}

using ProjectFn = void (*)(const int16_t* x, const SolidKernelProjection& p, int8_t* out);

template <ProjectFn Project>
void projectTargets(VoxelSearch* batch, int count, const int16_t* inColors, const Correction& c, const SolidTables& t,
                    Neighborhood& n) {
  for (int i = 0; i < count; ++i) {
    VoxelSearch& s = batch[i];
    gatherNeighborhood(s, inColors, c, n);
    Project(n.cross, *t.projection3d, s.target3d);
    Project(n.planes[0], *t.projection2d, s.target2d[0]);
    Project(n.planes[1], *t.projection2d, s.target2d[1]);
    Project(n.cross, *t.projection2d, s.target2d[2]);  // E_z's plane leads the cross
  }
}

// Step 1 in direction e: the packed coordinate of the best of the k2d candidates of each pixel.
uint32_t nearest2dSse(const int8_t* target, const uint32_t* pixels, const SolidTables& t, int e) {
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

void searchStep1Sse(VoxelSearch* batch, int count, const SolidTables& t) {
  for (int i = 0; i < count; ++i)
    for (int e = 0; e < 3; ++e) keepStep1(batch[i], e, nearest2dSse(batch[i].target2d[e], batch[i].bases[e], t, e), t);
}

void searchStep2Sse(VoxelSearch* batch, int count, const SolidTables& t) {
  for (int i = 0; i < count; ++i) {
    VoxelSearch& s = batch[i];
    keepStep2(s, tripleOf(t, s.pixels, nearest3d(s, t, ssd)));
  }
}

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

// AVX2 where the CPU has it and the limit allows; else SSE.
Variant variantFor(const SolidTables& t, SolidSimd simd) {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (simd == SolidSimd::Avx2 && avx2) {
    static constexpr decltype(Variant::searchStep1) kStep1[4] = {searchStep1Avx2<1>, searchStep1Avx2<2>,
                                                                 searchStep1Avx2<3>, searchStep1Avx2<4>};
    static constexpr decltype(Variant::projectTargets) kProject[4] = {projectTargetsAvx2<4>, projectTargetsAvx2<8>,
                                                                        projectTargetsAvx2<12>, projectTargetsAvx2<16>};
    return {findBasesAvx2, kProject[t.projection3d->rows / 4 - 1], kStep1[(t.k2d - 1) / 2],
            t.dims == kSolid2dDims ? searchStep2Avx2Pairs
            : t.dims > kSolid2dDims ? searchStep2Avx2Singles
                                    : searchStep2Sse};
  }
  return {findBasesSse, projectTargets<projectSse>, searchStep1Sse, searchStep2Sse};
}

} // namespace

bool solidCorrectX86(const uint32_t* in, const int16_t* inColors, uint32_t* out, int16_t* outColors,
                     const int8_t* last, const VolumeGrid& g, const SolidTables& t, int interleave, int step,
                     int rowBegin, int rowEnd, SolidSimd simd) {
  if (simd == SolidSimd::Portable) return false;
  const Correction c(g, t);
  const Variant variant = variantFor(t, simd);
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
  forEachCorrected(last, g, interleave, step, rowBegin, rowEnd, [&](size_t v) {
    batch[count++].voxel = v;
    if (count == kBatch) correctBatch();
  });
  correctBatch();
  return true;
}

} // namespace texfab::synthesis::cpu

#else

namespace texfab::synthesis::cpu {
bool solidCorrectX86(const uint32_t*, const int16_t*, uint32_t*, int16_t*, const int8_t*, const VolumeGrid&,
                     const SolidTables&, int, int, int, int, SolidSimd) {
  return false;
}
} // namespace texfab::synthesis::cpu

#endif
