// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/fracture/cell_complex.h"

#include <algorithm>
#include <unordered_map>

namespace texfab::geometry {

CellSurface CellComplex::surfaceOf(std::span<const int> group) const {
  std::vector<uint8_t> member(size_t(std::max(cells, 0)), 0);
  for (int c : group)
    if (c >= 0 && c < cells) member[size_t(c)] = 1;
  auto in = [&](int32_t c) { return c >= 0 && member[size_t(c)]; };

  CellSurface s;
  std::unordered_map<uint32_t, uint32_t> local;  // complex vertex -> surface vertex
  auto vertex = [&](uint32_t v) {
    const auto [it, inserted] = local.emplace(v, uint32_t(s.vertices.size()));
    if (inserted) s.vertices.push_back(vertices[v]);
    return it->second;
  };
  for (size_t f = 0; f < faces.size(); ++f) {
    const CellFace& face = faces[f];
    const bool innerIn = in(face.inner), outerIn = in(face.outer);
    if (innerIn == outerIn) continue;
    for (const auto& t : face.triangles) {
      const std::array<uint32_t, 3> tri = {vertex(t[0]), vertex(t[1]), vertex(t[2])};
      // Stored outward of `inner`; reversed when the group is on the outer side.
      s.triangles.push_back(innerIn ? tri : std::array<uint32_t, 3>{tri[0], tri[2], tri[1]});
      s.face.push_back(uint32_t(f));
    }
  }
  return s;
}

} // namespace texfab::geometry
