// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Per-texel Jacobians for synthesis in the atlas (Lefebvre & Hoppe 2006, §3 "Anisometric
// synthesis"): J_f = ∂(surface point)/∂(atlas position), 3×2 in model units per texel (analytic
// per triangle), and J = (t b)⁺ J_f × textureScale, the 2×2 map from an atlas offset (texels, x
// right, y down) to an exemplar offset (pixels), with (t, b) the orthonormal tangent frame of the
// tangent field (b = n × t).

#include "atlas/atlas.h"
#include "atlas/rasterize_atlas.h"
#include "atlas/texel_field.h"
#include "core/context.h"
#include "geometry/mesh.h"
#include "geometry/tangent_field.h"

namespace texfab::atlas {

struct TexelJacobian {
  float jf[6] = {0, 0, 0, 0, 0, 0}; ///< J_f columns: ∂P/∂x (jf[0..2]), ∂P/∂y (jf[3..5])
  float j[4] = {0, 0, 0, 0};        ///< J row-major: [j0 j1; j2 j3]
  float tangent[3] = {0, 0, 0};     ///< t of the frame at this texel (unit)
};

/// J_f of triangle t from its atlas corners (texels) and 3D corners (3×2).
Eigen::Matrix<double, 3, 2> triangleJf(const geometry::Mesh& mesh, const Atlas& atlas, size_t t);

/// Fills every texel that has a triangle (chart texels and filled gutters); empty texels stay 0.
/// textureScale: exemplar pixels per model unit (> 0).
TexelField<TexelJacobian> computeJacobians(const geometry::Mesh& mesh, const Atlas& atlas, const AtlasFields& fields,
                                           const geometry::TangentField& field, double textureScale, const Context& ctx = {});

/// Singular values (largest, smallest) of a 2×2 J.
Eigen::Vector2d singularValues(const float j[4]);

} // namespace texfab::atlas
