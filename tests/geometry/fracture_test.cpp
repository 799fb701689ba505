// SPDX-License-Identifier: GPL-3.0-or-later
// Cut and fracture geometry on small meshes: every piece closed, manifold and oriented; volumes
// add up to the model's; no two pieces overlap (sample points inside exactly one piece);
// attributes carried through splits; determinism; repairs and refusals of bad solids.
#include "core/hash.h"
#include "geometry/embree_scene.h"
#include "geometry/fracture/cut_mesh.h"
#include "geometry/fracture/fracture_mesh.h"
#include "geometry/fracture/measure_solid.h"
#include "geometry/mesh_connectivity.h"
#include "geometry/repair/prepare_mesh.h"
#include "tests/atlas/test_meshes.h"
#include "tests/geometry/test_meshes.h"

#include <algorithm>
#include <cmath>

using namespace texfab;
using namespace texfab::geometry;
using texfab::test::makeCylinder;
using texfab::test::makeSphere;
using texfab::test::errorOf;

namespace {

Mesh cube() { return texfab::test::texturedCube(); }  // [-1, 1]^3, UVs, two materials, a tag on the top

// A torus around z (genus 1: pieces of it are not convex).
Mesh torus(int around, int tube, float r = 1.0f, float t = 0.35f) {
  Mesh m;
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < tube; ++j) {
      const double a = 2 * M_PI * i / around, b = 2 * M_PI * j / tube;
      m.positions.push_back({float((r + t * std::cos(b)) * std::cos(a)), float((r + t * std::cos(b)) * std::sin(a)),
                             float(t * std::sin(b))});
    }
  auto id = [&](int i, int j) { return uint32_t((i % around) * tube + (j % tube)); };
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < tube; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

std::vector<Mesh> meshesOf(const std::vector<CellPiece>& pieces) {
  std::vector<Mesh> out;
  for (const CellPiece& p : pieces) out.push_back(p.mesh);
  return out;
}

// Closed, manifold, oriented (positive volume); volumes sum to the model's; sample points of the
// model's box lie in exactly as many pieces as the model (0 or 1).
void expectPartition(const Mesh& model, const std::vector<Mesh>& pieces, int samples = 1500) {
  double sum = 0;
  for (size_t i = 0; i < pieces.size(); ++i) {
    const MeshConnectivity t = computeConnectivity(pieces[i]);
    EXPECT_TRUE(t.closed && t.manifold && t.oriented) << "piece " << i << ": " << t.boundaryEdges
                                                                     << " boundary, " << t.nonManifoldEdges << " non-manifold";
    const double v = measureSolid(pieces[i]).volume;
    EXPECT_GT(v, 0) << "piece " << i;
    sum += v;
  }
  const double total = measureSolid(model).volume;
  EXPECT_NEAR(sum, total, 1e-6 * total);
  const EmbreeScene whole(model);
  std::vector<std::unique_ptr<EmbreeScene>> scenes;
  for (const Mesh& p : pieces) scenes.push_back(std::make_unique<EmbreeScene>(p));
  const BoundingBox box = boundingBox(model);
  int inside = 0;
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector3f u(float(unitInterval(counterHash(3, uint32_t(i), 0))), float(unitInterval(counterHash(3, uint32_t(i), 1))),
                            float(unitInterval(counterHash(3, uint32_t(i), 2))));
    const Eigen::Vector3f p = box.min + u.cwiseProduct(box.max - box.min);
    int in = 0;
    for (const auto& s : scenes) in += s->inside(p);
    const int expected = whole.inside(p) ? 1 : 0;
    inside += expected;
    EXPECT_EQ(in, expected) << "point " << p.transpose() << " is in " << in << " pieces";
    if (in != expected) break;
  }
  EXPECT_GT(inside, samples / 10);
}

bool identical(const std::vector<CellPiece>& a, const std::vector<CellPiece>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].mesh.positions != b[i].mesh.positions || a[i].mesh.triangles != b[i].mesh.triangles ||
        a[i].mesh.uvs != b[i].mesh.uvs || a[i].cutFace != b[i].cutFace)
      return false;
  return true;
}

CutMeshResult cut(const Mesh& m, std::vector<CutPlane> planes, const Context& ctx = {}) {
  return cutMesh(std::span<const Mesh>(&m, 1), planes, {1, 0}, ctx);
}

