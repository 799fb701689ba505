// SPDX-License-Identifier: GPL-3.0-or-later
// Properties every atlas must have, on CGAL data-set meshes (skipped when models/cgal is absent):
// no flipped triangles, disk charts, no overlap after packing, gutters, determinism across thread
// counts, and indirection maps that continue the surface across seams.
#include "atlas/build_indirection_map.h"
#include "atlas/chart_mesh.h"
#include "atlas/generate_atlas.h"
#include "core/error.h"
#include "geometry/io/mesh_io.h"
#include "tests/atlas/test_meshes.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace texfab::atlas {
namespace {

geometry::Mesh loadOrSkip(const std::string& name) {
  const auto path = test::cgalModel(name);
  if (!std::filesystem::exists(path)) return {};
  return geometry::readMesh(path);
}

#define LOAD_OR_SKIP(var, name)                                                 \
  const geometry::Mesh var = loadOrSkip(name);                                  \
  if (var.triangleCount() == 0) GTEST_SKIP() << name << " absent (run models/fetch)"

GenerateAtlasOptions options(int size) {
  GenerateAtlasOptions o;
  o.pack.width = o.pack.height = size;
  return o;
}

/// Independent checks of a finished atlas.
void checkAtlas(const geometry::Mesh& mesh, const GenerateAtlasResult& r, int gutter) {
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  EXPECT_EQ(r.report.overlappingTexels, 0u);
  EXPECT_LT(r.report.l2Stretch, 1.05);
  EXPECT_LT(r.report.maxStretch, 3.0);
  // Every chart a disk, recomputed from scratch; every non-degenerate triangle in exactly one chart.
  std::vector<int> seen(mesh.triangleCount(), 0);
  for (const Chart& c : r.atlas.charts) {
    EXPECT_TRUE(detail::buildChartMesh(mesh, r.connectivity, c.faces).isDisk());
    for (uint32_t f : c.faces) ++seen[f];
  }
  for (size_t t = 0; t < mesh.triangleCount(); ++t) EXPECT_EQ(seen[t], r.connectivity.degenerate[t] ? 0 : 1);
  // Every UV inside the atlas.
  for (const auto& p : r.atlas.texelUvs) {
    EXPECT_GE(p.x(), 0.0f);
    EXPECT_GE(p.y(), 0.0f);
    EXPECT_LE(p.x(), float(r.atlas.width));
    EXPECT_LE(p.y(), float(r.atlas.height));
  }
  // Gutters: no texel of another chart within `gutter` texels (Chebyshev) of a chart texel.
  const auto& s = r.fields.samples;
  size_t violations = 0;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const int32_t c = s.at(x, y).chart;
      if (c < 0) continue;
      for (int dy = -gutter; dy <= gutter; ++dy)
        for (int dx = -gutter; dx <= gutter; ++dx) {
          if (!s.contains(x + dx, y + dy)) continue;
          const int32_t o = s.at(x + dx, y + dy).chart;
          if (o >= 0 && o != c) ++violations;
        }
    }
  EXPECT_EQ(violations, 0u);
  // Gutter texels were filled from a chart texel: triangle valid, normal unit.
  for (size_t i = 0; i < s.values.size(); i += 97) {
    EXPECT_LT(s.values[i].triangle, mesh.triangleCount());
    const Float3& n = r.fields.normal.values[i];
    EXPECT_NEAR(n.x * n.x + n.y * n.y + n.z * n.z, 1.0f, 1e-3f);
  }
}

TEST(AtlasOnCgalMeshes, CowElephantEightAndCamel) {
  for (const char* name : {"cow.off", "elephant.off", "eight.off", "camel.off"}) {
    SCOPED_TRACE(name);
    LOAD_OR_SKIP(mesh, name);
    const GenerateAtlasResult r = generateAtlas(mesh, options(1024));
    checkAtlas(mesh, r, 4);
    EXPECT_GT(r.report.utilization, 0.45);
  }
}

