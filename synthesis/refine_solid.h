// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Slice refinement of lazy solid synthesis: the search and vote of
//   J. Kopf, C.-W. Fu, D. Cohen-Or, O. Deussen, D. Lischinski, T.-T. Wong. Solid Texture Synthesis
//   from 2D Exemplars. ACM TOG 26(3), SIGGRAPH 2007: §3.2 (search: each voxel's three slice
//   neighbourhoods, across x, y and z, matched with neighbourhoods of that axis' exemplar), §3.1
//   (optimization: each voxel takes the colours its neighbours' matches predict for it, weighted
//   by their matching error),
// run after the finest level of Dong et al. 2008 (synthesize_solid.h), whose triples it starts from.
//
// One pass:
//   search: for each axis, and each voxel whose two coordinates in the slice across it are even
//     (a sparse set of windows that still overlap every voxel, as in Kwatra et al. 2005's texture
//     optimization, on which Kopf et al. build), the 5x5 window of the voxels' colours (mean of
//     three) in that slice, its contrast raised around the window's mean (gain 1.5), is compared
//     with exemplar windows centred on k-coherence candidates: the 2-D candidate sets
//     (SolidLevel::candidates2d) of the voxel's coordinate in that exemplar and of its four slice
//     neighbours', shifted back by the neighbour's offset. The best is the voxel's match for that
//     axis.
//   vote: each searched slice neighbour within 2 (in the three slices; 4 to 9 per slice) predicts
//     the voxel's colour from its match, weighted by 1 / (error + 512); each of the voxel's three
//     coordinates becomes the prediction of its exemplar nearest the weighted mean colour.
// The result is again a triple of exemplar pixels, so companion maps follow it, and its three
// colours are chosen to agree, so their mean regresses less to grey.
//
// Deviations from Kopf et al., on purpose: k-coherence candidates instead of a search of every
// exemplar window; the vote picks exemplar pixels (three, one per exemplar) instead of averaging
// colours (no blur, and triples stay triples); no histogram weights (the volume's histogram is
// not lazy), a gain on the search's targets instead; the finest level only, 5x5 windows; weights
// 1 / error (their r = 0 where they use 0.8, same figures); integers throughout, so that triples
// from any backend refine to the same bytes.
// Figures: docs/measurements.md#slice-refinement.
//
// Laziness: pass p at a voxel reads pass p - 1 within kRefineSearchRadius + kRefineVoteRadius
// voxels in its three slices, so refined voxels are a pure function of position: a request
// synthesizes Dong et al.'s triples of every voxel those reads reach (at most refineMargin(passes)
// per axis away), then refines a shrinking region, pass by pass, searching each axis only where a
// vote reads its matches (in the slice across that axis around each voting voxel).

#include "core/context.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <span>

namespace texfab::synthesis {

inline constexpr int kRefineSearchRadius = 2;  ///< 5x5 slice windows
inline constexpr int kRefineVoteRadius = 2;    ///< predictions from slice neighbours within 2
inline constexpr int kRefineGain16 = 24;       ///< the search targets' gain, in sixteenths (1.5)
inline constexpr int kRefineSearchStride = 2;  ///< windows searched on every second voxel of a slice

/// Voxels, per axis, that `passes` refinement passes read around a voxel.
constexpr int refineMargin(int passes) { return passes * (kRefineSearchRadius + kRefineVoteRadius); }

/// Voxels a request refines at once: larger requests refine in slabs of about this many requested
/// voxels (bounded memory), across the axis of their largest extent (a box's: z), cut between
/// layers and at least 4 margins thick (the margins add at most half the work). The values do not
/// depend on the slabs.
inline constexpr int64_t kRefineSlabVoxels = int64_t(1) << 20;

/// Peak memory that refining `voxels` requested voxels adds to their synthesis, in bytes: one
/// slab's region (a surface's: about 10 voxels per requested one at one pass; about 1,150 bytes per
/// requested voxel measured on the bundled elephant's texture job, 1,260 estimated).
double refineSolidMemoryBytes(int64_t voxels, int passes);

/// Triples of `voxels` after options.refinePasses passes (>= 1): per slab, Dong et al.'s triples of
/// every voxel within refineMargin (synthesizeSolid without refinement: any backend, the cache),
/// then the passes on the CPU. Level statistics are those of that synthesis. Stages, per slab:
/// "refinement region" (the region's masks), those of synthesis, then "refinement".
SolidSynthesisResult refineSolid(const SolidAnalysis& analysis, std::span<const Voxel> voxels,
                                 const SolidSynthesisOptions& options, SolidLevelCache* cache, const Context& ctx,
                                 int64_t slabVoxels = kRefineSlabVoxels);

/// The same for every voxel of `box`, x fastest, then y, then z (synthesizeSolidBox).
SolidSynthesisResult refineSolidBox(const SolidAnalysis& analysis, const VoxelBox& box,
                                    const SolidSynthesisOptions& options, SolidLevelCache* cache, const Context& ctx,
                                    int64_t slabVoxels = kRefineSlabVoxels);

} // namespace texfab::synthesis
