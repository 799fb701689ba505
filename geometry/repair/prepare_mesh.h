// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The one preparation of an input model, shared by every job. Its stages run in order; what the
// use needs decides how far it goes:
//
//   stage                                   Surface    Print      Solid
//   1. weld equal positions                 yes        yes        yes
//      drop triangles with a repeated corner           yes        yes
//   2. orient each edge-connected part      yes        yes        yes   (orientMesh)
//   3. close holes                                     fans       Liepa (repairSolid)
//   4. when 3 cannot close it                          4'         -
//   4'. a solid: consistent fans split, holes filled, and where the surface still cannot be
//       closed, or (Solid) is non-manifold or intersects itself, rebuilt as the volume it encloses
//       (remeshVolume), turned outward                              (repairSolid)
//
// Surface (texture, atlas): open, non-manifold and self-intersecting surfaces are textured as they
// are. Print (slice): the voxelizer's non-zero winding rule prints overlapping shells and
// self-intersections as their union, so only a closed surface is needed; hole fans keep the
// model's UVs at the hole's edge. Solid (fracture, cut): a closed, manifold, outward surface without
// self-intersections, with filled holes tagged as cut faces.
//
// Every repair is one line, sent to ctx as a warning when it is made (before the job's long work)
// and kept in the result for the report. Faults that cannot be repaired throw texfab::Error with one
// line naming the fault and what to do.

#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/repair/remesh_volume.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace texfab::geometry {

enum class MeshUse {
  Surface,  ///< a surface to texture
  Print,    ///< a closed surface whose winding number defines the printed volume
  Solid,    ///< a solid to cut
};

/// "surface", "print", "solid".
const char* meshUseName(MeshUse use);

struct PrepareMeshOptions {
  PrepareMeshOptions(MeshUse use = MeshUse::Surface) : use(use) {}  // NOLINT: prepareMesh(mesh, MeshUse::Print)

  MeshUse use;
  /// Print and Solid: holes (boundary loops) of at most this many edges are filled by stage 4';
  /// a larger one is refused (which surface is meant needs a person). Print's fans (stage 3) close
  /// simple loops of any size.
  size_t maxHoleEdges = 1000;
  /// Solid: faceTags value of the triangles that fill holes (cut faces: they show the interior).
  uint32_t holeTag = 1;
  /// Print and Solid: the grid of the last resort (its resolution 0 = refuse instead).
  RemeshVolumeOptions remesh;
};

struct MeshPreparation {
  MeshUse use = MeshUse::Surface;
  std::vector<std::string> repairs;   ///< what was done, one line each; empty when nothing was needed
  std::vector<std::string> warnings;  ///< faults kept (a non-orientable part), one line each
  size_t holeTriangles = 0;           ///< Solid: triangles added by hole filling, tagged holeTag
  bool rebuilt = false;               ///< rebuilt from its volume: UVs, normals and materials but the first are gone
};

/// A model prepared for a use, with what that took. Jobs take it from callers that prepare the
/// model before long work of their own (an exemplar analysis), so that the repairs are said, and a
/// model that cannot be prepared is refused, before that work.
struct PreparedMesh {
  Mesh mesh;
  MeshPreparation preparation;
};

/// Prepares `mesh` in place for `options.use`. Triangles keep their order unless the surface is
/// rebuilt; added ones are appended. Deterministic whatever ctx.threads.
MeshPreparation prepareMesh(Mesh& mesh, const PrepareMeshOptions& options, const Context& ctx = {});
/// The same on a copy of `model`.
PreparedMesh preparedCopy(const Mesh& model, const PrepareMeshOptions& options, const Context& ctx = {});

} // namespace texfab::geometry
