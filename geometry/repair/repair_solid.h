// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Makes a mesh a solid that can be cut: closed, manifold, consistently oriented with its normals
// outward, without self-intersections; or says why it cannot. What can be repaired is, and each
// repair is reported in a line: repeated vertices welded, triangles with a repeated corner
// removed, inconsistent orientation made consistent (vertices shared by separate fans split),
// holes filled, components turned outward. Non-manifold edges, degenerate triangles and
// self-intersections are refused (they need a person's judgement: which surface is meant).

#include "core/context.h"
#include "geometry/mesh.h"

#include <string>
#include <vector>

namespace texfab::geometry {

struct RepairSolidOptions {
  /// Fill holes (boundary loops) of at most this many edges; a larger hole is refused. 0 = refuse
  /// every open mesh.
  size_t maxHoleEdges = 1000;
  uint32_t holeTag = 1;  ///< faceTags value of hole-filling triangles (cut faces: they show the interior)
};

struct RepairSolidReport {
  std::vector<std::string> repairs;  ///< what was done, one line each; empty when the mesh was a solid
  size_t holeTriangles = 0;          ///< triangles added by hole filling (appended, tagged holeTag)
};

/// Repairs `mesh` in place (triangles keep their order; filled holes are appended) or throws
/// texfab::Error with a one-line message naming the fault ("the model intersects itself: ...").
RepairSolidReport repairSolid(Mesh& mesh, const RepairSolidOptions& options = {}, const Context& ctx = {});

} // namespace texfab::geometry
