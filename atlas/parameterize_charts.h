// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Per-chart parameterization with CGAL's Surface_mesh_parameterization (LSCM by default, ARAP as
// an option), with validation and repair: a chart whose map has a flipped triangle, a
// self-intersecting boundary (overlap), or too much stretch is split in two and both halves are
// parameterized again; a chart still bad after the last round is cut into single triangles, which
// are always valid. The result never has flipped or overlapping triangles.

#include "atlas/atlas.h"
#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/mesh_connectivity.h"

#include <cstddef>

namespace texfab::atlas {

enum class Parameterizer {
  Lscm, ///< Lévy et al. 2002, CGAL::Surface_mesh_parameterization::LSCM_parameterizer_3
  Arap, ///< Liu et al. 2008, CGAL::Surface_mesh_parameterization::ARAP_parameterizer_3 (slower)
};

struct ParameterizeChartsOptions {
  Parameterizer parameterizer = Parameterizer::Lscm;
  /// A chart whose largest per-triangle stretch Γ (Sander et al. 2001, normalized per chart) exceeds
  /// this is split (>= 1).
  double maxTriangleStretch = 2.0;
  /// A chart whose L2 stretch exceeds this is split (>= 1).
  double maxChartL2Stretch = 1.10;
  /// Split-and-retry rounds before bad charts are cut into single triangles (>= 1).
  int maxRounds = 10;

  void validate() const;
};

struct ParameterizeChartsReport {
  size_t charts = 0;
  size_t splitsForFlips = 0;
  size_t splitsForOverlaps = 0;
  size_t splitsForStretch = 0;
  size_t splitsForSolver = 0;    ///< the solver failed (e.g. a degenerate system)
  size_t chartsCutToTriangles = 0;
  size_t flippedTriangles = 0;   ///< in the final maps: always 0
};

/// Fills atlas.chartUvs (chart-local, model units, UV area = surface area per chart) and the
/// charts' stretch figures; may split charts (then renumbered by smallest triangle id).
/// Charts are solved in parallel on ctx.threads threads (0 = all); the result does not depend on it.
ParameterizeChartsReport parameterizeCharts(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, Atlas& atlas,
                                            const ParameterizeChartsOptions& options = {}, const Context& ctx = {});

} // namespace texfab::atlas
