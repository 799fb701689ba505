// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: the corefinement of CGAL's Polygon Mesh Processing package (S. Loriot, M. Rouxel-Labbé,
//   J. Tournois, I. O. Yaz, "Polygon Mesh Processing", CGAL User and Reference Manual 5.5,
//   "Corefinement and Boolean Operations"); patches are classified, as its Boolean operations do,
//   by the order of the four faces around an intersection edge (exact orientation predicates).
// Deviation: only the input triangles near a cell's surface are corefined, the others are kept or
//   dropped whole by flooding from the corefined ones, so one cell costs its neighbourhood instead
//   of the whole mesh (bunny00, a cell of 1/27 of its box: 30 ms instead of 450 ms for
//   corefine_and_compute_intersection).
#include "geometry/fracture/intersect_cells.h"

#include "core/error.h"
#include "core/parallel.h"
#include "geometry/cgal_surface_mesh.h"

#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <numeric>
#include <unordered_map>

namespace texfab::geometry {
namespace {

using namespace cgal;
using SideOfMesh = CGAL::Side_of_triangle_mesh<SurfaceMesh, Kernel>;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, uint32_t>;
namespace PMP = CGAL::Polygon_mesh_processing;

Point toPoint(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }
Point toPoint(const Eigen::Vector3f& p) { return {double(p.x()), double(p.y()), double(p.z())}; }

struct PointHash {
  size_t operator()(const Point& p) const {
    size_t h = 0;
    for (int i = 0; i < 3; ++i) {
      uint64_t bits;
      const double c = p[i];
      std::memcpy(&bits, &c, 8);
      h = (h ^ bits) * 0x100000001b3ull + (h >> 29);
    }
    return h;
  }
};

// The input mesh with what every group needs: exact points, triangle boxes, the triangle across
// each edge, connected components, and an exact inside test built on first use.
class Solid {
public:
  explicit Solid(const Mesh& mesh) : mesh(mesh) {
    points.reserve(mesh.positions.size());
    for (const auto& p : mesh.positions) points.push_back(toPoint(p));
    boxes.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles)
      boxes.push_back(points[t[0]].bbox() + points[t[1]].bbox() + points[t[2]].bbox());
    std::vector<uint32_t> count(points.size() + 1, 0);
    for (const auto& t : mesh.triangles)
      for (uint32_t v : t) ++count[v + 1];
    for (size_t v = 1; v < count.size(); ++v) count[v] += count[v - 1];
    incident_.assign(count.begin(), count.end());
    faces_.resize(3 * mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (uint32_t v : mesh.triangles[t]) faces_[count[v]++] = uint32_t(t);
    findComponents();
    CGAL::Bbox_3 all;
    for (const auto& b : boxes) all += b;
    weldStep = std::max({all.xmax() - all.xmin(), all.ymax() - all.ymin(), all.zmax() - all.zmin(), 1e-30}) * 1e-7;
  }

  /// The triangle holding the directed edge b -> a (across the edge a -> b of another).
  int64_t triangleWithEdge(uint32_t b, uint32_t a) const {
    for (uint32_t i = incident_[b]; i < incident_[b + 1]; ++i) {
      const auto& t = mesh.triangles[faces_[i]];
      for (int k = 0; k < 3; ++k)
        if (t[size_t(k)] == b && t[size_t((k + 1) % 3)] == a) return faces_[i];
    }
    return -1;
  }
  std::span<const uint32_t> trianglesAt(uint32_t v) const {
    return {faces_.data() + incident_[v], incident_[v + 1] - incident_[v]};
  }

  CGAL::Bounded_side side(const Point& p) const {
    std::call_once(once_, [&] {
      for (const Point& q : points) surface_.add_vertex(q);
      for (const auto& t : mesh.triangles) surface_.add_face(VI(t[0]), VI(t[1]), VI(t[2]));
      side_ = std::make_unique<SideOfMesh>(surface_);
    });
    return (*side_)(p);
  }

