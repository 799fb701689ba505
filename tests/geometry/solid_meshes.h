// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Closed meshes of known volume for the voxelization and slicing tests.

#include "geometry/mesh.h"

#include <array>
#include <cmath>

namespace texfab::test {

/// An axis-aligned box [lo, hi], 12 triangles, outward facing.
inline geometry::Mesh makeBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  geometry::Mesh m;
  for (int k = 0; k < 8; ++k)
    m.positions.push_back({k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z()});
  // Faces -x, +x, -y, +y, -z, +z, counter-clockwise seen from outside.
  const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    m.triangles.push_back({uint32_t(q[0]), uint32_t(q[1]), uint32_t(q[2])});
    m.triangles.push_back({uint32_t(q[0]), uint32_t(q[2]), uint32_t(q[3])});
  }
  return m;
}

/// A sphere of radius r around c: an octahedron subdivided `levels` times, vertices on the sphere.
inline geometry::Mesh makeIcoSphere(float r, int levels, const Eigen::Vector3f& c = {0, 0, 0}) {
  geometry::Mesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int l = 0; l < levels; ++l) {
    std::vector<std::array<uint32_t, 3>> next;
    auto mid = [&](uint32_t a, uint32_t b) {
      m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      return uint32_t(m.positions.size() - 1);
    };
    for (const auto& t : m.triangles) {
      const uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({ab, t[1], bc});
      next.push_back({ca, bc, t[2]});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  for (auto& p : m.positions) p = c + r * p;
  weldPositions(m);  // midpoints of shared edges were added twice
  return m;
}

/// Signed volume of a closed mesh (divergence theorem), in model units cubed.
inline double meshVolume(const geometry::Mesh& m) {
  double v = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    v += m.corner(t, 0).cast<double>().dot(m.corner(t, 1).cast<double>().cross(m.corner(t, 2).cast<double>())) / 6.0;
  return v;
}

/// Surface area, in model units squared.
inline double meshArea(const geometry::Mesh& m) {
  double a = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    a += 0.5 * (m.corner(t, 1) - m.corner(t, 0)).cast<double>().cross((m.corner(t, 2) - m.corner(t, 0)).cast<double>()).norm();
  return a;
}

} // namespace texfab::test