TEST(AtlasOnCgalMeshes, SliversThinnerThanFloatTexelsNeitherFlipNorOverlap) {
  // triceratops has a sliver that lost or turned its area when its texel coordinates were stored
  // as floats: one flipped triangle at 128²..1024² before the packer and the measure knew the
  // rounding.
  LOAD_OR_SKIP(mesh, "triceratops.off");
  GenerateAtlasOptions o = options(128);
  const GenerateAtlasResult r = generateAtlas(mesh, o);
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  EXPECT_EQ(r.report.overlappingTexels, 0u);
  EXPECT_GE(r.report.collapsedTriangles, 1u);
}

TEST(AtlasOnCgalMeshes, SameAtlasWhateverTheThreadCount) {
  LOAD_OR_SKIP(mesh, "elephant.off");
  const GenerateAtlasResult a = generateAtlas(mesh, options(512), Context{.threads = 1});
  const GenerateAtlasResult b = generateAtlas(mesh, options(512), Context{.threads = 2});
  ASSERT_EQ(a.atlas.faceChart, b.atlas.faceChart);
  ASSERT_EQ(a.atlas.texelUvs.size(), b.atlas.texelUvs.size());
  EXPECT_EQ(0, std::memcmp(a.atlas.texelUvs.data(), b.atlas.texelUvs.data(), a.atlas.texelUvs.size() * sizeof(Eigen::Vector2f)));
  EXPECT_EQ(0, std::memcmp(a.fields.samples.values.data(), b.fields.samples.values.data(),
                           a.fields.samples.values.size() * sizeof(SurfaceSample)));
  const IndirectionMap ia = buildIndirectionMap(mesh, a.connectivity, a.atlas, a.fields, {}, Context{.threads = 1});
  const IndirectionMap ib = buildIndirectionMap(mesh, b.connectivity, b.atlas, b.fields, {}, Context{.threads = 2});
  ASSERT_EQ(ia.targets.size(), ib.targets.size());
  EXPECT_EQ(0, std::memcmp(ia.targets.data(), ib.targets.data(), ia.targets.size() * sizeof(ia.targets[0])));
}

TEST(AtlasOnCgalMeshes, CuttingChartsForPackingKeepsUvsAndDisks) {
  // Box Cutter-style cuts (cut_charts.h): the pieces keep their chart-local UVs (so stretch and
  // flips are unchanged), are disks, and the atlas packs tighter for a modest seam increase.
  LOAD_OR_SKIP(mesh, "camel.off");
  GenerateAtlasOptions whole = options(1024);
  whole.cut.enabled = false;
  const GenerateAtlasResult a = generateAtlas(mesh, whole);
  const GenerateAtlasResult b = generateAtlas(mesh, options(1024));
  EXPECT_EQ(a.report.cut.cuts, 0u);
  EXPECT_GT(b.report.cut.cuts, 0u);
  EXPECT_GT(b.report.charts, a.report.charts);
  ASSERT_EQ(a.atlas.chartUvs.size(), b.atlas.chartUvs.size());
  EXPECT_EQ(0, std::memcmp(a.atlas.chartUvs.data(), b.atlas.chartUvs.data(),
                           a.atlas.chartUvs.size() * sizeof(Eigen::Vector2d)));
  // Every piece lies inside one chart of the uncut atlas.
  for (const Chart& c : b.atlas.charts)
    for (uint32_t f : c.faces) EXPECT_EQ(a.atlas.faceChart[f], a.atlas.faceChart[c.faces.front()]);
  checkAtlas(mesh, b, 4);
  EXPECT_NEAR(b.report.l2Stretch, a.report.l2Stretch, 1e-3);
  EXPECT_NEAR(b.report.seamLength - a.report.seamLength, b.report.cut.seamLengthAdded, 1e-6 * a.report.seamLength);
  EXPECT_LT(b.report.seamLength, 1.25 * a.report.seamLength);
  EXPECT_GT(b.report.utilization, a.report.utilization);
}

TEST(AtlasOnCgalMeshes, PackingIsRerunnableWithOtherOptions) {
  LOAD_OR_SKIP(mesh, "cow.off");
  GenerateAtlasResult r = generateAtlas(mesh, options(512));
  PackChartsOptions pack;
  pack.width = 1024;
  pack.height = 256;
  pack.gutter = 8;
  packCharts(mesh, r.atlas, pack, Context{.threads = 0});
  const AtlasFields fields = rasterizeAtlas(mesh, r.atlas);
  EXPECT_EQ(fields.overlappingTexels, 0u);
  EXPECT_EQ(fields.samples.width, 1024);
  EXPECT_EQ(fields.samples.height, 256);
  r.fields = fields;
  checkAtlas(mesh, r, 8);
}

