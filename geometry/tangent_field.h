// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A smooth unit tangent field on a triangle mesh, one vector per vertex (perpendicular to the
// vertex normal). Either a user direction ("up") projected to the tangent planes and smoothed, or
// the smoothed direction of minimum principal curvature (a line field: its sign is made consistent
// where possible). Singularities (where the field turns around a triangle) are allowed and
// reported with their index.

#include "geometry/mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace texfab::geometry {

enum class TangentFieldKind {
  Direction, ///< follow `direction` projected to the tangent plane
  Curvature, ///< follow the minimum principal curvature direction (ridges, cylinder axes)
};

struct TangentFieldOptions {
  TangentFieldKind kind = TangentFieldKind::Direction;
  Eigen::Vector3f direction{0.0f, 1.0f, 0.0f}; ///< model space; any non-zero length
  /// Weight of smoothness against fidelity to the target directions (> 0). Larger: smoother,
  /// further from the targets. 1 smooths over a few rings.
  double smoothness = 1.0;

  void validate() const;
};

struct TangentField {
  std::vector<Eigen::Vector3f> tangents; ///< #V unit vectors (zero for unused vertices)
  std::vector<Eigen::Vector3f> normals;  ///< #V unit area-weighted vertex normals
  std::vector<uint32_t> singularTriangles; ///< triangles around which the field turns
  std::vector<float> singularIndex;        ///< their indices (±1 for vector fields, ±1/2 for line fields)
  double totalIndex() const {
    double s = 0;
    for (float i : singularIndex) s += i;
    return s;
  }
  /// Unit tangent at barycentrics (b1, b2) of triangle t, projected to the triangle's plane.
  Eigen::Vector3f at(const Mesh& mesh, size_t t, float b1, float b2) const;
};

/// Solves one sparse Hermitian system over the vertices (Eigen conjugate gradients).
TangentField computeTangentField(const Mesh& mesh, const TangentFieldOptions& options = {});

} // namespace texfab::geometry
