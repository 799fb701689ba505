// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: the Voronoi diagram as the dual of the Delaunay triangulation (CGAL's
//   Delaunay_triangulation_3, exact predicates); relief by value noise [Perlin 1985] on a
//   constrained Delaunay triangulation of each face (CGAL's Constrained_Delaunay_triangulation_2).
#include "geometry/fracture/voronoi_cells.h"

#include "core/error.h"
#include "core/hash.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <set>

namespace texfab::geometry {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Vb3 = CGAL::Triangulation_vertex_base_with_info_3<int, Kernel>;
using Cb3 = CGAL::Triangulation_cell_base_with_info_3<uint32_t, Kernel, CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, CGAL::Triangulation_data_structure_3<Vb3, Cb3>>;
struct CdtVertexId {
  uint32_t id = UINT32_MAX;  // none: a point the triangulation added itself
};
using Vb2 = CGAL::Triangulation_vertex_base_with_info_2<CdtVertexId, Kernel>;
using Fb2 = CGAL::Constrained_triangulation_face_base_2<Kernel, CGAL::Triangulation_face_base_with_info_2<int, Kernel>>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, CGAL::Triangulation_data_structure_2<Vb2, Fb2>,
                                                       CGAL::Exact_predicates_tag>;
using SurfaceMesh = CGAL::Surface_mesh<Point3>;
constexpr uint32_t kNoVertex = UINT32_MAX;

Eigen::Vector3d toEigen(const Point3& p) { return {p.x(), p.y(), p.z()}; }

// A face between two cells before triangulation: its vertex loop, counter-clockwise seen from
// `outer` (normal from inner's site towards outer's).
struct Polygon {
  std::vector<uint32_t> loop;
  int32_t inner = -1, outer = -1;
  int outerSite = -1;  // the Delaunay vertex info on the outer side (a site or a sentinel), for ordering
};

// The Delaunay triangulation of the sites and 8 sentinels far outside `bounds` (so that every
// site's cell is bounded and the sites' cells cover the bounds).
Delaunay triangulate(std::span<const Eigen::Vector3d> sites, const Eigen::AlignedBox3d& bounds) {
  std::vector<std::pair<Point3, int>> points;
  for (size_t i = 0; i < sites.size(); ++i) points.emplace_back(Point3(sites[i].x(), sites[i].y(), sites[i].z()), int(i));
  const Eigen::Vector3d c = bounds.center();
  const double r = 4 * std::max(bounds.diagonal().norm(), 1e-300);
  for (int k = 0; k < 8; ++k)
    points.emplace_back(Point3(c.x() + (k & 1 ? r : -r), c.y() + (k & 2 ? r : -r), c.z() + (k & 4 ? r : -r)),
                        int(sites.size()) + k);
  Delaunay dt;
  for (const auto& [p, info] : points) {
    const size_t before = dt.number_of_vertices();
    const Delaunay::Vertex_handle v = dt.insert(p);
    if (dt.number_of_vertices() > before) v->info() = info;  // a repeated site keeps the first one's cell
  }
  return dt;
}

// The Voronoi face dual to the Delaunay edge e, oriented from the lower-numbered site's cell
// (inner) towards the other; circumcentre ids are those of the Delaunay cells.
Polygon dualFace(const Delaunay& dt, const Delaunay::Edge& e, int sites) {
  Delaunay::Vertex_handle u = e.first->vertex(e.second), v = e.first->vertex(e.third);
  const bool swap = u->info() >= sites || (v->info() < sites && v->info() < u->info());
  if (swap) std::swap(u, v);
  Polygon poly;
  poly.inner = u->info();
  poly.outer = v->info() < sites ? v->info() : -1;
  poly.outerSite = v->info();
  std::vector<Delaunay::Cell_handle> ring;
  Delaunay::Cell_circulator start = dt.incident_cells(e), c = start;
  do {
    if (dt.is_infinite(c)) throw Error("internal: an unbounded Voronoi cell");
    ring.push_back(c);
  } while (++c != start);
  // Rotation sense of the ring around u -> v, exactly: from the vertex only in ring[0] to the one
  // it shares with ring[1] (not u, not v).
  Delaunay::Vertex_handle only0, shared;
  for (int k = 0; k < 4; ++k) {
    const auto w = ring[0]->vertex(k);
    if (w == u || w == v) continue;
    (ring[1]->has_vertex(w) ? shared : only0) = w;
  }
  const bool counterClockwise = CGAL::orientation(u->point(), v->point(), only0->point(), shared->point()) == CGAL::POSITIVE;
  for (const auto& cell : ring) poly.loop.push_back(cell->info());
  if (!counterClockwise) std::reverse(poly.loop.begin(), poly.loop.end());
  // The circulator starts at e.first, which CGAL's edge iterator picks by cell address: start the
  // loop at its lowest circumcentre id instead, so the faces' triangles do not depend on the heap.
  std::rotate(poly.loop.begin(), std::min_element(poly.loop.begin(), poly.loop.end()), poly.loop.end());
  return poly;
}

// Circumcentres (once per Delaunay cell) and the faces of the sites' cells, sorted by (inner, outer).
std::vector<Polygon> voronoiPolygons(Delaunay& dt, int sites, std::vector<Eigen::Vector3d>& vertices) {
  for (auto c : dt.finite_cell_handles()) {
    c->info() = uint32_t(vertices.size());
    vertices.push_back(toEigen(CGAL::circumcenter(c->vertex(0)->point(), c->vertex(1)->point(), c->vertex(2)->point(),
                                                  c->vertex(3)->point())));
  }
  std::vector<Polygon> polys;
  for (const auto& e : dt.finite_edges()) {
    if (e.first->vertex(e.second)->info() >= sites && e.first->vertex(e.third)->info() >= sites) continue;
    Polygon p = dualFace(dt, e, sites);
    // Exactly cospherical sites give repeated circumcentres: drop the repeats.
    std::vector<uint32_t> loop;
    for (size_t i = 0; i < p.loop.size(); ++i)
      if (vertices[p.loop[i]] != vertices[p.loop[(i + 1) % p.loop.size()]]) loop.push_back(p.loop[i]);
    if (loop.size() < 3) continue;
    p.loop = std::move(loop);
    polys.push_back(std::move(p));
  }
  std::sort(polys.begin(), polys.end(),
            [](const Polygon& a, const Polygon& b) { return std::pair(a.inner, a.outerSite) < std::pair(b.inner, b.outerSite); });
  return polys;
}

// Value noise in [-1, 1]: hashed lattice values, smoothly interpolated; two octaves.
double valueNoise(const Eigen::Vector3d& p, uint32_t seed) {
  double sum = 0, amplitude = 1, norm = 0;
  Eigen::Vector3d q = p;
  for (int octave = 0; octave < 2; ++octave) {
    const Eigen::Vector3d f = q.array().floor();
    const Eigen::Vector3d t = q - f;
    const Eigen::Vector3d s = t.array() * t.array() * (3.0 - 2.0 * t.array());
    double value = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
      const uint32_t h = counterHash(seed, uint32_t(int64_t(f.x()) + dx), uint32_t(int64_t(f.y()) + dy),
                                     uint32_t(int64_t(f.z()) + dz), uint32_t(octave));
      value += (dx ? s.x() : 1 - s.x()) * (dy ? s.y() : 1 - s.y()) * (dz ? s.z() : 1 - s.z()) * (2 * unitInterval(h) - 1);
    }
    sum += amplitude * value;
    norm += amplitude;
    amplitude *= 0.5;
    q = 2.03 * q;
  }
  return sum / norm;
}

