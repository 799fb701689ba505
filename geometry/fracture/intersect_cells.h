// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The pieces of a closed mesh cut by the cells of a cell complex: each piece is the solid the mesh
// bounds intersected with a group of cells, as a closed, consistently oriented manifold mesh made
// of the mesh's own triangles (split where the cells cut them, carrying their UVs, normals,
// tangents, materials and tags) and of the parts of the cells' faces inside the mesh: the new cut
// faces, tagged. Neighbouring pieces share their cut surfaces exactly (cell_complex.h), so the
// pieces' volumes add up to the mesh's and no two pieces overlap.
//
// Robustness comes from CGAL's corefinement (exact predicates, intersection points constructed
// exactly and rounded once, so both sides of a cut get the same points) and from classifying every
// patch by exact orientation tests around an intersection edge; coplanar contacts are resolved.

#include "core/context.h"
#include "geometry/fracture/cell_complex.h"
#include "geometry/mesh.h"

#include <cstdint>
#include <span>
#include <vector>

namespace texfab::geometry {

struct IntersectCellsOptions {
  uint32_t cutTag = 1;       ///< faceTags value given to the new cut faces
  uint32_t cutMaterial = 0;  ///< faceMaterials value given to the new cut faces (the caller adds the material)
};

struct CellPiece {
  /// Closed, outward oriented; in the input's frame. Attribute arrays are present when the input
  /// has them; cut faces get flat normals, zero UVs and tangents, `cutMaterial` and `cutTag`.
  Mesh mesh;
  std::vector<int32_t> source;   ///< per triangle: the input triangle it is (part of), or -1 for a new cut face
  std::vector<int32_t> cutFace;  ///< per triangle: the CellFace a new cut face lies on, or -1
  std::vector<int> cells;        ///< the group of cells
};

struct IntersectCellsReport {
  size_t corefinedTriangles = 0;  ///< input triangles near a cell's surface, corefined (summed over groups)
  size_t keptWhole = 0;           ///< input triangles kept or dropped without corefinement (summed)
};

/// One piece per group of cells (each group a set of cell indices; a piece may be empty, or have
/// several connected components). `solid` must be a closed, consistently oriented manifold
/// without self-intersections (repairSolid); throws texfab::Error when it is not closed, and when
/// a piece comes out open (which would be a bug). Deterministic; groups run in parallel.
std::vector<CellPiece> intersectCells(const Mesh& solid, const CellComplex& complex,
                                      std::span<const std::vector<int>> groups, const IntersectCellsOptions& options = {},
                                      const Context& ctx = {}, IntersectCellsReport* report = nullptr);

} // namespace texfab::geometry
