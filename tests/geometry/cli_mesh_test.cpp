// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end: texfab info / convert / render on the bundled models.
#include "geometry/mesh_io.h"
#include "render/image/image_io.h"
#include "tests/geometry/test_meshes.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>

using namespace texfab;
using texfab::testing::TempDir;

namespace {

const std::filesystem::path kMeshes = std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes";

// Runs the CLI; returns (exit status, stdout).
std::pair<int, std::string> runCli(const std::string& args) {
  const std::string command = std::string(TEXFAB_CLI) + " " + args + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  std::array<char, 4096> buffer{};
  while (pipe && fgets(buffer.data(), int(buffer.size()), pipe)) out += buffer.data();
  const int status = pipe ? pclose(pipe) : -1;
  return {WEXITSTATUS(status), out};
}

std::string quote(const std::filesystem::path& p) {
  std::string out = p.string();
  out.insert(out.begin(), '\'');
  out.push_back('\'');
  return out;
}

} // namespace

TEST(CliMesh, InfoJsonDescribesTheBundledModels) {
  auto [status, out] = runCli("info --json " + quote(kMeshes / "marble_cube.glb"));
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
  std::tie(status, out) = runCli("info --json " + quote(kMeshes / "knot1.off"));
  ASSERT_EQ(status, 0);
  EXPECT_EQ(nlohmann::json::parse(out)["genus"], 1);
  EXPECT_EQ(nlohmann::json::parse(out)["uvs"], false);
}

TEST(CliMesh, ConvertKeepsMaterialsAndRefusesBadRequests) {
  TempDir dir("texfab-cli-convert");
  ASSERT_EQ(runCli("convert -q " + quote(kMeshes / "marble_cube.obj") + " " + quote(dir / "cube.glb") + " --draco").first, 0);
  const geometry::Mesh mesh = geometry::readMesh(dir / "cube.glb");
  EXPECT_EQ(mesh.triangleCount(), 12u);
  ASSERT_EQ(mesh.materials.size(), 1u);
  EXPECT_TRUE(mesh.materials[0].baseColorTexture);
  ASSERT_EQ(runCli("convert -q " + quote(dir / "cube.glb") + " " + quote(dir / "cube.obj")).first, 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "cube.mtl"));
  EXPECT_EQ(runCli("convert -q " + quote(dir / "cube.glb") + " " + quote(dir / "cube.ply") + " --draco").first, 1);  // a usage error
  EXPECT_EQ(runCli("convert -q " + quote(dir / "cube.glb") + " " + quote(dir / "cube.fbx")).first, 2);
  EXPECT_FALSE(std::filesystem::exists(dir / "cube.ply"));
}

TEST(CliMesh, RenderWritesViewsAndTurntables) {
  TempDir dir("texfab-cli-render");
  ASSERT_EQ(runCli("render -q " + quote(kMeshes / "marble_cube.glb") + " -o " + quote(dir / "view.png") +
                   " --size 64x48 --spp 4 --background transparent")
                .first,
            0);
  const Image view = readImage(dir / "view.png");
  EXPECT_EQ(view.width, 64);
  EXPECT_EQ(view.height, 48);
  ASSERT_EQ(view.channels, 4);
  EXPECT_EQ(view.at(0, 0, 3), 0.0f);     // corner: background
  EXPECT_EQ(view.at(32, 24, 3), 1.0f);   // centre: the cube
  ASSERT_EQ(runCli("render -q " + quote(kMeshes / "knot1.off") + " -o " + quote(dir / "turn.png") +
                   " --size 32 --spp 1 --turntable 3 --background '#336699'")
                .first,
            0);
  for (const char* name : {"turn_000.png", "turn_001.png", "turn_002.png"}) EXPECT_TRUE(std::filesystem::exists(dir / name));
  EXPECT_FALSE(std::filesystem::exists(dir / "turn.png"));
  EXPECT_EQ(runCli("render -q " + quote(kMeshes / "knot1.off") + " -o " + quote(dir / "x.png") + " --background pink").first, 1);  // a bad flag value: usage
}
