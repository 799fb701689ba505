// SPDX-License-Identifier: GPL-3.0-or-later
// One connectivity for every module, and orientation repair: tiny meshes with one defect each.
#include "geometry/mesh_connectivity.h"
#include "geometry/repair/orient_mesh.h"
#include "tests/geometry/test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace texfab::geometry;

namespace {

Mesh cube(Eigen::Vector3f lo = {0, 0, 0}, float size = 1) {
  return texfab::test::box(lo, Eigen::Vector3f::Constant(size));
}

using texfab::test::append;

double signedVolume(const Mesh& m) {
  double v = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    v += m.corner(t, 0).cast<double>().dot(m.corner(t, 1).cast<double>().cross(m.corner(t, 2).cast<double>())) / 6;
  return v;
}

/// Flips every other triangle (the mesh a new user's exporter wrote).
Mesh everyOtherFlipped(Mesh m) {
  for (size_t t = 1; t < m.triangleCount(); t += 2) std::swap(m.triangles[t][1], m.triangles[t][2]);
  return m;
}

/// A Möbius strip of n quads (non-orientable, one boundary loop).
Mesh moebius(int n = 12) {
  Mesh m;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n, twist = a / 2;
    for (int s : {-1, 1}) {
      const double r = 2 + 0.5 * s * std::cos(twist);
      m.positions.push_back({float(r * std::cos(a)), float(r * std::sin(a)), float(0.5 * s * std::sin(twist))});
    }
  }
  for (int i = 0; i < n; ++i) {
    const uint32_t a0 = uint32_t(2 * i), a1 = a0 + 1;
    // The last quad joins the strip to its start with the sides swapped (the half twist).
    const uint32_t b0 = i + 1 < n ? a0 + 2 : 1, b1 = i + 1 < n ? a0 + 3 : 0;
    m.triangles.push_back({a0, b0, b1});
    m.triangles.push_back({a0, b1, a1});
  }
  return m;
}

} // namespace

TEST(MeshConnectivity, ClosedCubeIsAnOrientedManifoldOfGenusZero) {
  const MeshConnectivity c = computeConnectivity(cube());
  EXPECT_TRUE(c.closed && c.manifold && c.oriented && c.watertight);
  EXPECT_EQ(c.edges.size(), 18u);
  EXPECT_EQ(c.genus, 0);
  EXPECT_EQ(c.components, 1u);
  for (size_t t = 0; t < 12; ++t)
    for (int k = 0; k < 3; ++k) EXPECT_GE(c.neighbor(t, k), 0);
}

TEST(MeshConnectivity, TwoCubesJoinedAtOneVertexAreNotManifold) {
  Mesh m = cube();
  append(m, cube({1, 1, 1}));
  // Weld the second cube's corner (1,1,1) + (0,0,0) onto the first's (1,1,1): vertex 7.
  for (auto& t : m.triangles)
    for (auto& v : t)
      if (v == 8) v = 7;
  const MeshConnectivity c = computeConnectivity(m);
  EXPECT_TRUE(c.closed);
  EXPECT_EQ(c.nonManifoldEdges, 0u);
  EXPECT_EQ(c.nonManifoldVertices, 1u);
  EXPECT_FALSE(c.manifold);
  EXPECT_FALSE(c.genus.has_value());
  EXPECT_EQ(c.components, 1u);
}

TEST(MeshConnectivity, ThreeTrianglesOnAnEdgeMakeANonManifoldEdge) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshConnectivity c = computeConnectivity(m);
  EXPECT_EQ(c.nonManifoldEdges, 1u);
  EXPECT_EQ(c.nonManifoldVertices, 2u); // the edge's ends
  for (size_t t = 0; t < 3; ++t) EXPECT_EQ(c.mate[t][0], -1);
}

TEST(MeshConnectivity, DegenerateTrianglesCountButAreNobodysNeighbor) {
  Mesh m = cube();
  m.positions.push_back({0.5f, 0, 0});                 // on the edge 0-1
  m.triangles.push_back({0, 1, 8});                    // zero area
  m.triangles.push_back({0, 0, 1});                    // repeated vertex
  const MeshConnectivity c = computeConnectivity(m);
  EXPECT_EQ(c.degenerateTriangles, 2u);
  EXPECT_TRUE(c.degenerate[12] && c.degenerate[13]);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(c.mate[12][size_t(k)], -1);
  EXPECT_EQ(c.area[12], 0.0);
}

