// SPDX-License-Identifier: GPL-3.0-or-later
// Files that open everywhere: OBJ with shared texture coordinates and normals and the normal map
// where Blender looks for it, OBJ readers' tolerance of missing material files, a dielectric
// default material, texture encodings (PNG, JPEG, WebP; input bytes kept as they are), and .gltf
// with its buffer and images beside it.
#include "geometry/io/mesh_io.h"
#include "tests/geometry/test_meshes.h"

#include <nlohmann/json.hpp>

#include <array>
#include <fstream>
#include <set>
#include <sstream>

using namespace texfab;
using namespace texfab::geometry;
using texfab::test::TempDir;

namespace {

// A smooth n x n grid: one UV and one normal per vertex, so an OBJ needs n^2 vt and vn.
Mesh smoothGrid(int n) {
  Mesh m;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) m.positions.emplace_back(float(x), float(y), 0.1f * float((x * y) % 3));
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x) {
      const uint32_t a = uint32_t(y * n + x), b = a + 1, c = a + uint32_t(n), d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  for (const auto& t : m.triangles)
    for (uint32_t v : t) m.uvs.emplace_back(m.positions[v].x() / float(n - 1), m.positions[v].y() / float(n - 1));
  computeSmoothNormals(m, 180.0f);
  Material mat;
  mat.name = "grid";
  mat.metallicFactor = 0;
  mat.baseColorTexture.image = texfab::test::gradientImage(16, 16);
  mat.normalTexture.image = texfab::test::gradientImage(8, 8);
  m.materials = {mat};
  return m;
}

size_t linesStartingWith(const std::string& text, const std::string& prefix) {
  size_t n = 0;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) n += line.rfind(prefix, 0) == 0;
  return n;
}

// Collects the warnings a reader reports.
struct Warnings {
  std::vector<std::string> messages;
  Context context() {
    return Context{.progress = [this](const ProgressEvent& e) {
      if (e.kind == ProgressEvent::Kind::Warning) messages.emplace_back(e.detail);
    }};
  }
};

nlohmann::json gltfJson(const std::filesystem::path& file) { return nlohmann::json::parse(test::readFile(file)); }

} // namespace

TEST(ModelFiles, ObjSharesTexcoordsAndNormalsAndNamesTheNormalMapForBlender) {
  TempDir dir("texfab-objshare");
  const Mesh grid = smoothGrid(10);  // 100 vertices, 162 triangles, 486 corners
  writeMesh(grid, dir / "grid.obj");
  const std::string obj = test::readFile(dir / "grid.obj");
  EXPECT_EQ(linesStartingWith(obj, "v "), 100u);
  EXPECT_EQ(linesStartingWith(obj, "vt "), 100u);  // not one per corner (486)
  // One vn per distinct normal (the grid's flat parts share theirs), not one per corner.
  std::set<std::array<float, 3>> normals;
  for (const auto& n : grid.normals) normals.insert({n.x(), n.y(), n.z()});
  ASSERT_GT(normals.size(), 1u);
  EXPECT_EQ(linesStartingWith(obj, "vn "), normals.size());
  EXPECT_NE(obj.find("f 1/1/1 "), std::string::npos);
  const std::string mtl = test::readFile(dir / "grid.mtl");
  for (const char* key : {"map_Kd ", "map_Bump ", "bump ", "norm "}) EXPECT_NE(mtl.find(key), std::string::npos) << key;
  const Mesh back = readMesh(dir / "grid.obj");
  ASSERT_EQ(back.materials.size(), 1u);
  EXPECT_TRUE(back.materials[0].normalTexture);
  EXPECT_EQ(back.uvs, grid.uvs);

  // A mesh without normals gets them: every OBJ reader then shades it smoothly.
  Mesh bare = grid;
  bare.normals.clear();
  writeMesh(bare, dir / "bare.obj");
  EXPECT_GT(linesStartingWith(test::readFile(dir / "bare.obj"), "vn "), 0u);
}

TEST(ModelFiles, ObjWithAMissingMaterialLibraryOrTextureLoadsItsGeometry) {
  TempDir dir("texfab-objmissing");
  const std::string geometry = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl stone\nf 1/1 2/2 3/3\n";
  std::ofstream(dir / "nomtl.obj") << "mtllib none.mtl\n" << geometry;
  std::ofstream(dir / "notex.obj") << "mtllib notex.mtl\n" << geometry;
  std::ofstream(dir / "notex.mtl") << "newmtl stone\nKd 0.5 0.5 0.5\nmap_Kd missing.png\n";
  for (const char* name : {"nomtl.obj", "notex.obj"}) {
    Warnings warnings;
    const Mesh m = readMesh(dir / name, warnings.context());
    EXPECT_EQ(m.triangleCount(), 1u) << name;
    EXPECT_TRUE(m.hasUvs()) << name;
    ASSERT_EQ(m.materials.size(), 1u) << name;
    EXPECT_FALSE(m.materials[0].baseColorTexture) << name;
    ASSERT_EQ(warnings.messages.size(), 1u) << name;
    EXPECT_NE(warnings.messages[0].find(std::string(name) == "nomtl.obj" ? "none.mtl" : "missing.png"), std::string::npos)
        << warnings.messages[0];
  }
}

