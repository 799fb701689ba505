// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Multiscale synthesis from an exemplar graph: any window of an infinite texture, at any zoom,
// with the structure of every exemplar at its own scale.
//
// Based on:
//   C. Han, E. Risser, R. Ramamoorthi, E. Grinspun. Multiscale texture synthesis. SIGGRAPH 2008;
//     C. Han, PhD thesis, 2011, §5.2 (per-texel pointers (i, k, u) and spacing h_k, upsampling to
//     the next stack level, jitter, correction in sub-passes over admissible candidates) and §5.3
//     (inconsistency correction: a cumulative colour offset R per texel, bilinear on upsampling).
//   S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005 (the pyramid
//     this extends; texfab's synthesize2d).
// Notes: docs/exemplar-graphs.md.
//
// Synthesis level t has texels 2^(L-t) root pixels wide: level L shows the root exemplar at its own
// resolution, level L + z a zoom of 2^z into it, where finer exemplars take over along the graph's
// edges. A texel is an atlas coordinate of GraphAnalysis (exemplar, stack level, position); its
// colour is that stack level's, so a zoomed-out view shows each exemplar prefiltered.
//
// Determinism: every output texel is a pure function of (analysis, options, position); a window
// equals, bit for bit, the same texels of any larger window; the thread count changes nothing.
// Deviations (beyond exemplar_graph.h's): jitter strength follows the stack level a texel points
// to, counted from near where texels enter its exemplar, not the synthesis level (without jitter there,
// texels that entered an exemplar copied coherent blocks of it, which showed as squares); a leaf
// exemplar's finest level, zoomed further, is magnified; a candidate's offset composes onto the
// transfer of the neighbour that offered it (cpu::GraphTransferChoice).

#include "core/context.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_graph.h"
#include "synthesis/synthesize_2d.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace texfab::synthesis {

struct GraphSynthesisOptions {
  uint32_t seed = 1;
  /// Output texels are 2^-zoomOctaves root pixels wide: 0 shows the root at its own resolution,
  /// 4 a 16x zoom (where an edge of 4 octaves hands over to its destination), -2 a view 4x
  /// farther out. At least -L.
  int zoomOctaves = 0;
  /// Jitter strength per stack level of the exemplar a texel points to, coarsest first, each in
  /// [0, 1]; fewer values than levels repeat the last; empty: defaultJitter() (1, 1, 1, 0.5, 0...).
  /// The root's levels take it from level 0; another exemplar's from two levels before
  /// GraphAnalysis::entryLevel, where texels enter it: it is randomized where it takes over.
  std::vector<float> jitter;
  int passes = 2;      ///< correction passes per level
  int interleave = 2;  ///< sub-passes per pass = interleave^2; 1..3
  /// Output wraps with this period (output texels) when > 0: the texture tiles at its size (a
  /// multiple of the interleave). Levels from graphFirstPeriodicLevel on wrap at the period
  /// halved per level; the coarser ones are synthesized as usual and read wrapped, so the tile
  /// keeps their structure (synthesize2d's rule, except that it skips those levels).
  int periodX = 0;
  int periodY = 0;

  /// Throws texfab::Error naming the field when a value is out of range for `analysis`.
  void validate(const GraphAnalysis& analysis) const;
};

/// The octaves of a zoom (1, 2, 4, ... or 0.5, 0.25, ...); throws texfab::Error ("zoom: ...")
/// for anything else.
int graphZoomOctaves(double zoom);

/// The synthesis level of the output: L + zoomOctaves.
int graphOutputLevel(const GraphAnalysis& analysis, const GraphSynthesisOptions& options);
/// The coarsest level whose periods are whole and multiples of the interleave (0 without a period):
/// the levels from it on tile; a period that is a multiple of interleave * 2^graphOutputLevel
/// tiles every level.
int graphFirstPeriodicLevel(const GraphAnalysis& analysis, const GraphSynthesisOptions& options);

/// Jitter amplitude per atlas tile (node * levels + level), in 1/256 pixels of the tile's exemplar:
/// h_k times the strength `jitter` (as GraphSynthesisOptions::jitter; empty: defaultJitter) gives
/// the tile's level, counted from level 0 for the root and from entryLevel - 2 for other nodes.
std::vector<int64_t> graphJitterAmplitudes256(const GraphAnalysis& analysis, const std::vector<float>& jitter);

/// Peak memory of synthesizeGraph on `window`, in bytes, with its colours resolved (applyCoords).
double synthesizeGraphMemoryBytes(const Window& window);

/// Synthesizes the atlas coordinates of `window` (at most kMaxImageSide per side) at the options'
/// zoom, and with the analysis' transfers (GraphAnalysis::transfers) the colour offsets they are
/// shown with (result.colorOffsets); graphColors resolves both. Reports "level t/T" stages.
SynthesisResult synthesizeGraph(const GraphAnalysis& analysis, const Window& window,
                                const GraphSynthesisOptions& options, const Context& ctx = {});

/// A colour value as graph synthesis shows it: the atlas colour moved by its texel's offset,
/// clamped to [0, 1] (graphColors; texture --graph on surfaces).
inline float transferredColor(float colour, float offset) { return std::clamp(colour + offset, 0.0f, 1.0f); }

/// The colours of a graph synthesis: its coordinates' colours in the atlas plus its colour offsets
/// (transferredColor). Companion maps take the coordinates alone (applyCoords).
Image graphColors(const SynthesisResult& result, const GraphAnalysis& analysis, const Context& ctx = {});

} // namespace texfab::synthesis
