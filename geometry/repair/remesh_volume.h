// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The volume a mesh encloses, as a new closed surface: the mesh's signed distance on a sparse grid
// (OpenVDB's mesh to level set, which accepts self-intersections, overlapping shells and
// non-manifold edges, but needs the surface closed up to about a voxel) and the zero isosurface of
// that distance (OpenVDB's volume to mesh, each quad split along its shorter diagonal). It is the
// last stage of repairSolid, for surfaces that cannot bound a solid as they are.
//
// Based on: K. Museth. VDB: High-resolution sparse volumes with dynamic topology. ACM TOG 32(3), 2013.
// Deviations: none; detail finer than a voxel is lost, and the input's UVs, normals and materials
//   do not carry over (the new surface has positions and triangles only).

#include "core/context.h"
#include "geometry/mesh.h"

namespace texfab::geometry {

struct RemeshVolumeOptions {
  /// Voxels along the longest side of the bounding box. [16, 4096]
  int resolution = 256;
};

/// Throws texfab::Error when the mesh encloses no volume at this resolution (an open surface whose
/// distance has no inside). Deterministic whatever ctx.threads.
Mesh remeshVolume(const Mesh& mesh, const RemeshVolumeOptions& options = {}, const Context& ctx = {});

} // namespace texfab::geometry