  const Mesh& mesh;
  std::vector<Point> points;
  std::vector<CGAL::Bbox_3> boxes;
  std::vector<uint32_t> component;         // per triangle (triangles sharing an edge are connected)
  std::vector<uint32_t> componentTriangle; // per component: its first triangle
  std::vector<CGAL::Bbox_3> componentBox;
  // About a float's precision at the model's size, and not a power of two: float coordinates do
  // not fall on its half-steps, where rounding errors would part equal points.
  double weldStep = 0;

private:
  void findComponents() {
    component.assign(mesh.triangles.size(), UINT32_MAX);
    std::vector<uint32_t> stack;
    for (uint32_t seed = 0; seed < mesh.triangles.size(); ++seed) {
      if (component[seed] != UINT32_MAX) continue;
      const uint32_t c = uint32_t(componentTriangle.size());
      componentTriangle.push_back(seed);
      componentBox.push_back(boxes[seed]);
      component[seed] = c;
      stack.push_back(seed);
      while (!stack.empty()) {
        const uint32_t t = stack.back();
        stack.pop_back();
        componentBox[c] += boxes[t];
        const auto& tri = mesh.triangles[t];
        for (int k = 0; k < 3; ++k) {
          const int64_t r = triangleWithEdge(tri[size_t((k + 1) % 3)], tri[size_t(k)]);
          if (r >= 0 && component[size_t(r)] == UINT32_MAX) component[size_t(r)] = c, stack.push_back(uint32_t(r));
        }
      }
    }
  }

  std::vector<uint32_t> incident_, faces_;  // vertex -> triangles (CSR)
  mutable std::once_flag once_;
  mutable SurfaceMesh surface_;
  mutable std::unique_ptr<SideOfMesh> side_;
};

// Per group: the input triangles that may touch its surface (their box overlaps a triangle of it
// whose plane they reach), found in one pass over all groups.
std::vector<std::vector<uint32_t>> touchingTriangles(const Solid& solid, const CellComplex& complex,
                                                     std::span<const std::vector<int>> groups) {
  std::vector<std::vector<int>> groupsOfCell(size_t(std::max(complex.cells, 0)));
  for (size_t g = 0; g < groups.size(); ++g)
    for (int c : groups[g])
      if (c >= 0 && c < complex.cells) groupsOfCell[size_t(c)].push_back(int(g));
  std::vector<std::vector<int>> boundaryOf(complex.faces.size());  // face -> groups it bounds
  for (size_t f = 0; f < complex.faces.size(); ++f) {
    const CellFace& face = complex.faces[f];
    auto groupsAt = [&](int32_t c) { return c >= 0 && c < complex.cells ? groupsOfCell[size_t(c)] : std::vector<int>{}; };
    const std::vector<int> a = groupsAt(face.inner), b = groupsAt(face.outer);
    std::set_symmetric_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(boundaryOf[f]));
  }
  std::vector<Box> model, cells;
  for (size_t t = 0; t < solid.boxes.size(); ++t) model.emplace_back(solid.boxes[t], uint32_t(t));
  std::vector<std::pair<uint32_t, uint32_t>> cellTriangles;  // (face, triangle)
  for (size_t f = 0; f < complex.faces.size(); ++f) {
    if (boundaryOf[f].empty()) continue;
    for (size_t i = 0; i < complex.faces[f].triangles.size(); ++i) {
      CGAL::Bbox_3 box;
      for (uint32_t v : complex.faces[f].triangles[i]) box += toPoint(complex.vertices[v]).bbox();
      cells.emplace_back(box, uint32_t(cellTriangles.size()));
      cellTriangles.emplace_back(uint32_t(f), uint32_t(i));
    }
  }
  std::vector<std::vector<uint32_t>> touching(groups.size());
  CGAL::box_intersection_d(model.begin(), model.end(), cells.begin(), cells.end(), [&](const Box& a, const Box& c) {
    const auto [f, i] = cellTriangles[c.info()];
    const auto& q = complex.faces[f].triangles[i];
    const Point q0 = toPoint(complex.vertices[q[0]]), q1 = toPoint(complex.vertices[q[1]]), q2 = toPoint(complex.vertices[q[2]]);
    int above = 0, below = 0;
    for (uint32_t v : solid.mesh.triangles[a.info()]) {
      const CGAL::Orientation o = CGAL::orientation(q0, q1, q2, solid.points[v]);
      above += o == CGAL::POSITIVE;
      below += o == CGAL::NEGATIVE;
    }
    if (above == 3 || below == 3) return;
    for (int g : boundaryOf[f]) touching[size_t(g)].push_back(a.info());
  });
  for (auto& list : touching) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return touching;
}

// Carries each face's origin (input triangle or cell face) to the faces it is split into.
struct OriginVisitor : PMP::Corefinement::Default_visitor<SurfaceMesh> {
  const SurfaceMesh* first = nullptr;
  SurfaceMesh::Property_map<FI, int32_t> origin[2];
  int32_t pending[2] = {-1, -1};
  int which(const SurfaceMesh& tm) const { return &tm == first ? 0 : 1; }
  void before_subface_creations(FI f, SurfaceMesh& tm) { pending[which(tm)] = origin[which(tm)][f]; }
  void after_subface_created(FI f, SurfaceMesh& tm) { origin[which(tm)][f] = pending[which(tm)]; }
};

enum class Side : uint8_t { Unknown, Inside, Outside, Coplanar, Opposite };

// Where the face (a, b, p), running a -> b, lies near the edge ab relative to the closed surface
// whose two faces at ab are (a, b, q1) (running a -> b too) and (b, a, q2). Coplanar: it overlaps
// (a, b, q1) with the same orientation; Opposite: it overlaps (b, a, q2), facing it. Unknown when
// the face is degenerate at the edge.
Side sideAtEdge(const Point& a, const Point& b, const Point& p, const Point& q1, const Point& q2) {
  if (CGAL::collinear(a, b, p)) return Side::Unknown;
  const CGAL::Orientation o1 = CGAL::orientation(a, b, q1, p), o2 = CGAL::orientation(b, a, q2, p);
  if (o1 == CGAL::COPLANAR && CGAL::coplanar_orientation(a, b, q1, p) == CGAL::POSITIVE) return Side::Coplanar;
  if (o2 == CGAL::COPLANAR && CGAL::coplanar_orientation(b, a, q2, p) == CGAL::POSITIVE) return Side::Opposite;
  const bool convex = CGAL::orientation(a, b, q1, q2) != CGAL::POSITIVE;
  const bool in1 = o1 == CGAL::NEGATIVE, in2 = o2 == CGAL::NEGATIVE;
  return (convex ? in1 && in2 : in1 || in2) ? Side::Inside : Side::Outside;
}

// Side of a patch from the majority of its first few vertices that are not on the other surface;
// Unknown when every vertex is on it.
template <class SideOf>
Side sideByVertices(const std::vector<Point>& vertices, const SideOf& sideOf) {
  constexpr int kVotes = 5;
  int inside = 0, outside = 0;
  for (size_t i = 0; i < vertices.size() && inside + outside < kVotes; ++i) {
    const CGAL::Bounded_side s = sideOf(vertices[i]);
    inside += s == CGAL::ON_BOUNDED_SIDE;
    outside += s == CGAL::ON_UNBOUNDED_SIDE;
  }
  return inside + outside == 0 ? Side::Unknown : inside > outside ? Side::Inside : Side::Outside;
}

// A triangle mesh with per-face origins and constrained (intersection) edges, and its patches:
// the components that the constrained edges separate.
struct Surface {
  SurfaceMesh mesh;
  SurfaceMesh::Property_map<FI, int32_t> origin = mesh.add_property_map<FI, int32_t>("f:origin", -1).first;
  SurfaceMesh::Property_map<EI, bool> constrained = mesh.add_property_map<EI, bool>("e:constrained", false).first;
  SurfaceMesh::Property_map<FI, std::size_t> patch = mesh.add_property_map<FI, std::size_t>("f:patch", 0).first;
  std::vector<Side> sides;  // per patch

