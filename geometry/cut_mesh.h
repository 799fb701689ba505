// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Planar cuts of solids: every solid a plane crosses splits into its parts behind and in front of
// the plane, each closed by the cut (capped); planes apply in turn, to every piece so far. The
// half-spaces of a plane are a two-cell complex (cell_complex.h) intersected with each solid
// (intersect_cells.h), so the two parts share their cut exactly. The same call re-cuts the pieces
// of an earlier cut or fracture.

#include "geometry/cell_complex.h"
#include "geometry/intersect_cells.h"
#include "geometry/mesh.h"
#include "render/image/context.h"

#include <Eigen/Geometry>

#include <span>
#include <vector>

namespace texfab::geometry {

struct CutPlane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< a point of the plane, model units
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); ///< need not be unit; points to the front side
};

/// The two half-spaces of `plane` within `bounds`: cell 0 behind the plane, cell 1 in front;
/// face 0 is the section of the box, oriented along the normal. Throws texfab::Error for a zero
/// or non-finite normal, or a plane that misses the box.
CellComplex halfSpaces(const CutPlane& plane, const Eigen::AlignedBox3d& bounds);

struct CutMeshResult {
  /// Per input solid that no plane crosses: the solid itself (source = identity); the others'
  /// parts. Ordered by input solid, then behind before in front, plane by plane.
  std::vector<CellPiece> pieces;
  std::vector<int> inputOf;               ///< per piece: the input solid it comes from
  std::vector<std::vector<int32_t>> cut;  ///< per piece and triangle: the plane that made it, or -1
  std::vector<int> missed;                ///< planes that cross no solid
  IntersectCellsReport intersect;
};

/// Cuts the closed solids (repairSolid) by the planes in turn. `options.cutTag`/`cutMaterial` go
/// to the new faces; the faces of the input keep theirs.
CutMeshResult cutMesh(std::span<const Mesh> solids, std::span<const CutPlane> planes,
                      const IntersectCellsOptions& options = {}, const Context& ctx = {});

} // namespace texfab::geometry
