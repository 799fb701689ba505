// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/repair/prepare_mesh.h"

#include "core/error.h"
#include "core/text.h"
#include "geometry/repair/close_holes.h"
#include "geometry/repair/orient_mesh.h"
#include "geometry/repair/repair_solid.h"

namespace texfab::geometry {
namespace {

// Collects the repairs and warnings, and sends each to ctx at once.
class Log {
public:
  Log(MeshPreparation& p, const Context& ctx) : p_(p), ctx_(ctx) {}
  void repair(std::string line) {
    if (line.empty()) return;
    ctx_.warn("repaired: " + line);
    p_.repairs.push_back(std::move(line));
  }
  void warning(std::string line) {
    if (line.empty()) return;
    ctx_.warn(line);
    p_.warnings.push_back(std::move(line));
  }

private:
  MeshPreparation& p_;
  const Context& ctx_;
};

// Keeps the triangles with three distinct corners, with their attributes; returns how many went.
size_t dropRepeatedCorners(Mesh& mesh) {
  size_t out = 0;
  const size_t n = mesh.triangles.size();
  for (size_t t = 0; t < n; ++t) {
    const auto& c = mesh.triangles[t];
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    mesh.triangles[out] = c;
    for (size_t k = 0; k < 3; ++k) {
      if (mesh.hasUvs()) mesh.uvs[3 * out + k] = mesh.uvs[3 * t + k];
      if (mesh.hasNormals()) mesh.normals[3 * out + k] = mesh.normals[3 * t + k];
      if (mesh.hasTangents()) mesh.tangents[3 * out + k] = mesh.tangents[3 * t + k];
    }
    if (!mesh.faceMaterials.empty()) mesh.faceMaterials[out] = mesh.faceMaterials[t];
    if (!mesh.faceTags.empty()) mesh.faceTags[out] = mesh.faceTags[t];
    ++out;
  }
  mesh.triangles.resize(out);
  if (mesh.hasUvs()) mesh.uvs.resize(3 * out);
  if (mesh.hasNormals()) mesh.normals.resize(3 * out);
  if (mesh.hasTangents()) mesh.tangents.resize(3 * out);
  if (!mesh.faceMaterials.empty()) mesh.faceMaterials.resize(out);
  if (!mesh.faceTags.empty()) mesh.faceTags.resize(out);
  return n - out;
}

// Stage 1.
void weld(Mesh& mesh, MeshUse use, Log& log) {
  const size_t before = mesh.positions.size();
  weldPositions(mesh);
  if (mesh.positions.size() < before)
    log.repair("welded " + counted(int64_t(before - mesh.positions.size()), "repeated vertex", "repeated vertices"));
  if (use == MeshUse::Surface) return;
  if (const size_t dropped = dropRepeatedCorners(mesh))
    log.repair("removed " + counted(int64_t(dropped), "triangle") + " with a repeated corner");
  if (mesh.triangles.empty()) throw Error("the model has no triangles with three distinct corners");
  removeUnusedVertices(mesh);
}

// Stage 3 for Print: fans over simple loops; false when the surface is still not closed.
bool closeWithFans(Mesh& mesh, Log& log) {
  const CloseHolesReport holes = closeHoles(mesh);
  if (holes.holes > 0)
    log.repair("closed " + counted(int64_t(holes.holes), "hole") + " (" + counted(int64_t(holes.boundaryEdges), "boundary edge") +
               ") with fans of triangles");
  return holes.closed;
}

} // namespace

const char* meshUseName(MeshUse use) {
  switch (use) {
    case MeshUse::Surface: return "surface";
    case MeshUse::Print: return "print";
    case MeshUse::Solid: return "solid";
  }
  return "?";
}

MeshPreparation prepareMesh(Mesh& mesh, const PrepareMeshOptions& o, const Context& ctx) {
  validateMesh(mesh, "the model");
  if (mesh.triangles.empty()) throw Error("the model has no triangles");
  Stage stage(ctx, "preparation");
  MeshPreparation p;
  p.use = o.use;
  Log log(p, ctx);
  weld(mesh, o.use, log);
  const MeshOrientation orientation = orientMesh(mesh);
  log.repair(describeRepair(orientation));
  if (o.use == MeshUse::Surface) log.warning(describeWarning(orientation));
  const bool solid = o.use == MeshUse::Solid;
  if (solid || (o.use == MeshUse::Print && !closeWithFans(mesh, log))) {
    const RepairSolidOptions repair{o.maxHoleEdges, o.holeTag, o.remesh, /*allowSelfIntersections=*/!solid};
    const RepairSolidReport r = repairSolid(mesh, repair, stage.inner());
    for (const std::string& line : r.repairs) log.repair(line);
    p.holeTriangles = solid ? r.holeTriangles : 0;
    p.rebuilt = r.rebuilt;
  }
  stage.finish(p.repairs.empty() ? std::string("as it is") : counted(int64_t(p.repairs.size()), "repair"));
  return p;
}

PreparedMesh preparedCopy(const Mesh& model, const PrepareMeshOptions& options, const Context& ctx) {
  PreparedMesh prepared{model, {}};
  prepared.preparation = prepareMesh(prepared.mesh, options, ctx);
  return prepared;
}

} // namespace texfab::geometry