TEST(OrientMesh, EveryOtherFaceFlippedIsTurnedBackExactly) {
  const Mesh good = cube();
  Mesh bad = everyOtherFlipped(good);
  const MeshConnectivity before = computeConnectivity(bad);
  EXPECT_FALSE(before.oriented);
  EXPECT_TRUE(before.manifold);
  const MeshOrientation o = computeOrientation(bad, before);
  EXPECT_EQ(o.flip.size(), 6u);
  EXPECT_EQ(o.nonOrientableParts, 0u);
  EXPECT_EQ(o.inconsistentEdgesLeft, 0u);
  flipTriangles(bad, o.flip);
  EXPECT_EQ(bad.triangles, good.triangles);
  EXPECT_TRUE(computeConnectivity(bad).oriented);
}

TEST(OrientMesh, ClosedPartsFaceOutwardAndCavitiesInward) {
  // Inside out: every triangle flipped.
  Mesh inverted = cube();
  for (auto& t : inverted.triangles) std::swap(t[1], t[2]);
  MeshOrientation o = computeOrientation(inverted, computeConnectivity(inverted));
  EXPECT_EQ(o.flip.size(), 12u);
  EXPECT_EQ(o.reversedParts, 1u);
  flipTriangles(inverted, o.flip);
  EXPECT_GT(signedVolume(inverted), 0);

  // A hollow box: the inner shell faces into the cavity (negative volume). Both outward at first.
  Mesh hollow = cube({0, 0, 0}, 3);
  append(hollow, cube({1, 1, 1}, 1));
  o = computeOrientation(hollow, computeConnectivity(hollow));
  ASSERT_EQ(o.flip.size(), 12u);
  EXPECT_EQ(o.flip.front(), 12u); // the inner shell's
  flipTriangles(hollow, o.flip);
  EXPECT_NEAR(signedVolume(hollow), 27.0 - 1.0, 1e-9);
  // Correct already: nothing to do.
  EXPECT_TRUE(computeOrientation(hollow, computeConnectivity(hollow)).flip.empty());
}

TEST(OrientMesh, OpenPartsKeepTheSideMostOfTheirAreaFaces) {
  Mesh m = cube();
  m.triangles.resize(10); // open box: one side missing
  for (size_t t : {0, 1, 2}) std::swap(m.triangles[t][1], m.triangles[t][2]);
  const Mesh expected = [&] {
    Mesh e = cube();
    e.triangles.resize(10);
    return e;
  }();
  const MeshOrientation o = computeOrientation(m, computeConnectivity(m));
  EXPECT_EQ(o.flip, (std::vector<uint32_t>{0, 1, 2}));
  flipTriangles(m, o.flip);
  EXPECT_EQ(m.triangles, expected.triangles);
}

TEST(OrientMesh, AMoebiusStripIsFoundNonOrientable) {
  Mesh m = moebius();
  const MeshConnectivity c = computeConnectivity(m);
  EXPECT_TRUE(c.manifold);
  EXPECT_EQ(c.boundaryEdges, 24u);
  const MeshOrientation o = computeOrientation(m, c);
  EXPECT_EQ(o.nonOrientableParts, 1u);
  EXPECT_EQ(o.inconsistentEdgesLeft, 1u); // one edge must disagree: the strip's cut
}

TEST(OrientMesh, FlippingKeepsCornerAttributesWithTheirCorners) {
  Mesh m = cube();
  for (size_t c = 0; c < 36; ++c) m.uvs.push_back({float(c), 0});
  for (size_t t = 0; t < 12; ++t)
    for (int k = 0; k < 3; ++k) m.normals.push_back(faceNormal(m, t));
  flipTriangles(m, {3});
  EXPECT_EQ(m.uvs[10].x(), 11.0f);
  EXPECT_EQ(m.uvs[11].x(), 10.0f);
  // The normal followed the old winding: it now points against the triangle, and is turned.
  for (int k = 0; k < 3; ++k) EXPECT_GT(m.normals[9 + size_t(k)].dot(faceNormal(m, 3)), 0.99f);
}
