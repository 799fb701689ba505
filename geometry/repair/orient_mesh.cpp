// SPDX-License-Identifier: GPL-3.0-or-later
// Orientation repair by a breadth-first walk over triangle neighbours; the side of closed parts by
// signed volume, of nested closed parts by generalized winding numbers (A. Jacobson, L. Kavan,
// O. Sorkine-Hornung, "Robust Inside-Outside Segmentation using Generalized Winding Numbers",
// SIGGRAPH 2013, eq. 4: the solid angle of a triangle after A. Van Oosterom, J. Strackee 1983).
#include "geometry/repair/orient_mesh.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace texfab::geometry {

namespace {

struct Part {
  std::vector<uint32_t> triangles; ///< in walk order; the first is the smallest id
  bool closed = true;
  bool orientable = true;
};

/// Walks the part of `seed`, setting flip[] relative to the seed (kept as it is).
Part walkPart(const MeshConnectivity& c, uint32_t seed, std::vector<int32_t>& partOf, int32_t id,
              std::vector<uint8_t>& flip) {
  Part part;
  partOf[seed] = id;
  part.triangles.push_back(seed);
  for (size_t i = 0; i < part.triangles.size(); ++i) {
    const uint32_t t = part.triangles[i];
    for (int k = 0; k < 3; ++k) {
      const int32_t g = c.mate[t][size_t(k)];
      if (g < 0) {
        part.closed = false;
        continue;
      }
      const uint8_t want = flip[t] ^ ((c.misoriented[t] >> k) & 1);
      if (partOf[size_t(g)] < 0) {
        partOf[size_t(g)] = id;
        flip[size_t(g)] = want;
        part.triangles.push_back(uint32_t(g));
      } else if (flip[size_t(g)] != want) {
        part.orientable = false;
      }
    }
  }
  return part;
}

Eigen::Vector3d cornerOf(const Mesh& mesh, uint32_t t, int k) { return mesh.corner(t, k).cast<double>(); }

/// Six times the signed volume enclosed by the part's triangles as flipped (about a corner of the
/// part: the same for a closed part, better conditioned far from the origin).
double signedVolume6(const Mesh& mesh, const Part& part, const std::vector<uint8_t>& flip) {
  const Eigen::Vector3d o = cornerOf(mesh, part.triangles[0], 0);
  double v = 0;
  for (uint32_t t : part.triangles) {
    const double d = (cornerOf(mesh, t, 0) - o).dot((cornerOf(mesh, t, 1) - o).cross(cornerOf(mesh, t, 2) - o));
    v += flip[t] ? -d : d;
  }
  return v;
}

/// Generalized winding number of p with respect to the part (±1 inside a closed part, 0 outside).
double windingNumber(const Mesh& mesh, const Part& part, const std::vector<uint8_t>& flip, const Eigen::Vector3d& p) {
  double sum = 0;
  for (uint32_t t : part.triangles) {
    const Eigen::Vector3d a = cornerOf(mesh, t, 0) - p, b = cornerOf(mesh, t, 1) - p, c = cornerOf(mesh, t, 2) - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double det = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    const double omega = 2 * std::atan2(det, den);
    sum += flip[t] ? -omega : omega;
  }
  return sum / (4 * std::numbers::pi);
}

bool boxInside(const BoundingBox& inner, const BoundingBox& outer) {
  return (inner.min.array() >= outer.min.array()).all() && (inner.max.array() <= outer.max.array()).all();
}

/// How many of the other closed parts contain closed part i: its box lies in theirs, and so do the
/// centroid of its largest triangle and up to 16 of its corners spread over its triangles. One
/// point alone would take a shell that overlaps another (an eye set into a head) for a cavity.
int nestingDepth(const Mesh& mesh, const std::vector<Part>& parts, const std::vector<BoundingBox>& boxes, size_t i,
                 const std::vector<uint8_t>& flip, const std::vector<double>& area) {
  const std::vector<uint32_t>& tris = parts[i].triangles;
  const uint32_t largest =
      *std::max_element(tris.begin(), tris.end(), [&](uint32_t a, uint32_t b) { return area[a] < area[b]; });
  std::vector<Eigen::Vector3d> points{(cornerOf(mesh, largest, 0) + cornerOf(mesh, largest, 1) + cornerOf(mesh, largest, 2)) / 3};
  const size_t samples = std::min<size_t>(16, tris.size());
  for (size_t s = 0; s < samples; ++s) points.push_back(cornerOf(mesh, tris[s * tris.size() / samples], 0));
  int depth = 0;
  for (size_t j = 0; j < parts.size(); ++j) {
    if (j == i || !parts[j].closed || !parts[j].orientable || !boxInside(boxes[i], boxes[j])) continue;
    const bool inside = std::all_of(points.begin(), points.end(), [&](const Eigen::Vector3d& p) {
      return std::abs(windingNumber(mesh, parts[j], flip, p)) > 0.5;
    });
    depth += inside;
  }
  return depth;
}

BoundingBox boxOf(const Mesh& mesh, const Part& part) {
  BoundingBox b{mesh.corner(part.triangles[0], 0), mesh.corner(part.triangles[0], 0)};
  for (uint32_t t : part.triangles)
    for (int k = 0; k < 3; ++k) b.min = b.min.cwiseMin(mesh.corner(t, k)), b.max = b.max.cwiseMax(mesh.corner(t, k));
  return b;
}

void turnOver(const Part& part, std::vector<uint8_t>& flip) {
  for (uint32_t t : part.triangles) flip[t] ^= 1;
}

} // namespace

