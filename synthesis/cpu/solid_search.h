// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The pieces of the solid correction kernel's two-step search (Dong et al. 2008 §5.1) shared by
// its portable specification (solid_kernels.cpp, one voxel at a time) and its x86 batches
// (solid_kernels_x86.cpp). Internal to synthesis/cpu/.
//
// Both steps minimize a key (SSD << 32 | tie-break) over their candidates. SSDs of int8
// descriptors are below 2^31 (at most 16 * 254^2), so keys order as the pairs (SSD, tie-break),
// as unsigned or as signed 64-bit integers. Step 1's tie-break is the candidate's packed
// coordinate; step 2's is its rank e * kSolidMaxCandidates + k, so that the earliest of equally
// near candidates wins. Either way a candidate seen twice cannot change the minimum: step 1 need
// not skip pixels reached from two neighbours, and SIMD groups may be padded with repeats.

#include "synthesis/coord_map.h"
#include "synthesis/cpu/solid_kernels.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/solid_analysis.h"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace texfab::synthesis::cpu {

inline constexpr int kAxisU[3] = {1, 2, 0};  // as in solid_analysis.h: E_x (y, z), E_y (z, x), E_z (x, y)
inline constexpr int kAxisV[3] = {2, 0, 1};

/// One voxel's search, carried from step to step.
struct VoxelSearch {
  size_t voxel;
  uint32_t bases[3][9];  // step 1's pixels (v * w + u) per direction, see BaseLayout
  alignas(16) int8_t target3d[SolidKernelProjection::kLanes];
  alignas(16) int8_t target2d[3][SolidKernelProjection::kLanes];
  uint32_t pixels[3];    // step 1's winners (v * w + u)
  const uint32_t* triple;  // step 2's winner
};

/// Where step 1's 27 pixels come from: C(S[v + P d] - d) for the 3x3 plane neighbours d of each
/// direction e (§5.1), as the offset of S_e[v + P d] in `in` from the voxel's first coordinate and
/// -d h_l mod w (resp. h), so that each wraps with one compare (coordinates are below w and h).
struct BaseLayout {
  int32_t taps[27];
  uint32_t du[27], dv[27];
  uint32_t w = 0, h = 0;
};

/// Projection inputs: colour records' 3 channels side by side, in projection order (a record is
/// copied whole, 4 int16, the next one overwriting the 4th), then padding to whole chunks (zero
/// weights; zero-initialized so that it stays finite).
inline constexpr int kCrossLanes = (3 * kSolidCrossVoxels + 1 + 15) / 16 * 16;
inline constexpr int kPlaneLanes = (3 * 25 + 1 + 15) / 16 * 16;
struct Neighborhood {
  alignas(32) int16_t cross[kCrossLanes] = {};      // the 3-neighborhood; E_z's plane is its first 25 voxels
  alignas(32) int16_t planes[2][kPlaneLanes] = {};  // E_x's and E_y's planes
};

/// What a correction call derives from the grid and the tables, once.
struct Correction {
  int64_t cross[kSolidCrossVoxels];  // offsets of the 3-neighborhood's colour records (int16)
  int64_t planes[2][25];             // the same for E_x's and E_y's planes
  BaseLayout bases;
  int contrastGain16 = 16;  // SolidTables::contrastGain16

  Correction(const VolumeGrid& g, const SolidTables& t);
};

/// A voxel's colour record, as the search sees it: the sum of its three exemplar colours, doubled
/// (6x their mean) or through the level's colour transfer (SolidTables::searchColors), then 0.
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

/// The sub-pass class of step t and the row's first voxel of that class; false if the row has none.
/// interleave 2: 8 classes (x, y, z parities); interleave 1: every voxel in every step.
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

