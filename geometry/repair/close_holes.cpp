// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/repair/close_holes.h"

#include <algorithm>
#include <map>

namespace texfab::geometry {

namespace {

struct BoundaryEdge {
  uint32_t to;
  size_t triangle;
  int corner;  // of `from` in the triangle
};

// Net direction of every undirected edge: +1 per a -> b with a < b, -1 per b -> a.
std::map<std::pair<uint32_t, uint32_t>, int> netDirections(const Mesh& mesh) {
  std::map<std::pair<uint32_t, uint32_t>, int> net;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
      if (a != b) net[{std::min(a, b), std::max(a, b)}] += a < b ? 1 : -1;
    }
  return net;
}

// Adds the fan closing one loop (boundary edges from -> to, in triangle order) around its centroid.
void addFan(Mesh& mesh, const std::vector<std::pair<uint32_t, BoundaryEdge>>& loop) {
  Eigen::Vector3f centroid(0, 0, 0);
  for (const auto& [from, edge] : loop) centroid += mesh.positions[from];
  mesh.positions.push_back(centroid / float(loop.size()));
  const uint32_t c = uint32_t(mesh.positions.size() - 1);
  for (const auto& [from, edge] : loop) {
    const size_t t = edge.triangle;
    const size_t ka = 3 * t + size_t(edge.corner), kb = 3 * t + size_t((edge.corner + 1) % 3);
    mesh.triangles.push_back({edge.to, from, c});  // runs the hole's edge the other way
    for (auto* attribute : {&mesh.uvs})
      if (!attribute->empty()) attribute->insert(attribute->end(), {(*attribute)[kb], (*attribute)[ka], (*attribute)[ka]});
    if (!mesh.normals.empty()) mesh.normals.insert(mesh.normals.end(), {mesh.normals[kb], mesh.normals[ka], mesh.normals[ka]});
    if (!mesh.tangents.empty()) mesh.tangents.insert(mesh.tangents.end(), {mesh.tangents[kb], mesh.tangents[ka], mesh.tangents[ka]});
    if (!mesh.faceMaterials.empty()) mesh.faceMaterials.push_back(mesh.faceMaterials[t]);
    if (!mesh.faceTags.empty()) mesh.faceTags.push_back(mesh.faceTags[t]);
  }
}

} // namespace

CloseHolesReport closeHoles(Mesh& mesh) {
  weldPositions(mesh);
  CloseHolesReport report;
  const auto net = netDirections(mesh);
  std::map<uint32_t, BoundaryEdge> outgoing;  // boundary vertex -> its one boundary edge
  bool simple = true;
  for (size_t t = 0; t < mesh.triangles.size() && simple; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.triangles[t][size_t(k)], b = mesh.triangles[t][size_t((k + 1) % 3)];
      if (a == b) continue;
      const int n = net.at({std::min(a, b), std::max(a, b)});
      if (n == 0) continue;
      if (std::abs(n) != 1 || (n == 1) != (a < b) || !outgoing.emplace(a, BoundaryEdge{b, t, k}).second) simple = false;
    }
  if (!simple || outgoing.empty()) {
    report.closed = outgoing.empty() && std::all_of(net.begin(), net.end(), [](const auto& e) { return e.second == 0; });
    return report;
  }
  // Follow the loops; every boundary vertex must lead to another one.
  std::vector<std::vector<std::pair<uint32_t, BoundaryEdge>>> loops;
  std::map<uint32_t, bool> visited;
  for (const auto& [start, first] : outgoing) {
    if (visited[start]) continue;
    std::vector<std::pair<uint32_t, BoundaryEdge>> loop;
    for (uint32_t v = start; !visited[v];) {
      visited[v] = true;
      const auto it = outgoing.find(v);
      if (it == outgoing.end()) return report;  // an open chain, not a loop
      loop.push_back({v, it->second});
      v = it->second.to;
    }
    if (loop.back().second.to != start) return report;
    loops.push_back(std::move(loop));
  }
  for (const auto& loop : loops) {
    addFan(mesh, loop);
    report.boundaryEdges += loop.size();
  }
  report.holes = loops.size();
  const auto after = netDirections(mesh);
  report.closed = std::all_of(after.begin(), after.end(), [](const auto& e) { return e.second == 0; });
  return report;
}

} // namespace texfab::geometry
