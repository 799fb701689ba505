// SPDX-License-Identifier: GPL-3.0-or-later
// The Embree scene against brute-force references: ray hits, inside/outside on closed meshes from
// CGAL's data set (generalized winding number over every triangle), closest points.
#include "geometry/embree_scene.h"
#include "geometry/io/mesh_io.h"
#include "geometry/mesh_connectivity.h"
#include "tests/geometry/test_meshes.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>

using namespace texfab;
using namespace texfab::geometry;

namespace {

// Generalized winding number: sum of signed solid angles / 4π, in double precision
// [Van Oosterom & Strackee 1983; Jacobson et al. 2013]. ~1 inside a closed mesh, ~0 outside.
double windingNumber(const Mesh& m, const Eigen::Vector3f& p) {
  double total = 0;
  for (const auto& tri : m.triangles) {
    const Eigen::Vector3d a = (m.positions[tri[0]] - p).cast<double>(), b = (m.positions[tri[1]] - p).cast<double>(),
                          c = (m.positions[tri[2]] - p).cast<double>();
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double det = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2 * std::atan2(det, den);
  }
  return total / (4 * M_PI);
}

double bruteDistance(const Mesh& m, const Eigen::Vector3f& p) {
  double best = INFINITY;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    Eigen::Vector2f uv;
    best = std::min(best, double((closestPointOnTriangle(p, m.corner(t, 0), m.corner(t, 1), m.corner(t, 2), uv) - p).norm()));
  }
  return best;
}

std::vector<Eigen::Vector3f> randomPoints(const BoundingBox& box, int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  const Eigen::Vector3f lo = box.min - 0.1f * (box.max - box.min), size = 1.2f * (box.max - box.min);
  std::vector<Eigen::Vector3f> pts;
  pts.resize(size_t(n));
  for (auto& p : pts) p = lo + Eigen::Vector3f(u(rng), u(rng), u(rng)).cwiseProduct(size);
  return pts;
}

void checkInsideAgainstWindingNumber(const Mesh& mesh, const std::string& name, int n) {
  const EmbreeScene scene(mesh);
  ASSERT_TRUE(scene.watertight()) << name;
  const auto points = randomPoints(scene.bounds(), n, 17);
  const auto inside = scene.inside(points, Context{.threads = 0});
  int compared = 0, disagree = 0, insideCount = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const double w = windingNumber(mesh, points[i]);
    if (std::abs(w - std::round(w)) > 0.1) continue;  // on (or numerically at) the surface
    ++compared;
    const bool reference = std::llround(std::abs(w)) % 2 == 1;
    insideCount += reference;
    disagree += (inside[i] != 0) != reference;
  }
  EXPECT_GT(compared, n * 9 / 10) << name;
  EXPECT_GT(insideCount, 0) << name << ": no sample point fell inside; the test would prove nothing";
  EXPECT_EQ(disagree, 0) << name << ": " << disagree << " of " << compared << " points disagree with the winding number";
}

} // namespace

TEST(EmbreeScene, RayHitsReportTriangleBarycentricsAndDistance) {
  const Mesh cube = texfab::test::texturedCube();
  const EmbreeScene scene(cube);
  const RayHit hit = scene.intersect({{0.2f, 0.3f, 5.0f}, {0, 0, -1}});
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.distance, 4.0f, 1e-5f);
  EXPECT_GT(faceNormal(cube, hit.triangle).z(), 0.99f);  // the +Z face
  const float u = hit.barycentric.x(), v = hit.barycentric.y();
  const Eigen::Vector3f p = (1 - u - v) * cube.corner(hit.triangle, 0) + u * cube.corner(hit.triangle, 1) +
                            v * cube.corner(hit.triangle, 2);
  EXPECT_LT((p - Eigen::Vector3f(0.2f, 0.3f, 1.0f)).norm(), 1e-5f);
  EXPECT_FALSE(scene.intersect({{0, 3, 5}, {0, 0, -1}}).hit);
  EXPECT_TRUE(scene.occluded({{0, 0, 5}, {0, 0, -1}}));
  EXPECT_FALSE(scene.occluded({{0, 0, 5}, {0, 0, -1}, 0.0f, 3.5f}));
  std::vector<Ray> rays(100, Ray{{0, 0, 5}, {0, 0, -1}});
  for (const RayHit& h : scene.intersect(rays, Context{.threads = 2})) EXPECT_NEAR(h.distance, 4.0f, 1e-5f);
}

