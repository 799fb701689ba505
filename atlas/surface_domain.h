// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The surface as synthesis in the atlas sees it (synthesis/synthesize_surface.h): a pyramid of
// sites with Jacobians and surface neighbors, built from a packed atlas, its texel fields and the
// per-texel Jacobians.
//
// Level 0 has one site per chart texel. Level a+1 has one site per (texel of the half-resolution
// grid, chart) that a level-a site falls in, with the mean of its children's Jacobians times 2. A
// site's neighbor in direction δ is the site of the next texel of the same chart when there is
// one; otherwise (at a chart border) it is found the way Lefebvre & Hoppe 2006 (§6) build their
// indirection maps: by walking the step 2^a δ over the surface from the site (walkAtlas), across
// the seam into the adjacent chart, and taking the site where the walk lands. Level 0's neighbor
// table is therefore the indirection map of the finest level; coarse levels get theirs the same way.
//
// Orientation: the tangent field t gives the exemplar's "up" on the surface (the user's
// --direction), so exemplar +v (rows run down the image) is -t and exemplar +u is t × n = -b
// (b = n × t): seen from outside the surface, the exemplar shows as it does on the screen, upright
// and not mirrored. The domain's Jacobians are computeJacobians()'s J = (t b)⁺ J_f with its rows
// swapped and negated.

#include "atlas/atlas.h"
#include "atlas/compute_jacobians.h"
#include "atlas/rasterize_atlas.h"
#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/mesh_connectivity.h"
#include "synthesis/synthesize_surface.h"

namespace texfab::atlas {

struct SurfaceDomainOptions {
  int maxLevels = 16; ///< levels built at most (also stops when the grid is 1 texel); >= 1
  bool neighbors = true; ///< link the sites' neighbors (false: the tables stay empty)
};

/// Deterministic; ctx.threads only spreads the work. `jacobians` may be empty when
/// only level 0 is built (maxLevels = 1: sites and neighbors without a texture frame, as solid
/// texturing needs): every site's Jacobian is then the identity.
synthesis::SurfaceDomain buildSurfaceDomain(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity,
                                            const Atlas& atlas, const AtlasFields& fields,
                                            const TexelField<TexelJacobian>& jacobians,
                                            const SurfaceDomainOptions& options = {}, const Context& ctx = {});

} // namespace texfab::atlas