// A needle (a sliver that a cut leaves) longer than the atlas at the density the other charts get
// is laid out smaller instead of holding every chart's density down to its own; an atlas sized to
// fit a density (width and height 0) keeps it and fills at least 60 % of its texels.
TEST(AtlasPacking, LongChartsShrinkAndAtlasesSizeToFit) {
  geometry::Mesh mesh = geometry::readMesh(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes/knot1.off");
  const GenerateAtlasResult plain = generateAtlas(mesh, options(512));
  EXPECT_EQ(plain.report.pack.chartsShrunk, 0u);

  const geometry::BoundingBox box = geometry::boundingBox(mesh);
  const float length = 3 * box.diagonal();
  const uint32_t v = uint32_t(mesh.positions.size());
  mesh.positions.push_back(box.max + Eigen::Vector3f(1, 0, 0));
  mesh.positions.push_back(box.max + Eigen::Vector3f(1 + length, 0, 0));
  mesh.positions.push_back(box.max + Eigen::Vector3f(1 + length / 2, length / 300, 0));
  mesh.triangles.push_back({v, v + 1, v + 2});
  const GenerateAtlasResult needle = generateAtlas(mesh, options(512));
  EXPECT_EQ(needle.report.pack.chartsShrunk, 1u);
  EXPECT_GT(needle.atlas.texelsPerUnit, 0.9 * plain.atlas.texelsPerUnit);
  EXPECT_EQ(needle.report.overlappingTexels, 0u);

  GenerateAtlasOptions fit;
  fit.pack.width = fit.pack.height = 0;
  fit.pack.texelsPerUnit = 1.5 * plain.atlas.texelsPerUnit;
  const GenerateAtlasResult sized = generateAtlas(mesh, fit);
  EXPECT_EQ(sized.atlas.texelsPerUnit, fit.pack.texelsPerUnit);
  EXPECT_GT(sized.atlas.width, 512);
  EXPECT_EQ(sized.atlas.width % 4, 0);
  EXPECT_EQ(sized.atlas.height % 4, 0);
  EXPECT_GE(sized.report.utilization, 0.6);
  EXPECT_EQ(sized.report.overlappingTexels, 0u);
  EXPECT_EQ(sized.report.pack.chartsShrunk, 1u);
}

Eigen::Vector3d surfacePoint(const geometry::Mesh& mesh, const Atlas& atlas, uint32_t t, double x, double y) {
  double b1, b2;
  atlasBarycentrics(atlas, t, {x, y}, b1, b2);
  return (1 - b1 - b2) * mesh.corner(t, 0).cast<double>() + b1 * mesh.corner(t, 1).cast<double>() +
         b2 * mesh.corner(t, 2).cast<double>();
}

TEST(AtlasOnCgalMeshes, IndirectionWalksAreContinuousAcrossSeams) {
  LOAD_OR_SKIP(mesh, "cow.off");
  const GenerateAtlasResult r = generateAtlas(mesh, options(1024));
  const IndirectionMap map = buildIndirectionMap(mesh, r.connectivity, r.atlas, r.fields, {}, Context{.threads = 0});
  ASSERT_GT(map.seamCrossings, 0u);
  const auto& s = r.fields.samples;
  std::vector<std::pair<int, int>> starts;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x)
      if (map.entry.at(x, y) >= 0) starts.push_back({x, y});
  ASSERT_FALSE(starts.empty());
  std::mt19937 rng(7);
  size_t steps = 0, crossings = 0, bad = 0;
  std::vector<double> ratios, seamRatios;
  double worst = 0;
  for (int walk = 0; walk < 300; ++walk) {
    auto [x, y] = starts[rng() % starts.size()];
    for (int step = 0; step < 40; ++step) {
      const SurfaceSample& here = s.at(x, y);
      ASSERT_GE(here.chart, 0);
      const int k = int(rng() % 8);
      const double len = std::hypot(kStepX[k], kStepY[k]);
      IndirectionTarget t;
      const int32_t e = map.entry.at(x, y);
      if (e >= 0) {
        t = map.targets[size_t(e)][size_t(k)];
      } else { // interior texel: the neighbour is in the same chart
        t.x = float(x + kStepX[k] + 0.5), t.y = float(y + kStepY[k] + 0.5);
        t.triangle = s.at(x + kStepX[k], y + kStepY[k]).triangle;
        t.chart = s.at(x + kStepX[k], y + kStepY[k]).chart;
        ASSERT_EQ(t.chart, here.chart);
      }
      const Eigen::Vector3d from = surfacePoint(mesh, r.atlas, here.triangle, x + 0.5, y + 0.5);
      const Eigen::Vector3d to = surfacePoint(mesh, r.atlas, t.triangle, t.x, t.y);
      // One step of `len` texels covers len / texelsPerUnit of surface, up to the stretch.
      const double ratio = (to - from).norm() * r.atlas.texelsPerUnit / len;
      worst = std::max(worst, ratio);
      // The chord is shorter than the step where the path folds over a sharp edge, so single
      // steps are only bounded loosely (no stall, no jump); the medians below must be ≈ 1. A wrong
      // seam jump lands many texels away.
      const double lower = 0.05;
      if (!t.hitBoundary) (t.crossedSeam ? seamRatios : ratios).push_back(ratio);
      if (!t.hitBoundary && (ratio < lower || ratio > 3.0)) {
        ++bad;
        ADD_FAILURE() << "step from texel " << x << "," << y << " dir " << k << " ratio " << ratio << " seam "
                      << int(t.crossedSeam) << " to " << t.x << "," << t.y << " chart " << here.chart << "->" << t.chart
                      << " entry " << e;
      }
      ++steps;
      crossings += t.crossedSeam;
      const int nx = int(std::floor(t.x)), ny = int(std::floor(t.y));
      if (!s.contains(nx, ny) || s.at(nx, ny).chart < 0) break; // landed in a partly covered border texel
      x = nx, y = ny;
    }
  }
  EXPECT_EQ(bad, 0u) << "worst ratio " << worst;
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  ASSERT_FALSE(seamRatios.empty());
  EXPECT_NEAR(median(ratios), 1.0, 0.15);
  EXPECT_NEAR(median(seamRatios), 1.0, 0.25);
  EXPECT_GT(steps, 1000u);
  EXPECT_GT(crossings, 20u);
}