TEST(CutMesh, CubeHalvesAreCappedAndCarryAttributes) {
  const Mesh m = cube();
  const CutMeshResult r = cut(m, {{{0, 0, 0.25}, {0, 0, 1}}});  // exact in float: exact volumes
  ASSERT_EQ(r.pieces.size(), 2u);
  EXPECT_TRUE(r.missed.empty());
  expectPartition(m, meshesOf(r.pieces));
  EXPECT_NEAR(measureSolid(r.pieces[0].mesh).volume, 4 * 1.25, 1e-9);
  EXPECT_NEAR(measureSolid(r.pieces[1].mesh).volume, 4 * 0.75, 1e-9);
  for (const CellPiece& p : r.pieces) {
    EXPECT_NEAR(measureSolid(p.mesh, 1).taggedArea, 4.0, 1e-9);  // the cap
    for (size_t t = 0; t < p.mesh.triangles.size(); ++t) {
      if (p.source[t] < 0) continue;
      // A split face keeps its material, tag and the UV the original face has at each corner.
      const size_t s = size_t(p.source[t]);
      EXPECT_EQ(p.mesh.materialOf(t), m.materialOf(s));
      EXPECT_EQ(p.mesh.tagOf(t), m.tagOf(s));
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3f q = p.mesh.corner(t, k), a = m.corner(s, 0), b = m.corner(s, 1), c = m.corner(s, 2);
        const float area = (b - a).cross(c - a).norm();
        const Eigen::Vector3f w((b - q).cross(c - q).norm() / area, (c - q).cross(a - q).norm() / area,
                                (a - q).cross(b - q).norm() / area);
        const Eigen::Vector2f uv = w[0] * m.uvs[3 * s] + w[1] * m.uvs[3 * s + 1] + w[2] * m.uvs[3 * s + 2];
        EXPECT_LT((p.mesh.uvs[3 * t + size_t(k)] - uv).norm(), 1e-5f);
      }
    }
  }
}

TEST(CutMesh, PlaneThroughEdgesAndPlanesOnFacesOrOutside) {
  const Mesh m = cube();
  const CutMeshResult diagonal = cut(m, {{{0, 0, 0}, {1, -1, 0}}});  // through two vertical edges
  ASSERT_EQ(diagonal.pieces.size(), 2u);
  expectPartition(m, meshesOf(diagonal.pieces));
  EXPECT_NEAR(measureSolid(diagonal.pieces[0].mesh).volume, 4.0, 1e-9);
  // A plane on the top face touches the model and one outside misses it: the model as it was.
  for (const CutPlane& plane : {CutPlane{{0, 0, 1}, {0, 0, 1}}, CutPlane{{0, 0, 5}, {0, 0, -1}}}) {
    const CutMeshResult r = cut(m, {plane});
    ASSERT_EQ(r.pieces.size(), 1u);
    EXPECT_EQ(r.missed, std::vector<int>{0});
    EXPECT_EQ(r.pieces[0].mesh.triangles, m.triangles);
  }
}

