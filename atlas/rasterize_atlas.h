// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Texel fields at the atlas resolution: for every texel whose center lies in a chart triangle,
// the chart, the triangle and barycentrics, the 3D position and the (smooth) normal. Texels outside
// every chart (gutters, unused space) keep chart = -1 but get the triangle, position and normal of
// the nearest chart texel (Euclidean, two-pass propagation), so bilinear lookups and mipmaps never
// read empty texels.

#include "atlas/atlas.h"
#include "atlas/texel_field.h"
#include "core/context.h"
#include "geometry/mesh.h"

#include <cstddef>

namespace texfab::atlas {

struct AtlasFields {
  TexelField<SurfaceSample> samples;
  TexelField<Float3> position; ///< model units
  TexelField<Float3> normal;   ///< unit
  size_t chartTexels = 0;      ///< texels whose center is in a chart
  size_t overlappingTexels = 0; ///< texel centers inside triangles of two different charts (0 for a valid atlas)
  double utilization() const {
    return samples.empty() ? 0.0 : double(chartTexels) / double(samples.values.size());
  }
};

/// Rasterizes the packed atlas (after packCharts). Normals come from mesh.normals when present,
/// else from area-weighted vertex normals. Deterministic on any number of threads (ctx.threads).
AtlasFields rasterizeAtlas(const geometry::Mesh& mesh, const Atlas& atlas, const Context& ctx = {});

/// The triangle id and barycentrics (b1, b2) of atlas point p (texels) in triangle t (extrapolated
/// when p is outside it).
void atlasBarycentrics(const Atlas& atlas, uint32_t t, const Eigen::Vector2d& p, double& b1, double& b2);

} // namespace texfab::atlas
