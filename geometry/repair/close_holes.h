// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Closing the holes of a nearly closed mesh, as a print needs a closed surface: every boundary
// loop (after merging vertices at equal positions) is closed by a fan of triangles around a new
// vertex at the loop's centroid, oriented like the triangles around the hole. The fan of a
// non-planar loop may cross other triangles; the non-zero winding rule of the voxelizer takes the
// union, so the print is still well defined.
//
// Only simple loops are closed (each boundary vertex starts and ends one boundary edge); a mesh
// with boundary vertices shared by several loops, or with flipped triangles (edges matched by an
// edge running the same way), is left as it is, for the caller to refuse.

#include "geometry/mesh.h"

#include <cstddef>

namespace texfab::geometry {

struct CloseHolesReport {
  size_t holes = 0;          ///< loops closed
  size_t boundaryEdges = 0;  ///< edges around them
  bool closed = false;       ///< every edge is now matched by one running the other way
};

/// Closes the holes of `mesh` in place (welding vertices at equal positions first; per-corner
/// attributes of the new triangles copy the hole's edge's corners, face attributes its triangle's).
CloseHolesReport closeHoles(Mesh& mesh);

} // namespace texfab::geometry
