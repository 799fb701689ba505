// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The voxel grid of a print: how a model, scaled to millimetres, is cut into layers (z) and each
// layer into pixels (x, y) at the printer's resolution. Material-jetting printers take one image
// per layer; every image has the grid's width x height pixels, and layer k is sampled on the plane
// through the centres of its voxels.

#include "geometry/mesh.h"
#include "geometry/up_axis.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>

namespace texfab::print {

struct PrintGridOptions {
  /// Height of the print (its z extent) in mm; (0, 10000]. Used when mmPerUnit is 0.
  double heightMm = 50.0;
  /// Millimetres per model unit; 0 = derived from heightMm. (0, 1e6] otherwise.
  double mmPerUnit = 0.0;
  /// Printer resolution in dots per inch along x and y; (0, 100000]. PolyJet printers: 600 x 300
  /// (x along the print heads' travel) or 600 x 600.
  double dpiX = 600.0;
  double dpiY = 300.0;
  /// Layer thickness in mm; (0, 10]. Stratasys J-series: 0.027 (high quality) or 0.014.
  double layerMm = 0.027;
  geometry::UpAxis up = geometry::UpAxis::Z;  ///< the model axis along which layers stack

  /// Throws texfab::Error naming the first field out of range (NaN and infinities included).
  void validate() const;
};

/// The grid: `layers` images of `width` x `height` pixels, in the print frame (the model rotated so
/// that its up axis is +z; model units). Voxel (x, y, layer) spans [origin + (x, y, layer) * pitch,
/// origin + (x + 1, y + 1, layer + 1) * pitch) there; image row r holds y = height - 1 - r (images
/// show the layer from above, +y up).
struct PrintGrid {
  int width = 0, height = 0, layers = 0;
  double mmPerUnit = 1.0;
  Eigen::Vector3d pitchMm{0, 0, 0};   ///< voxel size in mm (x, y, z)
  Eigen::Vector3d pitch{0, 0, 0};     ///< voxel size in model units
  Eigen::Vector3d origin{0, 0, 0};    ///< print-frame coordinates of the grid's minimum corner
  /// print = rotation * model: a signed permutation (det 1) that takes the up axis to +z and the
  /// print's x axis to a positive model axis (modelAxisOfX).
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  int modelAxisOfX = 0;

  /// Print-frame coordinate of the centres of column x, row index y, layer z.
  double centerX(int x) const { return origin.x() + (double(x) + 0.5) * pitch.x(); }
  double centerY(int y) const { return origin.y() + (double(y) + 0.5) * pitch.y(); }
  double centerZ(int layer) const { return origin.z() + (double(layer) + 0.5) * pitch.z(); }
  /// Model coordinates of the centre of voxel (x, y, layer).
  Eigen::Vector3d center(int x, int y, int layer) const {
    return rotation.transpose() * Eigen::Vector3d(centerX(x), centerY(y), centerZ(layer));
  }
  int64_t voxelsPerLayer() const { return int64_t(width) * height; }
  int64_t voxels() const { return voxelsPerLayer() * layers; }
  /// Size of the print in mm.
  Eigen::Vector3d sizeMm() const { return {width * pitchMm.x(), height * pitchMm.y(), layers * pitchMm.z()}; }
};

/// Largest accepted number of pixels per layer side and of layers.
inline constexpr int kMaxPrintPixels = 1 << 20;

/// The grid covering `box` (model units) turned up: scale from options.mmPerUnit, or from heightMm
/// over the extent along the up axis; just enough whole voxels to cover the box, starting at its
/// minimum corner.
/// Throws texfab::Error for invalid options, an empty or flat box, or a grid beyond
/// kMaxPrintPixels per side.
PrintGrid printGrid(const geometry::BoundingBox& box, const PrintGridOptions& options);

} // namespace texfab::print
