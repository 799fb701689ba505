// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/mesh_topology.h"

#include <algorithm>
#include <numeric>

namespace texfab::geometry {

namespace {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

} // namespace

MeshTopology computeTopology(const Mesh& mesh) {
  MeshTopology topo;
  const size_t nv = mesh.positions.size();
  std::vector<uint8_t> used(nv, 0);
  UnionFind uf(nv);
  // Directed edges (a, b) stored as (min, max, direction).
  struct Edge {
    uint32_t a, b;
    bool forward;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const bool repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
    if (repeated || faceNormal(mesh, t).squaredNorm() == 0) ++topo.degenerateTriangles;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[size_t(k)], b = tri[size_t((k + 1) % 3)];
      used[a] = 1;
      uf.unite(a, b);
      if (a != b) edges.push_back({std::min(a, b), std::max(a, b), a < b});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return std::tie(x.a, x.b) < std::tie(y.a, y.b); });
  topo.watertight = true;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i, forward = 0;
    while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) forward += edges[j++].forward;
    const size_t count = j - i;
    ++topo.edges;
    if (count == 1) ++topo.boundaryEdges;
    if (count > 2) ++topo.nonManifoldEdges;
    if (count == 2 && forward != 1) ++topo.inconsistentEdges;
    if (count % 2) topo.watertight = false;
    i = j;
  }
  topo.usedVertices = size_t(std::count(used.begin(), used.end(), 1));
  std::vector<uint8_t> root(nv, 0);
  for (uint32_t v = 0; v < nv; ++v)
    if (used[v] && !root[uf.find(v)]) {
      root[uf.find(v)] = 1;
      ++topo.components;
    }
  topo.closed = topo.boundaryEdges == 0 && !mesh.triangles.empty();
  topo.manifold = topo.nonManifoldEdges == 0 && topo.inconsistentEdges == 0;
  if (topo.closed && topo.manifold) {
    const long long chi = (long long)topo.usedVertices - (long long)topo.edges + (long long)mesh.triangles.size();
    topo.genus = ((long long)topo.components * 2 - chi) / 2;
  }
  return topo;
}

} // namespace texfab::geometry