// x = 0 passes within 1e-16 of the sphere's vertices at x = 0: intersection points within rounding of them.
TEST(CutMesh, SeveralPlanesCutEveryPiece) {
  const Mesh m = makeSphere(40, 20);
  const CutMeshResult r = cut(m, {{{0, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {0, 1, 0.1}}, {{0, 0, 0.2}, {0, 0, 1}}});
  EXPECT_EQ(r.pieces.size(), 8u);
  expectPartition(m, meshesOf(r.pieces));
  // Each new face remembers its plane; faces of an earlier cut stay that plane's.
  std::vector<int> seen(3, 0);
  for (const auto& cuts : r.cut)
    for (int32_t k : cuts)
      if (k >= 0) seen[size_t(k)] = 1;
  EXPECT_EQ(seen, std::vector<int>({1, 1, 1}));
}

// Planes through each other's lines and through the model's corners: all cuts come from one
// intersection with the planes' cells, so none meets the rounded corners of another.
TEST(CutMesh, PlanesThroughEachOtherAndThroughCorners) {
  const Mesh m = cube();
  const CutMeshResult star = cut(m, {{{0, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {0, 1, 0}}, {{0, 0, 0}, {0, 0, 1}}, {{0, 0, 0}, {1, 1, 1}}});
  EXPECT_EQ(star.pieces.size(), 14u);  // eight octants, six of them halved by the diagonal plane
  expectPartition(m, meshesOf(star.pieces));
  // Corefinement rounds intersection points near (1, -1, -1) onto each other: zero-area triangles.
  const CutMeshResult corners = cut(m, {{{-1, 1, -1}, {-0.4898619485211566, -0.009129825816118098, -0.10101787042252375}},
                                        {{1, -1, -1}, {-0.8122808264515302, -0.9433050469559874, 0.6715302078397394}},
                                        {{0, 0, 0}, {-1, 1, 0}}});
  EXPECT_EQ(corners.pieces.size(), 7u);
  expectPartition(m, meshesOf(corners.pieces));
}

TEST(CutMesh, RefusesDegeneratePlanes) {
  const Mesh m = cube();
  EXPECT_NE(errorOf([&] { cut(m, {{{0, 0, 0}, {0, 0, 0}}}); }).find("zero normal"), std::string::npos);
  EXPECT_NE(errorOf([&] { cut(m, {{{0, 0, NAN}, {0, 0, 1}}}); }).find("not finite"), std::string::npos);
}

TEST(FractureMesh, SpherePiecesPartitionTheModel) {
  const Mesh m = makeSphere(48, 24);
  FractureOptions o;
  o.pieces = 12;
  const FractureResult r = fractureMesh(m, o);
  EXPECT_EQ(r.pieces.size(), 12u);
  expectPartition(m, meshesOf(r.pieces));
  for (const CellPiece& p : r.pieces) EXPECT_GT(measureSolid(p.mesh, 1).taggedArea, 0.0);
}

TEST(FractureMesh, DeterministicAcrossRunsAndThreads) {
  const Mesh m = makeSphere(32, 16);
  FractureOptions o;
  o.pieces = 7;
  o.seed = 5;
  const FractureResult a = fractureMesh(m, o, Context{.threads = 1});
  const FractureResult b = fractureMesh(m, o, Context{.threads = 2});
  const FractureResult c = fractureMesh(m, o, Context{.threads = 2});
  EXPECT_TRUE(identical(a.pieces, b.pieces));
  EXPECT_TRUE(identical(b.pieces, c.pieces));
  o.seed = 6;
  EXPECT_FALSE(identical(a.pieces, fractureMesh(m, o).pieces));
}

TEST(FractureMesh, NonConvexTorus) {
  const Mesh m = torus(48, 16);
  FractureOptions o;
  o.pieces = 9;
  const FractureResult r = fractureMesh(m, o);
  EXPECT_EQ(r.pieces.size(), 9u);
  expectPartition(m, meshesOf(r.pieces));
}

// Normal spread of the cut faces of a piece: 0 when every crack is flat.
double crackNormalSpread(const CellPiece& p) {
  std::map<int32_t, std::vector<Eigen::Vector3f>> normals;
  for (size_t t = 0; t < p.mesh.triangles.size(); ++t)
    if (p.cutFace[t] >= 0) normals[p.cutFace[t]].push_back(faceNormal(p.mesh, t));
  double spread = 0;
  for (const auto& [face, list] : normals)
    for (const auto& n : list) spread = std::max(spread, double(1 - n.dot(list.front())));
  return spread;
}

TEST(FractureMesh, RoughCracksStillFit) {
  const Mesh m = makeSphere(48, 24);
  FractureOptions o;
  o.pieces = 6;
  const FractureResult flat = fractureMesh(m, o);
  o.roughness = 0.15;
  const FractureResult rough = fractureMesh(m, o);
  ASSERT_EQ(rough.pieces.size(), 6u);
  expectPartition(m, meshesOf(rough.pieces));
  double flatSpread = 0, roughSpread = 0;
  for (const CellPiece& p : flat.pieces) flatSpread = std::max(flatSpread, crackNormalSpread(p));
  for (const CellPiece& p : rough.pieces) roughSpread = std::max(roughSpread, crackNormalSpread(p));
  EXPECT_LT(flatSpread, 1e-3);
  EXPECT_GT(roughSpread, 0.05);
}

TEST(FractureMesh, SmallPiecesMergeIntoANeighbour) {
  const Mesh m = makeSphere(48, 24);
  FractureOptions o;
  o.pieces = 40;
  const FractureResult all = fractureMesh(m, o);
  o.minVolume = 0.03;
  const FractureResult merged = fractureMesh(m, o);
  EXPECT_GT(merged.report.merged, 0);
  EXPECT_EQ(merged.pieces.size() + size_t(merged.report.merged), all.pieces.size());
  expectPartition(m, meshesOf(merged.pieces));
  const double total = measureSolid(m).volume;
  for (const CellPiece& p : merged.pieces) EXPECT_GE(measureSolid(p.mesh).volume, 0.03 * total);
}

TEST(FractureMesh, ImpactConcentratesTheSites) {
  const Mesh m = makeSphere(32, 16);
  FractureOptions o;
  o.pieces = 30;
  const Eigen::Vector3d impact(0.6, 0, 0);
  auto meanDistance = [&](const FractureResult& r) {
    double d = 0;
    for (const auto& s : r.sites) d += (s - impact).norm();
    return d / double(r.sites.size());
  };
  const double uniform = meanDistance(fractureMesh(m, o));
  o.impact = impact;
  const double concentrated = meanDistance(fractureMesh(m, o));
  EXPECT_LT(concentrated, 0.6 * uniform);
}

TEST(FractureMesh, RefusesBadOptions) {
  const Mesh m = cube();
  auto error = [&](auto edit) {
    FractureOptions o;
    edit(o);
    return errorOf([&] { fractureMesh(m, o); });
  };
  EXPECT_NE(error([](FractureOptions& o) { o.pieces = 0; }).find("pieces"), std::string::npos);
  EXPECT_NE(error([](FractureOptions& o) { o.pieces = kMaxFracturePieces + 1; }).find("pieces"), std::string::npos);
  EXPECT_NE(error([](FractureOptions& o) { o.roughness = NAN; }).find("roughness"), std::string::npos);
  EXPECT_NE(error([](FractureOptions& o) { o.roughness = 0.5; }).find("roughness"), std::string::npos);
  EXPECT_NE(error([](FractureOptions& o) { o.minVolume = 0.5; }).find("min volume"), std::string::npos);
  EXPECT_NE(error([](FractureOptions& o) { o.impact = Eigen::Vector3d(0, NAN, 0); }).find("impact"), std::string::npos);
}

TEST(FractureMesh, MoreSitesThanAThinModelHolds) {
  // A thin rod along the diagonal of its box: about 2e-5 of the box is inside.
  Mesh rod = makeCylinder(8, 1, 0.004f, 1.7f);
  const Eigen::Matrix3f turn = Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitY(), Eigen::Vector3f(1, 1, 1)).toRotationMatrix();
  for (auto& p : rod.positions) p = turn * p;
  prepareMesh(rod, MeshUse::Solid);  // caps the open cylinder
  FractureOptions o;
  o.pieces = 1000;
  EXPECT_NE(errorOf([&] { fractureMesh(rod, o); }).find("holds only"), std::string::npos);
}

// Repairs: each defect of a cube made, found and fixed (or refused), reported in a line.
Mesh unwelded(const Mesh& m) {
  Mesh out = m;
  out.positions.clear();
  for (auto& t : out.triangles)
    for (uint32_t& v : t) {
      out.positions.push_back(m.positions[v]);
      v = uint32_t(out.positions.size() - 1);
    }
  return out;
}

MeshPreparation prepareSolid(Mesh& m, PrepareMeshOptions o = {}, const Context& ctx = {}) {
  o.use = MeshUse::Solid;
  return prepareMesh(m, o, ctx);
}

void expectRepairedSolid(Mesh m, const std::string& says) {
  const double volume = measureSolid(cube()).volume;
  const MeshPreparation r = prepareSolid(m);
  std::string all;
  for (const auto& line : r.repairs) all += line + "; ";
  EXPECT_NE(all.find(says), std::string::npos) << all;
  const MeshConnectivity t = computeConnectivity(m);
  EXPECT_TRUE(t.closed && t.manifold && t.oriented) << all;
  EXPECT_NEAR(measureSolid(m).volume, volume, 1e-9) << all;
}

TEST(PrepareMesh, SolidWeldsFillsReorientsAndTurnsOutward) {
  expectRepairedSolid(unwelded(cube()), "welded");
  Mesh holed = cube();
  holed.triangles.pop_back(), holed.uvs.resize(holed.uvs.size() - 3), holed.normals.resize(holed.normals.size() - 3);
  holed.faceMaterials.pop_back(), holed.faceTags.pop_back();
  expectRepairedSolid(holed, "filled 1 hole with 1 triangle");
  Mesh flipped = cube();
  std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
  expectRepairedSolid(flipped, "consistent");
  Mesh insideOut = cube();
  for (auto& t : insideOut.triangles) std::swap(t[1], t[2]);
  expectRepairedSolid(insideOut, "inside-out parts turned over");
  Mesh solid = cube();
  EXPECT_TRUE(prepareSolid(solid).repairs.empty());
}

// Two cubes that overlap, as one self-intersecting mesh.
Mesh overlappingCubes() {
  Mesh m = cube();
  const Mesh other = cube();
  const uint32_t base = uint32_t(m.positions.size());
  for (const auto& p : other.positions) m.positions.push_back(p + Eigen::Vector3f(0.5f, 0.3f, 0.2f));
  for (auto t : other.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  m.uvs.clear(), m.normals.clear(), m.faceMaterials.clear(), m.faceTags.clear();
  return m;
}

// A cube with a fin: one triangle on one of its edges, which three triangles then share.
Mesh finnedCube() {
  Mesh m = cube();
  m.uvs.clear(), m.normals.clear(), m.faceMaterials.clear(), m.faceTags.clear();
  m.positions.push_back({0, 3, 0});
  m.triangles.push_back({m.triangles[0][0], m.triangles[0][1], uint32_t(m.positions.size() - 1)});
  return m;
}

TEST(PrepareMesh, SolidRebuildsSurfacesThatCannotBoundASolidFromTheirVolume) {
  // The union of the two cubes: 2 * 8 - 1.5 * 1.7 * 1.8.
  const double unionVolume = 16 - 1.5 * 1.7 * 1.8;
  PrepareMeshOptions coarse;  // voxels of 3.5 / 96 units
  coarse.remesh.resolution = 96;
  Mesh one = overlappingCubes(), two = overlappingCubes();
  const MeshPreparation r = prepareSolid(one, coarse, Context{.threads = 1});
  ASSERT_EQ(r.repairs.size(), 1u);
  EXPECT_NE(r.repairs[0].find("intersects itself"), std::string::npos) << r.repairs[0];
  EXPECT_NE(r.repairs[0].find("rebuilt as the volume it encloses"), std::string::npos) << r.repairs[0];
  EXPECT_TRUE(r.rebuilt);
  const MeshConnectivity t = computeConnectivity(one);
  EXPECT_TRUE(t.closed && t.manifold && t.oriented);
  EXPECT_NEAR(measureSolid(one).volume, unionVolume, 0.01 * unionVolume);
  Mesh again = one;
  EXPECT_TRUE(prepareSolid(again).repairs.empty());  // a solid: no self-intersections left
  prepareSolid(two, coarse, Context{.threads = 2});
  EXPECT_EQ(one.positions, two.positions);
  EXPECT_EQ(one.triangles, two.triangles);

  Mesh fin = finnedCube();
  const MeshPreparation f = prepareSolid(fin, coarse);
  ASSERT_EQ(f.repairs.size(), 1u);
  EXPECT_NE(f.repairs[0].find("not a manifold"), std::string::npos) << f.repairs[0];
  EXPECT_NEAR(measureSolid(fin).volume, 8.0, 0.08);
}

// Six times the volume the triangles enclose as they are wound (an inverted shell subtracts).
double signedVolume(const Mesh& m) {
  double v = 0;
  for (size_t t = 0; t < m.triangles.size(); ++t)
    v += m.corner(t, 0).cast<double>().dot(m.corner(t, 1).cast<double>().cross(m.corner(t, 2).cast<double>()));
  return v / 6;
}

TEST(PrepareMesh, OverlappingShellsStayOutwardSoThatAPrintTakesTheirUnion) {
  // Each cube's largest triangle lies inside the other: one point alone took both for cavities and
  // turned them inside out (inward normals on a textured model; where only one shell turns, a
  // print's winding rule leaves the overlap empty).
  for (const MeshUse use : {MeshUse::Surface, MeshUse::Print}) {
    Mesh m = overlappingCubes();
    const MeshPreparation r = prepareMesh(m, use);
    EXPECT_TRUE(r.repairs.empty()) << meshUseName(use) << ": " << r.repairs.front();
    EXPECT_NEAR(signedVolume(m), 16.0, 1e-5) << meshUseName(use);
  }
  // A cavity (a shell wholly inside another) is still turned inward.
  const Mesh outer = makeSphere(24, 12, 1.0f), inner = makeSphere(24, 12, 0.5f);
  Mesh hollow = outer;
  const uint32_t base = uint32_t(hollow.positions.size());
  hollow.positions.insert(hollow.positions.end(), inner.positions.begin(), inner.positions.end());
  for (auto t : inner.triangles) hollow.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  hollow.uvs.clear(), hollow.normals.clear(), hollow.tangents.clear();
  const MeshPreparation r = prepareMesh(hollow, MeshUse::Print);
  ASSERT_EQ(r.repairs.size(), 1u);
  EXPECT_NE(r.repairs[0].find("1 inside-out parts turned over"), std::string::npos) << r.repairs[0];
  EXPECT_NEAR(signedVolume(hollow), signedVolume(outer) - signedVolume(inner), 1e-5);
}

TEST(PrepareMesh, EachUseGoesAsFarAsItNeeds) {
  // A sphere with two holes that share a corner: a boundary vertex starts two boundary edges, so
  // hole fans cannot close it.
  const Mesh sphere = makeSphere(16, 8);
  const uint32_t first = 20, v = sphere.triangles[first][0];
  uint32_t second = 0;
  for (uint32_t t = 0; t < sphere.triangles.size() && !second; ++t) {
    int shared = 0;
    for (uint32_t a : sphere.triangles[t])
      for (uint32_t b : sphere.triangles[first]) shared += a == b;
    if (shared == 1 && std::find(sphere.triangles[t].begin(), sphere.triangles[t].end(), v) != sphere.triangles[t].end())
      second = t;
  }
  ASSERT_GT(second, 0u);
  Mesh holed;
  holed.positions = sphere.positions;
  for (uint32_t t = 0; t < sphere.triangles.size(); ++t)
    if (t != first && t != second) holed.triangles.push_back(sphere.triangles[t]);

  Mesh surface = holed;  // textured as it is
  EXPECT_TRUE(prepareMesh(surface, MeshUse::Surface).repairs.empty());
  EXPECT_EQ(surface.triangles, holed.triangles);

  for (const MeshUse use : {MeshUse::Print, MeshUse::Solid}) {
    Mesh m = holed;
    const MeshPreparation r = prepareMesh(m, use);
    std::string all;
    for (const auto& line : r.repairs) all += line + "; ";
    EXPECT_NE(all.find("filled 2 holes"), std::string::npos) << meshUseName(use) << ": " << all;
    const MeshConnectivity c = computeConnectivity(m);
    EXPECT_TRUE(c.closed && c.oriented) << meshUseName(use) << ": " << all;
    EXPECT_GT(signedVolume(m), 0.9 * signedVolume(sphere)) << meshUseName(use);
    EXPECT_EQ(r.holeTriangles > 0, use == MeshUse::Solid);  // tagged as cut faces only where they show
  }
}

TEST(PrepareMesh, SolidRefusesWhatItMayNotRebuildAndLargeHoles) {
  PrepareMeshOptions refuse;
  refuse.remesh.resolution = 0;
  Mesh twoCubes = overlappingCubes();
  const std::string crossing = errorOf([&] { prepareSolid(twoCubes, refuse); });
  EXPECT_NE(crossing.find("intersects itself"), std::string::npos) << crossing;
  Mesh fin = finnedCube();
  const std::string nonManifold = errorOf([&] { prepareSolid(fin, refuse); });
  EXPECT_NE(nonManifold.find("not a manifold"), std::string::npos) << nonManifold;
  Mesh open = makeSphere(40, 20);
  open.triangles.resize(open.triangles.size() / 2);  // a hemisphere: one hole of 40 edges
  PrepareMeshOptions small;
  small.maxHoleEdges = 10;
  const std::string hole = errorOf([&] { prepareSolid(open, small); });
  EXPECT_NE(hole.find("open"), std::string::npos) << hole;
}

} // namespace