// Relief of the faces: each polygon's edges subdivided (shared edges identically, from their
// lower vertex), its inside filled by a constrained Delaunay triangulation of a grid of spacing
// h, inner vertices displaced along the face normal, tapered to zero at the border.
class Relief {
public:
  /// Only the parts of the faces within `region` get relief (the cells reach far beyond the model).
  Relief(CellComplex& complex, const Eigen::AlignedBox3d& region, double h, double amplitude, uint32_t seed)
      : cx_(complex), region_(region), h_(h), amplitude_(amplitude), seed_(seed) {}

  /// Edges of rough faces get subdivided (in every face that has them).
  void addRoughEdges(const Polygon& poly) {
    for (size_t i = 0; i < poly.loop.size(); ++i) roughEdges_.insert(std::minmax(poly.loop[i], poly.loop[(i + 1) % poly.loop.size()]));
  }

  // Triangles of `poly`, with inner points displaced when `rough`; `displaced` records the inner
  // vertices and their flat positions.
  void triangulate(const Polygon& poly, bool rough, CellFace& face, std::vector<std::pair<uint32_t, Eigen::Vector3d>>& displaced) {
    std::vector<uint32_t> border;
    for (size_t i = 0; i < poly.loop.size(); ++i) {
      const std::vector<uint32_t>& edge = edgePoints(poly.loop[i], poly.loop[(i + 1) % poly.loop.size()]);
      border.insert(border.end(), edge.begin(), edge.end() - 1);
    }
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(), origin = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < border.size(); ++i) {
      normal += cx_.vertices[border[i]].cross(cx_.vertices[border[(i + 1) % border.size()]]);
      origin += cx_.vertices[border[i]] / double(border.size());
    }
    normal.normalize();
    const Eigen::Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
    auto to2 = [&](const Eigen::Vector3d& p) { return Kernel::Point_2((p - origin).dot(e1), (p - origin).dot(e2)); };
    Cdt cdt;
    std::vector<Cdt::Vertex_handle> handles;
    for (uint32_t v : border) {
      handles.push_back(cdt.insert(to2(cx_.vertices[v])));
      if (handles.back()->info().id != kNoVertex) return centroidFan(border, face, displaced);  // two border points project together
      handles.back()->info().id = v;
    }
    for (size_t i = 0; i < handles.size(); ++i) cdt.insert_constraint(handles[i], handles[(i + 1) % handles.size()]);
    if (rough) addInnerPoints(cdt, border, origin, normal, e1, e2, displaced);
    markInside(cdt);
    for (auto f : cdt.finite_face_handles()) {
      if (f->info() % 2 != 1) continue;
      const std::array<uint32_t, 3> t = {f->vertex(0)->info().id, f->vertex(1)->info().id, f->vertex(2)->info().id};
      if (t[0] == kNoVertex || t[1] == kNoVertex || t[2] == kNoVertex) return centroidFan(border, face, displaced);
      face.triangles.push_back(t);
    }
  }

