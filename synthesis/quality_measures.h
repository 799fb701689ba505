// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Quality measures of a synthesized texture against its exemplar (DESIGN.md, "Quality measures").
// Synthesis has no ground truth: these measure properties that good synthesis has and bad
// synthesis (noise, verbatim tiling, one region copied everywhere) lacks. Colour measures use the
// first three channels (or the grey channel); alpha is ignored. All values are deterministic.

#include "render/image/context.h"
#include "render/image/image.h"
#include "synthesis/coord_map.h"

#include <optional>
#include <span>

namespace texfab::synthesis {

struct FidelityOptions {
  int radius = 3;      ///< neighborhoods are (2*radius+1)^2: 7x7 by default
  int samples = 2048;  ///< output neighborhoods measured (a regular grid); 0 = all of them
};

/// Neighborhood fidelity: mean over output neighborhoods of the RMS difference (values in [0,1])
/// to the nearest exemplar neighborhood (toroidal), found by exact search. Lower is better.
/// Output neighborhoods must lie inside the image; the image needs 2*radius+1 texels per side.
double neighborhoodFidelity(const Image& image, const Image& exemplar, const FidelityOptions& options = {},
                            const Context& ctx = {});

/// Fidelity of neighborhoods gathered elsewhere (e.g. resampled from a surface texture in
/// exemplar space): `patches` holds (2*radius+1)^2 neighborhoods of the exemplar's colour channels
/// (3, or 1 for grey), row-major, channels interleaved, values in [0,1]. Same measure as above.
double patchFidelity(std::span<const float> patches, const Image& exemplar, int radius, const Context& ctx = {});

/// Histogram distance: the largest per-channel earth mover's distance between the value
/// histograms (256 bins over [0,1]) of the image and the exemplar, in value units. 0 = identical.
double histogramDistance(const Image& image, const Image& exemplar);

/// Coherence: fraction of horizontally and vertically adjacent texel pairs whose exemplar
/// coordinates are adjacent in the same direction (toroidally). 1 = verbatim tiling, ~0 = noise.
double coherence(const CoordMap& coords);

/// Coverage: fraction of exemplar pixels that at least one output texel uses.
double coverage(const CoordMap& coords);

/// Correlation of the image's luminance with itself shifted by (dx, 0) and by (0, dy): the larger
/// of the two Pearson correlations. 1 for an image that repeats with that period.
/// Throws if the image is not larger than the shift in both directions.
double shiftedSelfCorrelation(const Image& image, int dx, int dy);

/// All measures at once; coherence and coverage need the coordinate map.
struct QualityReport {
  double fidelity = 0;
  double histogramDistance = 0;
  double shiftedCorrelation = 0;
  std::optional<double> coherence;
  std::optional<double> coverage;
};
QualityReport measureQuality(const Image& image, const Image& exemplar, const CoordMap* coords,
                             const FidelityOptions& fidelity = {}, const Context& ctx = {});

} // namespace texfab::synthesis
