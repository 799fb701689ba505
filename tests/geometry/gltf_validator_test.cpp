// SPDX-License-Identifier: GPL-3.0-or-later
// Every glTF/GLB texfab writes must pass the Khronos glTF validator with zero errors and zero
// warnings: binary and text (buffers and images beside the file, or embedded), Draco, textures
// as PNG, JPEG or WebP (EXT_texture_webp), and a texture's own MIP chain as KTX2
// (KHR_texture_basisu, which the validator does not support: validate_gltf.js says what it skips),
// and KHR_materials_anisotropy. The validator is the npm package gltf-validator, installed by scripts/install-deps.sh
// into .tools/ (or found through $TEXFAB_GLTF_VALIDATOR = a node_modules folder).
#include "geometry/io/mesh_io.h"
#include "tests/geometry/test_meshes.h"

using namespace texfab;
using namespace texfab::geometry;
using texfab::test::TempDir;

namespace {

Mesh normalMappedMesh() {
  Mesh m = texfab::test::texturedCube();
  m.materials[0].normalTexture.image = texfab::test::gradientImage(8, 8);
  m.materials[0].metallicRoughnessTexture.image = texfab::test::gradientImage(4, 4);
  // A MIP chain of its own: a KTX2 image (KHR_texture_basisu) beside the fallback.
  auto mips = std::make_shared<std::vector<Image>>();
  for (int side : {4, 2, 1}) mips->push_back(*texfab::test::gradientImage(side, side));
  m.materials[0].metallicRoughnessTexture.mips = std::move(mips);
  // KHR_materials_anisotropy, its texture with a chain of its own too.
  m.materials[0].anisotropy.strength = 0.8f;
  m.materials[0].anisotropy.rotation = 0.25f;
  m.materials[0].anisotropy.texture.image = texfab::test::gradientImage(8, 8);
  auto directions = std::make_shared<std::vector<Image>>();
  for (int side : {8, 4, 2, 1}) directions->push_back(*texfab::test::gradientImage(side, side));
  m.materials[0].anisotropy.texture.mips = std::move(directions);
  m.materials[0].baseColorTexture.rotation = 0.5f;
  m.materials[1].baseColorFactor.w() = 0.5f;
  m.materials[1].blend = true;
  m.materials[1].doubleSided = true;
  return m;
}

} // namespace

class GltfValidator : public ::testing::TestWithParam<std::string> {
protected:
  void SetUp() override {
    if (const std::string missing = texfab::test::gltfValidatorMissing(); !missing.empty()) GTEST_SKIP() << missing;
  }
};

TEST_P(GltfValidator, OutputHasNoErrorsOrWarnings) {
  TempDir dir("texfab-validator");
  const std::string name = GetParam();
  MeshWriteOptions options;
  options.draco = name.find("draco") != std::string::npos;
  options.embed = name.find("embed") != std::string::npos;
  if (name.find("jpeg") != std::string::npos) options.textures = TextureEncoding::Jpeg;
  if (name.find("webp") != std::string::npos) options.textures = TextureEncoding::Webp;
  std::vector<std::pair<std::string, Mesh>> meshes = {{"cube", texfab::test::texturedCube()},
                                                      {"normalmapped", normalMappedMesh()}};
  Mesh plain;  // no UVs, no normals, no materials
  plain.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  plain.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  meshes.emplace_back("plain", plain);
  const std::filesystem::path bundled = std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes/marble_cube.obj";
  meshes.emplace_back("bundled", readMesh(bundled));
  for (const auto& [label, mesh] : meshes) {
    const std::filesystem::path file = dir / (label + name.substr(name.find('.')));
    writeMesh(mesh, file, options);
    const std::string report = texfab::test::validateGltf(file);
    EXPECT_EQ(report.rfind("errors=0 warnings=0 ", 0), 0u) << label << " " << name << ":\n" << report;
    // The KTX2 image is there, and drew only the warnings of the validator's known gap.
    if (label == "normalmapped") {
      EXPECT_NE(report.find("known IMAGE_UNRECOGNIZED_FORMAT"), std::string::npos) << report;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, GltfValidator, ::testing::Values("model.glb", "model.gltf", "embed.gltf", "draco.glb", "draco.gltf",
                                                                   "jpeg.glb", "jpeg.gltf", "webp.glb", "webp.gltf"),
                         [](const auto& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '.', '_');
                           return n;
                         });
