// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Quality measures of a synthesized texture against its exemplar (docs/design.md#quality-measures).
// Synthesis has no ground truth: these measure properties that good synthesis has and bad
// synthesis (noise, verbatim tiling, one region copied everywhere) lacks. Colour measures use the
// first three channels (or the grey channel); alpha is ignored. All values are deterministic.

#include "core/context.h"
#include "core/image.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"

#include <optional>
#include <span>
#include <vector>

namespace texfab::synthesis {

struct FidelityOptions {
  int radius = 3;      ///< neighborhoods are (2*radius+1)^2: 7x7 by default
  int samples = 2048;  ///< neighborhoods measured on a regular grid (the image's; completeness: the exemplar's); 0 = all
  bool toroidal = true; ///< exemplar neighborhoods wrap; false: only those wholly inside it (a photograph)
  /// Structure only: each neighbourhood's mean colour is removed on both sides, so that a colour
  /// offset constant over a neighbourhood costs nothing (graph synthesis' transfers, exposure).
  bool removeMean = false;
};

/// Neighborhood fidelity: mean over output neighborhoods of the RMS difference (values in [0,1])
/// to the nearest exemplar neighborhood (toroidal, or inside only), found by exact search. Lower is better.
/// Output neighborhoods must lie inside the image; the image needs 2*radius+1 texels per side.
double neighborhoodFidelity(const Image& image, const Image& exemplar, const FidelityOptions& options = {},
                            const Context& ctx = {});

/// Neighborhood completeness, the reverse direction of fidelity: mean over exemplar neighborhoods
/// (about `samples` on a regular grid; toroidal, or wholly inside) of the RMS difference to the
/// nearest neighborhood wholly inside the image, by exact search. Lower is better. Fidelity alone
/// favours flat images (a flat one matches the exemplar's flat regions); completeness asks that
/// the image show all of the exemplar, its dark cracks and bright speckles too. Together they are
/// the bidirectional similarity of Simakov et al. 2008, "Summarizing visual data using
/// bidirectional similarity".
double neighborhoodCompleteness(const Image& image, const Image& exemplar, const FidelityOptions& options = {},
                                const Context& ctx = {});

/// Fidelity of neighborhoods gathered elsewhere (e.g. resampled from a surface texture in
/// exemplar space): `patches` holds (2*radius+1)^2 neighborhoods of the exemplar's colour channels
/// (3, or 1 for grey), row-major, channels interleaved, values in [0,1]. Same measure as above
/// (options.samples unused).
double patchFidelity(std::span<const float> patches, const Image& exemplar, const FidelityOptions& options = {},
                     const Context& ctx = {});

/// Histogram distance: the largest per-channel earth mover's distance between the value
/// histograms (256 bins over [0,1]) of the image and the exemplar, in value units. 0 = identical.
double histogramDistance(const Image& image, const Image& exemplar);

/// Coherence: fraction of horizontally and vertically adjacent texel pairs whose exemplar
/// coordinates are adjacent in the same direction (toroidally). 1 = verbatim tiling, ~0 = noise.
double coherence(const CoordMap& coords);

/// Wrap crossings: adjacent texel pairs whose exemplar coordinates are adjacent only through the
/// exemplar's wrap (toroidal distance at most 2 pixels per axis, plain distance more): the pairs
/// that show the exemplar's opposite borders side by side. 0 for a non-toroidal synthesis.
int64_t wrapCrossings(const CoordMap& coords);

/// Seam visibility: the mean luminance jump between adjacent texels whose exemplar coordinates
/// are not adjacent in the same direction (without wrap: a wrap crossing is a seam), over the mean
/// jump between adjacent pixels inside the exemplar (no wrap). About 1 when seams look like the
/// exemplar's own edges; larger when they show (a photograph's dark edge against its bright one).
/// 0 when the map has no seam. `exemplar` is the image the coordinates index.
double seamVisibility(const CoordMap& coords, const Image& exemplar);

/// Coverage: fraction of exemplar pixels that at least one output texel uses.
double coverage(const CoordMap& coords);

/// Correlation of the image's luminance with itself shifted by (dx, 0) and by (0, dy): the larger
/// of the two Pearson correlations. 1 for an image that repeats with that period.
/// Throws if the image is not larger than the shift in both directions.
double shiftedSelfCorrelation(const Image& image, int dx, int dy);

/// The largest shiftedSelfCorrelation at `period` and its multiples below half the image's smaller
/// side: how strongly the image repeats with that period (0 when it does not; 0 when no multiple fits).
double latticeCorrelation(const Image& image, int period);

/// Steps across a lattice of planes `period` pixels apart (solid tiles' faces) on an image whose
/// pixel (x, y) lies at lattice position (originX + x, originY + y): the mean colour step (summed
/// over the colour channels) between neighbouring pixels, horizontal and vertical together, by the
/// offset k within the period of the pixel it starts at.
struct LatticeSteps {
  std::vector<double> meanStep;  ///< period values, k = 0 .. period - 1
  /// The mean step into and out of a lattice plane (k = period - 1 and 0) over the mean step at
  /// the other offsets: about 1 when the planes do not show.
  double seamRatio() const;
  /// The largest mean step at any offset over the median offset's: a step off the planes too.
  double peak() const;
};
/// Throws if period < 3 (no offset would be off the planes).
LatticeSteps latticeSteps(const Image& image, int period, int64_t originX, int64_t originY);

/// Luminance contrast ratio: the standard deviation of the image's luminance over the
/// exemplar's. Near 1 keeps the exemplar's contrast; below 1 is washed out. NaN if the exemplar
/// is flat.
double contrastRatio(const Image& image, const Image& exemplar);

/// All measures at once; coherence and coverage need the coordinate map.
struct QualityReport {
  double fidelity = 0;
  /// neighborhoodCompleteness() in the image's centre, at most twice the exemplar's size per side
  /// (the exact search over all of a large image's windows would take minutes).
  double completeness = 0;
  double histogramDistance = 0;
  double contrast = 0;  ///< contrastRatio()
  double shiftedCorrelation = 0;
  std::optional<double> coherence;
  std::optional<double> coverage;
};
/// Peak memory of measureQuality on these images, in bytes, beyond the images themselves (meant as
/// an upper bound): the exemplar's 8-bit neighborhoods searched for fidelity, the image crop's
/// searched for completeness (the larger phase), and the sampled neighborhoods of each.
double measureQualityMemoryBytes(const Image& image, const Image& exemplar, const FidelityOptions& fidelity);

QualityReport measureQuality(const Image& image, const Image& exemplar, const CoordMap* coords,
                             const FidelityOptions& fidelity = {}, const Context& ctx = {});

/// The measures of a 2-D synthesis (synthesize2d, default options, seed 1) of width x height from
/// `analysis` of `exemplar`: the baseline a solid texture's slices are held to (a slice should keep
/// the exemplar as well as 2-D synthesis does; docs/design.md#quality-measures). Deterministic.
QualityReport measureSynthesisBaseline(const ExemplarAnalysis& analysis, const Image& exemplar, int width, int height,
                                       const FidelityOptions& fidelity = {}, const Context& ctx = {});

} // namespace texfab::synthesis