MeshOrientation computeOrientation(const Mesh& mesh, const MeshConnectivity& c) {
  const size_t n = mesh.triangleCount();
  MeshOrientation result;
  std::vector<int32_t> partOf(n, -1);
  std::vector<uint8_t> flip(n, 0);
  std::vector<Part> parts;
  for (uint32_t t = 0; t < n; ++t)
    if (!c.degenerate[t] && partOf[t] < 0) parts.push_back(walkPart(c, t, partOf, int32_t(parts.size()), flip));
  result.parts = parts.size();
  std::vector<BoundingBox> boxes;
  for (const Part& part : parts) boxes.push_back(boxOf(mesh, part));
  // Sides are chosen from the walks' flips (nesting only asks whether a point is inside, which
  // does not depend on a closed part's side), then applied.
  std::vector<uint8_t> turn(parts.size(), 0);
  for (size_t i = 0; i < parts.size(); ++i) {
    const Part& part = parts[i];
    bool consistent = true; // the walk flipped nothing
    for (uint32_t t : part.triangles) consistent = consistent && !flip[t];
    if (part.closed && part.orientable) {
      const bool cavity = nestingDepth(mesh, parts, boxes, i, flip, c.area) % 2 == 1;
      turn[i] = (signedVolume6(mesh, part, flip) > 0) == cavity;
    } else {
      double flippedArea = 0, keptArea = 0;
      for (uint32_t t : part.triangles) (flip[t] ? flippedArea : keptArea) += c.area[t];
      turn[i] = flippedArea > keptArea;
    }
    if (turn[i] && consistent) ++result.reversedParts;
    if (!part.orientable) ++result.nonOrientableParts;
  }
  for (size_t i = 0; i < parts.size(); ++i)
    if (turn[i]) turnOver(parts[i], flip);
  for (uint32_t t = 0; t < n; ++t) {
    if (flip[t]) result.flip.push_back(t);
    for (int k = 0; k < 3; ++k) {
      const int32_t g = c.mate[t][size_t(k)];
      if (g > int32_t(t) && (((c.misoriented[t] >> k) & 1) ^ flip[t] ^ flip[size_t(g)])) ++result.inconsistentEdgesLeft;
    }
  }
  return result;
}

void flipTriangles(Mesh& mesh, const std::vector<uint32_t>& triangles) {
  for (uint32_t t : triangles) flipTriangle(mesh, t);
}

MeshOrientation orientMesh(Mesh& mesh) {
  MeshOrientation o = computeOrientation(mesh, computeConnectivity(mesh));
  flipTriangles(mesh, o.flip);
  return o;
}

std::string describeRepair(const MeshOrientation& o) {
  if (o.flip.empty()) return {};
  std::string s = "re-oriented " + std::to_string(o.flip.size()) + " triangles (consistent winding";
  if (o.reversedParts) s += "; " + std::to_string(o.reversedParts) + " inside-out parts turned over";
  return s + ")";
}

std::string describeWarning(const MeshOrientation& o) {
  if (!o.nonOrientableParts) return {};
  return "the mesh is not orientable (" + std::to_string(o.nonOrientableParts) + " parts, like a Moebius strip): " +
         std::to_string(o.inconsistentEdgesLeft) +
         " edges keep inconsistent windings and become chart borders; normals and shading may be wrong there";
}

} // namespace texfab::geometry
