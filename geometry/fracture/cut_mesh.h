// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Planar cuts of solids: every solid the planes cross splits into its parts in the cells of their
// arrangement (plane_arrangement.h), each closed by the cuts (capped). All cuts of a solid come
// from one intersection with those cells (intersect_cells.h), so neighbouring parts share their
// cut exactly and no cut meets the rounded corners of another. The same call re-cuts the pieces
// of an earlier cut or fracture.

#include "core/context.h"
#include "geometry/fracture/intersect_cells.h"
#include "geometry/fracture/plane_arrangement.h"
#include "geometry/mesh.h"

#include <span>
#include <vector>

namespace texfab::geometry {

struct CutMeshResult {
  /// Per input solid that no plane crosses: the solid itself (source = identity); the others'
  /// parts, ordered as the cells of the arrangement (behind before in front, plane by plane).
  std::vector<CellPiece> pieces;
  std::vector<int> inputOf;               ///< per piece: the input solid it comes from
  std::vector<std::vector<int32_t>> cut;  ///< per piece and triangle: the plane that made it, or -1
  std::vector<int> missed;                ///< planes that cross no solid
  IntersectCellsReport intersect;
};

/// Cuts the closed solids (repairSolid) by the planes. `options.cutTag`/`cutMaterial` go
/// to the new faces; the faces of the input keep theirs.
CutMeshResult cutMesh(std::span<const Mesh> solids, std::span<const CutPlane> planes,
                      const IntersectCellsOptions& options = {}, const Context& ctx = {});

} // namespace texfab::geometry
