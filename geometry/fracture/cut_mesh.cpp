// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/fracture/cut_mesh.h"

#include "core/error.h"

#include <algorithm>
#include <numeric>

namespace texfab::geometry {
namespace {

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

// The solid's triangles as its own piece (a solid the planes miss).
CellPiece whole(const Mesh& solid) {
  CellPiece p;
  p.mesh = solid;
  p.source.resize(solid.triangles.size());
  std::iota(p.source.begin(), p.source.end(), 0);
  p.cutFace.assign(solid.triangles.size(), -1);
  return p;
}

// The parts of `solid` (within `box`) in the cells of the planes that reach it (`across`: their
// indices), with the plane of each new face in `cut`; one part, or none, when the planes only
// touch it. Each plane moves by `shift` along its unit normal.
std::vector<CellPiece> parts(const Mesh& solid, const BoundingBox& box, std::span<const CutPlane> planes,
                             std::span<const int> across, double shift, const IntersectCellsOptions& options,
                             const Context& ctx, IntersectCellsReport& report, std::vector<std::vector<int32_t>>& cut) {
  std::vector<CutPlane> reaching;
  for (int k : across) {
    const CutPlane& p = planes[size_t(k)];
    reaching.push_back({p.point + shift * p.normal.normalized(), p.normal});
  }
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.0137 * box.diagonal() + 1e-6);
  const PlaneArrangement cells =
      planeArrangement(reaching, {box.min.cast<double>() - margin, box.max.cast<double>() + margin});
  std::vector<std::vector<int>> groups(size_t(cells.complex.cells));
  for (size_t c = 0; c < groups.size(); ++c) groups[c] = {int(c)};
  std::vector<CellPiece> pieces = intersectCells(solid, cells.complex, groups, options, ctx, &report);
  std::erase_if(pieces, [](const CellPiece& p) { return p.mesh.triangles.empty(); });
  cut.clear();
  for (const CellPiece& p : pieces) {
    std::vector<int32_t>& planeOf = cut.emplace_back(p.mesh.triangles.size(), -1);
    for (size_t t = 0; t < planeOf.size(); ++t)
      if (p.cutFace[t] >= 0) planeOf[t] = across[size_t(cells.planeOf[size_t(p.cutFace[t])])];
  }
  return pieces;
}

} // namespace

CutMeshResult cutMesh(std::span<const Mesh> solids, std::span<const CutPlane> planes, const IntersectCellsOptions& options,
                      const Context& ctx) {
  for (const CutPlane& p : planes) validatePlane(p);
  CutMeshResult r;
  std::vector<uint8_t> crossed(planes.size(), 0);
  for (size_t i = 0; i < solids.size(); ++i) {
    std::vector<int> across;
    for (size_t k = 0; k < planes.size(); ++k)
      if (!misses(solids[i], planes[k])) across.push_back(int(k));
    std::vector<std::vector<int32_t>> cut;
    std::vector<CellPiece> pieces;
    // A plane along the model's edges meets them within the rounding of the cells' vertices (which
    // lie on several planes), and can leave a piece open: then every plane moves by a millionth of
    // the model's size, which no one sees and which leaves the model's vertices off the planes.
    const BoundingBox box = boundingBox(solids[i]);
    const double nudge = 1e-6 * box.diagonal();
    for (int attempt = 0; !across.empty(); ++attempt) {
      try {
        IntersectCellsReport report;
        pieces = parts(solids[i], box, planes, across, attempt * nudge, options, ctx.nested(), report, cut);
        r.intersect.corefinedTriangles += report.corefinedTriangles;
        r.intersect.keptWhole += report.keptWhole;
        break;
      } catch (const Cancelled&) {
        throw;
      } catch (const Error&) {
        if (attempt == 2) throw;
      }
    }
    if (pieces.size() < 2) {  // missed or only touched
      pieces = {whole(solids[i])};
      cut = {std::vector<int32_t>(solids[i].triangles.size(), -1)};
    }
    for (size_t p = 0; p < pieces.size(); ++p) {
      for (int32_t k : cut[p])
        if (k >= 0) crossed[size_t(k)] = 1;
      r.pieces.push_back(std::move(pieces[p]));
      r.inputOf.push_back(int(i));
      r.cut.push_back(std::move(cut[p]));
    }
  }
  for (size_t k = 0; k < planes.size(); ++k)
    if (!crossed[k]) r.missed.push_back(int(k));
  return r;
}

} // namespace texfab::geometry
