// SPDX-License-Identifier: GPL-3.0-or-later
// Voxelization by layers: volumes of known solids within the discretization bound, the shell's
// thickness measured on a layer, agreement with Embree's ray-parity inside test and closest
// points on real meshes, and refusals of open meshes and bad grids.
#include "geometry/embree_scene.h"
#include "geometry/io/mesh_io.h"
#include "geometry/repair/close_holes.h"
#include "print/print_grid.h"
#include "print/voxelize_layers.h"
#include "tests/geometry/solid_meshes.h"
#include "tests/geometry/test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace texfab::test {
namespace {

using namespace geometry;
using namespace print;

PrintGrid gridFor(const Mesh& mesh, double pitchMm, double mmPerUnit = 1.0) {
  PrintGridOptions o;
  o.mmPerUnit = mmPerUnit;
  o.dpiX = o.dpiY = 25.4 / pitchMm;
  o.layerMm = pitchMm;
  return printGrid(boundingBox(mesh), o);
}

int64_t countInside(const LayerVoxelizer& v) {
  int64_t n = 0;
  for (int k = 0; k < v.grid().layers; ++k) n += v.voxelize(k).insideVoxels();
  return n;
}

// |voxel volume - exact volume| <= area * voxel diagonal: only voxels whose centres lie within half
// a diagonal of the surface can be misclassified.
void expectVolume(const Mesh& mesh, double pitchMm) {
  const LayerVoxelizer v(mesh, gridFor(mesh, pitchMm));
  const double voxel = std::pow(pitchMm, 3);
  const double exact = meshVolume(mesh), measured = double(countInside(v)) * voxel;
  const double bound = meshArea(mesh) * pitchMm * std::sqrt(3.0) / 2;
  EXPECT_NEAR(measured, exact, bound) << "pitch " << pitchMm;
}

TEST(VoxelizeLayers, AlignedCubeIsExact) {
  // Voxel centres never lie on the faces of a box spanning whole voxels: every count is exact.
  const Mesh box = makeBox({0, 0, 0}, {4, 3, 2});
  const LayerVoxelizer v(box, gridFor(box, 0.25));
  EXPECT_EQ(v.grid().width, 16);
  EXPECT_EQ(v.grid().height, 12);
  EXPECT_EQ(v.grid().layers, 8);
  EXPECT_EQ(countInside(v), 16 * 12 * 8);
}

TEST(VoxelizeLayers, CubeAndSphereVolumesWithinTheDiscretizationBound) {
  Mesh box = makeBox({0.13f, -0.71f, 0.05f}, {3.3f, 2.9f, 2.77f});
  for (auto& p : box.positions) p = Eigen::AngleAxisf(0.4f, Eigen::Vector3f(1, 2, 3).normalized()) * p;
  const Mesh sphere = makeIcoSphere(2.0f, 5, {0.3f, 0.1f, -0.2f});
  for (double pitch : {0.2, 0.07}) {
    expectVolume(box, pitch);
    expectVolume(sphere, pitch);
  }
}

TEST(VoxelizeLayers, ShellIsShellThickOnALayer) {
  // A 10 mm cube, 0.05 mm voxels, 1 mm shell: the middle layer's middle row is shell for 1 mm
  // (20 voxels) at each end, core between; the middle column of the top layer is all shell.
  const Mesh box = makeBox({0, 0, 0}, {10, 10, 10});
  VoxelizeOptions o;
  o.shellMm = 1.0;
  const LayerVoxelizer v(box, gridFor(box, 0.05), o);
  const LayerSpans mid = v.voxelize(v.grid().layers / 2);
  const auto row = mid.row(mid.rows() / 2);
  ASSERT_EQ(row.size(), 3u);
  EXPECT_TRUE(row[0].shell && !row[1].shell && row[2].shell);
  EXPECT_EQ(row[0].end - row[0].begin, 20);
  EXPECT_EQ(row[2].end - row[2].begin, 20);
  EXPECT_EQ(row[1].end - row[1].begin, 200 - 40);
  const LayerSpans top = v.voxelize(v.grid().layers - 1);
  EXPECT_EQ(top.shellVoxels(), top.insideVoxels());
  // The layer 1 mm below the top: centre 0.975 mm deep, still shell; 1.025 mm deep is core.
  EXPECT_EQ(v.voxelize(v.grid().layers - 20).row(100).size(), 1u);
  EXPECT_EQ(v.voxelize(v.grid().layers - 21).row(100).size(), 3u);
}

TEST(VoxelizeLayers, AgreesWithEmbreeOnRealMeshes) {
  for (const char* name : {"knot1.off", "elephant.off"}) {
    const Mesh mesh = readMesh(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes" / name);
    const BoundingBox box = boundingBox(mesh);
    PrintGridOptions go;
    go.heightMm = 20;
    go.dpiX = go.dpiY = 300;
    go.layerMm = 0.1;
    const PrintGrid grid = printGrid(box, go);
    VoxelizeOptions vo;
    vo.shellMm = 0.8;
    const LayerVoxelizer v(mesh, grid, vo);
    const EmbreeScene scene(mesh);
    std::mt19937 rng(7);
    int checked = 0, disagree = 0, shellDisagree = 0;
    for (int k = 0; k < grid.layers; k += 7) {
      const LayerSpans spans = v.voxelize(k);
      for (int i = 0; i < 60; ++i) {
        const int x = int(rng() % uint32_t(grid.width)), r = int(rng() % uint32_t(grid.height));
        bool inside = false, shell = false;
        for (const VoxelSpan& s : spans.row(r))
          if (x >= s.begin && x < s.end) inside = true, shell = s.shell;
        const Eigen::Vector3f p = grid.center(x, grid.height - 1 - r, k).cast<float>();
        const SurfacePoint near = scene.closestPoint(p);
        const double distanceMm = near.distance * grid.mmPerUnit;
        if (distanceMm < 1e-4) continue;  // on the surface: either answer is right
        ++checked;
        disagree += inside != scene.inside(p);
        if (inside && std::abs(distanceMm - vo.shellMm) > 1e-4) shellDisagree += shell != (distanceMm < vo.shellMm);
      }
    }
    EXPECT_GT(checked, 500) << name;
    EXPECT_EQ(disagree, 0) << name;
    EXPECT_EQ(shellDisagree, 0) << name;
  }
}

TEST(VoxelizeLayers, LayersDoNotDependOnOrder) {
  const Mesh sphere = makeIcoSphere(1.0f, 3);
  const LayerVoxelizer v(sphere, gridFor(sphere, 0.05));
  const LayerSpans a = v.voxelize(17);
  v.voxelize(3);
  const LayerSpans b = v.voxelize(17);
  ASSERT_EQ(a.spans.size(), b.spans.size());
  for (size_t i = 0; i < a.spans.size(); ++i)
    EXPECT_TRUE(a.spans[i].begin == b.spans[i].begin && a.spans[i].end == b.spans[i].end &&
                a.spans[i].shell == b.spans[i].shell);
  EXPECT_EQ(a.rowStart, b.rowStart);
}

TEST(VoxelizeLayers, CavitiesAndOverlapsFollowTheWindingRule) {
  // A box with an inward-facing box inside (a cavity), and a second box overlapping the first.
  Mesh m = makeBox({0, 0, 0}, {4, 4, 4});
  const Mesh cavity = makeBox({1, 1, 1}, {3, 3, 3});
  const Mesh overlap = makeBox({3.5f, 0, 0}, {6, 4, 4});
  auto append = [&](const Mesh& part, bool flip) {
    const uint32_t base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), part.positions.begin(), part.positions.end());
    for (auto t : part.triangles) {
      if (flip) std::swap(t[1], t[2]);
      m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
  };
  append(cavity, true);
  append(overlap, false);
  const LayerVoxelizer v(m, gridFor(m, 0.25));
  // Union of [0,6]x[0,4]x[0,4] minus the 2^3 cavity, in 0.25 mm voxels.
  EXPECT_EQ(countInside(v), (24 * 16 * 16) - (8 * 8 * 8));
}

TEST(VoxelizeLayers, RefusesOpenAndFlippedMeshes) {
  Mesh open = makeBox({0, 0, 0}, {1, 1, 1});
  open.triangles.pop_back();
  const PrintGrid grid = gridFor(open, 0.1);
  EXPECT_NE(errorOf([&] { LayerVoxelizer(open, grid); }).find("not closed"), std::string::npos);
  Mesh flipped = makeBox({0, 0, 0}, {1, 1, 1});
  std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
  EXPECT_NE(errorOf([&] { LayerVoxelizer(flipped, grid); }).find("flipped"), std::string::npos);
  // Split vertices (as STL stores them) are welded: the box is closed.
  Mesh soup;
  const Mesh box = makeBox({0, 0, 0}, {1, 1, 1});
  for (const auto& t : box.triangles) {
    for (uint32_t i : t) soup.positions.push_back(box.positions[i]);
    const uint32_t b = uint32_t(soup.positions.size() - 3);
    soup.triangles.push_back({b, b + 1, b + 2});
  }
  EXPECT_EQ(LayerVoxelizer(soup, grid).report().weldedVertices, 36u - 8u);
}

TEST(CloseHoles, ClosesSimpleHolesAndLeavesTheRest) {
  // A box missing one triangle, and a sphere missing a ring of triangles: closed by fans, and
  // the volume is the closed solid's.
  Mesh box = makeBox({0, 0, 0}, {2, 2, 2});
  box.triangles.pop_back();
  CloseHolesReport r = closeHoles(box);
  EXPECT_EQ(r.holes, 1u);
  EXPECT_EQ(r.boundaryEdges, 3u);
  EXPECT_TRUE(r.closed);
  EXPECT_NEAR(meshVolume(box), 8.0, 1e-5);
  Mesh sphere = makeIcoSphere(1.0f, 3);
  const double full = meshVolume(sphere);
  sphere.triangles.erase(sphere.triangles.begin() + 40, sphere.triangles.begin() + 44);
  r = closeHoles(sphere);
  EXPECT_TRUE(r.closed);
  EXPECT_NEAR(meshVolume(sphere), full, 1e-3);
  const LayerVoxelizer v(sphere, gridFor(sphere, 0.1));  // accepted now
  // A vertex shared by two holes is not a simple loop: left open.
  Mesh bowtie = makeBox({0, 0, 0}, {1, 1, 1});
  bowtie.triangles.erase(bowtie.triangles.begin() + 8, bowtie.triangles.begin() + 10);  // -z face
  bowtie.triangles.erase(bowtie.triangles.begin() + 0, bowtie.triangles.begin() + 1);   // a -x triangle
  const size_t before = bowtie.triangles.size();
  r = closeHoles(bowtie);
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(bowtie.triangles.size(), before);
}

TEST(PrintGrid, RefusesBadOptions) {
  const BoundingBox box{{0, 0, 0}, {1, 1, 1}};
  auto bad = [&](auto set) {
    PrintGridOptions o;
    set(o);
    return errorOf([&] { printGrid(box, o); });
  };
  EXPECT_NE(bad([](auto& o) { o.dpiX = 0; }).find("x resolution"), std::string::npos);
  EXPECT_NE(bad([](auto& o) { o.layerMm = -0.1; }).find("layer thickness"), std::string::npos);
  EXPECT_NE(bad([](auto& o) { o.heightMm = std::nan(""); }).find("print height"), std::string::npos);
  EXPECT_NE(bad([](auto& o) { o.mmPerUnit = std::numeric_limits<double>::infinity(); }).find("scale"), std::string::npos);
  EXPECT_NE(bad([](auto& o) { o.heightMm = 9000; o.layerMm = 0.001; }).find("voxels tall"), std::string::npos);
  EXPECT_NE(errorOf([&] { printGrid({{0, 0, 0}, {1, 1, 0}}, {}); }).find("flat"), std::string::npos);
  // 50 mm at 0.05 mm is 1000 layers, not 1001.
  PrintGridOptions o;
  o.layerMm = 0.05;
  EXPECT_EQ(printGrid(box, o).layers, 1000);
}

} // namespace
} // namespace texfab::test
