// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Atlas refinement for packing: charts whose parameterization wastes much of its bounding
// rectangle (arches, L shapes, combs) are cut in two along a straight line of their UV domain,
// as in Box Cutter (M. Limper, N. Vining, A. Sheffer, "Box Cutter: Atlas Refinement for Efficient
// Packing via Void Elimination", SIGGRAPH 2018). The pieces keep their UVs, so stretch and
// flips are unchanged; every piece is checked to be a topological disk. Runs between
// parameterizeCharts and packCharts.

#include "atlas/atlas.h"
#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/mesh_connectivity.h"

#include <cstddef>

namespace texfab::atlas {

struct CutChartsOptions {
  bool enabled = true;
  /// A cut is made when it shrinks the chart's padded bounding-rectangle area by at least this
  /// fraction, after charging the new seam (see seamCost) ([0, 1)).
  double minGain = 0.08;
  /// Charge for the new seam, in units of the gutter band it adds on both sides of the cut
  /// (>= 0; larger: fewer cuts, shorter seams).
  double seamCost = 4.0;
  /// Levels of recursive cuts per chart (each piece of a cut may be cut again) (>= 0; 0 = none).
  int maxCutsPerChart = 3;
  /// A chart smaller than this fraction of the surface is left whole (>= 0): the packer fills
  /// the voids of small charts with other small charts.
  double minChartArea = 0.002;

  void validate() const;
};

struct CutChartsReport {
  size_t cuts = 0;
  double seamLengthAdded = 0; ///< model units (3D length of the cut edges)
};

/// Cuts charts of a parameterized atlas (chartUvs unchanged); the atlas size and the gutter
/// (texels) give the gutter band the cuts are weighed against. Charts are renumbered by their
/// smallest triangle id. Deterministic whatever ctx.threads.
CutChartsReport cutChartsForPacking(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, Atlas& atlas,
                                    int width, int height, int gutter, const CutChartsOptions& options = {},
                                    const Context& ctx = {});

} // namespace texfab::atlas