/// Calls fn(voxel index) for every voxel of rows [rowBegin, rowEnd) corrected at `step`: of the
/// step's class, with last >= step.
template <class Fn>
void forEachCorrected(const int8_t* last, const VolumeGrid& g, int interleave, int step, int rowBegin, int rowEnd,
                      Fn&& fn) {
  for (int r = rowBegin; r < rowEnd; ++r) {
    int y, z, x0;
    if (!classRow(g, interleave, step, r, y, z, x0)) continue;
    for (int x = x0; x < g.nx; x += interleave) {
      const size_t v = size_t(r) * size_t(g.nx) + size_t(x);
      if (last[v] >= step) fn(v);
    }
  }
}

inline uint64_t searchKey(int32_t ssd, uint32_t tie) { return uint64_t(uint32_t(ssd)) << 32 | tie; }

/// Step 2: the rank e * kSolidMaxCandidates + k of the best of the k3d 3-D candidates of the three
/// pixels; `ssd(a, b, n)` is the file's sum of squared differences (exact integers, so every
/// variant gives the same rank).
template <class Ssd>
uint32_t nearest3d(const VoxelSearch& s, const SolidTables& t, Ssd&& ssd) {
  uint64_t best = UINT64_MAX;
  for (int e = 0; e < 3; ++e) {
    const int8_t* descriptors = t.descriptors3d[e] + size_t(s.pixels[e]) * kSolidMaxCandidates * size_t(t.dims);
    for (int k = 0; k < t.k3d; ++k)
      best = std::min(best, searchKey(ssd(s.target3d, descriptors + size_t(k) * size_t(t.dims), t.dims),
                                      uint32_t(e * kSolidMaxCandidates + k)));
  }
  return uint32_t(best);
}

/// (sum + offset) >> shift clamped to +-127: one projected dimension (round half up, as
/// SolidProjection).
inline int8_t clampProjected(int32_t sum, int32_t offset, int shift) {
  const int32_t q = (sum + offset) >> shift;
  return int8_t(q < -127 ? -127 : q > 127 ? 127 : q);
}

inline void finishProjection(const int32_t* sum, const SolidKernelProjection& p, int8_t* out) {
  for (int d = 0; d < SolidKernelProjection::kLanes; ++d) out[d] = clampProjected(sum[d], p.offset[d], p.shift);
}

/// Step 1's 27 pixels of one voxel.
inline void findBases(VoxelSearch& s, const uint32_t* in, const BaseLayout& b) {
  const uint32_t* at = in + s.voxel * 3;
  uint32_t* bases = &s.bases[0][0];
  for (int n = 0; n < 27; ++n) {
    const uint32_t q = at[b.taps[n]];
    const uint32_t u = coordU(q) + b.du[n], v = coordV(q) + b.dv[n];
    bases[n] = (v >= b.h ? v - b.h : v) * b.w + (u >= b.w ? u - b.w : u);
  }
}

/// The largest colour record: 6x an 8-bit colour.
inline constexpr int32_t kMaxColorRecord = 2 * (kSolidColorSums - 1);

/// Lanes of a neighborhood's records after which their channels repeat: 16 records, whole 16-lane
/// chunks, so that the gain's loops run over fixed patterns (and vectorize).
inline constexpr int kRecordPeriod = 48;
static_assert(kCrossLanes % kRecordPeriod == 0);

/// v = clamp(m + (((v - m) * gain16) >> 4), 0, kMaxColorRecord) over `Lanes` lanes, m the channel's
/// mean from the period's pattern. Padding lanes and the last record's 4th value hold 0 and stay 0
/// (gain16 >= 16).
template <int Lanes>
inline void scaleRecords(int16_t* v, const int16_t (&mean)[kRecordPeriod], int32_t gain16) {
  // In 16-bit lanes: ((x - m) * gain16) >> 4 == ((16 (x - m)) * (gain16 << 8)) >> 16, whose factors
  // fit int16 (|x - m| <= 1530, gain16 <= 64): the high half of a 16-bit product.
  const int16_t g = int16_t(gain16 << 8);
  auto scale = [&](int16_t& x, int16_t m) {
    const int16_t a = int16_t((x - m) * 16);
    const int16_t d = int16_t((int32_t(a) * int32_t(g)) >> 16);
    const int16_t y = int16_t(m + d);
    x = y < 0 ? int16_t(0) : y > kMaxColorRecord ? int16_t(kMaxColorRecord) : y;
  };
  int b = 0;
  for (; b + kRecordPeriod <= Lanes; b += kRecordPeriod)
    for (int j = 0; j < kRecordPeriod; ++j) scale(v[b + j], mean[j]);
  for (int j = 0; j < Lanes % kRecordPeriod; ++j) scale(v[b + j], mean[j]);
}

