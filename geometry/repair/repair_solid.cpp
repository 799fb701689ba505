// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: CGAL's Polygon Mesh Processing (orient_polygon_soup, triangulate_hole [Liepa 2003],
//   self_intersections, orient_to_bound_a_volume).
#include "geometry/repair/repair_solid.h"

#include "core/error.h"
#include "core/text.h"
#include "geometry/cgal_surface_mesh.h"
#include "geometry/mesh_connectivity.h"
#include "geometry/repair/remesh_volume.h"

#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <map>

namespace texfab::geometry {
namespace {

using namespace cgal;
namespace PMP = CGAL::Polygon_mesh_processing;

Point toPoint(const Eigen::Vector3f& p) { return {double(p.x()), double(p.y()), double(p.z())}; }

// The mesh as a surface mesh, face i = triangle i; false when it is not an oriented manifold.
bool toSurfaceMesh(const Mesh& mesh, SurfaceMesh& sm) {
  sm.clear();
  for (const auto& p : mesh.positions) sm.add_vertex(toPoint(p));
  for (const auto& t : mesh.triangles)
    if (sm.add_face(VI(t[0]), VI(t[1]), VI(t[2])) == SurfaceMesh::null_face()) return false;
  return true;
}

// Consistent orientation by CGAL's soup orientation (which splits vertices shared by fans that
// cannot be oriented together); triangles keep their order and each is flipped or not.
void orientConsistently(Mesh& mesh, RepairSolidReport& r) {
  std::vector<Point> points;
  for (const auto& p : mesh.positions) points.push_back(toPoint(p));
  std::vector<std::vector<size_t>> polygons;
  for (const auto& t : mesh.triangles) polygons.push_back({t[0], t[1], t[2]});
  const size_t before = points.size();
  PMP::orient_polygon_soup(points, polygons);
  // Welded positions are distinct: a split vertex is recognized by its position.
  std::map<std::array<double, 3>, uint32_t> original;
  for (size_t v = 0; v < before; ++v) original[{points[v].x(), points[v].y(), points[v].z()}] = uint32_t(v);
  size_t flipped = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    std::array<uint32_t, 3> base;
    for (int k = 0; k < 3; ++k) {
      const Point& p = points[polygons[t][size_t(k)]];
      base[size_t(k)] = original.at({p.x(), p.y(), p.z()});
    }
    const auto& c = mesh.triangles[t];
    const bool same = (base[0] == c[0] && base[1] == c[1]) || (base[0] == c[1] && base[1] == c[2]) ||
                      (base[0] == c[2] && base[1] == c[0]);
    if (!same) flipTriangle(mesh, t), ++flipped;
    // Each corner takes the (possibly split) vertex the soup gave it.
    for (uint32_t& v : mesh.triangles[t])
      for (int k = 0; k < 3; ++k)
        if (base[size_t(k)] == v) {
          v = uint32_t(polygons[t][size_t(k)]);
          break;
        }
  }
  for (size_t v = before; v < points.size(); ++v) mesh.positions.emplace_back(float(points[v].x()), float(points[v].y()), float(points[v].z()));
  if (flipped) r.repairs.push_back("made the orientation consistent (" + std::to_string(flipped) + " triangles flipped)");
  if (points.size() > before)
    r.repairs.push_back("split " + std::to_string(points.size() - before) + " vertices shared by separate fans of triangles");
}

void fillHoles(Mesh& mesh, SurfaceMesh& sm, const RepairSolidOptions& o, RepairSolidReport& r) {
  std::vector<HI> cycles;
  PMP::extract_boundary_cycles(sm, std::back_inserter(cycles));
  if (cycles.empty()) return;
  size_t added = 0;
  for (HI h : cycles) {
    size_t edges = 0;
    for (HI e : CGAL::halfedges_around_face(h, sm)) (void)e, ++edges;
    if (edges > o.maxHoleEdges)
      throw Error("the model is open: a hole of " + std::to_string(edges) + " edges (holes of up to " +
                  std::to_string(o.maxHoleEdges) + " are filled); close it in a mesh editor");
    std::vector<FI> patch;
    PMP::triangulate_hole(sm, h, std::back_inserter(patch));
    if (patch.empty()) throw Error("the model is open and a hole of " + std::to_string(edges) + " edges could not be filled");
    added += patch.size();
  }
  const size_t first = mesh.triangles.size();
  for (FI f = FI(uint32_t(first)); size_t(f) < sm.number_of_faces(); f = FI(uint32_t(size_t(f) + 1))) {
    std::array<uint32_t, 3> t;
    int k = 0;
    for (VI v : sm.vertices_around_face(sm.halfedge(f))) t[size_t(k++)] = uint32_t(v);
    mesh.triangles.push_back(t);
  }
  const size_t n = mesh.triangles.size();
  if (mesh.hasUvs()) mesh.uvs.resize(3 * n, Eigen::Vector2f::Zero());
  if (mesh.hasTangents()) mesh.tangents.resize(3 * n, Eigen::Vector4f(1, 0, 0, 1));
  if (mesh.hasNormals())
    for (size_t t = first; t < n; ++t)
      for (int k = 0; k < 3; ++k) mesh.normals.push_back(faceNormal(mesh, t));
  if (!mesh.faceMaterials.empty()) mesh.faceMaterials.resize(n, 0);
  mesh.faceTags.resize(n, 0);
  std::fill(mesh.faceTags.begin() + std::ptrdiff_t(first), mesh.faceTags.end(), o.holeTag);
  r.holeTriangles = added;
  r.repairs.push_back("filled " + counted(int64_t(cycles.size()), "hole") + " with " + counted(int64_t(added), "triangle"));
}

// A one-line description of the mesh's self-intersections, or "" when it has none. On
// ctx.threads of TBB's threads (CGAL's parallel search runs on the current task arena).
std::string selfIntersections(const SurfaceMesh& sm, const Context& ctx) {
  std::vector<std::pair<FI, FI>> pairs;
  tbb::task_arena arena(ctx.threads > 0 ? ctx.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    if (PMP::does_self_intersect<CGAL::Parallel_if_available_tag>(sm))
      PMP::self_intersections<CGAL::Parallel_if_available_tag>(sm, std::back_inserter(pairs));
  });
  if (pairs.empty()) return {};
  for (auto& [a, b] : pairs)
    if (b < a) std::swap(a, b);
  std::sort(pairs.begin(), pairs.end());
  const auto [a, b] = pairs.front();
  return "the model intersects itself (" + std::to_string(pairs.size()) + " pairs of triangles, e.g. " +
         (a == b ? "triangle " + std::to_string(size_t(a)) + " is degenerate"
                 : "triangles " + std::to_string(size_t(a)) + " and " + std::to_string(size_t(b))) +
         ")";
}