private:
  // A flat fan around the centroid: for a border the triangulation had to add points to (its
  // projection crosses itself, after rounding).
  void centroidFan(const std::vector<uint32_t>& border, CellFace& face, std::vector<std::pair<uint32_t, Eigen::Vector3d>>& displaced) {
    for (const auto& [v, flat] : displaced) cx_.vertices[v] = flat;  // unused from now on
    displaced.clear();
    face.triangles.clear();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (uint32_t v : border) centre += cx_.vertices[v] / double(border.size());
    const uint32_t c = uint32_t(cx_.vertices.size());
    cx_.vertices.push_back(centre);
    for (size_t i = 0; i < border.size(); ++i) face.triangles.push_back({c, border[i], border[(i + 1) % border.size()]});
  }

  // Points on edge a-b every h or less, a and b included, in the order a -> b; computed once per
  // edge from its lower vertex, so the faces sharing it get the same points.
  const std::vector<uint32_t>& edgePoints(uint32_t a, uint32_t b) {
    const auto key = std::minmax(a, b);
    auto it = edges_.find(key);
    if (it == edges_.end()) {
      const Eigen::Vector3d p = cx_.vertices[key.first], q = cx_.vertices[key.second];
      const int n = roughEdges_.count(key) ? std::max(1, int(std::ceil((q - p).norm() / h_))) : 1;
      std::vector<uint32_t> points = {key.first};
      for (int k = 1; k < n; ++k) {
        const Eigen::Vector3d point = p + (q - p) * (double(k) / n);
        if (!region_.contains(point)) continue;
        points.push_back(uint32_t(cx_.vertices.size()));
        cx_.vertices.push_back(point);
      }
      points.push_back(key.second);
      it = edges_.emplace(key, std::move(points)).first;
    }
    if (it->second.front() == a) return it->second;
    reversed_ = std::vector<uint32_t>(it->second.rbegin(), it->second.rend());
    return reversed_;
  }

  void addInnerPoints(Cdt& cdt, const std::vector<uint32_t>& border, const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& normal, const Eigen::Vector3d& e1, const Eigen::Vector3d& e2,
                      std::vector<std::pair<uint32_t, Eigen::Vector3d>>& displaced) {
    std::vector<Eigen::Vector2d> ring;
    for (uint32_t v : border) ring.emplace_back((cx_.vertices[v] - origin).dot(e1), (cx_.vertices[v] - origin).dot(e2));
    Eigen::AlignedBox2d box;
    for (const auto& p : ring) box.extend(p);
    auto borderDistance = [&](const Eigen::Vector2d& p) {
      double d = INFINITY;
      bool inside = true;
      for (size_t i = 0; i < ring.size(); ++i) {
        const Eigen::Vector2d a = ring[i], b = ring[(i + 1) % ring.size()], ab = b - a;
        const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
        d = std::min(d, (a + t * ab - p).norm());
        inside &= ab.x() * (p - a).y() - ab.y() * (p - a).x() > 0;
      }
      return inside ? d : -d;
    };
    std::vector<std::pair<Eigen::Vector2d, double>> inner;
    double deepest = 0;
    for (double y = box.min().y() + 0.5 * h_; y < box.max().y(); y += h_)
      for (double x = box.min().x() + 0.5 * h_; x < box.max().x(); x += h_) {
        if (!region_.contains(origin + x * e1 + y * e2)) continue;
        const double d = borderDistance({x, y});
        if (d < 0.5 * h_) continue;
        inner.push_back({{x, y}, d});
        deepest = std::max(deepest, d);
      }
    const double amplitude = std::min(amplitude_, 0.25 * deepest);
    for (const auto& [p, d] : inner) {
      const Eigen::Vector3d flat = origin + p.x() * e1 + p.y() * e2;
      const double t = std::min(1.0, d / (0.5 * deepest)), taper = t * t * (3 - 2 * t);
      const uint32_t id = uint32_t(cx_.vertices.size());
      cx_.vertices.push_back(flat + normal * (amplitude * taper * valueNoise(flat * (3.0 / (12 * h_)), seed_)));
      displaced.emplace_back(id, flat);
      cdt.insert(Kernel::Point_2(p.x(), p.y()))->info().id = id;
    }
  }

  // Nesting level of every face, from the infinite face across the constraints: odd = inside.
  static void markInside(Cdt& cdt) {
    for (auto f : cdt.all_face_handles()) f->info() = -1;
    std::deque<std::pair<Cdt::Face_handle, int>> queue = {{cdt.infinite_face(), 0}};
    while (!queue.empty()) {
      auto [start, level] = queue.front();
      queue.pop_front();
      if (start->info() != -1) continue;
      std::deque<Cdt::Face_handle> region = {start};
      start->info() = level;
      while (!region.empty()) {
        const Cdt::Face_handle f = region.front();
        region.pop_front();
        for (int i = 0; i < 3; ++i) {
          const Cdt::Face_handle n = f->neighbor(i);
          if (n->info() != -1) continue;
          if (cdt.is_constrained({f, i})) {
            queue.push_back({n, level + 1});
          } else {
            n->info() = level;
            region.push_back(n);
          }
        }
      }
    }
  }

  CellComplex& cx_;
  Eigen::AlignedBox3d region_;
  double h_, amplitude_;
  uint32_t seed_;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> edges_;
  std::set<std::pair<uint32_t, uint32_t>> roughEdges_;
  std::vector<uint32_t> reversed_;
};

