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

/// Calls fn(d, n, along, across) for each hull edge direction d (unit), its normal n, and the
/// hull's extents along d and along n: the candidate rectangles of a minimal-area bounding
/// rectangle (one of them has a side on a hull edge).
template <class Fn> void forEachHullEdgeRectangle(const std::vector<Eigen::Vector2d>& hull, Fn&& fn) {
  for (size_t i = 0; i < hull.size(); ++i) {
    Eigen::Vector2d d = hull[(i + 1) % hull.size()] - hull[i];
    if (!(d.norm() > 0)) continue;
    d.normalize();
    const Eigen::Vector2d n(-d.y(), d.x());
    double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
    for (const auto& h : hull) {
      a0 = std::min(a0, h.dot(d)), a1 = std::max(a1, h.dot(d));
      b0 = std::min(b0, h.dot(n)), b1 = std::max(b1, h.dot(n));
    }
    fn(d, n, a1 - a0, b1 - b0);
  }
}

} // namespace texfab::atlas
