// SPDX-License-Identifier: GPL-3.0-or-later
// Tiny pathological meshes (the xatlas habit): each has one feature that has broken atlas
// generators, swept over small atlases and large gutters. Every valid closed mesh gets an atlas
// with no flipped triangle and no overlap, or a clear "cannot fit" error; never the internal one.
#include "atlas/generate_atlas.h"
#include "core/error.h"
#include "tests/geometry/test_meshes.h"

#include <gtest/gtest.h>

#include <string>

namespace texfab::atlas {
namespace {

using geometry::Mesh;

using texfab::test::append;
using texfab::test::box;

/// A unit cube whose first triangle (0, 2, 3) is split around two points 1e-7 from its corner 0:
/// one of the five pieces has a positive area under the degeneracy threshold (1e-14 diag²).
Mesh cubeWithTinyTriangle() {
  Mesh m = box({0, 0, 0}, {1, 1, 1});
  const uint32_t p1 = 8, p2 = 9;
  m.positions.push_back({1e-7f, 4e-7f, 0});
  m.positions.push_back({2e-7f, 4e-7f, 0});
  m.triangles[0] = {0, 2, p1};
  m.triangles.push_back({p1, 2, p2});
  m.triangles.push_back({2, 3, p2});
  m.triangles.push_back({3, 0, p2});
  m.triangles.push_back({0, p1, p2});
  return m;
}

/// A cube with a fan of 64 needles from one corner of its top face (triangles 1e5 times longer
/// than wide).
Mesh cubeWithSliverFan() {
  Mesh m = box({0, 0, 0}, {1, 1, 1});
  // Top face quad {4, 5, 7, 6} (z = 1): replace its two triangles by a fan from corner 4 through
  // points along the edge 5-7 crowded near 5.
  m.triangles.erase(m.triangles.begin() + 2, m.triangles.begin() + 4);
  std::vector<uint32_t> edge{5};
  for (int i = 1; i < 64; ++i) {
    edge.push_back(uint32_t(m.positions.size()));
    m.positions.push_back({1, float(i) * 1e-5f, 1});
  }
  edge.push_back(7);
  for (size_t i = 0; i + 1 < edge.size(); ++i) m.triangles.push_back({4, edge[i], edge[i + 1]});
  m.triangles.push_back({4, 7, 6});
  return m;
}

struct Case {
  std::string name;
  Mesh mesh;
};

std::vector<Case> cases() {
  std::vector<Case> c;
  Mesh tetra;
  tetra.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  c.push_back({"tetrahedron", tetra});
  c.push_back({"needle box 100:1:1", box({0, 0, 0}, {100, 1, 1})});
  c.push_back({"plate 1:1:0.001", box({0, 0, 0}, {1, 1, 0.001f})});
  Mesh speck = box({0, 0, 0}, {1, 1, 1});
  append(speck, box({5, 5, 5}, {1e-3f, 1e-3f, 1e-3f}));
  c.push_back({"cube and a speck", speck});
  c.push_back({"tiny triangle", cubeWithTinyTriangle()});
  c.push_back({"sliver fan", cubeWithSliverFan()});
  return c;
}

TEST(PathologicalMeshes, SmallAtlasesAndLargeGuttersNeverFlipOrOverlap) {
  for (const Case& c : cases())
    for (int size : {16, 32, 64, 256})
      for (int gutter : {0, 4, 16, 64}) {
        SCOPED_TRACE(c.name + ", " + std::to_string(size) + "², gutter " + std::to_string(gutter));
        GenerateAtlasOptions o;
        o.pack.width = o.pack.height = size;
        o.pack.gutter = gutter;
        try {
          const GenerateAtlasResult r = generateAtlas(c.mesh, o);
          EXPECT_EQ(r.report.flippedTriangles, 0u);
          EXPECT_EQ(r.report.overlappingTexels, 0u);
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("cannot fit"), std::string::npos) << e.what();
        }
      }
}

TEST(PathologicalMeshes, ATriangleUnderTheDegeneracyThresholdIsNotAFlip) {
  const Mesh m = cubeWithTinyTriangle();
  const GenerateAtlasResult r = generateAtlas(m, {});
  EXPECT_EQ(r.connectivity.degenerateTriangles, 1u);
  EXPECT_EQ(r.atlas.faceChart[m.triangleCount() - 1], -1);
  EXPECT_EQ(r.report.flippedTriangles, 0u);
  EXPECT_EQ(r.report.overlappingTexels, 0u);
}

} // namespace
} // namespace texfab::atlas
