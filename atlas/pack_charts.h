// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Packing: every chart at one texel density (texels per model unit) into a W×H atlas with at
// least `gutter` empty texels between any two charts; quarter-turn rotations allowed after each
// chart is turned to its minimal-area bounding rectangle. Packing places raster masks of the
// charts: the texels whose centers a chart covers (exactly those the atlas rasterizer gives it),
// dilated by half the gutter, so charts cannot overlap and gutters hold by construction; the
// density is the largest found to fit (a few packing passes, two at a time on two cores; the
// result does not depend on the thread count).
// Re-runnable: call again with other options without redoing charts or parameterizations.

#include "atlas/atlas.h"
#include "core/context.h"
#include "core/error.h"
#include "geometry/mesh.h"

#include <cstddef>
#include <string>
#include <utility>

namespace texfab::atlas {

/// The charts cannot fit the atlas size asked for. `which()` names the atlas of a job that has
/// several ("outer", "interior"), so that the command line can name the flag that sizes it.
class AtlasTooSmall : public Error {
public:
  explicit AtlasTooSmall(const std::string& message, std::string which = "atlas")
      : Error(message), which_(std::move(which)) {}
  const std::string& which() const { return which_; }

private:
  std::string which_;
};

struct PackChartsOptions {
  static constexpr int kMinSide = 16, kMaxSide = 16384, kMaxGutter = 64;
  /// Atlas size in texels (kMinSide .. kMaxSide). Both 0 with a texelsPerUnit: the smallest atlas
  /// that holds the charts at that density (about square, multiples of 4, not powers of two).
  int width = 2048;
  int height = 2048;
  int gutter = 4;            ///< minimum empty texels between two charts (0 .. kMaxGutter)
  bool powerOfTwo = true;    ///< require power-of-two width and height
  double texelsPerUnit = 0;  ///< fixed density; 0 = the largest that fits
  int maxPasses = 8;         ///< packing passes of the density search (>= 1; run in pairs)
  /// Fill holes left under earlier charts (bounded search per chart; deterministic). ~+8 %
  /// utilization on CGAL meshes for ~2× the packing time.
  bool holeFilling = true;

  void validate() const;
};

struct PackChartsReport {
  double texelsPerUnit = 0;
  int passes = 0;
  int usedHeight = 0;          ///< rows used by the packed charts (<= height)
  size_t maskTexels = 0;        ///< texels of the packed masks (charts + half gutters): the packer's fill
  size_t chartsBelowOneTexel = 0; ///< charts whose extent is under one texel at the chosen density
  /// Thin charts (4:1 or more) longer than the atlas side at the density of a perfect packing (a
  /// sliver a cut left, a long strip), laid out smaller to fit: coarser texels there instead of
  /// everywhere.
  size_t chartsShrunk = 0;
};

/// Fills atlas.width/height/texelsPerUnit/texelUvs and each chart's placement. Throws
/// texfab::Error when the charts cannot fit (e.g. more charts than the resolution can hold).
PackChartsReport packCharts(const geometry::Mesh& mesh, Atlas& atlas, const PackChartsOptions& options = {},
                            const Context& ctx = {});

} // namespace texfab::atlas
