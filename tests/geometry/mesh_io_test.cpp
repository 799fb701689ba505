// SPDX-License-Identifier: GPL-3.0-or-later
// Round trips through every mesh format, what each keeps, and the real clients that must load
// our outputs (assimp, draco_decoder).
#include "core/ktx2_write.h"
#include "geometry/io/mesh_io.h"
#include "geometry/mesh_connectivity.h"
#include "tests/geometry/test_meshes.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>

using namespace texfab;
using namespace texfab::geometry;
using texfab::test::TempDir;
using texfab::test::texturedCube;

namespace {

// Triangles keyed by their corner positions (rotation-invariant), mapped to their index; lets
// tests compare meshes whose triangles were reordered (glTF groups by material).
std::map<std::vector<float>, size_t> triangleIndex(const Mesh& m) {
  std::map<std::vector<float>, size_t> index;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    int first = 0;
    for (int k = 1; k < 3; ++k) {
      const auto a = m.corner(t, k), b = m.corner(t, first);
      if (std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3)) first = k;
    }
    std::vector<float> key;
    for (int k = 0; k < 3; ++k) {
      const auto p = m.corner(t, (first + k) % 3);
      key.insert(key.end(), p.data(), p.data() + 3);
    }
    index[key] = t;
  }
  return index;
}

// Corner k of triangle `t` of `a` matched to the corner with the same position in triangle u of b.
int matchingCorner(const Mesh& a, size_t t, int k, const Mesh& b, size_t u) {
  for (int j = 0; j < 3; ++j)
    if ((a.corner(t, k) - b.corner(u, j)).norm() < 1e-6f) return j;
  return -1;
}

void expectSameSurface(const Mesh& a, const Mesh& b, bool uvs, bool normals, float tolerance = 1e-6f) {
  ASSERT_EQ(a.triangleCount(), b.triangleCount());
  const auto ia = triangleIndex(a), ib = triangleIndex(b);
  ASSERT_EQ(ia.size(), a.triangleCount());
  for (const auto& [key, t] : ia) {
    const auto it = ib.find(key);
    ASSERT_NE(it, ib.end()) << "triangle " << t << " is missing after the round trip";
    const size_t u = it->second;
    for (int k = 0; k < 3; ++k) {
      const int j = matchingCorner(a, t, k, b, u);
      ASSERT_GE(j, 0);
      if (uvs) {
        EXPECT_LT((a.uvs[3 * t + size_t(k)] - b.uvs[3 * u + size_t(j)]).norm(), tolerance) << "UV of triangle " << t;
      }
      if (normals) {
        EXPECT_LT((a.normals[3 * t + size_t(k)] - b.normals[3 * u + size_t(j)]).norm(), 1e-5f) << "normal of triangle " << t;
      }
    }
  }
}

int run(const std::string& command) { return std::system((command + " >/dev/null 2>&1").c_str()); }
bool haveProgram(const std::string& name) { return run("command -v " + name) == 0; }

} // namespace

TEST(MeshIo, FormatFromExtension) {
  EXPECT_EQ(meshFormatOf("a/b.OBJ"), MeshFormat::Obj);
  EXPECT_EQ(meshFormatOf("x.glb"), MeshFormat::Glb);
  EXPECT_EQ(meshFormatOf("x.gltf"), MeshFormat::Gltf);
  EXPECT_THROW(meshFormatOf("x.fbx"), Error);
}