TEST(AtlasBadInput, RepairsAndNeverOverlaps) {
  // Two components, a degenerate triangle, a duplicated face, a non-manifold fin, an isolated
  // vertex, and open boundaries.
  geometry::Mesh m = test::makePlane(6);
  geometry::Mesh cyl = test::makeCylinder(16, 4, 0.3f, 0.5f);
  const uint32_t base = uint32_t(m.positions.size());
  for (auto p : cyl.positions) m.positions.push_back(p + Eigen::Vector3f(2, 0, 0));
  for (auto t : cyl.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  m.triangles.push_back({0, 1, 1});                // degenerate
  m.triangles.push_back(m.triangles[3]);           // duplicate
  m.positions.push_back({0.5f, 0.5f, 1.0f});
  m.triangles.push_back({0, 1, uint32_t(m.positions.size() - 1)}); // fin on edge 0-1: non-manifold
  m.positions.push_back({9, 9, 9});                // isolated
  const GenerateAtlasResult r = generateAtlas(m, options(256));
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  EXPECT_EQ(r.report.overlappingTexels, 0u);
  EXPECT_GE(r.connectivity.degenerateTriangles, 1u);
  EXPECT_GE(r.connectivity.nonManifoldEdges + r.connectivity.inconsistentEdges, 1u);
  EXPECT_FALSE(r.report.repairs.empty());
  const IndirectionMap map = buildIndirectionMap(m, r.connectivity, r.atlas, r.fields, {}, Context{.threads = 0});
  EXPECT_GT(map.boundaryStops, 0u);
}

TEST(AtlasBadInput, TooManyChartsForTheResolutionIsRefused) {
  const geometry::Mesh sphere = test::makeSphere(64, 32);
  GenerateAtlasOptions o = options(16);
  o.segment.maxNormalDeviationDegrees = 1; // one chart per triangle or so
  EXPECT_THROW(generateAtlas(sphere, o), Error);
}

} // namespace
} // namespace texfab::atlas
