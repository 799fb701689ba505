// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Orientation repair: turns the triangles of each edge-connected part of a mesh one consistent
// way, facing out of the solid where the part is closed.
//
// A part is the set of triangles reached across two-triangle edges (MeshConnectivity::mate). It is
// walked breadth-first from its smallest triangle id; a triangle whose winding disagrees with the
// neighbour it is reached from is flipped. Then the part's side is chosen:
//  - closed parts (no edge without a mate): positive signed volume (outward normals), or negative
//    for a cavity, a part that lies inside an odd number of other closed parts (its box inside
//    theirs and the generalized winding number of 17 of its points: a shell that only overlaps
//    another stays outward, so that a print's winding rule takes their union; A. Jacobson,
//    L. Kavan, O. Sorkine-Hornung, "Robust Inside-Outside Segmentation using Generalized Winding
//    Numbers", SIGGRAPH 2013);
//  - open parts: the side most of the part's area already faced (ties: keep the first triangle's).
// A part where some edge cannot agree whatever the flips (a Möbius strip) is not orientable: its
// walk's flips are kept and the edges left inconsistent are counted; the atlas cuts along them.

#include "geometry/mesh.h"
#include "geometry/mesh_connectivity.h"

#include <cstdint>
#include <string>
#include <vector>

namespace texfab::geometry {

struct MeshOrientation {
  std::vector<uint32_t> flip;          ///< triangles to flip, ascending
  size_t parts = 0;                    ///< edge-connected parts
  size_t reversedParts = 0;            ///< consistent parts turned over as a whole (inside out)
  size_t nonOrientableParts = 0;
  size_t inconsistentEdgesLeft = 0;    ///< after the flips (non-orientable parts only)
};

/// The flips that orient the mesh; does not change it. Deterministic.
MeshOrientation computeOrientation(const Mesh& mesh, const MeshConnectivity& connectivity);

/// Reverses the winding of the given triangles (flipTriangle).
void flipTriangles(Mesh& mesh, const std::vector<uint32_t>& triangles);

/// Orients the mesh in place (computeConnectivity, computeOrientation, flipTriangles).
MeshOrientation orientMesh(Mesh& mesh);

/// What a repair did, in one line for a report ("re-oriented 6 triangles ..."); empty when the
/// mesh was oriented already.
std::string describeRepair(const MeshOrientation& orientation);
/// A warning for non-orientable parts (their inconsistent edges stay cuts); empty when none.
std::string describeWarning(const MeshOrientation& orientation);

} // namespace texfab::geometry
