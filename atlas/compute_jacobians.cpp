// SPDX-License-Identifier: GPL-3.0-or-later
// Jacobian fields: S. Lefebvre, H. Hoppe, "Appearance-Space Texture Synthesis", SIGGRAPH 2006,
// §5 (synthesis in an atlas: J = (t b)⁺ J_f).
#include "atlas/compute_jacobians.h"

#include "core/parallel.h"

#include <Eigen/Dense>

namespace texfab::atlas {

Eigen::Matrix<double, 3, 2> triangleJf(const geometry::Mesh& mesh, const Atlas& atlas, size_t t) {
  const Eigen::Vector2d p0 = atlas.texelUvs[3 * t].cast<double>();
  Eigen::Matrix2d P;
  P.col(0) = atlas.texelUvs[3 * t + 1].cast<double>() - p0;
  P.col(1) = atlas.texelUvs[3 * t + 2].cast<double>() - p0;
  Eigen::Matrix<double, 3, 2> Q;
  Q.col(0) = (mesh.corner(t, 1) - mesh.corner(t, 0)).cast<double>();
  Q.col(1) = (mesh.corner(t, 2) - mesh.corner(t, 0)).cast<double>();
  if (std::abs(P.determinant()) < 1e-300) return Eigen::Matrix<double, 3, 2>::Zero();
  return Q * P.inverse();
}

Eigen::Vector2d singularValues(const float j[4]) {
  Eigen::Matrix2d m;
  m << j[0], j[1], j[2], j[3];
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(m);
  return svd.singularValues();
}

TexelField<TexelJacobian> computeJacobians(const geometry::Mesh& mesh, const Atlas& atlas, const AtlasFields& fields,
                                           const geometry::TangentField& field, double textureScale, const Context& ctx) {
  const int W = fields.samples.width, H = fields.samples.height;
  TexelField<TexelJacobian> out(W, H);
  // J_f per triangle (analytic; constant over a triangle).
  std::vector<Eigen::Matrix<double, 3, 2>> jf(mesh.triangleCount());
  parallelFor(0, int(mesh.triangleCount()), ctx, [&](int b, int e) {
    for (int t = b; t < e; ++t) jf[size_t(t)] = triangleJf(mesh, atlas, size_t(t));
  }, 1024);
  const bool anyChart = fields.chartTexels > 0;
  parallelFor(0, H, ctx, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < W; ++x) {
        if (!anyChart) continue;
        const SurfaceSample& s = fields.samples.at(x, y);
        const Eigen::Matrix<double, 3, 2>& J = jf[s.triangle];
        const Eigen::Vector3d t = field.at(mesh, s.triangle, s.b1, s.b2).cast<double>();
        Eigen::Vector3d n = (mesh.corner(s.triangle, 1) - mesh.corner(s.triangle, 0))
                                .cross(mesh.corner(s.triangle, 2) - mesh.corner(s.triangle, 0))
                                .cast<double>();
        if (n.squaredNorm() > 0) n.normalize();
        const Eigen::Vector3d b = n.cross(t);
        TexelJacobian& out1 = out.at(x, y);
        for (int r = 0; r < 3; ++r) out1.jf[r] = float(J(r, 0)), out1.jf[3 + r] = float(J(r, 1));
        // (t b)⁺ = (t b)ᵀ for an orthonormal frame.
        out1.j[0] = float(textureScale * t.dot(J.col(0)));
        out1.j[1] = float(textureScale * t.dot(J.col(1)));
        out1.j[2] = float(textureScale * b.dot(J.col(0)));
        out1.j[3] = float(textureScale * b.dot(J.col(1)));
        out1.tangent[0] = float(t.x()), out1.tangent[1] = float(t.y()), out1.tangent[2] = float(t.z());
      }
  });
  return out;
}

} // namespace texfab::atlas
