// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The per-texel kernels of parallel synthesis (Lefebvre & Hoppe 2005 §3), on plain integer arrays.
// Each kernel reads only its input buffer and writes only its output buffer, processes the rows
// [rowBegin, rowEnd) it is given, and uses integer arithmetic only: the Vulkan compute shaders are
// ports of these functions, and the two backends must agree bit for bit.
//
// A level buffer holds the packed exemplar coordinates (synthesis/coord_map.h) of the texels of a
// rectangle of one level of the infinite plane; texel (x, y) of the buffer is level position
// (grid.x0 + x, grid.y0 + y).
//
// Exemplar coordinates wrap (a toroidal exemplar), or, when a kernel is given the level's valid
// region (`clampTo`, a non-toroidal exemplar), never leave that region: nothing wraps.

#include "synthesis/exemplar_analysis.h"

#include <cstdint>

namespace texfab::synthesis::cpu {

struct LevelGrid {
  int64_t x0 = 0;  ///< level position of buffer texel (0, 0)
  int64_t y0 = 0;
  int width = 0;
  int height = 0;
};

/// Rows of a LevelGrid per parallel task: enough work to amortize scheduling, small enough to
/// balance two cores.
inline constexpr int kRowGrain = 8;

/// `g` grown by `by` texels on every side.
inline LevelGrid expand(const LevelGrid& g, int by) { return {g.x0 - by, g.y0 - by, g.width + 2 * by, g.height + 2 * by}; }

/// The parent-level rectangle that upsampling `g` reads.
inline LevelGrid parentOf(const LevelGrid& g) {
  const int64_t x0 = g.x0 >> 1, y0 = g.y0 >> 1;
  const int64_t x1 = (g.x0 + g.width - 1) >> 1, y1 = (g.y0 + g.height - 1) >> 1;
  return {x0, y0, int(x1 - x0 + 1), int(y1 - y0 + 1)};
}

/// What the kernels need to know about the exemplar at one level (views into ExemplarAnalysis).
struct LevelTables {
  int exemplarWidth = 0;
  int exemplarHeight = 0;
  int spacing = 1;                      ///< h_l
  int k = 1;                            ///< candidates per exemplar pixel
  const int8_t* appearance = nullptr;   ///< exemplarWidth*exemplarHeight*kAppearanceDims
  const int8_t* neighborhood = nullptr; ///< exemplarWidth*exemplarHeight*kNeighborhoodDims
  const uint32_t* candidates = nullptr; ///< exemplarWidth*exemplarHeight*k packed coordinates
  const ValidRegion* clampTo = nullptr;  ///< non-toroidal: the level's valid region; null = wrap
};

/// A non-toroidal coordinate pushed back into [lo, hi]: mirrored at the bound it crossed, then
/// clamped (a step longer than the region).
constexpr int64_t reflectInto(int64_t v, int64_t lo, int64_t hi) {
  if (v < lo) v = 2 * lo - v;
  if (v > hi) v = 2 * hi - v;
  return v < lo ? lo : v > hi ? hi : v;
}

/// Integer SSD of two runtime neighborhoods (kNeighborhoodDims int8 values each): the distance
/// every backend computes identically.
inline int32_t neighborhoodDistance(const int8_t* a, const int8_t* b) {
  int32_t sum = 0;
  for (int i = 0; i < kNeighborhoodDims; ++i) {
    const int32_t d = int32_t(a[i]) - int32_t(b[i]);
    sum += d * d;
  }
  return sum;
}

/// a mod m in [0, m), for any sign of a.
constexpr int64_t floorMod(int64_t a, int64_t m) {
  const int64_t r = a % m;
  return r < 0 ? r + m : r;
}
/// floor(a / 2^s) for any sign of a.
constexpr int64_t floorShift(int64_t a, int s) { return a >> s; }

/// Coarsest level: S[q] = (q' * spacing) mod exemplar size, q' = q mod period (period 0: q' = q).
/// With no jitter and no correction this makes the finest level an exact tiling of the exemplar.
/// With `clampTo`: that value clamped to the region.
void initKernel(uint32_t* out, const LevelGrid& grid, int spacing, int exemplarWidth,
                int exemplarHeight, int64_t periodX, int64_t periodY, int rowBegin, int rowEnd,
                const ValidRegion* clampTo = nullptr);

/// Upsampling (errata §20.2): S_l[q] = S_{l-1}[floor(q/2)] + spacing * (q mod 2), wrapped.
/// `parent` must cover floor(grid/2). With `clampTo` = [x0, x1] (per axis): a parent coordinate
/// u becomes b + spacing * (q mod 2), b = min(u, x1 - spacing) (x0 if that is below x0), the
/// result at most x1: the two children stay distinct and inside.
void upsampleKernel(const uint32_t* parent, const LevelGrid& parentGrid, uint32_t* out,
                    const LevelGrid& grid, int spacing, int exemplarWidth, int exemplarHeight,
                    int rowBegin, int rowEnd, const ValidRegion* clampTo = nullptr);

/// Jitter in place: S[q] += round(amplitude/256 * H(q)), H uniform in [-1, 1)^2 from
/// texelHash(seed, level, q mod period). `amplitude256` = round(strength * spacing * 256).
/// Wrapped, or with `clampTo` reflected into the region (reflectInto).
void jitterKernel(uint32_t* coords, const LevelGrid& grid, uint32_t seed, int level,
                  int64_t amplitude256, int64_t periodX, int64_t periodY, int exemplarWidth,
                  int exemplarHeight, int rowBegin, int rowEnd, const ValidRegion* clampTo = nullptr);

/// One correction sub-pass. For every texel of the buffer rectangle [ax0, ax1) x [ay0, ay1) whose
/// level position q satisfies q mod interleave == (classX, classY), writes the best candidate
/// among { C_i(S[q+D]) - spacing*D : D in 3x3, i < k } (and S[q] itself), comparing 4-sample
/// appearance-space neighborhoods by integer SSD; ties go to S[q], then to the smallest packed
/// coordinate. With tables.clampTo, C_i(S[q+D]) - spacing*D is not wrapped: a candidate outside
/// the region is skipped. Every other texel of the rectangle is copied. Rows are buffer rows and must lie
/// in [ay0, ay1); the rectangle must keep one texel of margin inside the buffer.
void correctKernel(const uint32_t* in, uint32_t* out, const LevelGrid& grid, const LevelTables& tables,
                   int interleave, int classX, int classY, int ax0, int ax1, int rowBegin, int rowEnd);

} // namespace texfab::synthesis::cpu
