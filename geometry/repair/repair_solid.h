// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The solid stages of prepareMesh (prepare_mesh.h; jobs call that): makes a welded mesh a closed,
// manifold surface, consistently oriented with its normals outward, and (unless allowed) without
// self-intersections; or says why it cannot. What can be repaired is, and each repair is reported
// in a line: inconsistent orientation made consistent (vertices shared by separate fans split),
// holes filled, components turned outward. A surface that still cannot bound a solid (non-manifold
// edges, self-intersections, overlapping shells) is rebuilt as the volume it encloses
// (remeshVolume), which keeps its shape down to a voxel but not its UVs; holes larger than
// maxHoleEdges are refused (which surface is meant needs a person's judgement).

#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/repair/remesh_volume.h"

#include <string>
#include <vector>

namespace texfab::geometry {

struct RepairSolidOptions {
  /// Fill holes (boundary loops) of at most this many edges; a larger hole is refused. 0 = refuse
  /// every open mesh.
  size_t maxHoleEdges = 1000;
  uint32_t holeTag = 1;  ///< faceTags value of hole-filling triangles (cut faces: they show the interior)
  /// The last stage's grid; resolution 0 = refuse such surfaces instead.
  RemeshVolumeOptions remesh;
  /// Keep self-intersections and overlapping shells (a print's winding rule takes their union).
  bool allowSelfIntersections = false;
};

struct RepairSolidReport {
  std::vector<std::string> repairs;  ///< what was done, one line each; empty when the mesh was a solid
  size_t holeTriangles = 0;          ///< triangles added by hole filling (appended, tagged holeTag)
  bool rebuilt = false;              ///< rebuilt as the volume it encloses
};

/// Repairs `mesh` (welded: no two vertices at one position, no triangle with a repeated corner) in
/// place (triangles keep their order and filled holes are appended, unless the surface is rebuilt)
/// or throws texfab::Error with a one-line message naming the fault ("the model is open: a hole of
/// ...").
RepairSolidReport repairSolid(Mesh& mesh, const RepairSolidOptions& options = {}, const Context& ctx = {});

} // namespace texfab::geometry
