// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The texture stretch metric of P. Sander, J. Snyder, S. Gortler, H. Hoppe, "Texture Mapping
// Progressive Meshes", SIGGRAPH 2001: for the affine map S from a triangle's UV to its 3D
// position, with Jacobian columns Ss, St, the singular values are Γ (largest) and γ; the L2
// stretch is sqrt((Γ² + γ²) / 2), the L∞ stretch Γ. Over a surface, L2 = sqrt(Σ L2(T)² A(T) / Σ A(T))
// with A the surface area. Both are normalized so that the total UV area equals the surface area
// (multiplied by sqrt(Σ A_uv / Σ A)), so 1 is an isometry up to scale.

#include "geometry/mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <vector>

namespace texfab::atlas {

struct TriangleStretch {
  double uvArea = 0; ///< signed UV area (counter-clockwise positive, v up)
  double gammaMax = 0, gammaMin = 0, l2 = 0;
};

/// Stretch of one triangle: 3D corners q, UV corners p (v up).
inline TriangleStretch triangleStretch(const Eigen::Vector3d q[3], const Eigen::Vector2d p[3]) {
  TriangleStretch r;
  r.uvArea = 0.5 * ((p[1].x() - p[0].x()) * (p[2].y() - p[0].y()) - (p[2].x() - p[0].x()) * (p[1].y() - p[0].y()));
  if (r.uvArea == 0) {
    r.gammaMax = r.gammaMin = r.l2 = std::numeric_limits<double>::infinity();
    return r;
  }
  const double a2 = 2 * r.uvArea;
  const Eigen::Vector3d ss = (q[0] * (p[1].y() - p[2].y()) + q[1] * (p[2].y() - p[0].y()) + q[2] * (p[0].y() - p[1].y())) / a2;
  const Eigen::Vector3d st = (q[0] * (p[2].x() - p[1].x()) + q[1] * (p[0].x() - p[2].x()) + q[2] * (p[1].x() - p[0].x())) / a2;
  const double a = ss.dot(ss), b = ss.dot(st), c = st.dot(st);
  const double root = std::sqrt((a - c) * (a - c) + 4 * b * b);
  r.gammaMax = std::sqrt(std::max(0.0, 0.5 * (a + c + root)));
  r.gammaMin = std::sqrt(std::max(0.0, 0.5 * (a + c - root)));
  r.l2 = std::sqrt(0.5 * (a + c));
  return r;
}

struct StretchStats {
  double l2 = 1;          ///< normalized area-weighted L2 stretch
  double max = 1;         ///< normalized largest Γ
  double surfaceArea = 0;
  double uvArea = 0;      ///< unsigned
  size_t flipped = 0;     ///< non-degenerate triangles with UV area <= 0 (beyond the rounding)
  /// Triangles whose UV area is within the rounding of their UVs (|2 A_uv| <= 4 ρ · perimeter,
  /// ρ = uvRounding): mapped to a line, neither flipped nor counted in the stretch.
  size_t collapsed = 0;
};

/// Whether a triangle with UV corners p is within the rounding ρ of its coordinates of having no
/// area (each coordinate moved by up to ρ moves twice the area by at most ~2√2 ρ · perimeter).
inline bool collapsedUv(const Eigen::Vector2d p[3], double uvArea, double rounding) {
  const double perimeter = (p[1] - p[0]).norm() + (p[2] - p[1]).norm() + (p[0] - p[2]).norm();
  return rounding > 0 && std::abs(2 * uvArea) <= 4 * rounding * perimeter;
}

/// Stretch over `faces` (all triangles when empty) with per-corner UVs given by uvOf(corner)
/// (any Eigen 2-vector, v up). Triangles with zero surface area are skipped; `uvRounding` (UV
/// units) is the rounding of the UVs as stored (0: exact), see StretchStats::collapsed.
template <class UvOf>
StretchStats measureStretch(const geometry::Mesh& mesh, const std::vector<uint32_t>& faces, UvOf&& uvOf,
                            double uvRounding = 0) {
  StretchStats s;
  double sum = 0, maxRaw = 0;
  const size_t count = faces.empty() ? mesh.triangleCount() : faces.size();
  for (size_t i = 0; i < count; ++i) {
    const size_t t = faces.empty() ? i : faces[i];
    Eigen::Vector3d q[3];
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) {
      q[k] = mesh.corner(t, k).cast<double>();
      p[k] = uvOf(3 * t + size_t(k)).template cast<double>();
    }
    const double area = 0.5 * (q[1] - q[0]).cross(q[2] - q[0]).norm();
    if (!(area > 0)) continue;
    const TriangleStretch ts = triangleStretch(q, p);
    s.surfaceArea += area;
    s.uvArea += std::abs(ts.uvArea);
    if (collapsedUv(p, ts.uvArea, uvRounding)) {
      ++s.collapsed;
      continue;
    }
    if (!(ts.uvArea > 0)) {
      ++s.flipped;
      maxRaw = std::numeric_limits<double>::infinity();
      sum = std::numeric_limits<double>::infinity();
      continue;
    }
    sum += ts.l2 * ts.l2 * area;
    maxRaw = std::max(maxRaw, ts.gammaMax);
  }
  if (s.surfaceArea > 0) {
    const double norm = std::sqrt(s.uvArea / s.surfaceArea);
    s.l2 = std::sqrt(sum / s.surfaceArea) * norm;
    s.max = maxRaw * norm;
  }
  return s;
}

} // namespace texfab::atlas