  void findPatches() {
    sides.assign(PMP::connected_components(mesh, patch, CGAL::parameters::edge_is_constrained_map(constrained)),
                 Side::Unknown);
  }
  // Vertices on constrained edges by position: the same intersection point in the other mesh.
  std::unordered_map<Point, VI, PointHash> constrainedVertices() const {
    std::unordered_map<Point, VI, PointHash> map;
    for (EI e : mesh.edges())
      if (constrained[e])
        for (VI v : {mesh.vertex(e, 0), mesh.vertex(e, 1)}) map.emplace(mesh.point(v), v);
    return map;
  }
  // Classifies the patches still unknown by those of their vertices that `use` accepts
  // (sideByVertices) against `sideOf`.
  template <class SideOf, class Use>
  void classifyByVertices(const SideOf& sideOf, const Use& use) {
    std::vector<std::vector<Point>> samples(sides.size());
    for (FI f : mesh.faces())
      if (sides[patch[f]] == Side::Unknown)
        for (VI v : mesh.vertices_around_face(mesh.halfedge(f)))
          if (use(v)) samples[patch[f]].push_back(mesh.point(v));
    for (size_t p = 0; p < sides.size(); ++p)
      if (sides[p] == Side::Unknown) sides[p] = sideByVertices(samples[p], sideOf);
  }
  // Classifies the patches that reach a constrained edge against the closed surface `other`.
  void classifyAtEdges(const Surface& other) {
    const auto otherVertices = other.constrainedVertices();
    for (FI f : mesh.faces()) {
      Side& side = sides[patch[f]];
      if (side != Side::Unknown) continue;
      for (HI h : mesh.halfedges_around_face(mesh.halfedge(f))) {
        if (!constrained[mesh.edge(h)]) continue;
        const Point &a = mesh.point(mesh.source(h)), &b = mesh.point(mesh.target(h));
        const auto ia = otherVertices.find(a), ib = otherVertices.find(b);
        if (ia == otherVertices.end() || ib == otherVertices.end()) continue;
        const HI g = other.mesh.halfedge(ia->second, ib->second);
        if (g == SurfaceMesh::null_halfedge() || other.mesh.is_border(g) || other.mesh.is_border(other.mesh.opposite(g)))
          continue;
        const Point& p = mesh.point(mesh.target(mesh.next(h)));
        const Point& q1 = other.mesh.point(other.mesh.target(other.mesh.next(g)));
        const Point& q2 = other.mesh.point(other.mesh.target(other.mesh.next(other.mesh.opposite(g))));
        side = sideAtEdge(a, b, p, q1, q2);
        if (side != Side::Unknown) break;
      }
    }
  }
};

// What one group's piece is made of, before attributes: positions, triangles and their origin
// (>= 0: input triangle; < 0: -1 - cell face).
struct RawPiece {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<int32_t> origin;
};

// CGAL's corefinement reports intersections in an order that depends on where its boxes lie in
// memory (Box_intersection_d::ID_FROM_BOX_ADDRESS), so the order of the faces and vertices it
// creates changes from run to run once threads allocate beside it. The piece is put in an order
// its geometry defines: each triangle starts at its smallest corner (orientation kept), the
// model's triangles by input triangle then corners, the cut faces after them by cell face then
// corners, and vertices numbered by first use.
void canonicalize(RawPiece& piece) {
  const auto& pos = piece.positions;
  auto less = [&](uint32_t a, uint32_t b) {
    return std::lexicographical_compare(pos[a].data(), pos[a].data() + 3, pos[b].data(), pos[b].data() + 3);
  };
  for (auto& t : piece.triangles) {
    const int first = less(t[1], t[0]) ? (less(t[2], t[1]) ? 2 : 1) : (less(t[2], t[0]) ? 2 : 0);
    std::rotate(t.begin(), t.begin() + first, t.end());
  }
  auto rank = [](int32_t origin) { return origin >= 0 ? int64_t(origin) : int64_t(INT32_MAX) - origin; };
  std::vector<uint32_t> order(piece.triangles.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
    if (piece.origin[x] != piece.origin[y]) return rank(piece.origin[x]) < rank(piece.origin[y]);
    const auto &a = piece.triangles[x], &b = piece.triangles[y];
    for (int k = 0; k < 3; ++k) {
      if (less(a[size_t(k)], b[size_t(k)])) return true;
      if (less(b[size_t(k)], a[size_t(k)])) return false;
    }
    return false;
  });
  RawPiece out;
  std::vector<uint32_t> index(pos.size(), UINT32_MAX);
  for (uint32_t t : order) {
    std::array<uint32_t, 3> tri = piece.triangles[t];
    for (uint32_t& v : tri) {
      if (index[v] == UINT32_MAX) index[v] = uint32_t(out.positions.size()), out.positions.push_back(pos[v]);
      v = index[v];
    }
    out.triangles.push_back(tri);
    out.origin.push_back(piece.origin[t]);
  }
  piece = std::move(out);
}

