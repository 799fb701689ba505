// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Chart segmentation: region growing on normal cones, refined by a few Lloyd iterations of
// competitive growth (variational shape approximation with the L2,1 normal metric), then every
// chart is checked to be a topological disk and split until it is.

#include "atlas/atlas.h"
#include "geometry/mesh.h"
#include "geometry/mesh_connectivity.h"

#include <string>

namespace texfab::atlas {

struct SegmentChartsOptions {
  /// A triangle joins a chart only when its normal is within this angle of the chart's mean
  /// normal (degrees, (0, 90]). Smaller: more charts, less stretch, more seams.
  double maxNormalDeviationDegrees = 75.0;
  /// Weight of compactness (distance to the chart seed relative to the chart radius) against
  /// normal deviation when charts compete for triangles (>= 0; 0 = normals only). Round charts
  /// pack better and have shorter seams.
  double compactnessWeight = 0.25;
  /// Lloyd iterations of competitive growth after the greedy seeding (>= 0).
  int lloydIterations = 4;
  /// Passes of border smoothing (a triangle with two neighbours in another chart moves there) (>= 0).
  int smoothingPasses = 4;

  /// Throws texfab::Error naming the field.
  void validate() const;
};

struct SegmentChartsReport {
  size_t charts = 0;
  size_t splitsForDisks = 0; ///< splits made to turn non-disk charts into disks
  size_t degenerateTriangles = 0;
  size_t nonManifoldEdges = 0;
  size_t inconsistentEdges = 0;
};

/// Fills atlas.faceChart and atlas.charts (faces, area, boundary length, disk = true).
/// Deterministic (single-threaded, ordered by triangle id).
SegmentChartsReport segmentCharts(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, Atlas& atlas,
                                  const SegmentChartsOptions& options = {});

/// Splits `atlas.charts` until every chart is a connected topological disk; charts are then
/// renumbered by their smallest triangle id and faceChart refreshed. Returns the number of splits.
size_t makeChartsDisks(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, Atlas& atlas);

} // namespace texfab::atlas