TEST(EmbreeScene, InsideOfCubeAndOpenMeshesAreReported) {
  Mesh cube = texfab::test::texturedCube();
  const EmbreeScene scene(cube);
  EXPECT_TRUE(scene.inside({0.1f, 0.2f, 0.3f}));
  EXPECT_TRUE(scene.inside({0.99f, 0.99f, 0.99f}));
  EXPECT_FALSE(scene.inside({1.01f, 0.0f, 0.0f}));
  EXPECT_FALSE(scene.inside({5, 5, 5}));
  cube.triangles.pop_back();
  cube.uvs.resize(3 * cube.triangles.size());
  cube.normals.resize(3 * cube.triangles.size());
  cube.faceMaterials.pop_back();
  cube.faceTags.pop_back();
  const EmbreeScene open(cube);
  EXPECT_FALSE(open.watertight());
  EXPECT_THROW(open.inside(Eigen::Vector3f(0, 0, 0)), Error);
}

TEST(EmbreeScene, InsideAgreesWithWindingNumberOnBundledMeshes) {
  for (const char* name : {"elephant.off", "knot1.off"})
    checkInsideAgainstWindingNumber(readMesh(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes" / name), name, 600);
}

TEST(EmbreeScene, InsideAgreesWithWindingNumberOnCgalDataSet) {
  const auto dir = texfab::test::cgalDataDir();
  if (dir.empty()) GTEST_SKIP() << "CGAL data set not extracted (run models/fetch)";
  int tested = 0;
  for (const char* name : {"cow.off", "mushroom.off", "double-torus-example.off", "eight.off", "cube.off", "sphere.off",
                           "bones.off", "dino.off", "camel.off", "fandisk.off"}) {
    if (!std::filesystem::exists(dir / name)) continue;
    const Mesh mesh = readMesh(dir / name);
    if (!computeConnectivity(mesh).watertight || mesh.triangleCount() > 30000) continue;
    checkInsideAgainstWindingNumber(mesh, name, 300);
    ++tested;
  }
  EXPECT_GE(tested, 3);
}

TEST(EmbreeScene, ClosestPointMatchesBruteForce) {
  const Mesh mesh = readMesh(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes/knot1.off");
  const EmbreeScene scene(mesh);
  const auto points = randomPoints(scene.bounds(), 200, 5);
  const auto closest = scene.closestPoints(points, Context{.threads = 2});
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_TRUE(closest[i].found);
    EXPECT_NEAR(closest[i].distance, bruteDistance(mesh, points[i]), 1e-5);
    EXPECT_NEAR((closest[i].point - points[i]).norm(), closest[i].distance, 1e-5);
  }
  EXPECT_FALSE(scene.closestPoint(Eigen::Vector3f(10, 10, 10), 0.5f).found);
}

// A point nearest to a corner of the cube is as near to every triangle around it: the answer is
// the one of smallest index, not the first that Embree's traversal (which follows the CPU's
// instruction set) happens to visit.
TEST(EmbreeScene, ClosestPointTiesGoToTheSmallestTriangle) {
  const Mesh cube = texfab::test::texturedCube();
  const EmbreeScene scene(cube);
  const Eigen::Vector3f box[2] = {scene.bounds().min, scene.bounds().max};
  int cornersChecked = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3f corner(box[c & 1].x(), box[(c >> 1) & 1].y(), box[(c >> 2) & 1].z());
    const Eigen::Vector3f outside = corner + (corner - scene.bounds().center()).normalized();
    uint32_t smallest = UINT32_MAX;
    int around = 0;
    for (uint32_t t = 0; t < cube.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        if (cube.corner(t, k) == corner) smallest = std::min(smallest, t), ++around;
    ASSERT_GE(around, 3);
    const geometry::SurfacePoint near = scene.closestPoint(outside, 10.0f);
    ASSERT_TRUE(near.found);
    EXPECT_EQ(near.triangle, smallest) << "corner " << c;
    EXPECT_EQ(near.point, corner);
    ++cornersChecked;
  }
  EXPECT_EQ(cornersChecked, 8);
}
