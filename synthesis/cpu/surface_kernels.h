// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The per-site kernels of synthesis in an atlas (Lefebvre & Hoppe 2006 §5–6), on the plain arrays
// of a SurfaceLevel. Like synthesis_kernels.h: each kernel reads its input buffer and writes its
// output buffer for the sites [begin, end) it is given, so sites can be split across threads (or
// GPU invocations) freely. Coordinates are subpixel (kSubpixelBits); appearance, neighborhoods and
// candidates are looked up at the nearest exemplar pixel. Jacobians are floats; each product J·v
// is rounded to subpixels by floor(x + 1/2) in single precision, without fused multiply-add (the
// build compiles every target with -ffp-contract=off; the GLSL twins mark these products precise).

#include "core/context.h"
#include "core/hash.h"
#include "core/parallel.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/synthesize_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace texfab::synthesis::cpu {

/// fn(begin, end) over the sites [0, count) in parallel tasks of kSiteGrain sites.
inline constexpr size_t kSiteGrain = 4096;
template <class Fn>
void forSites(size_t count, const Context& ctx, Fn&& fn) {
  parallelFor(0, int((count + kSiteGrain - 1) / kSiteGrain), ctx, [&](int b, int e) {
    fn(size_t(b) * kSiteGrain, std::min(count, size_t(e) * kSiteGrain));
  });
}

/// One exemplar pixel in subpixel units.
inline constexpr int kSubpixelOne = 1 << kSubpixelBits;

/// A rounded offset in subpixels.
struct Offset {
  int x, y;
};

/// round(J * (vx, vy)) in subpixel units: two products, then their sum, each rounded to float, then
/// floor(x + 1/2). Naming the products does not stop a compiler from fusing them into a
/// multiply-add; the build's -ffp-contract=off does (and `precise` in the GLSL twin).
inline Offset applyJ(const std::array<float, 4>& j, float vx, float vy) {
  const float ax = j[0] * vx, bx = j[1] * vy;
  const float ay = j[2] * vx, by = j[3] * vy;
  return {int(std::floor((ax + bx) * float(kSubpixelOne) + 0.5f)), int(std::floor((ay + by) * float(kSubpixelOne) + 0.5f))};
}

/// Site s's jitter in subpixels: amplitude256 (1/256 exemplar pixels) times a hash of (seed, chart,
/// atlas level, x, y) uniform in [-1, 1)^2, in integers as jitterKernel.
inline Offset surfaceJitter(const SurfaceLevel& level, size_t s, uint32_t seed, int atlasLevel, int64_t amplitude256) {
  const uint32_t chartSeed = seed ^ pcgHash(uint32_t(level.chart[s]) + 0x9e3779b9u);
  const int64_t hx = int64_t(texelHash(chartSeed, uint32_t(atlasLevel), level.x[s], level.y[s], 0) >> 16) - 32768;
  const int64_t hy = int64_t(texelHash(chartSeed, uint32_t(atlasLevel), level.x[s], level.y[s], 1) >> 16) - 32768;
  return {int((amplitude256 * kSubpixelOne * hx + (int64_t(1) << 22)) >> 23),
          int((amplitude256 * kSubpixelOne * hy + (int64_t(1) << 22)) >> 23)};
}

/// The index into kSurfaceStepX/Y of the unit step (dx, dy), each in {-1, 0, 1}; -1 for (0, 0).
inline int stepIndex(int dx, int dy) {
  constexpr int kStepIndex[3][3] = {{5, 6, 7}, {4, -1, 0}, {3, 2, 1}};  // [dy + 1][dx + 1]
  return kStepIndex[dy + 1][dx + 1];
}

/// The unit step (index into kSurfaceStepX/Y) closest in direction to (fx, fy): the rounding of
/// errata 3 done on the circle (sectors of 45° around each step).
inline int stepToward(float fx, float fy) {
  constexpr float kTan22_5 = 0.41421356f;
  const float ax = std::fabs(fx), ay = std::fabs(fy);
  const int dx = ax > kTan22_5 * ay ? (fx > 0 ? 1 : -1) : 0;
  const int dy = ay > kTan22_5 * ax ? (fy > 0 ? 1 : -1) : 0;
  return stepIndex(dx, dy);
}

/// The two unit steps through which a neighbourhood sample at offset (dx, dy) (exemplar units) is
/// predicted (LH06 §5, "we average between several estimations taken around p + δ"): the one
/// closest in direction to J⁻¹(dx, dy), then the next closest (the neighbouring sector on that
/// side). Where J is singular, the steps toward (dx, dy) itself.
inline std::array<int, 2> stepsToward(const std::array<float, 4>& j, float dx, float dy) {
  const float det = j[0] * j[3] - j[1] * j[2];
  const float sgn = det < 0 ? -1.0f : 1.0f;
  // J⁻¹(dx, dy) up to the positive factor 1/|det|: only its direction matters.
  const float fx = sgn * (j[3] * dx - j[1] * dy), fy = sgn * (j[0] * dy - j[2] * dx);
  const float gx = det != 0.0f ? fx : dx, gy = det != 0.0f ? fy : dy;
  const int d1 = stepToward(gx, gy);
  const int d2 = (d1 + (float(kSurfaceStepX[d1]) * gy - float(kSurfaceStepY[d1]) * gx > 0 ? 1 : 7)) % 8;
  return {d1, d2};
}

// Non-toroidal exemplars: with `clampTo` (the stack level's valid region, in whole pixels), every
// coordinate these kernels write is reflected into the region (reflectInto, in subpixels) instead
// of wrapped; correctSurfaceKernel clamps predicted neighborhood samples to the region and skips
// candidates outside it.

/// Top level: S[s] = J(s) * (texel centre) mod exemplar size, a tiling that follows each chart's
/// Jacobian (jitter then randomizes it).
void initSurfaceKernel(const SurfaceLevel& level, uint32_t* out, int exemplarWidth, int exemplarHeight,
                       size_t begin, size_t end, const ValidRegion* clampTo = nullptr);

/// Upsampling: S[s] = S_parent[parent(s)] + J(s) * ((x mod 2, y mod 2) - 1/2): the child's offset
/// from its parent's centre, in this level's texels, mapped to the exemplar.
void upsampleSurfaceKernel(const SurfaceLevel& level, const uint32_t* parent, uint32_t* out, int exemplarWidth,
                           int exemplarHeight, size_t begin, size_t end, const ValidRegion* clampTo = nullptr);

/// Jitter in place, as jitterKernel, hashed on (seed, chart, level, x, y).
void jitterSurfaceKernel(const SurfaceLevel& level, uint32_t* coords, uint32_t seed, int atlasLevel,
                         int64_t amplitude256, int exemplarWidth, int exemplarHeight, size_t begin, size_t end,
                         const ValidRegion* clampTo = nullptr);

/// One correction sub-pass over the sites of class `cls` = (x mod 2) + 2 (y mod 2); other sites
/// are copied. The neighborhood of site s: for each diagonal Δ = h(±1, ±1), the mean appearance
/// of the estimates E[S[n] − round(Jδ) + Δ] through the two unit steps δ closest in direction to
/// J⁻¹Δ, n the neighbor of s in direction δ (E[S[s] + Δ] when s has neither). Candidates:
/// C_i(S[n]) − round(Jδ) over the 8 neighbors and C_i(S[s]); ties as in correctKernel.
void correctSurfaceKernel(const SurfaceLevel& level, const uint32_t* in, uint32_t* out, const LevelTables& tables,
                          int cls, size_t begin, size_t end);

} // namespace texfab::synthesis::cpu
