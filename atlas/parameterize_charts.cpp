// SPDX-License-Identifier: GPL-3.0-or-later
// Chart parameterization through CGAL's Surface_mesh_parameterization package.
//  - B. Lévy, S. Petitjean, N. Ray, J. Maillot, "Least Squares Conformal Maps for Automatic
//    Texture Atlas Generation", SIGGRAPH 2002 (LSCM, the default).
//  - L. Liu, L. Zhang, Y. Xu, C. Gotsman, S. Gortler, "A Local/Global Approach to Mesh
//    Parameterization", SGP 2008 (ARAP).
//  - P. Sander, J. Snyder, S. Gortler, H. Hoppe, "Texture Mapping Progressive Meshes", SIGGRAPH
//    2001 (the stretch metric used to accept a chart).
// This is the only translation unit that includes CGAL's parameterization headers.
#include "atlas/parameterize_charts.h"

#include "atlas/chart_mesh.h"
#include "atlas/measure_stretch.h"
#include "core/error.h"
#include "core/parallel.h"

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>

#include <algorithm>
#include <cmath>

namespace texfab::atlas {

void ParameterizeChartsOptions::validate() const {
  if (!(maxTriangleStretch >= 1)) throw Error("maxTriangleStretch must be >= 1");
  if (!(maxChartL2Stretch >= 1)) throw Error("maxChartL2Stretch must be >= 1");
  if (maxRounds < 1) throw Error("maxRounds must be >= 1");
}

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMP = CGAL::Surface_mesh_parameterization;

enum class Outcome { Ok, NotDisk, Solver, Flipped, Overlap, Stretch };

struct ChartResult {
  Outcome outcome = Outcome::Ok;
  std::vector<Eigen::Vector2d> uvs; ///< 3 per chart face
  StretchStats stretch;
};

bool segmentsCross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, const Eigen::Vector2d& d) {
  auto orient = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
    const double v = (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
    return (v > 0) - (v < 0);
  };
  const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  // Touching / collinear overlaps count too (a boundary must be a simple curve).
  auto onSeg = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
    return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) && std::min(p.y(), q.y()) <= r.y() &&
           r.y() <= std::max(p.y(), q.y());
  };
  if (o1 == 0 && onSeg(a, b, c)) return true;
  if (o2 == 0 && onSeg(a, b, d)) return true;
  if (o3 == 0 && onSeg(c, d, a)) return true;
  if (o4 == 0 && onSeg(c, d, b)) return true;
  return false;
}

/// True when the chart's boundary polygon(s) in UV intersect themselves (grid-accelerated).
bool boundarySelfIntersects(const detail::ChartMesh& cm, const std::vector<Eigen::Vector2d>& vertexUv,
                            const std::vector<std::array<uint32_t, 2>>& segs) {
  if (segs.size() < 4) return false;
  Eigen::Vector2d lo = vertexUv[segs[0][0]], hi = lo;
  double length = 0;
  for (const auto& s : segs) {
    lo = lo.cwiseMin(vertexUv[s[0]]);
    hi = hi.cwiseMax(vertexUv[s[0]]);
    length += (vertexUv[s[0]] - vertexUv[s[1]]).norm();
  }
  (void)cm;
  const double cell = std::max(length / double(segs.size()), 1e-300);
  const int gw = std::clamp(int((hi.x() - lo.x()) / cell) + 1, 1, 512);
  const int gh = std::clamp(int((hi.y() - lo.y()) / cell) + 1, 1, 512);
  const double cx = (hi.x() - lo.x()) / gw + 1e-300, cy = (hi.y() - lo.y()) / gh + 1e-300;
  std::vector<std::vector<uint32_t>> grid(size_t(gw) * size_t(gh));
  for (size_t i = 0; i < segs.size(); ++i) {
    const Eigen::Vector2d a = vertexUv[segs[i][0]], b = vertexUv[segs[i][1]];
    const int x0 = std::clamp(int((std::min(a.x(), b.x()) - lo.x()) / cx), 0, gw - 1);
    const int x1 = std::clamp(int((std::max(a.x(), b.x()) - lo.x()) / cx), 0, gw - 1);
    const int y0 = std::clamp(int((std::min(a.y(), b.y()) - lo.y()) / cy), 0, gh - 1);
    const int y1 = std::clamp(int((std::max(a.y(), b.y()) - lo.y()) / cy), 0, gh - 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) grid[size_t(y) * size_t(gw) + size_t(x)].push_back(uint32_t(i));
  }
  for (const auto& bucket : grid)
    for (size_t i = 0; i < bucket.size(); ++i)
      for (size_t j = i + 1; j < bucket.size(); ++j) {
        const auto& s = segs[bucket[i]];
        const auto& t = segs[bucket[j]];
        if (s[0] == t[0] || s[0] == t[1] || s[1] == t[0] || s[1] == t[1]) continue; // neighbours
        if (segmentsCross(vertexUv[s[0]], vertexUv[s[1]], vertexUv[t[0]], vertexUv[t[1]])) return true;
      }
  return false;
}

