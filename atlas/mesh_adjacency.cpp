// SPDX-License-Identifier: GPL-3.0-or-later
#include "atlas/mesh_adjacency.h"

#include <algorithm>

namespace texfab::atlas {

MeshAdjacency computeMeshAdjacency(const geometry::Mesh& mesh) {
  const size_t n = mesh.triangleCount();
  MeshAdjacency adj;
  adj.neighbor.assign(n, {-1, -1, -1});
  adj.degenerate.assign(n, 0);
  adj.area.assign(n, 0.0);
  adj.normal.assign(n, Eigen::Vector3d::Zero());
  adj.centroid.assign(n, Eigen::Vector3d::Zero());
  const geometry::BoundingBox box = geometry::boundingBox(mesh);
  const double diag = std::max(double(box.diagonal()), 1e-30);
  const double minArea = 1e-14 * diag * diag;
  for (size_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3d a = mesh.positions[tri[0]].cast<double>(), b = mesh.positions[tri[1]].cast<double>(),
                          c = mesh.positions[tri[2]].cast<double>();
    const Eigen::Vector3d cr = (b - a).cross(c - a);
    adj.area[t] = 0.5 * cr.norm();
    adj.centroid[t] = (a + b + c) / 3.0;
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || adj.area[t] <= minArea) {
      adj.degenerate[t] = 1;
      ++adj.degenerateCount;
      adj.area[t] = 0;
    } else {
      adj.normal[t] = cr / cr.norm();
    }
  }
  // Directed edges (min, max, triangle, corner, forward?) sorted by their undirected key.
  struct Edge {
    uint32_t lo, hi, tri;
    uint8_t corner, forward;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * n);
  for (size_t t = 0; t < n; ++t) {
    if (adj.degenerate[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.triangles[t][size_t(k)], b = mesh.triangles[t][size_t((k + 1) % 3)];
      edges.push_back({std::min(a, b), std::max(a, b), uint32_t(t), uint8_t(k), uint8_t(a < b)});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    return std::tie(x.lo, x.hi, x.tri, x.corner) < std::tie(y.lo, y.hi, y.tri, y.corner);
  });
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const size_t count = j - i;
    if (count == 1) {
      ++adj.boundaryEdges;
    } else if (count == 2) {
      const Edge& e0 = edges[i];
      const Edge& e1 = edges[i + 1];
      if (e0.forward != e1.forward && e0.tri != e1.tri) {
        adj.neighbor[e0.tri][e0.corner] = int32_t(e1.tri);
        adj.neighbor[e1.tri][e1.corner] = int32_t(e0.tri);
      } else {
        ++adj.inconsistentEdges;
      }
    } else {
      ++adj.nonManifoldEdges;
    }
    i = j;
  }
  return adj;
}

} // namespace texfab::atlas
