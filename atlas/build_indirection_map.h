// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Indirection maps (Lefebvre & Hoppe 2006, §5): for every chart texel within `radius` texels of
// the chart's border and each of the 8 one-texel steps, where the step lands on the surface. The
// step is walked across the chart's triangles in atlas space; crossing a seam it continues in the
// neighbouring chart (unfolded across the shared edge), so the landing point is the atlas position
// in the chart where the surface actually continues. At an open mesh boundary the walk stops on
// the boundary.

#include "atlas/atlas.h"
#include "atlas/rasterize_atlas.h"
#include "atlas/texel_field.h"
#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/mesh_connectivity.h"

#include <array>
#include <cstdint>
#include <vector>

namespace texfab::atlas {

/// The 8 steps, in order: (+1,0) (+1,+1) (0,+1) (-1,+1) (-1,0) (-1,-1) (0,-1) (+1,-1) (y down).
inline constexpr int kStepX[8] = {1, 1, 0, -1, -1, -1, 0, 1};
inline constexpr int kStepY[8] = {0, 1, 1, 1, 0, -1, -1, -1};

struct IndirectionTarget {
  float x = 0, y = 0;      ///< atlas position (texels, continuous; texel (i, j) has center (i+.5, j+.5))
  uint32_t triangle = 0;   ///< triangle containing the landing point
  int32_t chart = -1;      ///< its chart
  uint8_t crossedSeam = 0; ///< the step crossed into another chart
  uint8_t hitBoundary = 0; ///< the step stopped on an open mesh boundary
  uint8_t pad[2] = {0, 0};
};

struct IndirectionOptions {
  int radius = 4; ///< texels (1 .. 64) from the chart border that get entries

  void validate() const;
};

struct IndirectionMap {
  TexelField<int32_t> entry;                          ///< -1 = none, else index into targets
  std::vector<std::array<IndirectionTarget, 8>> targets;
  size_t seamCrossings = 0;
  size_t boundaryStops = 0;
};

IndirectionMap buildIndirectionMap(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, const Atlas& atlas,
                                   const AtlasFields& fields, const IndirectionOptions& options = {}, const Context& ctx = {});

/// Walks from atlas point `start` in triangle `triangle` by `step` (texels) across triangles and
/// seams; exposed for tests and for synthesis of longer steps.
IndirectionTarget walkAtlas(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, const Atlas& atlas,
                            uint32_t triangle, Eigen::Vector2d start, Eigen::Vector2d step);

} // namespace texfab::atlas