// Drops each pair of faces on the same three vertices that face opposite ways.
void dropFacingPairs(RawPiece& piece) {
  const uint32_t n = uint32_t(piece.triangles.size());
  std::vector<std::array<uint32_t, 3>> corners(piece.triangles);
  for (auto& c : corners) std::sort(c.begin(), c.end());
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return corners[a] < corners[b]; });
  auto opposite = [&](uint32_t a, uint32_t b) {
    const auto &x = piece.triangles[a], &y = piece.triangles[b];
    for (size_t k = 0; k < 3; ++k)
      if (x[0] == y[k]) return x[1] == y[(k + 2) % 3];
    return false;
  };
  std::vector<uint8_t> dropped(n, 0);
  for (uint32_t i = 0, j; i < n; i = j) {
    for (j = i + 1; j < n && corners[order[j]] == corners[order[i]]; ++j) {}
    for (uint32_t a = i; a < j; ++a)
      for (uint32_t b = a + 1; b < j && !dropped[order[a]]; ++b)
        if (!dropped[order[b]] && opposite(order[a], order[b])) dropped[order[a]] = dropped[order[b]] = 1;
  }
  size_t out = 0;
  for (uint32_t t = 0; t < n; ++t)
    if (!dropped[t]) piece.triangles[out] = piece.triangles[t], piece.origin[out++] = piece.origin[t];
  piece.triangles.resize(out);
  piece.origin.resize(out);
}

