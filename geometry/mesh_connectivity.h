// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The connectivity of a triangle mesh, computed once by sorting its edges: which triangles are
// neighbours, and the topological facts `texfab info` reports. Every module reads this one
// structure (the atlas grows charts over `neighbor`, orientation repair walks `mate`, inside tests
// need `watertight`), so they all agree on what a mesh is.
//
// One rule for degenerate triangles: a repeated vertex index, or an area of at most 1e-14 times
// the squared bounding-box diagonal. Degenerate triangles count in the edge figures (closed,
// boundary, non-manifold: those are combinatorial) but are nobody's neighbour.

#include "geometry/mesh.h"

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace texfab::geometry {

struct MeshConnectivity {
  // Per triangle (#T). Edge k of triangle t runs from corner k to corner k + 1 (mod 3).
  /// The other triangle on edge k when exactly two triangles share that edge and neither is
  /// degenerate, whatever their orientation; else -1.
  std::vector<std::array<int32_t, 3>> mate;
  /// Bit k set when mate[t][k] runs edge k the same way as t (one of the two is flipped).
  std::vector<uint8_t> misoriented;
  std::vector<uint8_t> degenerate; ///< 1 for degenerate triangles (the rule above)
  std::vector<double> area;        ///< model units² (0 for degenerate triangles)

  /// The triangle across edge k on the surface: the mate when both run the edge in opposite
  /// directions (a manifold, consistently oriented edge), else -1 (a cut).
  int32_t neighbor(size_t t, int k) const {
    return (misoriented[t] >> k) & 1 ? -1 : mate[t][size_t(k)];
  }

  // Counts.
  std::vector<std::array<uint32_t, 2>> edges; ///< distinct undirected edges (a < b), ascending
  size_t usedVertices = 0;        ///< vertices referenced by at least one triangle
  size_t boundaryEdges = 0;       ///< edges with one incident triangle
  size_t nonManifoldEdges = 0;    ///< edges with three or more incident triangles
  size_t inconsistentEdges = 0;   ///< two-triangle edges both triangles run the same way
  /// Vertices whose triangles do not form one fan joined across two-triangle edges: two surfaces
  /// touching at a point, and the ends of non-manifold edges.
  size_t nonManifoldVertices = 0;
  size_t degenerateTriangles = 0;
  size_t components = 0;          ///< connected components (triangles sharing a vertex are connected)

  bool closed = false;     ///< no boundary edges
  bool manifold = false;   ///< no non-manifold edges or vertices
  bool oriented = false;   ///< no inconsistently oriented edges
  /// Every edge has an even number of incident triangles: inside/outside is defined by ray
  /// parity. Implied by, but weaker than, closed && manifold.
  bool watertight = false;
  /// Closed, manifold and oriented meshes only: Σ over components of (2 - χ) / 2.
  std::optional<long long> genus;
};

/// O(T log T). Deterministic.
MeshConnectivity computeConnectivity(const Mesh& mesh);

} // namespace texfab::geometry