/// The isometric layout of a single triangle.
std::vector<Eigen::Vector2d> layoutTriangle(const geometry::Mesh& mesh, uint32_t face, const detail::ChartMesh& cm) {
  std::vector<Eigen::Vector2d> vertexUv(cm.vertexSource.size(), Eigen::Vector2d::Zero());
  const Eigen::Vector3d a = mesh.corner(face, 0).cast<double>(), b = mesh.corner(face, 1).cast<double>(),
                        c = mesh.corner(face, 2).cast<double>();
  const Eigen::Vector3d e = (b - a).normalized();
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3d f = n.cross(e);
  vertexUv[cm.triangles[0][0]] = {0, 0};
  vertexUv[cm.triangles[0][1]] = {(b - a).norm(), 0};
  vertexUv[cm.triangles[0][2]] = {(c - a).dot(e), (c - a).dot(f)};
  return vertexUv;
}

/// A disk chart's layout by CGAL (LSCM or ARAP); Outcome::NotDisk or Solver when it fails.
Outcome layoutDisk(const geometry::Mesh& mesh, const detail::ChartMesh& cm, Parameterizer parameterizer,
                   std::vector<Eigen::Vector2d>& vertexUv) {
  SurfaceMesh sm;
  std::vector<SurfaceMesh::Vertex_index> vds;
  vds.reserve(cm.vertexSource.size());
  // Coordinates relative to the chart's first vertex: better conditioned far from the origin.
  const Eigen::Vector3d origin = mesh.positions[cm.vertexSource[0]].cast<double>();
  for (uint32_t v : cm.vertexSource) {
    const Eigen::Vector3d p = mesh.positions[v].cast<double>() - origin;
    vds.push_back(sm.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
  }
  for (const auto& t : cm.triangles)
    if (sm.add_face(vds[t[0]], vds[t[1]], vds[t[2]]) == SurfaceMesh::null_face()) return Outcome::NotDisk;
  SurfaceMesh::Halfedge_index border;
  bool found = false;
  for (auto h : sm.halfedges())
    if (sm.is_border(h)) {
      border = h;
      found = true;
      break;
    }
  if (!found) return Outcome::NotDisk;
  auto uvmap = sm.add_property_map<SurfaceMesh::Vertex_index, Kernel::Point_2>("v:uv").first;
  SMP::Error_code err;
  if (parameterizer == Parameterizer::Arap)
    err = SMP::parameterize(sm, SMP::ARAP_parameterizer_3<SurfaceMesh>(), border, uvmap);
  else
    err = SMP::parameterize(sm, SMP::LSCM_parameterizer_3<SurfaceMesh>(), border, uvmap);
  if (err != SMP::OK) return Outcome::Solver;
  vertexUv.assign(cm.vertexSource.size(), Eigen::Vector2d::Zero());
  for (size_t v = 0; v < vds.size(); ++v) {
    const Kernel::Point_2 p = uvmap[vds[v]];
    vertexUv[v] = {p.x(), p.y()};
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return Outcome::Solver;
  }
  return Outcome::Ok;
}

/// Orientation and scale: counter-clockwise, UV area == surface area, minimum at the origin.
/// False when the layout has no area.
bool normalizeLayout(const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces,
                     const detail::ChartMesh& cm, std::vector<Eigen::Vector2d>& vertexUv) {
  double signedArea = 0, surfaceArea = 0;
  for (size_t i = 0; i < faces.size(); ++i) {
    const auto& t = cm.triangles[i];
    const Eigen::Vector2d e1 = vertexUv[t[1]] - vertexUv[t[0]], e2 = vertexUv[t[2]] - vertexUv[t[0]];
    signedArea += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
    surfaceArea += conn.area[faces[i]];
  }
  if (signedArea < 0) {
    for (auto& uv : vertexUv) uv.x() = -uv.x();
    signedArea = -signedArea;
  }
  if (!(signedArea > 0) || !(surfaceArea > 0)) return false;
  const double scale = std::sqrt(surfaceArea / signedArea);
  Eigen::Vector2d lo = vertexUv[0];
  for (const auto& uv : vertexUv) lo = lo.cwiseMin(uv);
  for (auto& uv : vertexUv) uv = (uv - lo) * scale;
  return true;
}

/// The chart's stretch (measureStretch's normalization), weighted by the connectivity's face areas.
/// Unlike measureStretch, a triangle of zero surface area counts, and is flipped unless its UV
/// area is positive: a chart must not fold even where the surface does.
StretchStats chartStretch(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn,
                          const std::vector<uint32_t>& faces, const std::vector<Eigen::Vector2d>& uvs) {
  StretchStats s;
  double sum = 0, maxG = 0;
  for (size_t i = 0; i < faces.size(); ++i) {
    Eigen::Vector3d q[3];
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) {
      q[k] = mesh.corner(faces[i], k).cast<double>();
      p[k] = uvs[3 * i + size_t(k)];
    }
    const double area = conn.area[faces[i]];
    const TriangleStretch ts = triangleStretch(q, p);
    s.surfaceArea += area;
    s.uvArea += std::abs(ts.uvArea);
    if (!(ts.uvArea > 0) || !std::isfinite(ts.gammaMax)) {
      ++s.flipped;
      continue;
    }
    sum += ts.l2 * ts.l2 * area;
    maxG = std::max(maxG, ts.gammaMax);
  }
  const double norm = std::sqrt(s.uvArea / s.surfaceArea);
  s.l2 = std::sqrt(sum / s.surfaceArea) * norm;
  s.max = maxG * norm;
  return s;
}

