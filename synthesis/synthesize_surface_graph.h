// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Multiscale synthesis from an exemplar graph directly in a texture atlas: a large model shows the
// root exemplar's structure and, where its texels are finer, the exemplars that detail it.
//
// Based on:
//   C. Han, E. Risser, R. Ramamoorthi, E. Grinspun. Multiscale texture synthesis. SIGGRAPH 2008
//     (thesis §5.2: pointers (i, k, u), spacing h_k, admissible candidates); texfab's
//     synthesize_graph.h in the plane.
//   S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6 (anisometric
//     steps J(p)δ, neighbourhoods predicted from immediate neighbours, across chart seams);
//     texfab's synthesize_surface.h.
//
// Atlas level a of the surface domain is synthesis level t = t0 - a of the graph, t0 the level whose
// texels are closest to the finest atlas texels (t0 = L - round(log2 p), p the median root pixels
// per texel; t0 > L zooms into the graph). A step δ of a site whose pointer is at stack level k < L
// moves it by 2^(t-k) J(p)δ pixels of that level's exemplar (J(p) maps this atlas level's texels to
// root pixels, 2^(L-t) root pixels a synthesis texel, h_k = 2^(L-k) pixels of the exemplar pointed
// to); for the root while t <= L that is J(p)δ, as in single-exemplar surface synthesis. At an
// exemplar's finest level the factor stops at 2^depth (GraphAnalysis::depth): past it the steps
// become subpixel, and a leaf is magnified smoothly (sampleSurfaceGraph is bilinear there).
// With the analysis' transfers (thesis §5.3) every site carries a cumulative colour offset R, as in
// the plane: bilinear from its four nearest parents on upsampling (the parent site and its surface
// neighbours toward the child's side; a missing one counts as the parent), neighbourhood estimates
// seen with the R of the neighbour they are predicted from, a candidate shown with its neighbour's
// R composed with its offset.
//
// Determinism: every coordinate is a pure function of (analysis, domain, options); the thread count
// changes nothing. Deviations: as synthesize_graph.h; CPU only (no Vulkan kernels yet); coordinates
// keep kSubpixelBits, so the packed atlas may be at most 4096 pixels a side (exemplars of 256 pixels
// with up to 16 nodes).

#include "core/context.h"
#include "synthesis/exemplar_graph.h"
#include "synthesis/synthesize_surface.h"

#include <cstdint>

namespace texfab::synthesis {

/// Throws texfab::Error unless a graph of `nodes` exemplars of `side` pixels packs into at most
/// 4096 pixels a side (what surface coordinates address); cheap, before the analysis.
void checkSurfaceGraphSize(int nodes, int side);

/// The graph synthesis level of the finest atlas texels, for `pixelsPerTexel` root pixels per texel.
int surfaceGraphOutputLevel(const GraphAnalysis& analysis, double pixelsPerTexel);

/// Synthesizes a subpixel atlas coordinate of `analysis` (kSubpixelBits) per site of
/// domain.levels[0]; options as synthesizeSurface's, jitter per stack level as
/// GraphSynthesisOptions::jitter. exemplarPixelsPerTexel: root pixels per texel; with the
/// analysis' transfers, colorOffsets: the RGB offset each site's colour is shown with (added to
/// sampleSurfaceGraph of analysis.colors, clamped; companion maps take none). Reports "level t/T"
/// stages.
SurfaceSynthesisResult synthesizeSurfaceGraph(const GraphAnalysis& analysis, const SurfaceDomain& domain,
                                              const SurfaceSynthesisOptions& options, const Context& ctx = {});

/// Channel `channel` (clamped to its channels) of `atlas` (the graph's colours, analysis.colors, or a
/// companion map's graphMapAtlas) at surface coordinate `coord`: bilinear (wrapped in the
/// coordinate's tile) at an exemplar's finest stack level, where a texel spans at most one pixel
/// (magnified past it); the nearest pixel at coarser levels, whose texels span h_k >= 2 pixels.
float sampleSurfaceGraph(const GraphAnalysis& analysis, const Image& atlas, uint32_t coord, int channel);

} // namespace texfab::synthesis
