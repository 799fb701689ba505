// SPDX-License-Identifier: GPL-3.0-or-later
// Plane, cylinder and sphere, where the stretch and the Jacobians are known analytically.
#include "atlas/compute_jacobians.h"
#include "atlas/generate_atlas.h"
#include "atlas/measure_stretch.h"
#include "geometry/tangent_field.h"
#include "tests/atlas/test_meshes.h"

#include <gtest/gtest.h>

namespace texfab::atlas {
namespace {

GenerateAtlasOptions smallAtlas(int size = 256) {
  GenerateAtlasOptions o;
  o.pack.width = o.pack.height = size;
  return o;
}

TEST(MeasureStretch, AnisotropicScaleOfAPlaneMatchesSanderFormula) {
  // uv = (2x, y): after normalization (UV area = surface area, factor 1/√2) the map UV -> 3D has
  // singular values √2 and 1/√2: Γ = √2, L2 = sqrt((2 + 1/2) / 2).
  const geometry::Mesh plane = test::makePlane(4);
  const StretchStats s = measureStretch(plane, {}, [&](size_t c) {
    const Eigen::Vector3f p = plane.positions[plane.triangles[c / 3][c % 3]];
    return Eigen::Vector2d(2 * p.x(), p.y());
  });
  EXPECT_NEAR(s.l2, std::sqrt(1.25), 1e-6);
  EXPECT_NEAR(s.max, std::sqrt(2.0), 1e-6);
  EXPECT_EQ(s.flipped, 0u);
  // A mirrored map flips every triangle.
  const StretchStats m = measureStretch(plane, {}, [&](size_t c) {
    const Eigen::Vector3f p = plane.positions[plane.triangles[c / 3][c % 3]];
    return Eigen::Vector2d(-p.x(), p.y());
  });
  EXPECT_EQ(m.flipped, plane.triangleCount());
}

TEST(AnalyticSurfaces, PlaneIsOneUndistortedChartWithKnownJacobian) {
  const geometry::Mesh plane = test::makePlane(16, 2.0f, 1.0f);
  const GenerateAtlasResult r = generateAtlas(plane, smallAtlas());
  EXPECT_EQ(r.report.charts, 1u);
  EXPECT_NEAR(r.report.l2Stretch, 1.0, 1e-4);
  EXPECT_LT(r.report.maxStretch, 1.001);
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  // Every triangle: J_f has orthogonal columns of length 1 / texelsPerUnit (an isometry up to scale).
  const double texel = 1.0 / r.atlas.texelsPerUnit;
  for (size_t t = 0; t < plane.triangleCount(); ++t) {
    const auto jf = triangleJf(plane, r.atlas, t);
    EXPECT_NEAR(jf.col(0).norm(), texel, 1e-3 * texel);
    EXPECT_NEAR(jf.col(1).norm(), texel, 1e-3 * texel);
    EXPECT_NEAR(jf.col(0).dot(jf.col(1)), 0.0, 1e-3 * texel * texel);
  }
  // J with the field along +x and one exemplar pixel per texel is a rotation (det +1 or a
  // reflection due to the y-down atlas: |det| = 1, singular values 1).
  geometry::TangentFieldOptions fo;
  fo.direction = {1, 0, 0};
  const geometry::TangentField field = geometry::computeTangentField(plane, fo);
  for (const auto& t : field.tangents) EXPECT_NEAR(t.x(), 1.0f, 1e-4f);
  const auto jac = computeJacobians(plane, r.atlas, r.fields, field, r.atlas.texelsPerUnit, Context{.threads = 1});
  int checked = 0;
  for (int y = 0; y < jac.height; ++y)
    for (int x = 0; x < jac.width; ++x) {
      if (r.fields.samples.at(x, y).chart < 0) continue;
      const Eigen::Vector2d sv = singularValues(jac.at(x, y).j);
      EXPECT_NEAR(sv(0), 1.0, 2e-3);
      EXPECT_NEAR(sv(1), 1.0, 2e-3);
      ++checked;
    }
  EXPECT_GT(checked, 1000);
}

TEST(AnalyticSurfaces, FiniteDifferencesOfThePositionFieldMatchAnalyticJf) {
  const geometry::Mesh sphere = test::makeSphere(32, 16);
  const GenerateAtlasResult r = generateAtlas(sphere, smallAtlas(512));
  int compared = 0;
  for (int y = 1; y + 1 < r.fields.samples.height; ++y)
    for (int x = 1; x + 1 < r.fields.samples.width; ++x) {
      const SurfaceSample& s = r.fields.samples.at(x, y);
      if (s.chart < 0) continue;
      // Central differences inside one triangle only (the position field is linear there).
      bool same = true;
      for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
        same = same && r.fields.samples.at(x + dx, y + dy).triangle == s.triangle &&
               r.fields.samples.at(x + dx, y + dy).chart == s.chart;
      if (!same) continue;
      auto pos = [&](int u, int v) {
        const Float3& p = r.fields.position.at(u, v);
        return Eigen::Vector3d(p.x, p.y, p.z);
      };
      const Eigen::Vector3d fx = 0.5 * (pos(x + 1, y) - pos(x - 1, y));
      const Eigen::Vector3d fy = 0.5 * (pos(x, y + 1) - pos(x, y - 1));
      const auto jf = triangleJf(sphere, r.atlas, s.triangle);
      const double scale = 1.0 / r.atlas.texelsPerUnit;
      EXPECT_LT((fx - jf.col(0)).norm(), 1e-3 * scale);
      EXPECT_LT((fy - jf.col(1)).norm(), 1e-3 * scale);
      ++compared;
    }
  EXPECT_GT(compared, 100);
}

TEST(AnalyticSurfaces, OpenCylinderIsCutIntoDisksWithoutStretch) {
  // A cylinder is developable: its charts unroll isometrically (stretch 1) once it is cut.
  const geometry::Mesh cyl = test::makeCylinder(48, 12);
  GenerateAtlasOptions o = smallAtlas(512);
  o.segment.maxNormalDeviationDegrees = 80;
  const GenerateAtlasResult r = generateAtlas(cyl, o);
  EXPECT_GE(r.report.charts, 1u);
  EXPECT_EQ(r.report.nonDiskCharts, 0u);
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  EXPECT_EQ(r.report.overlappingTexels, 0u);
  EXPECT_LT(r.report.l2Stretch, 1.01);
  EXPECT_LT(r.report.maxStretch, 1.05);
  // Jacobians with the field along the axis: singular values ≈ 1 (exemplar pixel per texel).
  geometry::TangentFieldOptions fo;
  fo.direction = {0, 0, 1};
  const geometry::TangentField field = geometry::computeTangentField(cyl, fo);
  EXPECT_TRUE(field.singularTriangles.empty());
  const auto jac = computeJacobians(cyl, r.atlas, r.fields, field, r.atlas.texelsPerUnit, Context{.threads = 1});
  double worst = 0;
  for (int y = 0; y < jac.height; ++y)
    for (int x = 0; x < jac.width; ++x)
      if (r.fields.samples.at(x, y).chart >= 0) {
        const Eigen::Vector2d sv = singularValues(jac.at(x, y).j);
        worst = std::max({worst, std::abs(sv(0) - 1), std::abs(sv(1) - 1)});
      }
  EXPECT_LT(worst, 0.05);
  // The curvature field follows the axis (the minimum curvature direction).
  fo.kind = geometry::TangentFieldKind::Curvature;
  const geometry::TangentField curv = geometry::computeTangentField(cyl, fo);
  for (const auto& t : curv.tangents) EXPECT_GT(std::abs(t.z()), 0.95f);
}

TEST(AnalyticSurfaces, SphereNeedsSeveralChartsAndKeepsStretchLow) {
  const geometry::Mesh sphere = test::makeSphere(48, 24);
  const GenerateAtlasResult r = generateAtlas(sphere, smallAtlas(512));
  EXPECT_GE(r.report.charts, 2u); // a closed sphere is not a disk
  EXPECT_EQ(r.report.nonDiskCharts, 0u);
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  EXPECT_EQ(r.report.overlappingTexels, 0u);
  EXPECT_LT(r.report.l2Stretch, 1.05);
  EXPECT_LT(r.report.maxStretch, 3.0);
  // Poincaré–Hopf: the singularities of a tangent field on a sphere add up to 2.
  const geometry::TangentField field = geometry::computeTangentField(sphere, {});
  EXPECT_GE(field.singularTriangles.size(), 1u);
  EXPECT_NEAR(field.totalIndex(), 2.0, 1e-6);
  for (size_t v = 0; v < sphere.vertexCount(); ++v) {
    EXPECT_NEAR(field.tangents[v].norm(), 1.0f, 1e-4f);
    EXPECT_NEAR(field.tangents[v].dot(field.normals[v]), 0.0f, 1e-4f);
  }
}

} // namespace
} // namespace texfab::atlas

namespace texfab::atlas {
namespace {

TEST(AnalyticSurfaces, ArapParameterizerGivesAValidAtlasToo) {
  const geometry::Mesh sphere = test::makeSphere(24, 12);
  GenerateAtlasOptions o;
  o.pack.width = o.pack.height = 256;
  o.parameterize.parameterizer = Parameterizer::Arap;
  const GenerateAtlasResult r = generateAtlas(sphere, o);
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  EXPECT_EQ(r.report.overlappingTexels, 0u);
  EXPECT_EQ(r.report.nonDiskCharts, 0u);
  EXPECT_LT(r.report.l2Stretch, 1.05);
}

} // namespace
} // namespace texfab::atlas