// Faces of the cells whose surface intersects itself (rough faces that cross a neighbour).
std::set<uint32_t> selfIntersectingFaces(const CellComplex& cx, const std::set<int>& cells) {
  std::set<uint32_t> faces;
  for (int c : cells) {
    const std::vector<int> group = {c};
    const CellSurface s = cx.surfaceOf(group);
    SurfaceMesh mesh;
    for (const auto& p : s.vertices) mesh.add_vertex(Point3(p.x(), p.y(), p.z()));
    for (const auto& t : s.triangles)
      if (mesh.add_face(SurfaceMesh::Vertex_index(t[0]), SurfaceMesh::Vertex_index(t[1]), SurfaceMesh::Vertex_index(t[2])) ==
          SurfaceMesh::null_face())
        throw Error("internal: a rough Voronoi cell is not a manifold");
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
    CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
    for (const auto& [a, b] : pairs) faces.insert({s.face[size_t(a)], s.face[size_t(b)]});
  }
  return faces;
}

double meanSiteSpacing(const Delaunay& dt, int sites) {
  // Summed in the order of the sites' ids (the edge iterator's order depends on cell addresses).
  std::vector<std::pair<std::pair<int, int>, double>> lengths;
  for (const auto& e : dt.finite_edges()) {
    const auto u = e.first->vertex(e.second), v = e.first->vertex(e.third);
    if (u->info() >= sites || v->info() >= sites) continue;
    lengths.push_back({std::minmax(u->info(), v->info()), std::sqrt(CGAL::squared_distance(u->point(), v->point()))});
  }
  std::sort(lengths.begin(), lengths.end());
  double sum = 0;
  for (const auto& [key, length] : lengths) sum += length;
  return lengths.empty() ? 0.0 : sum / double(lengths.size());
}

