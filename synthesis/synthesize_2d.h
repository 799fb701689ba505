// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Parallel, controllable texture synthesis on the infinite plane.
//
// Based on:
//   S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3
//     (coordinate upsampling in a Gaussian stack, hash jitter with per-level strength, correction
//     in sub-passes with k-coherence candidates).
//   S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §4 (4-sample
//     appearance-space neighborhoods).
// Notes: docs/synthesis-notes.md#parallel-synthesis and #stack-upsampling (stack upsampling adds
//   h_l * (p mod 2), h_l = 2^(L-l)).
//
// Determinism: every output texel is a pure function of (analysis, options, position). A window
// equals, bit for bit, the same texels of any larger window; neither the thread count nor the
// order of work changes a value. The padding each level needs is the dependency closure of the
// correction sub-passes (one texel each) and of upsampling, computed per window, not guessed.

#include "core/context.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"

#include <cstdint>
#include <vector>

namespace texfab::synthesis {

/// A rectangle of the infinite texture plane, in finest-level texels. x, y may be negative.
struct Window {
  int64_t x = 0;
  int64_t y = 0;
  int width = 0;
  int height = 0;
  /// Throws texfab::Error unless 1 to kMaxImageSide texels per side, |x|, |y| <= 2^40.
  void validate() const;
};

struct SynthesisOptions {
  uint32_t seed = 1;
  /// Jitter strength per level, coarsest first, each in [0, 1] (1 = up to one texel of that level).
  /// One value applies to every level; fewer values than levels repeat the last one; an empty list
  /// uses defaultJitter().
  std::vector<float> jitter;
  int passes = 2;         ///< correction passes per level
  int interleave = 2;     ///< sub-passes per pass = interleave^2 (1 = all texels at once); 1..3
  /// Output wraps with this period (texels) when > 0: the texture tiles at its size. Periods must
  /// be multiples of 2^n to synthesize n levels; coarser levels are skipped.
  int periodX = 0;
  int periodY = 0;
  bool correct = true;    ///< false: upsample + jitter only (for tests and illustrations)

  void validate() const;
};

/// The default jitter: 1 at the three coarsest levels, 0.5 at the fourth, 0 below.
std::vector<float> defaultJitter(int levelCount);

/// The coarsest level synthesized: 0, or for a tiling period the coarsest level at which the
/// period is still a whole number of texels and a multiple of the interleave.
int firstSynthesisLevel(int levelCount, const SynthesisOptions& options);

/// Per-level statistics (time, texels corrected), for reports. Never fed back into synthesis.
struct LevelStats {
  int level = 0;
  int64_t texels = 0;     ///< texels synthesized at this level, padding included
  double seconds = 0.0;
};

struct SynthesisResult {
  CoordMap coords;
  std::vector<LevelStats> levels;
  /// Graph synthesis' colour offsets (synthesize_graph.h): RGB per texel, added to the colours
  /// the coordinates resolve to; empty where there are none.
  Image colorOffsets;
};

/// Peak memory of synthesize2d on `window`, in bytes: two coordinate buffers while synthesizing,
/// plus `resolvedChannels` float channels of images resolved through the coordinates afterwards
/// (applyCoords: colours and companion maps).
double synthesize2dMemoryBytes(const Window& window, int resolvedChannels);

/// Synthesizes the exemplar coordinates of `window` (at most kMaxImageSide per side).
SynthesisResult synthesize2d(const ExemplarAnalysis& analysis, const Window& window,
                             const SynthesisOptions& options, const Context& ctx = {});

} // namespace texfab::synthesis
