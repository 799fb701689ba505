// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Voronoi fracture of a solid: sites inside the model (a hash of the seed, or concentrated around
// a point of impact), their Voronoi cells (voronoi_cells.h, optionally with rough faces), each cell
// intersected with the model (intersect_cells.h); pieces smaller than a minimum volume merge into
// the neighbour they share the most crack area with.

#include "core/context.h"
#include "geometry/fracture/intersect_cells.h"
#include "geometry/fracture/voronoi_cells.h"
#include "geometry/mesh.h"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace texfab::geometry {

inline constexpr int kMaxFracturePieces = 10000;

struct FractureOptions {
  int pieces = 10;     ///< Voronoi sites, one per piece before merging; [1, kMaxFracturePieces]
  uint32_t seed = 1;   ///< the sites (and the cracks' relief) are a hash of it
  /// Sites concentrated around this point (model units), as a blow would break the model: the
  /// distance of a site to it is the model's half-diagonal times u², u uniform in [0, 1).
  std::optional<Eigen::Vector3d> impact;
  double roughness = 0;   ///< relief of the cracks (VoronoiCellsOptions::roughness); [0, 0.25]
  /// Pieces smaller than this fraction of the model's volume merge into a neighbour; [0, 0.5).
  double minVolume = 0;
  IntersectCellsOptions cut;

  void validate() const;  ///< throws texfab::Error naming the bad option
};

struct FractureReport {
  int sites = 0;
  size_t candidates = 0;  ///< points drawn to find the sites inside the model
  int merged = 0;         ///< pieces merged into a neighbour (min volume)
  double modelVolume = 0;
  VoronoiCellsReport cells;
  IntersectCellsReport intersect;
};

struct FractureResult {
  std::vector<CellPiece> pieces;  ///< non-empty, ordered by their first cell (site)
  std::vector<Eigen::Vector3d> sites;
  CellComplex cells;
  FractureReport report;
};

/// `solid` must be closed, outward and free of self-intersections (repairSolid). Throws
/// texfab::Error for bad options and when the model cannot hold the sites asked for (too thin).
FractureResult fractureMesh(const Mesh& solid, const FractureOptions& options, const Context& ctx = {});

} // namespace texfab::geometry
