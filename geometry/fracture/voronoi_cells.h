// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The Voronoi cells of a set of sites as a cell complex (cell_complex.h): the faces between cells
// are the duals of the Delaunay edges, their vertices the circumcentres of the Delaunay
// tetrahedra, each computed once and shared by every face that uses it. Optionally the faces get a
// relief (rough cracks): subdivided and displaced by a hashed noise, identically for the two cells
// they separate, so that the cells still fit exactly.

#include "geometry/fracture/cell_complex.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <span>

namespace texfab::geometry {

struct VoronoiCellsOptions {
  /// Relief of the faces between cells, as the amplitude of their displacement over the mean
  /// distance between neighbouring sites; 0 = flat faces. [0, 0.25]. Faces are subdivided into
  /// triangles of about 1/12 of that distance; a face whose relief would make a cell intersect
  /// itself stays flat.
  double roughness = 0;
  uint32_t seed = 1;  ///< of the relief
};

struct VoronoiCellsReport {
  double meanSpacing = 0;   ///< mean length of the Delaunay edges between sites, model units
  size_t faces = 0;         ///< faces between cells (a site's and the outside's included)
  size_t flattenedFaces = 0;  ///< rough faces kept flat to keep their cells free of self-intersections
};

/// One cell per site (cell i belongs to sites[i]); the cells cover `bounds`, which must contain
/// every site. Sites closer than 1e-9 of the box's diagonal to an earlier one get an empty cell.
/// Throws texfab::Error for fewer than one site, non-finite coordinates or a site outside bounds.
CellComplex voronoiCells(std::span<const Eigen::Vector3d> sites, const Eigen::AlignedBox3d& bounds,
                         const VoronoiCellsOptions& options = {}, VoronoiCellsReport* report = nullptr);

} // namespace texfab::geometry