TEST(MeshIo, ObjRoundTripKeepsUvsNormalsMaterialsAndTextures) {
  TempDir dir("texfab-obj");
  const Mesh cube = texturedCube();
  writeMesh(cube, dir / "cube.obj");
  EXPECT_TRUE(std::filesystem::exists(dir / "cube.mtl"));
  const Mesh back = readMesh(dir / "cube.obj");
  EXPECT_EQ(back.vertexCount(), 8u);
  expectSameSurface(cube, back, true, true);
  ASSERT_EQ(back.materials.size(), 2u);
  EXPECT_EQ(back.materials[0].name, "textured");
  EXPECT_LT((back.materials[1].baseColorFactor - cube.materials[1].baseColorFactor).norm(), 1e-6f);
  EXPECT_NEAR(back.materials[1].metallicFactor, 0.25f, 1e-6f);
  EXPECT_NEAR(back.materials[1].roughnessFactor, 0.75f, 1e-6f);
  ASSERT_TRUE(back.materials[0].baseColorTexture);
  const Image& tex = *back.materials[0].baseColorTexture.image;
  EXPECT_EQ(tex.width, 16);
  EXPECT_EQ(tex.height, 8);
  EXPECT_NEAR(tex.at(5, 3, 1), cube.materials[0].baseColorTexture.image->at(5, 3, 1), 1.0f / 255);
  for (size_t t = 0; t < cube.triangleCount(); ++t) EXPECT_EQ(back.materialOf(t), cube.materialOf(t));
}

