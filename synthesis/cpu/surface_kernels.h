// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The per-site kernels of synthesis in an atlas (Lefebvre & Hoppe 2006 §5–6), on the plain arrays
// of a SurfaceLevel. Like synthesis_kernels.h: each kernel reads its input buffer and writes its
// output buffer for the sites [begin, end) it is given, so sites can be split across threads (or
// GPU invocations) freely. Coordinates are subpixel (kSubpixelBits); appearance, neighborhoods and
// candidates are looked up at the nearest exemplar pixel. Jacobians are floats; each product J·v
// is rounded to subpixels by floor(x + 1/2) in single precision, without fused multiply-add (the
// build compiles every target with -ffp-contract=off; the GLSL twins mark these products precise).

#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/synthesize_surface.h"

#include <cstdint>

namespace texfab::synthesis::cpu {

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