class GroupIntersection {
public:
  GroupIntersection(const Solid& solid, const CellSurface& cell) : solid_(solid), state_(solid.boxes.size(), kOther) {
    for (const auto& v : cell.vertices) cell_.mesh.add_vertex(toPoint(v));
    for (size_t t = 0; t < cell.triangles.size(); ++t) {
      const auto& tri = cell.triangles[t];
      const FI f = cell_.mesh.add_face(VI(tri[0]), VI(tri[1]), VI(tri[2]));
      if (f == SurfaceMesh::null_face()) throw Error("internal: a cell's surface is not a manifold");
      cell_.origin[f] = -1 - int32_t(cell.face[t]);
    }
    for (VI v : cell_.mesh.vertices()) cellBox_ += cell_.mesh.point(v).bbox();
    cellInput_ = cell_.mesh;
  }

  RawPiece run(std::span<const uint32_t> touching, size_t& corefined, size_t& flooded) {
    for (uint32_t t : touching)
      for (uint32_t v : solid_.mesh.triangles[t])
        for (uint32_t r : solid_.trianglesAt(v)) state_[r] = kCorefined;
    buildCorefined();
    corefined = solidPart_.mesh.number_of_faces();
    if (corefined > 0) {
      OriginVisitor visitor;
      visitor.first = &solidPart_.mesh;
      visitor.origin[0] = solidPart_.origin;
      visitor.origin[1] = cell_.origin;
      PMP::corefine(solidPart_.mesh, cell_.mesh,
                    CGAL::parameters::visitor(visitor).edge_is_constrained_map(solidPart_.constrained),
                    CGAL::parameters::edge_is_constrained_map(cell_.constrained));
    }
    solidPart_.findPatches();
    cell_.findPatches();
    classify();
    flooded = floodFromKept();
    keepUntouchedComponents();
    RawPiece piece = assemble();
    canonicalize(piece);
    return piece;
  }

private:
  static bool kept(Side s, bool cell) { return s == Side::Inside || (!cell && s == Side::Coplanar); }
  bool keptPart(FI f) const { return kept(solidPart_.sides[solidPart_.patch[f]], false); }
  bool keptCell(FI f) const { return kept(cell_.sides[cell_.patch[f]], true); }

  // The corefined part as a surface mesh; a vertex where the part pinches (two fans of triangles)
  // gets one copy per fan. Pinches lie away from the cell: every triangle at a vertex of a
  // touching triangle is in the part.
  void buildCorefined() {
    std::unordered_map<uint64_t, VI> copies;  // (input vertex, fan root triangle) -> vertex
    for (size_t t = 0; t < state_.size(); ++t) {
      if (state_[t] != kCorefined) continue;
      std::array<VI, 3> v;
      for (int k = 0; k < 3; ++k) {
        const uint32_t input = solid_.mesh.triangles[t][size_t(k)];
        const uint64_t key = uint64_t(input) << 32 | fanRoot(input, uint32_t(t));
        const auto [it, inserted] = copies.emplace(key, VI());
        if (inserted) {
          it->second = solidPart_.mesh.add_vertex(solid_.points[input]);
          inputVertex_.push_back(input);
        }
        v[size_t(k)] = it->second;
      }
      const FI f = solidPart_.mesh.add_face(v[0], v[1], v[2]);
      if (f == SurfaceMesh::null_face()) throw Error("internal: the corefined part of the model is not a manifold");
      const auto& tri = solid_.mesh.triangles[t];
      if (CGAL::collinear(solid_.points[tri[0]], solid_.points[tri[1]], solid_.points[tri[2]]))  // corefine would not end
        throw Error("a cut meets a triangle whose corners are collinear (of the model, or left by an earlier cut); "
                    "move the cut slightly");
      solidPart_.origin[f] = int32_t(t);
    }
  }

