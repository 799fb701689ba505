// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/cut_mesh.h"

#include "render/image/error.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace texfab::geometry {
namespace {

// Fan triangles of a convex loop of complex vertices.
void addFan(CellFace& face, const std::vector<uint32_t>& loop) {
  for (size_t i = 1; i + 1 < loop.size(); ++i) face.triangles.push_back({loop[0], loop[i], loop[i + 1]});
}

// Where the plane crosses the box: a vertex per crossed edge, shared by the faces that use it.
struct BoxSection {
  std::array<double, 8> side;                // signed distance of each corner (times |normal|)
  std::array<std::array<uint32_t, 8>, 8> edgePoint;  // corner pair -> vertex (UINT32_MAX: none)
};

// Part of a box face (corner loop) on one side of the plane (sign -1 behind, +1 in front).
std::vector<uint32_t> clipLoop(const std::array<uint32_t, 4>& loop, const BoxSection& s, double sign) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < 4; ++i) {
    const uint32_t a = loop[i], b = loop[(i + 1) % 4];
    if (sign * s.side[a] >= 0) out.push_back(a);
    if (s.edgePoint[a][b] != UINT32_MAX) out.push_back(s.edgePoint[a][b]);
  }
  return out;
}

void validatePlane(const CutPlane& plane) {
  if (!plane.point.allFinite() || !plane.normal.allFinite()) throw Error("a cutting plane is not finite");
  if (!(plane.normal.squaredNorm() > 0)) throw Error("a cutting plane has a zero normal");
}

// True when every vertex of the solid is strictly on one side of the plane.
bool misses(const Mesh& solid, const CutPlane& plane) {
  bool behind = false, front = false;
  for (const auto& v : solid.positions) {
    const double d = (v.cast<double>() - plane.point).dot(plane.normal);
    behind |= d <= 0;
    front |= d >= 0;
  }
  return !(behind && front);
}

// The solid's triangles as its own piece (a solid the plane misses).
CellPiece whole(const Mesh& solid) {
  CellPiece p;
  p.mesh = solid;
  p.source.resize(solid.triangles.size());
  std::iota(p.source.begin(), p.source.end(), 0);
  p.cutFace.assign(solid.triangles.size(), -1);
  return p;
}

} // namespace

