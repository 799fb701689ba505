// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Topological facts about a mesh, as `texfab info` reports them and as the inside test needs them.

#include "geometry/mesh.h"

#include <cstdint>
#include <optional>

namespace texfab::geometry {

struct MeshTopology {
  size_t usedVertices = 0;      ///< vertices referenced by at least one triangle
  size_t edges = 0;             ///< distinct undirected edges
  size_t boundaryEdges = 0;     ///< edges with one incident triangle
  size_t nonManifoldEdges = 0;  ///< edges with three or more incident triangles
  size_t inconsistentEdges = 0; ///< manifold edges whose two triangles run it the same way (orientation flip)
  size_t degenerateTriangles = 0; ///< triangles with a repeated vertex index or zero area
  size_t components = 0;        ///< connected components (triangles sharing a vertex are connected)
  /// True when every edge has an even number of incident triangles (no boundary): inside/outside
  /// is defined by ray parity. Implied by, but weaker than, closed && manifold.
  bool watertight = false;
  bool closed = false;    ///< no boundary edges
  bool manifold = false;  ///< every edge has at most two triangles, consistently oriented
  /// Genus, for closed oriented manifolds only: components - (V - E + F) / 2, summed.
  std::optional<long long> genus;
};

/// Computes the topology by sorting edges: O(T log T), no halfedge structure needed.
MeshTopology computeTopology(const Mesh& mesh);

} // namespace texfab::geometry