  // The smallest corefined triangle of the fan of corefined triangles around `v` that holds `t`
  // (0 for a vertex whose triangles are all corefined: one fan).
  uint32_t fanRoot(uint32_t v, uint32_t t) const {
    const auto around = solid_.trianglesAt(v);
    if (std::all_of(around.begin(), around.end(), [&](uint32_t r) { return state_[r] == kCorefined; })) return 0;
    uint32_t root = t;
    for (int dir = 0; dir < 2; ++dir) {
      uint32_t cur = t;
      while (true) {
        const auto& tri = solid_.mesh.triangles[cur];
        const int k = tri[0] == v ? 0 : tri[1] == v ? 1 : 2;
        // dir 0: across the edge leaving v; dir 1: across the edge entering v.
        const uint32_t a = dir == 0 ? v : tri[size_t((k + 2) % 3)], b = dir == 0 ? tri[size_t((k + 1) % 3)] : v;
        const int64_t next = solid_.triangleWithEdge(b, a);
        if (next < 0 || state_[size_t(next)] != kCorefined || uint32_t(next) == t) break;
        cur = uint32_t(next);
        root = std::min(root, cur);
      }
    }
    return root;
  }

  int64_t inputOf(VI v) const { return size_t(v) < inputVertex_.size() ? int64_t(inputVertex_[size_t(v)]) : -1; }

  // The model's patches by their input vertices first: those are exact, while the intersection
  // points are rounded to doubles, so where the cell passes within rounding of model vertices the
  // faces around an intersection edge can be slivers facing the wrong way (sideAtEdge misleads).
  // Then the patches at intersection edges, then the rest by any vertex; a patch whose every
  // vertex lies on the other surface and that reaches no edge is outside.
  void classify() {
    const auto& cellSide = sideOfCell();
    auto modelSide = [&](const Point& q) { return solid_.side(q); };
    solidPart_.classifyByVertices(cellSide, [&](VI v) { return inputOf(v) >= 0; });
    solidPart_.classifyAtEdges(cell_);
    cell_.classifyAtEdges(solidPart_);
    solidPart_.classifyByVertices(cellSide, [](VI) { return true; });
    cell_.classifyByVertices(modelSide, [](VI) { return true; });
    for (Surface* s : {&solidPart_, &cell_})
      for (Side& side : s->sides)
        if (side == Side::Unknown) side = Side::Outside;
  }

  const SideOfMesh& sideOfCell() {
    if (!sideOfCell_) sideOfCell_ = std::make_unique<SideOfMesh>(cellInput_);
    return *sideOfCell_;
  }

  // Input triangles beyond the corefined part that are connected to a kept patch without
  // crossing the cell's surface (its border edges are input edges, never split) are inside.
  size_t floodFromKept() {
    std::vector<uint32_t> stack;
    auto visit = [&](int64_t r) {
      if (r >= 0 && state_[size_t(r)] == kOther) state_[size_t(r)] = kFlooded, stack.push_back(uint32_t(r)), kept_.push_back(uint32_t(r));
    };
    for (HI h : solidPart_.mesh.halfedges()) {
      if (!solidPart_.mesh.is_border(h)) continue;
      const HI inner = solidPart_.mesh.opposite(h);
      if (!keptPart(solidPart_.mesh.face(inner))) continue;
      const int64_t u = inputOf(solidPart_.mesh.source(inner)), w = inputOf(solidPart_.mesh.target(inner));
      if (u >= 0 && w >= 0) visit(solid_.triangleWithEdge(uint32_t(w), uint32_t(u)));
    }
    while (!stack.empty()) {
      const auto& tri = solid_.mesh.triangles[stack.back()];
      stack.pop_back();
      for (int k = 0; k < 3; ++k) visit(solid_.triangleWithEdge(tri[size_t((k + 1) % 3)], tri[size_t(k)]));
    }
    return kept_.size();
  }

  // Components of the input with no corefined triangle do not meet the cell: in or out whole.
  void keepUntouchedComponents() {
    std::vector<uint8_t> touched(solid_.componentTriangle.size(), 0);
    for (size_t t = 0; t < state_.size(); ++t)
      if (state_[t] == kCorefined) touched[solid_.component[t]] = 1;
    for (size_t c = 0; c < touched.size(); ++c) {
      if (touched[c] || !CGAL::do_overlap(solid_.componentBox[c], cellBox_)) continue;
      const uint32_t v = solid_.mesh.triangles[solid_.componentTriangle[c]][0];
      if (sideOfCell()(solid_.points[v]) != CGAL::ON_BOUNDED_SIDE) continue;
      for (size_t t = 0; t < state_.size(); ++t)
        if (solid_.component[t] == c) kept_.push_back(uint32_t(t));
    }
  }

