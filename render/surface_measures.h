// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Quality measures of a texture synthesized over a surface (docs/design.md#quality-measures):
// continuity across chart seams, uniformity of the texture's scale on the surface, and
// neighborhood fidelity measured in exemplar space. All take the finest level of the surface
// domain (atlas/surface_domain.h) and are deterministic.

#include "atlas/rasterize_atlas.h"
#include "core/context.h"
#include "core/image.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_surface.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace texfab::render {

/// Mean colour difference (mean absolute over the colour channels) between surface-adjacent
/// texels (the 4 axis steps of the domain's neighbor table) across chart seams, divided by the
/// same within charts. Near 1: the seams do not show.
struct SeamMeasure {
  double ratio = 0;
  double seamDifference = 0;
  double interiorDifference = 0;
  size_t seamPairs = 0;
  size_t interiorPairs = 0;
};
SeamMeasure measureSeams(const synthesis::SurfaceLevel& finest, const Image& atlasImage);

/// The texture's scale on the surface, from the (subpixel) coordinate map: at each chart texel,
/// exemplar pixels per model unit, the median of |Δc| / |ΔP| over the coherent adjacent pairs of
/// its 5x5 window (the median ignores the small slips where two patches meet). A pair is coherent when its coordinate step is at most 2·requested + 1.5
/// pixels (not a jump between patches); a texel with fewer than 8 coherent pairs counts as not
/// measured, and so as not within the tolerance.
struct ScaleMeasure {
  double medianPixelsPerUnit = 0;
  double fractionWithin = 0;   ///< of chart texels (equal area at the atlas's uniform density)
  double fractionMeasured = 0;
  double tolerance = 0.15;
};
ScaleMeasure measureScale(const synthesis::SurfaceLevel& finest, const std::vector<uint32_t>& coords,
                          const atlas::AtlasFields& fields, int exemplarWidth, int exemplarHeight,
                          double requestedPixelsPerUnit, double tolerance = 0.15);

/// Neighborhood fidelity in exemplar space (synthesis/quality_measures.h): at up to
/// options.samples chart texels spread over the atlas, the exemplar-space neighborhood of
/// options.radius is resampled from the atlas image (bilinear, at p + J⁻¹(i, j)); neighborhoods
/// that leave their chart are skipped.
struct SurfaceFidelity {
  double fidelity = 0;
  size_t samples = 0;
};
SurfaceFidelity measureSurfaceFidelity(const synthesis::SurfaceLevel& finest, const Image& atlasImage,
                                       const Image& exemplar, const atlas::AtlasFields& fields,
                                       const synthesis::FidelityOptions& options = {.samples = 1024},
                                       const Context& ctx = {});

} // namespace texfab::render