/// The chart's boundary edges (vertex pairs of the chart mesh).
std::vector<std::array<uint32_t, 2>> boundarySegments(const geometry::MeshConnectivity& conn,
                                                      const std::vector<uint32_t>& faces, const detail::ChartMesh& cm) {
  std::vector<std::array<uint32_t, 2>> segs;
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int32_t g = conn.neighbor(faces[i], k);
      const bool inside = g >= 0 && std::binary_search(faces.begin(), faces.end(), uint32_t(g));
      if (!inside) segs.push_back({cm.triangles[i][size_t(k)], cm.triangles[i][size_t((k + 1) % 3)]});
    }
  return segs;
}

/// Lays out one chart and validates it: a disk, no flip, no boundary overlap, stretch in bounds.
ChartResult parameterizeChart(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const std::vector<uint32_t>& faces,
                              const ParameterizeChartsOptions& options) {
  ChartResult result;
  const detail::ChartMesh cm = detail::buildChartMesh(mesh, conn, faces);
  if (!cm.isDisk()) {
    result.outcome = Outcome::NotDisk;
    return result;
  }
  std::vector<Eigen::Vector2d> vertexUv;
  if (faces.size() == 1) vertexUv = layoutTriangle(mesh, faces[0], cm);
  else if (const Outcome o = layoutDisk(mesh, cm, options.parameterizer, vertexUv); o != Outcome::Ok) {
    result.outcome = o;
    return result;
  }
  if (!normalizeLayout(conn, faces, cm, vertexUv)) {
    result.outcome = Outcome::Solver;
    return result;
  }
  result.uvs.resize(3 * faces.size());
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) result.uvs[3 * i + size_t(k)] = vertexUv[cm.triangles[i][size_t(k)]];
  result.stretch = chartStretch(mesh, conn, faces, result.uvs);
  if (result.stretch.flipped > 0) result.outcome = Outcome::Flipped;
  else if (boundarySelfIntersects(cm, vertexUv, boundarySegments(conn, faces, cm))) result.outcome = Outcome::Overlap;
  else if (faces.size() > 1 &&
           (result.stretch.max > options.maxTriangleStretch || result.stretch.l2 > options.maxChartL2Stretch))
    result.outcome = Outcome::Stretch;
  return result;
}

} // namespace