/// SolidTables::contrastGain16 applied to a gathered neighborhood: every record moved away from the
/// mean of the 3-neighborhood's records (the planes hold some of the same records: the same values).
inline void applyContrastGain(Neighborhood& n, int gain16) {
  int32_t sums[kRecordPeriod] = {};
  for (int b = 0; b < kCrossLanes; b += kRecordPeriod)
    for (int j = 0; j < kRecordPeriod; ++j) sums[j] += n.cross[b + j];
  int32_t channel[3] = {0, 0, 0};
  for (int r = 0; r < kRecordPeriod / 3; ++r)
    for (int ch = 0; ch < 3; ++ch) channel[ch] += sums[3 * r + ch];
  for (int32_t& c : channel) c = (c + kSolidCrossVoxels / 2) / kSolidCrossVoxels;
  int16_t mean[kRecordPeriod];
  for (int r = 0; r < kRecordPeriod / 3; ++r)
    for (int ch = 0; ch < 3; ++ch) mean[3 * r + ch] = int16_t(channel[ch]);
  scaleRecords<kCrossLanes>(n.cross, mean, gain16);
  scaleRecords<kPlaneLanes>(n.planes[0], mean, gain16);
  scaleRecords<kPlaneLanes>(n.planes[1], mean, gain16);
}

/// The current 3-neighborhood of one voxel (its colour records) and its E_x and E_y planes,
/// through the targets' gain.
inline void gatherNeighborhood(const VoxelSearch& s, const int16_t* inColors, const Correction& c, Neighborhood& n) {
  const int16_t* centre = inColors + s.voxel * 4;
#pragma GCC unroll 61
  for (int i = 0; i < kSolidCrossVoxels; ++i) std::memcpy(n.cross + 3 * i, centre + c.cross[i], 8);
  for (int e = 0; e < 2; ++e)
#pragma GCC unroll 25
    for (int k = 0; k < 25; ++k) std::memcpy(n.planes[e] + 3 * k, centre + c.planes[e][k], 8);
  if (c.contrastGain16 != 16) applyContrastGain(n, c.contrastGain16);
}

/// Step 2's winner, from the tie-break of its key.
inline const uint32_t* tripleOf(const SolidTables& t, const uint32_t* pixels, uint32_t rank) {
  const uint32_t e = rank / kSolidMaxCandidates, k = rank % kSolidMaxCandidates;
  return t.triples[e] + (size_t(pixels[e]) * kSolidMaxCandidates + k) * 3;
}

/// The voxel's new triple and its colour.
inline void writeTriple(const VoxelSearch& s, const SolidTables& t, uint32_t* out, int16_t* outColors) {
  for (int e = 0; e < 3; ++e) out[s.voxel * 3 + size_t(e)] = s.triple[e];
  colorOf(t, s.triple, outColors + s.voxel * 4);
}

/// The x86 batches of the correction (solid_kernels_x86.cpp): false when this CPU or the SIMD
/// setting leaves the portable kernel to run.
bool solidCorrectX86(const uint32_t* in, const int16_t* inColors, uint32_t* out, int16_t* outColors,
                     const int8_t* last, const VolumeGrid& g, const SolidTables& t, int interleave, int step,
                     int rowBegin, int rowEnd, SolidSimd simd);

} // namespace texfab::synthesis::cpu