  // The kept faces: the model's inside the cell or on it with the same orientation, the cell's
  // inside the model, with one vertex per position. That joins the cell's intersection vertices
  // to the model's, and the intersection points that rounding made equal (where the cell passes
  // within rounding of a model vertex); a face whose corners it joins is dropped, and so are two
  // faces it makes into the same face facing both ways.
  RawPiece assemble() const {
    RawPiece piece;
    std::unordered_map<Point, uint32_t, PointHash> index;  // by position on the weld grid
    auto vertex = [&](const Point& p) {
      const double step = solid_.weldStep;
      const Point key(std::round(p.x() / step), std::round(p.y() / step), std::round(p.z() / step));
      const auto [it, inserted] = index.emplace(key, uint32_t(piece.positions.size()));
      if (inserted) piece.positions.emplace_back(p.x(), p.y(), p.z());
      return it->second;
    };
    auto face = [&](const SurfaceMesh& mesh, FI f) {
      std::array<uint32_t, 3> tri;
      int k = 0;
      for (VI v : mesh.vertices_around_face(mesh.halfedge(f))) tri[size_t(k++)] = vertex(mesh.point(v));
      return tri;
    };
    auto add = [&](const std::array<uint32_t, 3>& tri, int32_t origin) {
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) return;
      piece.triangles.push_back(tri);
      piece.origin.push_back(origin);
    };
    for (FI f : solidPart_.mesh.faces())
      if (keptPart(f)) add(face(solidPart_.mesh, f), solidPart_.origin[f]);
    for (uint32_t t : kept_) {
      const auto& in = solid_.mesh.triangles[t];
      add({vertex(solid_.points[in[0]]), vertex(solid_.points[in[1]]), vertex(solid_.points[in[2]])}, int32_t(t));
    }
    for (FI f : cell_.mesh.faces())
      if (keptCell(f)) add(face(cell_.mesh, f), cell_.origin[f]);
    dropFacingPairs(piece);
    return piece;
  }

  static constexpr int32_t kOther = 0, kCorefined = 1, kFlooded = 2;
  const Solid& solid_;
  std::vector<int32_t> state_;        // per input triangle: kOther, kCorefined or kFlooded
  Surface cell_, solidPart_;
  CGAL::Bbox_3 cellBox_;
  std::vector<uint32_t> inputVertex_; // per corefined-part vertex created from an input vertex
  std::vector<uint32_t> kept_;        // input triangles kept whole
  // The cell as it was before corefinement, for side queries: corefinement can leave zero-area
  // triangles (intersection points rounded onto each other), on which CGAL's ray casting never ends.
  SurfaceMesh cellInput_;
  std::unique_ptr<SideOfMesh> sideOfCell_;
};

// Barycentric coordinates of p in triangle (a, b, c), by least squares (p lies on it up to rounding).
Eigen::Vector3d barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  if (p == a) return {1, 0, 0};
  if (p == b) return {0, 1, 0};
  if (p == c) return {0, 0, 1};
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = d.dot(e0), d21 = d.dot(e1);
  const double det = d00 * d11 - d01 * d01;
  if (!(det > 0)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  const double v = (d11 * d20 - d01 * d21) / det, w = (d00 * d21 - d01 * d20) / det;
  return {1 - v - w, v, w};
}

// The piece as a Mesh: input attributes interpolated at the corners of split triangles, cut faces
// with flat normals, the cut material and tag.
CellPiece buildPiece(const Mesh& in, const RawPiece& raw, const IntersectCellsOptions& o) {
  CellPiece piece;
  Mesh& m = piece.mesh;
  m.materials = in.materials;
  for (const auto& p : raw.positions) m.positions.push_back(p.cast<float>());
  m.triangles = raw.triangles;
  const size_t n = raw.triangles.size();
  if (in.hasUvs()) m.uvs.resize(3 * n, Eigen::Vector2f::Zero());
  if (in.hasNormals()) m.normals.resize(3 * n);
  if (in.hasTangents()) m.tangents.resize(3 * n, Eigen::Vector4f(1, 0, 0, 1));
  m.faceMaterials.resize(n);
  m.faceTags.resize(n);
  piece.cutFace.resize(n, -1);
  piece.source.resize(n, -1);
  for (size_t t = 0; t < n; ++t) {
    const auto& tri = raw.triangles[t];
    if (raw.origin[t] >= 0) piece.source[t] = raw.origin[t];
    if (raw.origin[t] < 0) {
      piece.cutFace[t] = -1 - raw.origin[t];
      m.faceMaterials[t] = o.cutMaterial;
      m.faceTags[t] = o.cutTag;
      const Eigen::Vector3d normal =
          (raw.positions[tri[1]] - raw.positions[tri[0]]).cross(raw.positions[tri[2]] - raw.positions[tri[0]]).normalized();
      if (m.hasNormals())
        for (int k = 0; k < 3; ++k) m.normals[3 * t + size_t(k)] = normal.allFinite() ? normal.cast<float>() : Eigen::Vector3f(0, 0, 1);
      continue;
    }
    const size_t s = size_t(raw.origin[t]);
    m.faceMaterials[t] = in.materialOf(s);
    m.faceTags[t] = in.tagOf(s);
    const auto& src = in.triangles[s];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d w = barycentric(raw.positions[tri[size_t(k)]], in.positions[src[0]].cast<double>(),
                                            in.positions[src[1]].cast<double>(), in.positions[src[2]].cast<double>());
      const size_t c = 3 * t + size_t(k), c0 = 3 * s;
      auto mix = [&](const auto& a) { return (w[0] * a[c0].template cast<double>() + w[1] * a[c0 + 1].template cast<double>() +
                                              w[2] * a[c0 + 2].template cast<double>()).template cast<float>().eval(); };
      if (in.hasUvs()) m.uvs[c] = w == Eigen::Vector3d(1, 0, 0) ? in.uvs[c0] : w == Eigen::Vector3d(0, 1, 0) ? in.uvs[c0 + 1]
                                  : w == Eigen::Vector3d(0, 0, 1) ? in.uvs[c0 + 2] : mix(in.uvs);
      if (in.hasNormals()) m.normals[c] = mix(in.normals).normalized();
      if (in.hasTangents()) {
        Eigen::Vector4f tangent = mix(in.tangents);
        tangent.head<3>().normalize();
        tangent.w() = in.tangents[c0].w();
        m.tangents[c] = tangent;
      }
    }
  }
  return piece;
}