TEST(MeshIo, ObjReadsPolygonsNegativeIndicesAndMissingParts) {
  TempDir dir("texfab-obj2");
  std::ofstream(dir / "quad.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                     "f 1/1 2/2 3/3 4/4\nf -3 -2 -1\n";
  const Mesh m = readMesh(dir / "quad.obj");
  EXPECT_EQ(m.triangleCount(), 3u);
  EXPECT_TRUE(m.hasUvs());
  EXPECT_EQ(m.triangles[2], (std::array<uint32_t, 3>{2, 3, 4}));
  EXPECT_EQ(m.uvs[8], Eigen::Vector2f(0, 0));  // the face without vt gets (0, 0)
}

TEST(MeshIo, ConcavePolygonsAreTriangulatedInside) {
  // A concave pentagon whose fan from the first corner would flip a triangle. Same face in OBJ,
  // OFF and PLY: all triangles face +Z and their areas sum to the polygon's (2.5).
  TempDir dir("texfab-concave");
  const std::string v = "0 0 0\n2 0 0\n2 2 0\n1 0.5 0\n0 2 0\n";
  std::ofstream(dir / "p.obj") << "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 1 0.5 0\nv 0 2 0\nf 1 2 3 4 5\n";
  std::ofstream(dir / "p.off") << "OFF\n5 1 0\n" << v << "5 0 1 2 3 4\n";
  std::ofstream(dir / "p.ply") << "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                               << v << "5 0 1 2 3 4\n";
  for (const char* name : {"p.obj", "p.off", "p.ply"}) {
    const Mesh m = readMesh(dir / name);
    ASSERT_EQ(m.triangleCount(), 3u) << name;
    float area = 0;
    for (size_t t = 0; t < 3; ++t) {
      const Eigen::Vector3f n = (m.corner(t, 1) - m.corner(t, 0)).cross(m.corner(t, 2) - m.corner(t, 0));
      EXPECT_GT(n.z(), 0) << name << " triangle " << t << " is flipped";
      area += 0.5f * n.norm();
    }
    EXPECT_NEAR(area, 2.5f, 1e-5f) << name;
  }
}

TEST(MeshIo, PlyRoundTripBinaryAndAscii) {
  TempDir dir("texfab-ply");
  const Mesh cube = texturedCube();
  for (bool binary : {true, false}) {
    MeshWriteOptions options;
    options.binary = binary;
    writeMesh(cube, dir / "cube.ply", options);
    const Mesh back = readMesh(dir / "cube.ply");
    EXPECT_EQ(back.vertexCount(), 8u);
    expectSameSurface(cube, back, true, false);
    for (size_t t = 0; t < cube.triangleCount(); ++t) EXPECT_EQ(back.materialOf(t), cube.materialOf(t));
    EXPECT_TRUE(computeConnectivity(back).closed);
  }
}

TEST(MeshIo, OffAndStlRoundTripKeepGeometry) {
  TempDir dir("texfab-off");
  const Mesh cube = texturedCube();
  for (const char* name : {"cube.off", "cube.stl", "cube_ascii.stl"}) {
    MeshWriteOptions options;
    options.binary = std::string(name) != "cube_ascii.stl";
    writeMesh(cube, dir / name, options);
    const Mesh back = readMesh(dir / name);
    EXPECT_EQ(back.vertexCount(), 8u) << name;  // STL corners are welded back into shared vertices
    SCOPED_TRACE(name);
    expectSameSurface(cube, back, false, false);
    EXPECT_EQ(computeConnectivity(back).genus, 0) << name;
  }
}

TEST(MeshIo, GltfAndGlbRoundTripKeepEverything) {
  TempDir dir("texfab-gltf");
  Mesh cube = texturedCube();
  cube.materials[1].blend = true;
  cube.materials[1].baseColorFactor.w() = 0.5f;
  cube.materials[0].baseColorTexture.offset = {0.25f, 0.5f};
  cube.materials[0].baseColorTexture.scale = {2.0f, 2.0f};
  for (const char* name : {"cube.glb", "cube.gltf"}) {
    writeMesh(cube, dir / name);
    const Mesh back = readMesh(dir / name);
    EXPECT_EQ(back.vertexCount(), 8u) << name;  // split seam vertices are welded back
    expectSameSurface(cube, back, true, true);
    ASSERT_EQ(back.materials.size(), 2u);
    EXPECT_EQ(back.materials[1].name, "plain");
    EXPECT_LT((back.materials[1].baseColorFactor - cube.materials[1].baseColorFactor).norm(), 1e-6f);
    EXPECT_NEAR(back.materials[1].roughnessFactor, 0.75f, 1e-6f);
    EXPECT_TRUE(back.materials[1].blend);
    EXPECT_FALSE(back.materials[0].blend);
    ASSERT_TRUE(back.materials[0].baseColorTexture);
    EXPECT_EQ(back.materials[0].baseColorTexture.image->width, 16);
    EXPECT_EQ(back.materials[0].baseColorTexture.offset, Eigen::Vector2f(0.25f, 0.5f));
    EXPECT_EQ(back.materials[0].baseColorTexture.scale, Eigen::Vector2f(2.0f, 2.0f));
    const auto ia = triangleIndex(cube), ib = triangleIndex(back);
    for (const auto& [key, t] : ia) {
      EXPECT_EQ(back.materialOf(ib.at(key)), cube.materialOf(t));
      EXPECT_EQ(back.tagOf(ib.at(key)), cube.tagOf(t));
    }
    EXPECT_TRUE(computeConnectivity(back).closed);
  }
}

// A texture's own MIP chain (KHR_texture_basisu) is read back as the KTX2 bytes it was written as,
// beside the PNG fallback, and written again unchanged: converting a texfab glTF keeps it.
TEST(MeshIo, GltfKeepsATexturesOwnMipChain) {
  TempDir dir("texfab-ktx2");
  Mesh cube = texturedCube();
  auto mips = std::make_shared<std::vector<Image>>();
  for (int side : {16, 8, 4, 2, 1}) mips->push_back(*texfab::test::gradientImage(side, side));
  cube.materials[0].metallicRoughnessTexture.image = texfab::test::gradientImage(16, 16);
  cube.materials[0].metallicRoughnessTexture.mips = mips;
  for (const char* name : {"cube.glb", "cube.gltf"}) {
    writeMesh(cube, dir / name);
    const Mesh back = readMesh(dir / name);
    const Texture& mr = back.materials.at(0).metallicRoughnessTexture;
    ASSERT_TRUE(mr) << name;
    EXPECT_EQ(mr.image->width, 16);
    EXPECT_FALSE(mr.mips);
    ASSERT_TRUE(mr.encodedMips) << name;
    ASSERT_GT(mr.encodedMips->size(), 12u);
    EXPECT_EQ(0, std::memcmp(mr.encodedMips->data(), kKtx2Identifier.data(), 12));
    EXPECT_FALSE(back.materials.at(0).baseColorTexture.encodedMips);
    const std::string again = std::string("again_") + name;
    writeMesh(back, dir / again);
    EXPECT_EQ(*readMesh(dir / again).materials.at(0).metallicRoughnessTexture.encodedMips, *mr.encodedMips) << name;
  }
}

// KHR_materials_anisotropy is read back as written (strength, rotation, its texture and that
// texture's own chain), and a material without it has none.
TEST(MeshIo, GltfCarriesAnisotropy) {
  TempDir dir("texfab-anisotropy");
  Mesh cube = texturedCube();
  Material::Anisotropy& a = cube.materials[0].anisotropy;
  a.strength = 0.75f;
  a.rotation = -1.25f;
  a.texture.image = texfab::test::gradientImage(8, 8);
  auto mips = std::make_shared<std::vector<Image>>();
  for (int side : {8, 4, 2, 1}) mips->push_back(*texfab::test::gradientImage(side, side));
  a.texture.mips = mips;
  for (const char* name : {"cube.glb", "cube.gltf"}) {
    writeMesh(cube, dir / name);
    const Mesh back = readMesh(dir / name);
    const Material::Anisotropy& b = back.materials.at(0).anisotropy;
    EXPECT_EQ(b.strength, 0.75f) << name;
    EXPECT_EQ(b.rotation, -1.25f) << name;
    ASSERT_TRUE(b.texture) << name;
    ASSERT_EQ(b.texture.image->pixels.size(), a.texture.image->pixels.size()) << name;
    for (size_t i = 0; i < a.texture.image->pixels.size(); ++i)
      ASSERT_NEAR(b.texture.image->pixels[i], a.texture.image->pixels[i], 1e-6f) << name;  // 8-bit values
    ASSERT_TRUE(b.texture.encodedMips) << name;
    EXPECT_FALSE(back.materials.at(1).anisotropy) << name;
    EXPECT_TRUE(back.hasTangents()) << name;  // the extension's direction is in tangent space
  }
}

TEST(MeshIo, GltfNodeTransformsAreApplied) {
  TempDir dir("texfab-node");
  // One triangle in a base64 buffer, instanced by two nodes: one translated, one mirrored.
  const float data[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::string raw(reinterpret_cast<const char*>(data), sizeof data);
  static const char* chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (size_t i = 0; i < raw.size(); i += 3) {
    uint32_t n = uint8_t(raw[i]) << 16 | (i + 1 < raw.size() ? uint8_t(raw[i + 1]) << 8 : 0) | (i + 2 < raw.size() ? uint8_t(raw[i + 2]) : 0);
    b64 += chars[(n >> 18) & 63];
    b64 += chars[(n >> 12) & 63];
    b64 += i + 1 < raw.size() ? chars[(n >> 6) & 63] : '=';
    b64 += i + 2 < raw.size() ? chars[n & 63] : '=';
  }
  std::ofstream(dir / "nodes.gltf")
      << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1]}],
  "nodes":[{"mesh":0,"translation":[10,0,0]},{"mesh":0,"scale":[-1,1,1]}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
  "bufferViews":[{"buffer":0,"byteLength":36}],
  "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,)"
      << b64 << R"("}]})";
  const Mesh m = readMesh(dir / "nodes.gltf");
  ASSERT_EQ(m.triangleCount(), 2u);
  EXPECT_EQ(m.corner(0, 1), Eigen::Vector3f(11, 0, 0));
  // Both instances keep facing +Z: the mirrored one had its winding flipped.
  EXPECT_GT(faceNormal(m, 0).z(), 0.99f);
  EXPECT_GT(faceNormal(m, 1).z(), 0.99f);
  EXPECT_EQ(m.corner(1, 0), Eigen::Vector3f(0, 0, 0));
}

