// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end: texfab info / convert / render on the bundled models.
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "tests/geometry/test_meshes.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>

using namespace texfab;
using texfab::test::quote;
using texfab::test::runCli;
using texfab::test::TempDir;

namespace {

const std::filesystem::path kMeshes = std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes";

} // namespace

TEST(CliMesh, InfoJsonDescribesTheBundledModels) {
  auto [status, out, err] = runCli("info --json " + quote(kMeshes / "marble_cube.glb"));
  ASSERT_EQ(status, 0);
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["triangles"], 12);
  EXPECT_EQ(j["vertices"], 8);
  EXPECT_EQ(j["closed"], true);
  EXPECT_EQ(j["manifold"], true);
  EXPECT_EQ(j["genus"], 0);
  EXPECT_EQ(j["components"], 1);
  EXPECT_EQ(j["uvs"], true);
  ASSERT_EQ(j["materials"].size(), 1u);
  EXPECT_EQ(j["materials"][0]["base_color_texture"]["width"], 128);
  const texfab::test::CliResult knot = runCli("info --json " + quote(kMeshes / "knot1.off"));
  ASSERT_EQ(knot.status, 0);
  EXPECT_EQ(nlohmann::json::parse(knot.out)["genus"], 1);
  EXPECT_EQ(nlohmann::json::parse(knot.out)["uvs"], false);
}

TEST(CliMesh, InfoFindsTwoClosedCubesJoinedAtOneVertexNonManifold) {
  // Unit cubes [0,1]^3 and [1,2]^3 sharing the vertex (1,1,1): closed, no non-manifold edge, but
  // the shared vertex has two fans of triangles.
  TempDir dir("texfab-cli-info");
  std::string off = "OFF\n15 24 0\n";
  for (int cube = 0; cube < 2; ++cube)
    for (int i = 0; i < 8; ++i)
      if (cube == 0 || i != 0)
        off += std::to_string(cube + (i & 1)) + " " + std::to_string(cube + ((i >> 1) & 1)) + " " +
               std::to_string(cube + ((i >> 2) & 1)) + "\n";
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int cube = 0; cube < 2; ++cube) {
    auto index = [&](int i) { return cube == 0 ? i : i == 0 ? 7 : 7 + i; };
    for (const auto& q : quads)
      for (auto [a, b, c] : {std::array{q[0], q[1], q[2]}, std::array{q[0], q[2], q[3]}})
        off += "3 " + std::to_string(index(a)) + " " + std::to_string(index(b)) + " " + std::to_string(index(c)) + "\n";
  }
  std::FILE* f = std::fopen((dir / "touching.off").c_str(), "w");
  ASSERT_TRUE(f);
  std::fputs(off.c_str(), f);
  std::fclose(f);
  auto [status, out, err] = runCli("info --json " + quote(dir / "touching.off"));
  ASSERT_EQ(status, 0);
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["closed"], true);
  EXPECT_EQ(j["non_manifold_edges"], 0);
  EXPECT_EQ(j["non_manifold_vertices"], 1);
  EXPECT_EQ(j["manifold"], false);
  EXPECT_EQ(j["oriented"], true);
}

TEST(CliMesh, ConvertKeepsMaterialsAndRefusesBadRequests) {
  TempDir dir("texfab-cli-convert");
  ASSERT_EQ(runCli("convert -q " + quote(kMeshes / "marble_cube.obj") + " " + quote(dir / "cube.glb") + " --draco").status, 0);
  const geometry::Mesh mesh = geometry::readMesh(dir / "cube.glb");
  EXPECT_EQ(mesh.triangleCount(), 12u);
  ASSERT_EQ(mesh.materials.size(), 1u);
  EXPECT_TRUE(mesh.materials[0].baseColorTexture);
  ASSERT_EQ(runCli("convert -q " + quote(dir / "cube.glb") + " " + quote(dir / "cube.obj")).status, 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "cube.mtl"));
  EXPECT_EQ(runCli("convert -q " + quote(dir / "cube.glb") + " " + quote(dir / "cube.ply") + " --draco").status, 1);  // a usage error
  EXPECT_EQ(runCli("convert -q " + quote(dir / "cube.glb") + " " + quote(dir / "cube.fbx")).status, 2);
  EXPECT_FALSE(std::filesystem::exists(dir / "cube.ply"));
}

TEST(CliMesh, RenderWritesViewsAndTurntables) {
  TempDir dir("texfab-cli-render");
  ASSERT_EQ(runCli("render -q " + quote(kMeshes / "marble_cube.glb") + " -o " + quote(dir / "view.png") +
                   " --size 64x48 --spp 4 --background transparent")
                .status,
            0);
  const Image view = readImage(dir / "view.png");
  EXPECT_EQ(view.width, 64);
  EXPECT_EQ(view.height, 48);
  ASSERT_EQ(view.channels, 4);
  EXPECT_EQ(view.at(0, 0, 3), 0.0f);     // corner: background
  EXPECT_EQ(view.at(32, 24, 3), 1.0f);   // centre: the cube
  // glTF's microfacet BRDF for the key light's highlight: another picture of the same view.
  ASSERT_EQ(runCli("render -q " + quote(kMeshes / "marble_cube.glb") + " -o " + quote(dir / "microfacet.png") +
                   " --size 64x48 --spp 4 --background transparent --specular microfacet")
                .status,
            0);
  EXPECT_NE(readImage(dir / "microfacet.png").pixels, view.pixels);
  ASSERT_EQ(runCli("render -q " + quote(kMeshes / "knot1.off") + " -o " + quote(dir / "turn.png") +
                   " --size 32 --spp 1 --turntable 3 --background '#336699'")
                .status,
            0);
  for (const char* name : {"turn_000.png", "turn_001.png", "turn_002.png"}) EXPECT_TRUE(std::filesystem::exists(dir / name));
  EXPECT_FALSE(std::filesystem::exists(dir / "turn.png"));
  EXPECT_EQ(runCli("render -q " + quote(kMeshes / "knot1.off") + " -o " + quote(dir / "x.png") + " --background pink").status, 1);  // a bad flag value: usage
}
