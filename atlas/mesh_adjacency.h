// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Edge adjacency of a triangle soup as the atlas sees it: two triangles are neighbours across an
// edge only when that edge is manifold (exactly two triangles) and consistently oriented.
// Non-manifold, inconsistent and boundary edges are "cuts": charts never grow across them, so a
// bad mesh gives more charts, never a broken one.

#include "geometry/mesh.h"

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <vector>

namespace texfab::atlas {

struct MeshAdjacency {
  /// neighbor[t][k]: triangle across the edge from corner k to corner k+1, or -1 for a cut.
  std::vector<std::array<int32_t, 3>> neighbor;
  /// Triangles with (numerically) zero area or a repeated vertex.
  std::vector<uint8_t> degenerate;
  std::vector<double> area;                  ///< triangle areas
  std::vector<Eigen::Vector3d> normal;       ///< unit normals (zero when degenerate)
  std::vector<Eigen::Vector3d> centroid;
  size_t degenerateCount = 0;
  size_t nonManifoldEdges = 0;  ///< edges with three or more triangles
  size_t inconsistentEdges = 0; ///< two triangles running the edge the same way
  size_t boundaryEdges = 0;
};

/// Sorts the edges: O(T log T).
MeshAdjacency computeMeshAdjacency(const geometry::Mesh& mesh);

} // namespace texfab::atlas