void orientOutward(Mesh& mesh, SurfaceMesh& sm, RepairSolidReport& r) {
  PMP::orient_to_bound_a_volume(sm);
  size_t flipped = 0;
  for (FI f : sm.faces()) {
    const auto& c = mesh.triangles[size_t(f)];
    const HI h = sm.halfedge(f);
    const uint32_t a = uint32_t(sm.source(h)), b = uint32_t(sm.target(h));
    const bool same = (a == c[0] && b == c[1]) || (a == c[1] && b == c[2]) || (a == c[2] && b == c[0]);
    if (!same) flipTriangle(mesh, size_t(f)), ++flipped;
  }
  if (flipped) r.repairs.push_back("turned " + std::to_string(flipped) + " triangles to face outward");
}

// Orients and closes the surface as it is; returns "" when it bounds a solid, else the fault.
std::string closeSurface(Mesh& mesh, SurfaceMesh& sm, const RepairSolidOptions& o, RepairSolidReport& r,
                         const Context& ctx) {
  const MeshConnectivity topology = computeConnectivity(mesh);
  if (topology.nonManifoldEdges)
    return "the model is not a manifold (" + counted(int64_t(topology.nonManifoldEdges), "edge") +
           (topology.nonManifoldEdges == 1 ? " is" : " are") + " shared by three or more triangles)";
  if (topology.inconsistentEdges || !toSurfaceMesh(mesh, sm)) {
    orientConsistently(mesh, r);
    if (!toSurfaceMesh(mesh, sm)) return "the model is not a manifold and could not be oriented";
  }
  fillHoles(mesh, sm, o, r);
  if (o.allowSelfIntersections) return {};
  Stage check(ctx, "self-intersections");
  std::string fault = selfIntersections(sm, check.inner());
  check.finish();
  return fault;
}

// The last resort: the volume the surface encloses, meshed anew.
void rebuildFromVolume(Mesh& mesh, SurfaceMesh& sm, const std::string& fault, const RepairSolidOptions& o,
                       RepairSolidReport& r, const Context& ctx) {
  if (o.remesh.resolution == 0) throw Error(fault + ": cutting needs a solid; repair it in a mesh editor");
  Stage stage(ctx, "volume remesh");
  const BoundingBox box = boundingBox(mesh);
  const double voxel = double((box.max - box.min).maxCoeff()) / o.remesh.resolution;
  Mesh rebuilt;
  try {
    rebuilt = remeshVolume(mesh, o.remesh, stage.inner());
  } catch (const Error& e) {
    throw Error(fault + ", and its volume could not be rebuilt (" + e.what() + "): repair it in a mesh editor");
  }
  std::vector<Material> materials = std::move(mesh.materials);
  mesh = std::move(rebuilt);
  if (!materials.empty()) mesh.materials = {std::move(materials.front())};
  r.holeTriangles = 0;
  r.rebuilt = true;
  RepairSolidReport again;
  const std::string left = closeSurface(mesh, sm, o, again, stage.inner());
  if (!left.empty()) throw Error(fault + ", and the rebuilt volume is not a solid either: repair it in a mesh editor");
  stage.finish(std::to_string(mesh.triangles.size()) + " triangles");
  r.repairs.push_back(fault + ": rebuilt as the volume it encloses (" + std::to_string(mesh.triangles.size()) +
                      " triangles, voxels of " + figure(voxel) +
                      " units); its own UVs and materials are not kept");
}

} // namespace

RepairSolidReport repairSolid(Mesh& mesh, const RepairSolidOptions& o, const Context& ctx) {
  Stage stage(ctx, "repair");
  RepairSolidReport r;
  SurfaceMesh sm;
  const Context inner = stage.inner();
  if (const std::string fault = closeSurface(mesh, sm, o, r, inner); !fault.empty())
    rebuildFromVolume(mesh, sm, fault, o, r, inner);
  Stage outward(inner, "orientation");
  orientOutward(mesh, sm, r);
  outward.finish();
  stage.finish(r.repairs.empty() ? "a closed solid" : counted(int64_t(r.repairs.size()), "repair"));
  return r;
}

} // namespace texfab::geometry
