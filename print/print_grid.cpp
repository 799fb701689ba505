// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/print_grid.h"

#include "core/error.h"

#include <cmath>
#include <sstream>
#include <string>

namespace texfab::print {

namespace {

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void requireRange(double value, double lo, double hi, const char* name) {
  if (!(value > lo && value <= hi))  // false for NaN
    throw Error(std::string(name) + " must be in (" + number(lo) + ", " + number(hi) + "], got " + number(value));
}

// Whole voxels of `pitch` covering `extent`; a ratio within 1e-9 of an integer is that integer,
// so 50 mm at 0.05 mm is 1000 layers, not 1001.
int64_t cover(double extent, double pitch) {
  const double n = extent / pitch;
  const double nearest = std::round(n);
  return std::max<int64_t>(1, std::abs(n - nearest) <= 1e-9 * std::max(1.0, n) ? int64_t(nearest) : int64_t(std::ceil(n)));
}

} // namespace

namespace {

using geometry::UpAxis;

// Rows are the print axes in model coordinates: a proper rotation taking `up` to +z whose first row
// (the print's x) is a positive model axis.
Eigen::Matrix3d rotationFor(UpAxis up) {
  Eigen::Matrix3d r;
  switch (up) {
  case UpAxis::Z: r << 1, 0, 0, 0, 1, 0, 0, 0, 1; break;
  case UpAxis::NegZ: r << 1, 0, 0, 0, -1, 0, 0, 0, -1; break;
  case UpAxis::Y: r << 1, 0, 0, 0, 0, -1, 0, 1, 0; break;
  case UpAxis::NegY: r << 1, 0, 0, 0, 0, 1, 0, -1, 0; break;
  case UpAxis::X: r << 0, 1, 0, 0, 0, 1, 1, 0, 0; break;
  case UpAxis::NegX: r << 0, 1, 0, 0, 0, -1, -1, 0, 0; break;
  }
  return r;
}

} // namespace

void PrintGridOptions::validate() const {
  if (mmPerUnit == 0) requireRange(heightMm, 0, 1e4, "print height (mm)");
  else requireRange(mmPerUnit, 0, 1e6, "scale (mm per model unit)");
  requireRange(dpiX, 0, 1e5, "x resolution (dpi)");
  requireRange(dpiY, 0, 1e5, "y resolution (dpi)");
  requireRange(layerMm, 0, 10, "layer thickness (mm)");
}

PrintGrid printGrid(const geometry::BoundingBox& box, const PrintGridOptions& o) {
  o.validate();
  PrintGrid g;
  g.rotation = rotationFor(o.up);
  g.modelAxisOfX = g.rotation(0, 0) != 0 ? 0 : 1;
  const Eigen::Vector3d a = g.rotation * box.min.cast<double>(), b = g.rotation * box.max.cast<double>();
  const Eigen::Vector3d lo = a.cwiseMin(b), hi = a.cwiseMax(b);
  const Eigen::Vector3d extent = hi - lo;
  if (!extent.allFinite() || !(extent.minCoeff() > 0))
    throw Error("the model is flat or empty (bounding box " + number(extent.x()) + " x " + number(extent.y()) + " x " +
                number(extent.z()) + "): nothing to print");
  g.mmPerUnit = o.mmPerUnit > 0 ? o.mmPerUnit : o.heightMm / extent.z();
  g.pitchMm = {25.4 / o.dpiX, 25.4 / o.dpiY, o.layerMm};
  g.pitch = g.pitchMm / g.mmPerUnit;
  g.origin = lo;
  const Eigen::Vector3d sizeMm = extent * g.mmPerUnit;
  const int64_t n[3] = {cover(sizeMm.x(), g.pitchMm.x()), cover(sizeMm.y(), g.pitchMm.y()),
                        cover(sizeMm.z(), g.pitchMm.z())};
  static const char* const axes[3] = {"wide (x)", "deep (y)", "tall (layers)"};
  for (int a = 0; a < 3; ++a)
    if (n[a] > kMaxPrintPixels)
      throw Error("the print is " + std::to_string(n[a]) + " voxels " + axes[a] + ", more than the " +
                  std::to_string(kMaxPrintPixels) + " texfab accepts: lower the size or the resolution");
  g.width = int(n[0]);
  g.height = int(n[1]);
  g.layers = int(n[2]);
  return g;
}

} // namespace texfab::print