TEST(ModelFiles, UntexturedMeshesBecomeDielectricGltf) {
  TempDir dir("texfab-dielectric");
  Mesh tetra;
  tetra.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const char* name : {"t.stl", "t.ply", "t.off"}) {
    writeMesh(tetra, dir / name);
    const Mesh read = readMesh(dir / name);
    writeMesh(read, dir / "t.glb");
    const Mesh glb = readMesh(dir / "t.glb");
    ASSERT_EQ(glb.materials.size(), 1u) << name;
    EXPECT_EQ(glb.materials[0].metallicFactor, 0.0f) << name;  // glTF's default would be 1 (metal)
  }
}

TEST(ModelFiles, TexturesAsPngJpegOrWebp) {
  TempDir dir("texfab-encodings");
  const Mesh grid = smoothGrid(6);
  const std::vector<std::pair<TextureEncoding, std::string>> encodings = {
      {TextureEncoding::Png, "image/png"}, {TextureEncoding::Jpeg, "image/jpeg"}, {TextureEncoding::Webp, "image/webp"}};
  for (const auto& [encoding, mime] : encodings) {
    MeshWriteOptions options;
    options.textures = encoding;
    writeMesh(grid, dir / "g.glb", options);
    const Mesh back = readMesh(dir / "g.glb");
    ASSERT_TRUE(back.materials.at(0).baseColorTexture) << mime;
    ASSERT_TRUE(back.materials[0].baseColorTexture.encoded) << mime;
    EXPECT_EQ(mimeTypeOf(back.materials[0].baseColorTexture.encoded->codec), mime);
    // Lossy, but close: the gradient's pixels within a few levels.
    const Image& a = *grid.materials[0].baseColorTexture.image;
    const Image& b = *back.materials[0].baseColorTexture.image;
    ASSERT_EQ(b.width, a.width);
    EXPECT_NEAR(b.at(3, 3, 0), a.at(3, 3, 0), encoding == TextureEncoding::Png ? 1.0f / 255 : 0.25f) << mime;
    // OBJ: the image file has the format's extension.
    writeMesh(grid, dir / "g.obj", options);
    EXPECT_NE(test::readFile(dir / "g.mtl").find(std::string("g_grid_basecolor") + extensionOf(back.materials[0].baseColorTexture.encoded->codec)),
              std::string::npos);
  }
}

TEST(ModelFiles, ImagesReadFromFilesKeepTheirBytes) {
  TempDir dir("texfab-keep");
  MeshWriteOptions jpeg;
  jpeg.textures = TextureEncoding::Jpeg;
  writeMesh(smoothGrid(6), dir / "in.glb", jpeg);
  const Mesh in = readMesh(dir / "in.glb");
  ASSERT_TRUE(in.materials.at(0).baseColorTexture.encoded);
  for (const char* name : {"out.glb", "out.gltf", "out.obj"}) {
    writeMesh(in, dir / name);  // TextureEncoding::Keep
    const Mesh out = readMesh(dir / name);
    ASSERT_TRUE(out.materials.at(0).baseColorTexture.encoded) << name;
    EXPECT_EQ(out.materials[0].baseColorTexture.encoded->bytes, in.materials[0].baseColorTexture.encoded->bytes) << name;
    EXPECT_EQ(out.materials[0].normalTexture.encoded->bytes, in.materials[0].normalTexture.encoded->bytes) << name;
  }
}

TEST(ModelFiles, GltfWritesItsBufferAndImagesBesideIt) {
  TempDir dir("texfab-gltfside");
  const Mesh grid = smoothGrid(6);
  writeMesh(grid, dir / "model.gltf");
  const nlohmann::json doc = gltfJson(dir / "model.gltf");
  EXPECT_EQ(doc["buffers"][0]["uri"], "model.bin");
  EXPECT_TRUE(std::filesystem::exists(dir / "model.bin"));
  ASSERT_EQ(doc["images"].size(), 2u);
  for (const auto& image : doc["images"]) {
    const std::string uri = image["uri"];
    EXPECT_EQ(uri.rfind("data:", 0), std::string::npos) << uri;
    EXPECT_TRUE(std::filesystem::exists(dir / uri)) << uri;
  }
  EXPECT_EQ(readMesh(dir / "model.gltf").triangleCount(), grid.triangleCount());

  MeshWriteOptions embed;
  embed.embed = true;
  writeMesh(grid, dir / "embedded.gltf", embed);
  const nlohmann::json embedded = gltfJson(dir / "embedded.gltf");
  EXPECT_EQ(embedded["buffers"][0]["uri"].get<std::string>().rfind("data:", 0), 0u);
  EXPECT_FALSE(std::filesystem::exists(dir / "embedded.bin"));
  // Beside the file, the model is smaller than embedded (base64 adds a third).
  const auto sideBytes = std::filesystem::file_size(dir / "model.gltf") + std::filesystem::file_size(dir / "model.bin") +
                         std::filesystem::file_size(dir / "model_0.png") + std::filesystem::file_size(dir / "model_1.png");
  EXPECT_LT(sideBytes, std::filesystem::file_size(dir / "embedded.gltf"));
}
