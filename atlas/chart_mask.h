// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A chart's footprint for packing: the chart turned to its minimal-area bounding rectangle
// (H. Freeman, R. Shapira, "Determining the minimum-area encasing rectangle for an arbitrary
// closed curve", CACM 1975: rotating calipers over the convex hull), then rasterized at a density
// into the texels whose centers it covers (exactly those the atlas rasterizer gives it), dilated by
// half the gutter, with the profiles and row spans a packer needs in each quarter turn.

#include "atlas/atlas.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace texfab::atlas {

/// A chart turned to its minimal-area bounding rectangle, long side along x.
struct OrientedChart {
  std::vector<Eigen::Vector2d> corners; ///< 3 per face (chart.faces order), min at (0, 0), v up
  Eigen::Vector2d extent{0, 0};         ///< size of the bounding rectangle (chart units)
};

/// Turns `chart` (its atlas.chartUvs) by a rotation: orientation is kept.
OrientedChart orientChart(const Atlas& atlas, const Chart& chart);

/// The raster footprint of an oriented chart. Quarter turn q maps mask texel (x, y) to
///   q = 1: (h-1-y, x); q = 2: (w-1-x, h-1-y); q = 3: (y, w-1-x).
struct ChartMask {
  using Spans = std::vector<std::pair<int, int>>;
  int w = 0, h = 0;           ///< size in texels (unturned)
  int origin = 0;             ///< texels between the mask's edge and the chart's rectangle
  std::vector<uint8_t> bits;  ///< w×h, row-major: covered texel centers, dilated
  // Per quarter turn: its width, top[x] the first occupied row of column x and bottom[x] the last
  // occupied row + 1 (top = height, bottom = INT_MIN for an empty column), the largest bottom,
  // and the occupied spans [a, b) of each row.
  std::array<int, 4> width{}, maxBottom{};
  std::array<std::vector<int>, 4> top, bottom;
  std::array<std::vector<Spans>, 4> spans;

  int heightAt(int q) const { return (q % 2) ? w : h; }
  size_t texels() const;
};

/// Rasterizes `chart` at `density` texels per unit, dilated by `pad` texels (Chebyshev).
/// `rounding`: the rounding of the stored texel coordinates (texelUvRounding), in texels: a
/// triangle that may collapse to zero area there reserves every texel it could claim.
ChartMask rasterizeChartMask(const OrientedChart& chart, double density, int pad, double rounding);

} // namespace texfab::atlas