// Every edge has exactly two triangles running it in opposite directions (one sort of 64-bit
// keys: (min, max, direction)).
bool closedManifold(const Mesh& piece) {
  std::vector<uint64_t> keys;
  keys.reserve(3 * piece.triangles.size());
  for (const auto& t : piece.triangles)
    for (int k = 0; k < 3; ++k) {
      const uint64_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
      keys.push_back(std::min(a, b) << 33 | std::max(a, b) << 1 | uint64_t(a < b));
    }
  std::sort(keys.begin(), keys.end());
  size_t bad = keys.size() % 2;
  for (size_t i = 0; i + 1 < keys.size() && !bad; i += 2)
    bad += (keys[i] >> 1) != (keys[i + 1] >> 1) || (keys[i] & 1) != 0 || (keys[i + 1] & 1) != 1 ||
           (i + 2 < keys.size() && (keys[i + 2] >> 1) == (keys[i] >> 1));
  return !bad;
}

} // namespace

std::vector<CellPiece> intersectCells(const Mesh& solid, const CellComplex& complex, std::span<const std::vector<int>> groups,
                                      const IntersectCellsOptions& options, const Context& ctx,
                                      IntersectCellsReport* report) {
  if (!closedManifold(solid)) throw Error("the model is not a closed, consistently oriented manifold (repair it first)");
  Stage stage(ctx, "intersect");
  const Solid prepared(solid);
  const std::vector<std::vector<uint32_t>> touching = touchingTriangles(prepared, complex, groups);
  std::vector<CellPiece> pieces(groups.size());
  std::vector<size_t> corefined(groups.size()), flooded(groups.size());
  std::atomic<int64_t> done{0};
  parallelFor(0, int(groups.size()), ctx, [&](int b, int e) {
    for (int g = b; g < e; ++g) {
      const CellSurface surface = complex.surfaceOf(groups[size_t(g)]);
      RawPiece raw;
      if (!surface.triangles.empty()) {
        try {
          raw = GroupIntersection(prepared, surface).run(touching[size_t(g)], corefined[size_t(g)], flooded[size_t(g)]);
        } catch (const Error&) {
          throw;
        } catch (const std::exception& ex) {
          throw Error("intersecting piece " + std::to_string(g) + " failed: " + ex.what());
        }
      }
      pieces[size_t(g)] = buildPiece(solid, raw, options);
      pieces[size_t(g)].cells = groups[size_t(g)];
      if (!raw.triangles.empty() && !closedManifold(pieces[size_t(g)].mesh))
        throw Error("internal: piece " + std::to_string(g) + " is not a closed, oriented manifold; please report this model");
      stage.advance(++done, int64_t(groups.size()));
    }
  });
  if (report)
    for (size_t g = 0; g < groups.size(); ++g) report->corefinedTriangles += corefined[g], report->keptWhole += flooded[g];
  stage.finish(std::to_string(groups.size()) + " pieces");
  return pieces;
}

} // namespace texfab::geometry
