// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The convex hull of 2-D points (A. M. Andrew, "Another efficient algorithm for convex hulls in
// two dimensions", 1979: the monotone chain). Used by packing and chart cutting to find a chart's
// minimal-area rectangle over the hull's edge directions.

#include <Eigen/Core>

#include <algorithm>
#include <span>
#include <vector>

namespace texfab::atlas {

/// Lexicographic order (x, then y): the order convexHullOfSorted() expects.
inline bool lexLess(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
}

/// Counter-clockwise hull vertices (collinear points dropped), starting from the lexicographically
/// smallest point, of points already sorted by lexLess.
inline std::vector<Eigen::Vector2d> convexHullOfSorted(std::span<const Eigen::Vector2d> points) {
  if (points.empty()) return {};
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = points.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0) --k;
    hull[k++] = points[i - 1];
  }
  hull.resize(k > 1 ? k - 1 : k);
  return hull;
}

/// The same for points in any order.
inline std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(), lexLess);
  return convexHullOfSorted(points);
}

} // namespace texfab::atlas