TEST(MeshIo, DracoRoundTripWithinQuantization) {
  TempDir dir("texfab-draco");
  const Mesh cube = texturedCube();
  MeshWriteOptions options;
  options.draco = true;
  writeMesh(cube, dir / "cube.glb", options);
  const Mesh back = readMesh(dir / "cube.glb");
  ASSERT_EQ(back.triangleCount(), cube.triangleCount());
  // Positions on 14 bits over a 2-unit box: within 2 / 2^14 per coordinate; the cube's corners
  // are exact on the quantization grid.
  EXPECT_EQ(back.vertexCount(), 8u);
  expectSameSurface(cube, back, true, false, 2.0f / 4096);
  EXPECT_THROW(writeMesh(cube, dir / "cube.obj", options), Error);
}

TEST(MeshIo, OutputsLoadInAssimp) {
  if (!haveProgram("assimp")) GTEST_SKIP() << "assimp (assimp-utils) not installed";
  TempDir dir("texfab-assimp");
  const Mesh cube = texturedCube();
  for (const char* name : {"cube.glb", "cube.gltf", "cube.obj", "cube.ply", "cube.stl", "cube.off", "cube.3mf"}) {
    writeMesh(cube, dir / name);
    EXPECT_EQ(run("assimp info '" + (dir / name).string() + "'"), 0) << name;
  }
  // Every texture encoding and glTF layout: embedded .gltf, JPEG, WebP (EXT_texture_webp), Draco.
  const std::vector<std::pair<std::string, MeshWriteOptions>> variants = {
      {"embedded.gltf", MeshWriteOptions{.embed = true}},
      {"jpeg.glb", MeshWriteOptions{.textures = TextureEncoding::Jpeg}},
      {"jpeg.obj", MeshWriteOptions{.textures = TextureEncoding::Jpeg}},
      {"webp.glb", MeshWriteOptions{.textures = TextureEncoding::Webp}},
      {"webp.gltf", MeshWriteOptions{.textures = TextureEncoding::Webp}},
  };
  for (const auto& [name, options] : variants) {
    writeMesh(cube, dir / name, options);
    EXPECT_EQ(run("assimp info '" + (dir / name).string() + "'"), 0) << name;
  }
}

