// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Synthesis directly in a texture atlas: anisometric, multi-resolution, across chart seams.
//
// Based on:
//   S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5 (anisometric
//     synthesis: a per-texel Jacobian J maps atlas offsets to exemplar offsets; a neighborhood is
//     predicted from the immediate neighbors only, E[S[p+δ] − J(p)δ + Δ] with δ the unit steps
//     closest in direction to J⁻¹(p)Δ (two estimates averaged); candidates C_i(S[p+δ]) − J(p)δ)
//     and §6 (synthesis in an atlas: every neighbor access goes through an indirection map, so
//     neighborhoods continue across chart seams).
//   S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3 (coordinate
//     upsampling, hash jitter, correction sub-passes, k-coherence).
// Notes: docs/synthesis-notes.md#atlas-synthesis, #anisometric-step, #anisometric-candidates.
//
// synthesis/ knows nothing of meshes: the surface arrives as a SurfaceDomain, a pyramid of sites
// (atlas texels, one per chart a texel touches) with their Jacobians and their 8 neighbors, built by
// atlas/surface_domain.h. A neighbor is the site one texel step away *on the surface*: inside a
// chart the next texel, at a chart border the texel where the step lands in the adjacent chart.
//
// Determinism: every coordinate is a pure function of (analysis, domain, options); the thread
// count never changes a value (each kernel reads one buffer and writes another).

#include "core/context.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/synthesize_2d.h"

#include <array>
#include <cstdint>
#include <vector>

namespace texfab::synthesis {

/// The 8 unit steps, in neighbor order: (+1,0) (+1,+1) (0,+1) (-1,+1) (-1,0) (-1,-1) (0,-1) (+1,-1),
/// atlas x right, y down.
inline constexpr int kSurfaceStepX[8] = {1, 1, 0, -1, -1, -1, 0, 1};
inline constexpr int kSurfaceStepY[8] = {0, 1, 1, 1, 0, -1, -1, -1};

/// One level of the atlas pyramid: level a has texels 2^a atlas texels wide.
struct SurfaceLevel {
  int width = 0;   ///< grid size of this level
  int height = 0;
  // One entry per site, sites ordered by (y, x, chart):
  std::vector<int32_t> x, y;                     ///< the site's texel in this level's grid
  std::vector<int32_t> chart;                    ///< the chart it belongs to
  std::vector<std::array<float, 4>> jacobian;    ///< J (row-major 2x2): level-texel offset -> exemplar pixels
  std::vector<std::array<int32_t, 8>> neighbors; ///< site one step away on the surface; -1 = none (open boundary)
  std::vector<int32_t> parent;                   ///< the site of level+1 containing this one; -1 at the top

  size_t size() const { return x.size(); }
};

struct SurfaceDomain {
  std::vector<SurfaceLevel> levels; ///< [0] = the atlas itself, then each level half as fine
};

/// Surface coordinates are fixed point: packCoord(u, v) of u, v in 1/2^kSubpixelBits exemplar
/// pixels (pixel centres at whole values). Anisometric steps J(p)δ are not whole pixels; rounding
/// each one would bend and stretch every patch (a 30° turn at unit scale would step (1, 1), √2 too
/// far), so coordinates keep 1/16 pixel. 12 integer bits: exemplars up to 4096 pixels.
inline constexpr int kSubpixelBits = 4;

/// A surface coordinate in exemplar pixels.
inline float surfaceU(uint32_t c) { return float(c & 0xffffu) / float(1 << kSubpixelBits); }
inline float surfaceV(uint32_t c) { return float(c >> 16) / float(1 << kSubpixelBits); }

struct SurfaceSynthesisOptions {
  uint32_t seed = 1;
  /// Jitter per exemplar stack level, as SynthesisOptions::jitter (empty = defaultJitter()).
  std::vector<float> jitter;
  int passes = 2;       ///< correction passes per level (each of 4 sub-passes)
  bool correct = true;  ///< false: upsample + jitter only

  void validate() const;
};

struct SurfaceSynthesisResult {
  std::vector<uint32_t> coords;   ///< one subpixel exemplar coordinate (kSubpixelBits) per site of levels[0]
  std::vector<LevelStats> levels; ///< per synthesized atlas level, coarsest first (level = atlas level)
  double exemplarPixelsPerTexel = 0; ///< median sqrt|det J| at the finest level
  /// Graph synthesis with transfers (synthesize_surface_graph.h): the RGB offset each site's colour
  /// is shown with; empty otherwise.
  std::vector<std::array<float, 3>> colorOffsets;
};

/// Median over a level's sites of sqrt|det J| (exemplar pixels per texel), ignoring singular or
/// non-finite Jacobians; 0 when there are none.
double medianPixelsPerTexel(const SurfaceLevel& level);

/// The exemplar stack level that atlas level `atlasLevel` synthesizes at, for a finest-level
/// Jacobian of scale `pixelsPerTexel`: the level whose spacing is the power of two closest to
/// 2^atlasLevel * pixelsPerTexel, clamped to the stack.
int stackLevelForAtlasLevel(const ExemplarAnalysis& analysis, int atlasLevel, double pixelsPerTexel);

SurfaceSynthesisResult synthesizeSurface(const ExemplarAnalysis& analysis, const SurfaceDomain& domain,
                                         const SurfaceSynthesisOptions& options, const Context& ctx = {});

} // namespace texfab::synthesis
