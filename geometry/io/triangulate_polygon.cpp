// SPDX-License-Identifier: GPL-3.0-or-later
// Polygon triangulation for the readers (OBJ, PLY, OFF faces with more than 3 corners).
#include "geometry/io/mesh_formats.h"

#include <Eigen/Geometry>

namespace texfab::geometry::detail {

std::vector<std::array<uint32_t, 3>> triangulatePolygon(const std::vector<Eigen::Vector3f>& p) {
  const size_t n = p.size();
  std::vector<std::array<uint32_t, 3>> out;
  auto fan = [&] {
    out.clear();
    for (uint32_t k = 1; k + 1 < n; ++k) out.push_back({0, k, k + 1});
    return out;
  };
  if (n < 3) return out;
  if (n == 3 || n > 64) return fan();
  // Newell normal, then a 2-D frame in the polygon's plane.
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  for (size_t i = 0; i < n; ++i) normal += p[i].cross(p[(i + 1) % n]);
  if (!(normal.squaredNorm() > 0) || !normal.allFinite()) return fan();
  normal.normalize();
  const Eigen::Vector3f u = (std::abs(normal.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY()).cross(normal).normalized();
  const Eigen::Vector3f v = normal.cross(u);
  std::vector<Eigen::Vector2d> q(n);
  for (size_t i = 0; i < n; ++i) q[i] = Eigen::Vector2d(double(p[i].dot(u)), double(p[i].dot(v)));
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  };
  std::vector<uint32_t> ring(n);
  for (uint32_t i = 0; i < n; ++i) ring[i] = i;
  while (ring.size() > 3) {
    bool clipped = false;
    for (size_t i = 0; i < ring.size() && !clipped; ++i) {
      const uint32_t a = ring[(i + ring.size() - 1) % ring.size()], b = ring[i], c = ring[(i + 1) % ring.size()];
      if (cross(q[a], q[b], q[c]) <= 0) continue;  // reflex or degenerate corner: not an ear
      bool empty = true;
      for (uint32_t r : ring) {
        if (r == a || r == b || r == c) continue;
        if (cross(q[a], q[b], q[r]) >= 0 && cross(q[b], q[c], q[r]) >= 0 && cross(q[c], q[a], q[r]) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.push_back({a, b, c});
      ring.erase(ring.begin() + std::ptrdiff_t(i));
      clipped = true;
    }
    if (!clipped) return fan();
  }
  out.push_back({ring[0], ring[1], ring[2]});
  return out;
}

} // namespace texfab::geometry::detail
