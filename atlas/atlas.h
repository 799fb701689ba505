// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The atlas of a mesh, built in re-runnable stages (the staged API of xatlas):
//   segmentCharts (segment_charts.h) -> parameterizeCharts (parameterize_charts.h)
//   -> packCharts (pack_charts.h) -> texel fields, Jacobians and indirection maps.
// packCharts can be called again with other options without redoing the charts.
// Triangle order and count are those of the input mesh: faceChart and the corner arrays are
// indexed like mesh.triangles (corner c = 3 * t + k).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace texfab::atlas {

struct Chart {
  std::vector<uint32_t> faces; ///< ascending triangle ids
  double area = 0;             ///< surface area, model units²
  double boundaryLength = 0;   ///< length of the chart's border (seams + open mesh boundary), model units
  bool disk = false;           ///< topological disk (one boundary loop, Euler characteristic 1)
  // Parameterization (chart-local, model units, UV area == surface area):
  double l2Stretch = 0;  ///< Sander et al. 2001 L2 stretch of the chart
  double maxStretch = 0; ///< Sander et al. 2001 L∞ stretch (largest singular value)
  int flippedTriangles = 0;
  // Packing (atlas texels):
  int x = 0, y = 0;          ///< top-left corner of the chart's padded mask in the atlas
  int quarterTurns = 0;      ///< rotation applied at packing (multiples of 90°)
  int maskWidth = 0, maskHeight = 0;
};

/// Largest rounding error of a stored texel coordinate (a float in [0, max(width, height)]) of a
/// width×height atlas, in texels: half an ulp at the atlas size.
inline double texelUvRounding(int width, int height) { return std::ldexp(double(std::max(width, height)), -24); }

struct Atlas {
  std::vector<int32_t> faceChart;           ///< #T; -1 = degenerate triangle (no area, mapped to a point)
  std::vector<Chart> charts;                ///< ordered by their smallest triangle id (stable)
  std::vector<Eigen::Vector2d> chartUvs;    ///< 3·#T, chart-local coordinates in model units
  // Packing:
  int width = 0, height = 0;                ///< atlas size in texels
  double texelsPerUnit = 0;                 ///< texel density (texels per model unit)
  std::vector<Eigen::Vector2f> texelUvs;    ///< 3·#T, atlas position in texels (x right, y down; row 0 at top)

  double texelUvRounding() const { return atlas::texelUvRounding(width, height); }

  /// glTF/OBJ-style UV (v up, 0..1) of atlas texel position p.
  Eigen::Vector2f normalizedUv(const Eigen::Vector2f& p) const {
    return {p.x() / float(width), 1.0f - p.y() / float(height)};
  }
};

} // namespace texfab::atlas
