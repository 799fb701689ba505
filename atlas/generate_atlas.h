// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The whole atlas pipeline in one call, with a report: connectivity -> segmentCharts ->
// parameterizeCharts -> cutChartsForPacking -> packCharts -> rasterizeAtlas. Fields that need a tangent field
// (Jacobians) and indirection maps are separate calls (compute_jacobians.h,
// build_indirection_map.h) since not every user needs them.

#include "atlas/atlas.h"
#include "atlas/cut_charts.h"
#include "atlas/pack_charts.h"
#include "atlas/parameterize_charts.h"
#include "atlas/rasterize_atlas.h"
#include "atlas/segment_charts.h"
#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/mesh_connectivity.h"

#include <string>
#include <vector>

namespace texfab::atlas {

struct GenerateAtlasOptions {
  SegmentChartsOptions segment;
  ParameterizeChartsOptions parameterize;
  CutChartsOptions cut; ///< cuts of wasteful charts before packing (Box Cutter)
  PackChartsOptions pack;
};

struct AtlasReport {
  size_t triangles = 0;
  size_t charts = 0;
  double utilization = 0;     ///< chart texels / atlas texels
  double l2Stretch = 0;       ///< Sander et al. 2001, area-weighted, normalized (UV area = surface area)
  double maxStretch = 0;
  size_t flippedTriangles = 0;
  size_t collapsedTriangles = 0; ///< thinner than the rounding of texel coordinates (StretchStats::collapsed)
  size_t overlappingTexels = 0;
  size_t nonDiskCharts = 0;
  double seamLength = 0;      ///< total length of chart borders that are interior mesh edges, model units
  double boundaryLength = 0;  ///< total length of chart borders (seams counted on both sides + open boundary)
  double texelsPerUnit = 0;
  SegmentChartsReport segment;
  ParameterizeChartsReport parameterize;
  CutChartsReport cut;
  PackChartsReport pack;
  std::vector<std::pair<std::string, double>> seconds; ///< per stage
  std::vector<std::string> repairs; ///< what was wrong with the input and what was done
};

struct GenerateAtlasResult {
  Atlas atlas;
  geometry::MeshConnectivity connectivity;
  AtlasFields fields;
  AtlasReport report;
};

/// Deterministic: ctx.threads only spreads the work.
GenerateAtlasResult generateAtlas(const geometry::Mesh& mesh, const GenerateAtlasOptions& options = {},
                                  const Context& ctx = {});

/// Peak memory of a width x height atlas with its fields, in bytes: generateAtlas's texel fields
/// plus a Jacobian (computeJacobians) and an indirection entry (buildIndirectionMap) per texel.
double atlasMemoryBytes(int width, int height);

/// Global figures of a packed atlas (stretch over all charts in atlas space, flips, seams).
void measureAtlas(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, const Atlas& atlas, AtlasReport& report);

} // namespace texfab::atlas