CellComplex halfSpaces(const CutPlane& plane, const Eigen::AlignedBox3d& bounds) {
  validatePlane(plane);
  CellComplex cx;
  cx.cells = 2;
  BoxSection s;
  for (uint32_t k = 0; k < 8; ++k) {
    cx.vertices.push_back({k & 1 ? bounds.max().x() : bounds.min().x(), k & 2 ? bounds.max().y() : bounds.min().y(),
                           k & 4 ? bounds.max().z() : bounds.min().z()});
    s.side[k] = (cx.vertices[k] - plane.point).dot(plane.normal);
    s.edgePoint[k].fill(UINT32_MAX);
  }
  std::vector<uint32_t> section;
  for (uint32_t a = 0; a < 8; ++a) {
    if (s.side[a] == 0) section.push_back(a);
    for (uint32_t bit : {1u, 2u, 4u}) {
      const uint32_t b = a | bit;
      if (b == a || !(s.side[a] * s.side[b] < 0)) continue;
      const double t = s.side[a] / (s.side[a] - s.side[b]);
      s.edgePoint[a][b] = s.edgePoint[b][a] = uint32_t(cx.vertices.size());
      section.push_back(uint32_t(cx.vertices.size()));
      cx.vertices.push_back(cx.vertices[a] + t * (cx.vertices[b] - cx.vertices[a]));
    }
  }
  if (section.size() < 3) throw Error("internal: the cutting plane misses the box around the model");
  // The section, counter-clockwise around the normal (it is convex): face 0.
  const Eigen::Vector3d n = plane.normal.normalized(), e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (uint32_t v : section) centre += cx.vertices[v] / double(section.size());
  std::vector<double> angle(cx.vertices.size());
  for (uint32_t v : section) angle[v] = std::atan2((cx.vertices[v] - centre).dot(e2), (cx.vertices[v] - centre).dot(e1));
  std::sort(section.begin(), section.end(), [&](uint32_t a, uint32_t b) { return angle[a] < angle[b]; });
  cx.faces.push_back({{}, 0, 1});
  addFan(cx.faces.back(), section);
  // The box's faces, clipped to each side: corner loops counter-clockwise seen from outside.
  for (uint32_t axis : {1u, 2u, 4u})
    for (uint32_t high : {0u, axis}) {
      const uint32_t i = axis == 1 ? 2 : 1, j = axis == 4 ? 2 : 4;  // the other two bits
      std::array<uint32_t, 4> loop = {high, high | i, high | i | j, high | j};
      const Eigen::Vector3d outward = Eigen::Vector3d::Unit(axis == 1 ? 0 : axis == 2 ? 1 : 2) * (high ? 1.0 : -1.0);
      const Eigen::Vector3d normal = (cx.vertices[loop[1]] - cx.vertices[loop[0]]).cross(cx.vertices[loop[2]] - cx.vertices[loop[0]]);
      if (normal.dot(outward) < 0) std::reverse(loop.begin(), loop.end());
      for (int cell : {0, 1}) {
        const std::vector<uint32_t> part = clipLoop(loop, s, cell ? 1.0 : -1.0);
        if (part.size() < 3) continue;
        cx.faces.push_back({{}, cell, -1});
        addFan(cx.faces.back(), part);
      }
    }
  return cx;
}

CutMeshResult cutMesh(std::span<const Mesh> solids, std::span<const CutPlane> planes, const IntersectCellsOptions& options,
                      const Context& ctx) {
  for (const CutPlane& p : planes) validatePlane(p);
  CutMeshResult r;
  for (size_t i = 0; i < solids.size(); ++i) {
    r.pieces.push_back(whole(solids[i]));
    r.inputOf.push_back(int(i));
    r.cut.emplace_back(solids[i].triangles.size(), -1);
  }
  const std::vector<std::vector<int>> sides = {{0}, {1}};
  for (size_t k = 0; k < planes.size(); ++k) {
    CutMeshResult next;
    bool crossed = false;
    for (size_t p = 0; p < r.pieces.size(); ++p) {
      const Mesh& solid = r.pieces[p].mesh;
      std::vector<CellPiece> parts;
      if (!misses(solid, planes[k])) {
        const BoundingBox box = boundingBox(solid);
        const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.0137 * box.diagonal() + 1e-6);
        const CellComplex cx = halfSpaces(planes[k], {box.min.cast<double>() - margin, box.max.cast<double>() + margin});
        parts = intersectCells(solid, cx, sides, options, ctx.nested(), &r.intersect);
        std::erase_if(parts, [](const CellPiece& part) { return part.mesh.triangles.empty(); });
      }
      if (parts.size() < 2) parts = {whole(solid)};  // missed or only touched
      else crossed = true;
      for (CellPiece& part : parts) {
        std::vector<int32_t> cut(part.mesh.triangles.size());
        for (size_t t = 0; t < cut.size(); ++t) {
          const int32_t s = part.source[t];
          cut[t] = s < 0 ? int32_t(k) : r.cut[p][size_t(s)];
          part.source[t] = s < 0 ? -1 : r.pieces[p].source[size_t(s)];
        }
        next.pieces.push_back(std::move(part));
        next.inputOf.push_back(r.inputOf[p]);
        next.cut.push_back(std::move(cut));
      }
    }
    if (!crossed) r.missed.push_back(int(k));
    next.missed = std::move(r.missed);
    next.intersect = r.intersect;
    r = std::move(next);
  }
  return r;
}

} // namespace texfab::geometry
