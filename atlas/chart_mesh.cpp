// SPDX-License-Identifier: GPL-3.0-or-later
#include "atlas/chart_mesh.h"

#include <algorithm>
#include <numeric>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>

namespace texfab::atlas::detail {
namespace {

int32_t localIndex(const std::vector<uint32_t>& faces, int32_t g) {
  if (g < 0) return -1;
  auto it = std::lower_bound(faces.begin(), faces.end(), uint32_t(g));
  return (it != faces.end() && *it == uint32_t(g)) ? int32_t(it - faces.begin()) : -1;
}

uint32_t find(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

} // namespace

ChartMesh buildChartMesh(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces) {
  const size_t nf = faces.size();
  std::vector<uint32_t> parent(3 * nf);
  std::iota(parent.begin(), parent.end(), 0u);
  std::vector<std::array<int32_t, 3>> localNeighbor(nf);
  for (size_t i = 0; i < nf; ++i) {
    const uint32_t f = faces[i];
    for (int k = 0; k < 3; ++k) {
      const int32_t j = localIndex(faces, conn.neighbor(f, k));
      localNeighbor[i][size_t(k)] = j;
      if (j < 0) continue;
      const uint32_t g = faces[size_t(j)];
      const uint32_t a = mesh.triangles[f][size_t(k)], b = mesh.triangles[f][size_t((k + 1) % 3)];
      for (int m = 0; m < 3; ++m) {
        const uint32_t v = mesh.triangles[g][size_t(m)];
        const uint32_t other = uint32_t(3 * size_t(j) + size_t(m));
        if (v == a) parent[find(parent, uint32_t(3 * i + size_t(k)))] = find(parent, other);
        if (v == b) parent[find(parent, uint32_t(3 * i + size_t((k + 1) % 3)))] = find(parent, other);
      }
    }
  }
  ChartMesh cm;
  cm.triangles.resize(nf);
  std::vector<int32_t> rootVertex(3 * nf, -1);
  for (size_t c = 0; c < 3 * nf; ++c) {
    const uint32_t r = find(parent, uint32_t(c));
    if (rootVertex[r] < 0) {
      rootVertex[r] = int32_t(cm.vertexSource.size());
      cm.vertexSource.push_back(mesh.triangles[faces[c / 3]][c % 3]);
    }
    cm.triangles[c / 3][c % 3] = uint32_t(rootVertex[r]);
  }
  // Boundary halfedges: next boundary vertex from each boundary vertex.
  std::vector<int32_t> next(cm.vertexSource.size(), -1);
  size_t boundary = 0;
  bool manifoldBoundary = true;
  for (size_t i = 0; i < nf; ++i)
    for (int k = 0; k < 3; ++k)
      if (localNeighbor[i][size_t(k)] < 0) {
        const uint32_t a = cm.triangles[i][size_t(k)], b = cm.triangles[i][size_t((k + 1) % 3)];
        if (next[a] >= 0) manifoldBoundary = false;
        next[a] = int32_t(b);
        ++boundary;
        cm.boundaryLength += double((mesh.positions[cm.vertexSource[a]] - mesh.positions[cm.vertexSource[b]]).norm());
      }
  std::vector<uint8_t> seen(next.size(), 0);
  for (size_t v = 0; v < next.size(); ++v) {
    if (next[v] < 0 || seen[v]) continue;
    ++cm.boundaryLoops;
    size_t u = v;
    size_t guard = 0;
    while (!seen[u] && next[u] >= 0 && guard++ <= next.size()) {
      seen[u] = 1;
      u = size_t(next[u]);
    }
  }
  if (!manifoldBoundary) cm.boundaryLoops += 1000; // never a disk
  const long long edges = (3 * (long long)nf + (long long)boundary) / 2;
  cm.eulerCharacteristic = int((long long)cm.vertexSource.size() - edges + (long long)nf);
  return cm;
}

bool splitFaces(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces, std::vector<uint32_t>& first,
                std::vector<uint32_t>& second) {
  first.clear();
  second.clear();
  if (faces.size() < 2) return false;
  const size_t nf = faces.size();
  // Dijkstra over centroid distances from a source set; returns distances.
  auto dijkstra = [&](std::vector<int32_t> sources, std::vector<double>& dist, std::vector<int32_t>* label) {
    dist.assign(nf, std::numeric_limits<double>::infinity());
    using Item = std::tuple<double, int32_t, int32_t>; // distance, local face, label
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> pq;
    for (size_t s = 0; s < sources.size(); ++s) pq.push({0.0, sources[s], int32_t(s)});
    if (label) label->assign(nf, -1);
    std::vector<uint8_t> done(nf, 0);
    for (int32_t s : sources) dist[size_t(s)] = 0;
    while (!pq.empty()) {
      auto [d, i, l] = pq.top();
      pq.pop();
      if (done[size_t(i)]) continue;
      done[size_t(i)] = 1;
      dist[size_t(i)] = d;
      if (label) (*label)[size_t(i)] = l;
      const uint32_t f = faces[size_t(i)];
      for (int k = 0; k < 3; ++k) {
        const int32_t j = localIndex(faces, conn.neighbor(f, k));
        if (j < 0 || done[size_t(j)]) continue;
        const double nd = d + (geometry::triangleCentroid(mesh, f) - geometry::triangleCentroid(mesh, faces[size_t(j)])).norm();
        if (nd <= dist[size_t(j)]) {
          dist[size_t(j)] = nd;
          pq.push({nd, j, l});
        }
      }
    }
  };
  std::vector<double> dist;
  auto farthest = [&](const std::vector<double>& d) {
    int32_t best = 0;
    for (size_t i = 0; i < nf; ++i)
      if (std::isfinite(d[i]) && (!std::isfinite(d[size_t(best)]) || d[i] > d[size_t(best)])) best = int32_t(i);
    return best;
  };
  dijkstra({0}, dist, nullptr);
  const int32_t a = farthest(dist);
  dijkstra({a}, dist, nullptr);
  const int32_t b = farthest(dist);
  std::vector<int32_t> label;
  dijkstra({a, b}, dist, &label);
  for (size_t i = 0; i < nf; ++i) (label[i] == 1 ? second : first).push_back(faces[i]);
  if (first.empty() || second.empty()) { // disconnected leftovers: split by index
    first.assign(faces.begin(), faces.begin() + long(nf / 2));
    second.assign(faces.begin() + long(nf / 2), faces.end());
  }
  return true;
}

std::vector<std::vector<uint32_t>> connectedParts(const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces) {
  std::vector<std::vector<uint32_t>> parts;
  std::vector<uint8_t> seen(faces.size(), 0);
  for (size_t s = 0; s < faces.size(); ++s) {
    if (seen[s]) continue;
    std::vector<uint32_t> part;
    std::vector<size_t> stack{s};
    seen[s] = 1;
    while (!stack.empty()) {
      const size_t i = stack.back();
      stack.pop_back();
      part.push_back(faces[i]);
      for (int k = 0; k < 3; ++k) {
        const int32_t j = localIndex(faces, conn.neighbor(faces[i], k));
        if (j >= 0 && !seen[size_t(j)]) {
          seen[size_t(j)] = 1;
          stack.push_back(size_t(j));
        }
      }
    }
    std::sort(part.begin(), part.end());
    parts.push_back(std::move(part));
  }
  return parts;
}

} // namespace texfab::atlas::detail
