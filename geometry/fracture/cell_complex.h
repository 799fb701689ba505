// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A partition of a region of space into closed polyhedral cells that share their faces exactly.
// Every face between two cells is stored once, as triangles over shared vertices, with the cells
// on its two sides; a cell's boundary is the set of faces that name it. Cut and fracture build
// one (half-spaces of a plane, Voronoi cells) and intersect a model with its cells
// (intersect_cells.h): since neighbouring cells are bounded by the very same triangles, the
// pieces fit together exactly, whatever the rounding of the cells' vertices.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace texfab::geometry {

struct CellFace {
  /// Indices into CellComplex::vertices, counter-clockwise seen from `outer`: the normals point
  /// out of `inner`.
  std::vector<std::array<uint32_t, 3>> triangles;
  int32_t inner = -1;  ///< the cell whose outward boundary the triangles are, as stored
  int32_t outer = -1;  ///< the cell on the other side; -1: outside the complex
};

/// The closed surface of a group of cells: the faces with exactly one side in the group, each
/// oriented outward of the group.
struct CellSurface {
  std::vector<Eigen::Vector3d> vertices;          ///< only those the triangles use
  std::vector<std::array<uint32_t, 3>> triangles; ///< counter-clockwise seen from outside
  std::vector<uint32_t> face;                     ///< per triangle: its CellFace index
};

struct CellComplex {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<CellFace> faces;
  int cells = 0;

  /// The boundary of the union of `group` (cell indices, each at most once).
  CellSurface surfaceOf(std::span<const int> group) const;
};

} // namespace texfab::geometry
