// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The arrangement of planes inside a box: the convex cells into which the planes divide it, as a
// cell complex (cell_complex.h). Cutting a model by several planes intersects the model once with
// these cells, instead of cutting the pieces of each cut again: no cut then meets the rounded
// corners of an earlier one.
//
// The box is split by one plane after another, every cell it crosses in two. Each polygonal face
// is stored once, so the faces of neighbouring cells are split at the same points; a cell vertex
// closer to a plane than 1e-10 of the box's diagonal counts as on it (no sliver cells). Polygons
// become triangles at the end, as fans around their centroid (never a zero-area triangle where
// points lie on a polygon's sides).

#include "geometry/fracture/cell_complex.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <span>
#include <vector>

namespace texfab::geometry {

struct CutPlane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< a point of the plane, model units
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); ///< need not be unit; points to the front side
};

/// Throws texfab::Error for a plane with a zero or non-finite normal, or a non-finite point.
void validatePlane(const CutPlane& plane);

struct PlaneArrangement {
  /// Cells in the order of their sides, plane 0 first: behind before in front (for two planes:
  /// behind both, behind 0 and in front of 1, in front of 0 and behind 1, in front of both).
  CellComplex complex;
  std::vector<int32_t> planeOf;  ///< per face: the plane it lies on, or -1 for the box's faces
};

/// The cells of `planes` (validated) within `bounds`. A plane that misses the box adds nothing.
PlaneArrangement planeArrangement(std::span<const CutPlane> planes, const Eigen::AlignedBox3d& bounds);

} // namespace texfab::geometry
