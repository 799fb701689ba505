// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/mesh_connectivity.h"

#include <algorithm>
#include <numeric>
#include <tuple>

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

/// A directed edge of a triangle, keyed by its undirected vertex pair.
struct HalfEdge {
  uint32_t lo, hi, tri;
  uint8_t corner;  ///< the edge runs from this corner to the next
  uint8_t forward; ///< it runs from lo to hi
  /// The corner of `tri` at vertex lo (`hi`: at vertex hi).
  uint32_t cornerAt(bool atHi) const { return 3 * tri + (corner + (bool(forward) == atHi ? 1u : 0u)) % 3; }
};

bool repeatsVertex(const std::array<uint32_t, 3>& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

void measureTriangles(const Mesh& mesh, MeshConnectivity& c) {
  const size_t n = mesh.triangleCount();
  c.degenerate.assign(n, 0);
  c.area.assign(n, 0.0);
  const BoundingBox box = boundingBox(mesh);
  const double diag = std::max(double(box.diagonal()), 1e-30);
  const double minArea = 1e-14 * diag * diag;
  for (size_t t = 0; t < n; ++t) {
    const Eigen::Vector3d a = mesh.corner(t, 0).cast<double>(), b = mesh.corner(t, 1).cast<double>(),
                          d = mesh.corner(t, 2).cast<double>();
    const double area = 0.5 * (b - a).cross(d - a).norm();
    if (repeatsVertex(mesh.triangles[t]) || area <= minArea) {
      c.degenerate[t] = 1;
      ++c.degenerateTriangles;
    } else {
      c.area[t] = area;
    }
  }
}

/// Every edge of every triangle (but a vertex's edge to itself), sorted by vertex pair.
std::vector<HalfEdge> sortedHalfEdges(const Mesh& mesh) {
  std::vector<HalfEdge> edges;
  edges.reserve(3 * mesh.triangleCount());
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.triangles[t][size_t(k)], b = mesh.triangles[t][size_t((k + 1) % 3)];
      if (a != b) edges.push_back({std::min(a, b), std::max(a, b), uint32_t(t), uint8_t(k), uint8_t(a < b)});
    }
  std::sort(edges.begin(), edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.lo, x.hi, x.tri, x.corner) < std::tie(y.lo, y.hi, y.tri, y.corner);
  });
  return edges;
}

/// Edge figures and mates; two-triangle edges join the corners at their ends into fans.
void matchEdges(const std::vector<HalfEdge>& halfEdges, MeshConnectivity& c, UnionFind& fans) {
  c.watertight = true;
  for (size_t i = 0; i < halfEdges.size();) {
    size_t j = i;
    while (j < halfEdges.size() && halfEdges[j].lo == halfEdges[i].lo && halfEdges[j].hi == halfEdges[i].hi) ++j;
    const size_t count = j - i;
    c.edges.push_back({halfEdges[i].lo, halfEdges[i].hi});
    if (count % 2) c.watertight = false;
    if (count == 1) ++c.boundaryEdges;
    if (count > 2) ++c.nonManifoldEdges;
    if (count == 2) {
      const HalfEdge& e0 = halfEdges[i];
      const HalfEdge& e1 = halfEdges[i + 1];
      const bool misoriented = e0.forward == e1.forward;
      if (misoriented) ++c.inconsistentEdges;
      if (e0.tri != e1.tri) {
        fans.unite(e0.cornerAt(false), e1.cornerAt(false));
        fans.unite(e0.cornerAt(true), e1.cornerAt(true));
        if (!c.degenerate[e0.tri] && !c.degenerate[e1.tri]) {
          c.mate[e0.tri][e0.corner] = int32_t(e1.tri);
          c.mate[e1.tri][e1.corner] = int32_t(e0.tri);
          c.misoriented[e0.tri] |= uint8_t(misoriented << e0.corner);
          c.misoriented[e1.tri] |= uint8_t(misoriented << e1.corner);
        }
      }
    }
    i = j;
  }
}

/// Used vertices, non-manifold vertices (more than one fan of corners) and components.
void countVertices(const Mesh& mesh, MeshConnectivity& c, UnionFind& fans) {
  const size_t nv = mesh.vertexCount();
  std::vector<int64_t> firstFan(nv, -1);
  std::vector<uint8_t> nonManifold(nv, 0);
  UnionFind parts(nv);
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = tri[size_t(k)];
      parts.unite(v, tri[size_t((k + 1) % 3)]);
      const int64_t fan = repeatsVertex(tri) ? -2 : int64_t(fans.find(uint32_t(3 * t + size_t(k))));
      if (firstFan[v] == -1) firstFan[v] = fan;
      else if (fan != -2 && firstFan[v] != -2 && firstFan[v] != fan) nonManifold[v] = 1;
      if (firstFan[v] == -2) firstFan[v] = fan;
    }
  }
  std::vector<uint8_t> root(nv, 0);
  for (uint32_t v = 0; v < nv; ++v) {
    if (firstFan[v] == -1) continue;
    ++c.usedVertices;
    c.nonManifoldVertices += nonManifold[v];
    if (!root[parts.find(v)]) {
      root[parts.find(v)] = 1;
      ++c.components;
    }
  }
}

} // namespace

MeshConnectivity computeConnectivity(const Mesh& mesh) {
  MeshConnectivity c;
  const size_t n = mesh.triangleCount();
  c.mate.assign(n, {-1, -1, -1});
  c.misoriented.assign(n, 0);
  measureTriangles(mesh, c);
  UnionFind fans(3 * n);
  matchEdges(sortedHalfEdges(mesh), c, fans);
  countVertices(mesh, c, fans);
  c.closed = c.boundaryEdges == 0 && n > 0;
  c.manifold = c.nonManifoldEdges == 0 && c.nonManifoldVertices == 0;
  c.oriented = c.inconsistentEdges == 0;
  if (c.closed && c.manifold && c.oriented) {
    const long long chi = (long long)c.usedVertices - (long long)c.edges.size() + (long long)n;
    c.genus = ((long long)c.components * 2 - chi) / 2;
  }
  return c;
}

} // namespace texfab::geometry