ParameterizeChartsReport parameterizeCharts(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, Atlas& atlas,
                                            const ParameterizeChartsOptions& options, const Context& ctx) {
  options.validate();
  ParameterizeChartsReport report;
  atlas.chartUvs.assign(3 * mesh.triangleCount(), Eigen::Vector2d::Zero());
  std::vector<Chart> charts = std::move(atlas.charts);
  std::vector<size_t> work(charts.size());
  for (size_t i = 0; i < work.size(); ++i) work[i] = i;
  for (int round = 0; !work.empty(); ++round) {
    const bool last = round + 1 >= options.maxRounds;
    std::vector<ChartResult> results(work.size());
    parallelFor(0, int(work.size()), ctx, [&](int b, int e) {
      for (int i = b; i < e; ++i) results[size_t(i)] = parameterizeChart(mesh, conn, charts[work[size_t(i)]].faces, options);
    });
    std::vector<size_t> next;
    for (size_t i = 0; i < work.size(); ++i) {
      Chart& chart = charts[work[i]];
      const ChartResult& r = results[i];
      if (r.outcome == Outcome::Ok) {
        for (size_t j = 0; j < chart.faces.size(); ++j)
          for (int k = 0; k < 3; ++k) atlas.chartUvs[3 * size_t(chart.faces[j]) + size_t(k)] = r.uvs[3 * j + size_t(k)];
        chart.l2Stretch = r.stretch.l2;
        chart.maxStretch = r.stretch.max;
        chart.flippedTriangles = 0;
        continue;
      }
      switch (r.outcome) {
      case Outcome::Flipped: ++report.splitsForFlips; break;
      case Outcome::Overlap: ++report.splitsForOverlaps; break;
      case Outcome::Stretch: ++report.splitsForStretch; break;
      default: ++report.splitsForSolver; break;
      }
      std::vector<std::vector<uint32_t>> pieces;
      if (last) { // cut into single triangles: always valid
        ++report.chartsCutToTriangles;
        for (uint32_t f : chart.faces) pieces.push_back({f});
      } else {
        std::vector<uint32_t> a, b;
        detail::splitFaces(mesh, conn, chart.faces, a, b);
        for (auto* half : {&a, &b})
          for (auto& part : detail::connectedParts(conn, *half)) pieces.push_back(std::move(part));
      }
      chart.faces = std::move(pieces[0]);
      next.push_back(work[i]);
      for (size_t p = 1; p < pieces.size(); ++p) {
        Chart extra;
        extra.faces = std::move(pieces[p]);
        charts.push_back(std::move(extra));
        next.push_back(charts.size() - 1);
      }
    }
    work = std::move(next);
  }
  std::sort(charts.begin(), charts.end(), [](const Chart& x, const Chart& y) { return x.faces.front() < y.faces.front(); });
  atlas.faceChart.assign(mesh.triangleCount(), -1);
  for (size_t c = 0; c < charts.size(); ++c) {
    Chart& chart = charts[c];
    chart.disk = true;
    chart.area = 0;
    for (uint32_t f : chart.faces) {
      atlas.faceChart[f] = int32_t(c);
      chart.area += conn.area[f];
    }
    chart.boundaryLength = detail::buildChartMesh(mesh, conn, chart.faces).boundaryLength;
  }
  atlas.charts = std::move(charts);
  report.charts = atlas.charts.size();
  return report;
}

} // namespace texfab::atlas