void validate(std::span<const Eigen::Vector3d> sites, const Eigen::AlignedBox3d& bounds, const VoronoiCellsOptions& o) {
  if (sites.empty()) throw Error("Voronoi cells: no sites");
  if (!(o.roughness >= 0 && o.roughness <= 0.25)) throw Error("roughness must be in [0, 0.25]");
  if (bounds.isEmpty() || !bounds.min().allFinite() || !bounds.max().allFinite()) throw Error("Voronoi cells: empty bounds");
  for (const auto& s : sites)
    if (!s.allFinite() || !bounds.contains(s)) throw Error("Voronoi cells: a site is outside the bounds or not finite");
}

} // namespace

CellComplex voronoiCells(std::span<const Eigen::Vector3d> sites, const Eigen::AlignedBox3d& bounds,
                         const VoronoiCellsOptions& options, VoronoiCellsReport* report) {
  validate(sites, bounds, options);
  Delaunay dt = triangulate(sites, bounds);
  const int n = int(sites.size());
  CellComplex cx;
  cx.cells = n;
  const std::vector<Polygon> polys = voronoiPolygons(dt, n, cx.vertices);
  const double spacing = meanSiteSpacing(dt, n);
  VoronoiCellsReport r;
  r.meanSpacing = spacing;
  r.faces = polys.size();
  cx.faces.resize(polys.size());
  std::vector<std::vector<std::pair<uint32_t, Eigen::Vector3d>>> displaced(polys.size());
  const bool rough = options.roughness > 0 && spacing > 0;
  Relief relief(cx, bounds, spacing / 12, options.roughness * spacing, options.seed);
  for (const Polygon& p : polys)
    if (rough && p.outer >= 0) relief.addRoughEdges(p);
  for (size_t f = 0; f < polys.size(); ++f) {
    CellFace& face = cx.faces[f];
    face.inner = polys[f].inner;
    face.outer = polys[f].outer;
    if (rough) {
      relief.triangulate(polys[f], face.outer >= 0, face, displaced[f]);
    } else {
      const auto& loop = polys[f].loop;  // a fan from the first vertex (the faces are convex)
      for (size_t i = 1; i + 1 < loop.size(); ++i) face.triangles.push_back({loop[0], loop[i], loop[i + 1]});
    }
  }
  // A rough face that makes a cell intersect itself is flattened, until none does.
  if (options.roughness > 0) {
    std::set<int> check;
    for (int c = 0; c < n; ++c) check.insert(c);
    for (int round = 0; round < 4 && !check.empty(); ++round) {
      const std::set<uint32_t> bad = selfIntersectingFaces(cx, check);
      check.clear();
      for (uint32_t f : bad) {
        if (displaced[f].empty()) continue;
        for (const auto& [v, flat] : displaced[f]) cx.vertices[v] = flat;
        displaced[f].clear();
        ++r.flattenedFaces;
        for (int32_t c : {cx.faces[f].inner, cx.faces[f].outer})
          if (c >= 0) check.insert(c);
      }
    }
  }
  if (report) *report = r;
  return cx;
}

} // namespace texfab::geometry