TEST(MeshIo, DracoOutputDecodesWithDracoDecoder) {
  if (!haveProgram("draco_decoder")) GTEST_SKIP() << "draco_decoder (Debian package draco) not installed";
  TempDir dir("texfab-dracotool");
  Mesh cube = texturedCube();
  cube.materials.resize(1);
  cube.materials[0].baseColorTexture = {};  // so the Draco stream is the first buffer view
  cube.faceMaterials.clear();
  cube.faceTags.clear();
  MeshWriteOptions options;
  options.draco = true;
  writeMesh(cube, dir / "cube.glb", options);
  // The single primitive's Draco stream is the first buffer view: cut it out and decode it.
  std::ifstream in(dir / "cube.glb", std::ios::binary);
  const std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto [json, bin] = texfab::test::glbChunks(glb);
  const size_t view = json.find("\"bufferViews\"");
  ASSERT_NE(view, std::string::npos);
  const size_t lengthAt = json.find("\"byteLength\":", view);
  const size_t offsetAt = json.find("\"byteOffset\":", view);
  const size_t length = std::stoul(json.substr(lengthAt + 13)), offset = std::stoul(json.substr(offsetAt + 13));
  std::ofstream(dir / "cube.drc", std::ios::binary) << bin.substr(offset, length);
  ASSERT_EQ(run("draco_decoder -i '" + (dir / "cube.drc").string() + "' -o '" + (dir / "decoded.obj").string() + "'"), 0);
  const Mesh decoded = readMesh(dir / "decoded.obj");
  EXPECT_EQ(decoded.triangleCount(), 12u);
}
