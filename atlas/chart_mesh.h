// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Internal: a chart as a small indexed mesh of its own, with its topology. Corners of one mesh
// vertex that are connected through the chart's interior edges share one chart vertex; corners in
// separate fans (a chart touching itself at a vertex) get separate vertices, so the chart is a
// manifold surface with boundary and its disk-ness is a matter of counting.

#include "geometry/mesh_connectivity.h"

#include <array>
#include <cstdint>
#include <vector>

namespace texfab::atlas::detail {

struct ChartMesh {
  std::vector<std::array<uint32_t, 3>> triangles; ///< chart vertex ids, one per chart face (same order)
  std::vector<uint32_t> vertexSource;             ///< chart vertex -> mesh vertex
  int boundaryLoops = 0;
  int eulerCharacteristic = 0; ///< V - E + F
  double boundaryLength = 0;
  bool isDisk() const { return boundaryLoops == 1 && eulerCharacteristic == 1; }
};

/// `faces` ascending; chart vertices are joined across the edges `connectivity` calls neighbours.
ChartMesh buildChartMesh(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces);

/// Splits a connected set of faces in two connected parts grown from two far-apart seeds
/// (deterministic). Returns false when `faces` has fewer than two faces.
bool splitFaces(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces, std::vector<uint32_t>& first,
                std::vector<uint32_t>& second);

/// Connected components (through connectivity) of a face set, each ascending, ordered by their
/// smallest face.
std::vector<std::vector<uint32_t>> connectedParts(const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces);

} // namespace texfab::atlas::detail
