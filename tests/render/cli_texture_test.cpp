// SPDX-License-Identifier: GPL-3.0-or-later
// texfab texture end to end on the bundled model: both modes, companion maps, files a real glTF
// validator accepts, the report's measures; bad input fails with one line and leaves no output.
#include "core/crop.h"
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace {
namespace fs = std::filesystem;
using texfab::test::TempDir;

const fs::path kSource(TEXFAB_SOURCE_DIR);
const fs::path kModel = kSource / "models" / "meshes" / "elephant.off";
const fs::path kExemplar = kSource / "models" / "exemplars" / "brick.png";

// A command line built word by word; paths are quoted for the shell. (Appending, not
// "'" + std::string: GCC 12 warns falsely on that.)
struct Args {
  std::string text;
  Args& operator<<(const char* word) {
    if (!text.empty()) text += ' ';
    text += word;
    return *this;
  }
  Args& operator<<(const std::string& word) { return *this << word.c_str(); }
  Args& operator<<(const fs::path& path) {
    if (!text.empty()) text += ' ';
    text += '\'';
    text += path.string();
    text += '\'';
    return *this;
  }
};

texfab::test::CliResult texture(const Args& args) { return texfab::test::runCli("texture " + args.text); }

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

nlohmann::json readJson(const fs::path& p) { return nlohmann::json::parse(readText(p)); }

void expectValidGltf(const fs::path& file) {
  if (const std::string missing = texfab::test::gltfValidatorMissing(); !missing.empty()) {
    std::cout << "glTF validator skipped: " << missing << "\n";
    return;
  }
  const std::string report = texfab::test::validateGltf(file);
  EXPECT_EQ(report.rfind("errors=0 warnings=0 ", 0), 0u) << file << ":\n" << report;
}

// The bytes of the KTX2 image that a GLB's texture names as its KHR_texture_basisu source, or
// empty when no texture names one.
std::string basisuImageOf(const fs::path& glb) {
  const auto [json, bin] = texfab::test::glbChunks(readText(glb));
  const nlohmann::json doc = nlohmann::json::parse(json);
  for (const nlohmann::json& t : doc.value("textures", nlohmann::json::array()))
    if (const auto ext = t.value("extensions", nlohmann::json::object()); ext.contains("KHR_texture_basisu")) {
      const nlohmann::json& image = doc["images"][ext["KHR_texture_basisu"]["source"].get<size_t>()];
      EXPECT_EQ(image["mimeType"], "image/ktx2");
      const nlohmann::json& view = doc["bufferViews"][image["bufferView"].get<size_t>()];
      return bin.substr(view.value("byteOffset", size_t(0)), view["byteLength"].get<size_t>());
    }
  return {};
}

} // namespace

TEST(CliTexture, SurfaceModeOnTheBundledModel) {
  TempDir d("texfab-texture-cli");
  const auto common = [&] {
    Args a;
    a << kModel << "-e" << kExemplar << "--resolution 512 --cache-dir" << d / "cache" << "-q";
    return a;
  };
  ASSERT_EQ(0, texture(common() << "-o" << d / "out.glb" << "--preview" << d / "view.png" << "--preview-size 200"
                                << "--report" << d / "r.json").status);
  const texfab::geometry::Mesh out = texfab::geometry::readMesh(d / "out.glb");
  ASSERT_TRUE(out.hasUvs());
  ASSERT_EQ(out.materials.size(), 1u);
  ASSERT_TRUE(out.materials[0].baseColorTexture);
  EXPECT_EQ(out.materials[0].baseColorTexture.image->width, 512);
  EXPECT_EQ(texfab::readImage(d / "view.png").width, 200);
  expectValidGltf(d / "out.glb");

  const nlohmann::json r = readJson(d / "r.json");
  EXPECT_LE(r["measures"]["seams"]["ratio"].get<double>(), 1.3);
  EXPECT_GE(r["measures"]["scale"]["fraction_within_tolerance"].get<double>(), 0.9);
  EXPECT_GT(r["measures"]["fidelity"]["exemplar_space"].get<double>(), 0.0);
  for (const char* stage : {"load", "analysis", "atlas", "fields", "synthesis", "resolve", "write", "preview"})
    EXPECT_TRUE(r["timings"].contains(stage)) << stage;

  // Same seed, same file: the whole job is deterministic (also on one thread).
  ASSERT_EQ(0, texture(common() << "-o" << d / "again.glb" << "--threads 1").status);
  EXPECT_EQ(readText(d / "out.glb"), readText(d / "again.glb"));
}

TEST(CliTexture, SolidModeAndCompanionMapsOnTheBundledModel) {
  TempDir d("texfab-texture-cli");
  // Solid mode, a small exemplar (the solid precomputation grows with its size).
  const texfab::Image small = texfab::crop(texfab::readImage(kExemplar), 0, 0, 32, 32);
  texfab::writeImage(small, d / "small.png");
  // At the 256² atlas's density (the default, a 2048² atlas's, would sample one voxel in eight).
  ASSERT_EQ(0, texture(Args() << kModel << "-e" << d / "small.png"
                              << "--mode solid --resolution 256 --texture-scale 192 -q --cache-dir"
                              << d / "cache" << "-o" << d / "solid.glb" << "--report" << d / "solid.json").status);
  expectValidGltf(d / "solid.glb");
  const nlohmann::json r = readJson(d / "solid.json");
  EXPECT_LE(r["measures"]["seams"]["ratio"].get<double>(), 1.1);
  EXPECT_GT(r["solid"]["voxels_requested"].get<int64_t>(), 1000);

  // Surface mode with normal, roughness and height maps, written as OBJ and as Draco GLB.
  texfab::Image normal(small.width, small.height, 3), rough(small.width, small.height, 1);
  for (int y = 0; y < small.height; ++y)
    for (int x = 0; x < small.width; ++x) {
      normal.at(x, y, 0) = 0.5f + 0.3f * float(x % 4) / 4.0f;
      normal.at(x, y, 1) = 0.5f;
      normal.at(x, y, 2) = 0.9f;
      rough.at(x, y, 0) = small.at(x, y, 0);
    }
  texfab::writeImage(normal, d / "n.png");
  texfab::writeImage(rough, d / "r.png");
  const std::string maps = "normal=" + (d / "n.png").string() + ",roughness=" + (d / "r.png").string() +
                           ",height=" + (d / "r.png").string();
  const auto withMapsTo = [&](const fs::path& out) {
    Args a;
    a << kModel << "-e" << d / "small.png" << "--resolution 256 -q --maps" << fs::path(maps) << "-o" << out;
    return a;
  };
  ASSERT_EQ(0, texture(withMapsTo(d / "maps.glb") << "--draco").status);
  expectValidGltf(d / "maps.glb");
  EXPECT_TRUE(fs::exists(d / "maps_height.png"));
  const texfab::geometry::Mesh withMaps = texfab::geometry::readMesh(d / "maps.glb");
  EXPECT_TRUE(withMaps.materials.at(0).normalTexture);
  EXPECT_TRUE(withMaps.materials.at(0).metallicRoughnessTexture);
  // The normal map's spread widens roughness in a MIP chain of its own (KTX2, KHR_texture_basisu),
  // which three.js's transcoder reads level by level down to 1x1; --no-ndf-filtering leaves it out.
  const std::string ktx2 = basisuImageOf(d / "maps.glb");
  ASSERT_FALSE(ktx2.empty());
  std::ofstream(d / "mr.ktx2", std::ios::binary) << ktx2;
  if (const std::string missing = texfab::test::threeMissing(); missing.empty()) {
    const std::string report = texfab::test::transcode(d / "mr.ktx2", d / "mr");
    EXPECT_NE(report.find(R"("ok":true,"uastc":true,"hasAlpha":false,"width":256,"height":256)"), std::string::npos) << report;
    EXPECT_NE(report.find(R"({"width":1,"height":1,"bytes":4}]})"), std::string::npos) << report;
  }
  const texfab::test::CliResult info = texfab::test::runCli("info --json " + texfab::test::quote(d / "maps.glb"));
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["materials"][0]["metallic_roughness_texture"]["mip_chain"]["bytes"].get<size_t>(),
            ktx2.size());
  // This map's normals tilt along x only: the lobe widens one way (KHR_materials_anisotropy, its
  // texture with a chain of its own); --no-anisotropy writes one isotropic lobe per texel.
  EXPECT_TRUE(withMaps.materials.at(0).anisotropy);
  EXPECT_TRUE(withMaps.materials.at(0).anisotropy.texture.encodedMips);
  ASSERT_EQ(0, texture(withMapsTo(d / "isotropic.glb") << "--no-anisotropy").status);
  expectValidGltf(d / "isotropic.glb");
  EXPECT_FALSE(texfab::geometry::readMesh(d / "isotropic.glb").materials.at(0).anisotropy);
  ASSERT_EQ(0, texture(withMapsTo(d / "plain.glb") << "--no-ndf-filtering").status);
  EXPECT_TRUE(basisuImageOf(d / "plain.glb").empty());
  ASSERT_EQ(0, texture(withMapsTo(d / "maps.obj")).status);
  EXPECT_TRUE(fs::exists(d / "maps.mtl"));
}

// A scale that puts several exemplar pixels in every texel synthesizes from a smaller copy of the
// exemplar (and says so); the report keeps the exemplar as given, the scale asked for, and the
// wrap measured on the exemplar as given (a photograph: clamp).
TEST(CliTexture, MinifyingScaleAnalysesASmallerExemplar) {
  TempDir d("texfab-texture-cli");
  const fs::path photo = kSource / "models" / "exemplars" / "photos" / "rock.png";
  const texfab::test::CliResult r =
      texture(Args() << kModel << "-e" << photo << "--resolution 256 --scale 1600 --no-cache -o" << d / "out.glb"
                     << "--report" << d / "r.json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("a copy 4 times smaller (32x32)"), std::string::npos) << r.err;
  const nlohmann::json report = readJson(d / "r.json");
  EXPECT_EQ(report["exemplar"]["downsampled"], 4);
  EXPECT_EQ(report["exemplar"]["width"], 128);
  EXPECT_EQ(report["parameters"]["texture_scale"], 1600.0);
  EXPECT_EQ(report["parameters"]["exemplar_wrap"], "clamp");
  EXPECT_GE(report["parameters"]["exemplar_pixels_per_texel"].get<double>(), 4.0);
  expectValidGltf(d / "out.glb");
}

TEST(CliTexture, BadInputFailsWithOneLineAndNoOutput) {
  TempDir d("texfab-texture-cli");
  std::ofstream(d / "points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  std::ofstream(d / "notimage.png") << "not an image";
  // Model, exemplar and a valid output, then what is wrong.
  const auto base = [&](const fs::path& model, const fs::path& exemplar) {
    Args a;
    a << model << "-e" << exemplar << "-o" << d / "out.glb" << "--resolution 256 -q --cache-dir" << d / "cache";
    return a;
  };
  const std::vector<std::pair<std::string, Args>> cases = {
      {"no triangles", base(d / "points.obj", kExemplar)},
      {"missing model", base(d / "missing.obj", kExemplar)},
      {"missing exemplar", base(kModel, d / "missing.png")},
      {"corrupt exemplar", base(kModel, d / "notimage.png")},
      {"unknown mode", base(kModel, kExemplar) << "--mode cloud"},
      {"scale and feature size", base(kModel, kExemplar) << "--scale 10 --feature-size 1"},
      {"scale too large", base(kModel, kExemplar) << "--scale 1e9"},
      {"normal map in solid mode", base(kModel, kExemplar) << "--mode solid --maps" << fs::path("normal=" + kExemplar.string())},
      {"bad output format", Args() << kModel << "-e" << kExemplar << "-o" << d / "out.xyz" << "-q"},
      {"unknown flag", base(kModel, kExemplar) << "--frobnicate"},
      {"bad direction", base(kModel, kExemplar) << "--direction 0,0,0"},
      {"gutter too small", base(kModel, kExemplar) << "--gutter 1"},
      {"atlas larger than memory", base(kModel, kExemplar) << "--resolution 16384 --mode solid"},  // ~118 GB
  };
  for (const auto& [name, args] : cases) {
    const texfab::test::CliResult r = texture(args);
    EXPECT_NE(0, r.status) << name;
    const std::string& text = r.err;
    EXPECT_FALSE(text.empty()) << name;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << name << ": " << text;
    EXPECT_EQ(text.rfind("texfab", 0), 0u) << name << ": " << text;  // texfab's message, not the shell's
    EXPECT_FALSE(fs::exists(d / "out.glb")) << name;
  }
}

TEST(CliTexture, TexturesABrokenMeshAndSaysWhatWasRepaired) {
  TempDir d("texfab-texture-cli");
  // A non-manifold edge (three triangles), inconsistent orientation, a zero-area and a duplicated
  // triangle, an isolated vertex.
  std::ofstream(d / "broken.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 2 2 2\nv 0.5 0 0\n"
                                     "f 1 2 3\nf 2 1 4\nf 1 2 5\nf 1 7 2\nf 1 2 3\n";
  const texfab::test::CliResult r = texture(Args() << d / "broken.obj" << "-e" << kExemplar << "--resolution 256 -o"
                                                  << d / "out.glb" << "--cache-dir" << d / "cache");
  ASSERT_EQ(0, r.status) << r.err;
  const std::string& text = r.err;
  EXPECT_NE(text.find("non-manifold"), std::string::npos) << text;
  EXPECT_NE(text.find("degenerate"), std::string::npos) << text;
  expectValidGltf(d / "out.glb");
}

// texture --graph: the elephant textured from the rock -> stone graph (the root spanning the
// model by default) is a valid GLB, deterministic, and its report names the graph; flags the graph
// does not take are one line and no output.
TEST(CliTexture, ExemplarGraphOverTheSurface) {
  TempDir d("texfab-texture-cli");
  const fs::path photos = kSource / "models" / "exemplars" / "photos";
  std::ofstream(d / "g.json") << R"({"exemplars": [{"name": "rock", "image": ")" << (photos / "rock.png").string()
                              << R"("}, {"name": "stone", "image": ")" << (photos / "stone.png").string()
                              << R"("}], "edges": [{"from": "rock", "to": "stone", "scale": 16}]})";
  const auto common = [&] {
    Args a;
    a << kModel << "--graph" << d / "g.json" << "--resolution 512 -q --cache-dir" << d / "cache";
    return a;
  };
  ASSERT_EQ(0, texture(common() << "-o" << d / "out.glb" << "--report" << d / "r.json").status);
  expectValidGltf(d / "out.glb");
  const nlohmann::json r = readJson(d / "r.json");
  EXPECT_EQ(r["graph"]["exemplars"], nlohmann::json({"rock", "stone"}));
  EXPECT_EQ(r["graph"]["colors"], "coarse");
  EXPECT_LT(r["parameters"]["exemplar_pixels_per_texel"].get<double>(), 1.0) << "the default scale zooms into the root";
  ASSERT_EQ(0, texture(common() << "-o" << d / "again.glb" << "--threads 1").status);
  EXPECT_EQ(readText(d / "out.glb"), readText(d / "again.glb"));

  // The graph's companion maps: its exemplars' normal and height maps, through the same coordinates.
  const texfab::Image flat = [] {
    texfab::Image n(128, 128, 3);
    for (size_t i = 0; i < n.pixels.size(); ++i) n.pixels[i] = i % 3 == 2 ? 1.0f : 0.5f;
    return n;
  }();
  texfab::writeImage(flat, d / "flat.png");
  std::ofstream(d / "maps.json") << R"({"exemplars": [{"name": "rock", "image": ")" << (photos / "rock.png").string()
                                 << R"(", "maps": {"normal": "flat.png", "height": ")" << (photos / "rock.png").string()
                                 << R"("}}, {"name": "stone", "image": ")" << (photos / "stone.png").string()
                                 << R"(", "maps": {"normal": "flat.png", "height": ")" << (photos / "stone.png").string()
                                 << R"("}}], "edges": [{"from": "rock", "to": "stone", "scale": 16}]})";
  ASSERT_EQ(0, texture(Args() << kModel << "--graph" << d / "maps.json" << "--resolution 256 -q --no-cache -o"
                              << d / "maps.glb").status);
  expectValidGltf(d / "maps.glb");
  const texfab::Image height = texfab::readImage(d / "maps_height.png");
  EXPECT_EQ(height.width, 256);
  EXPECT_NE(readText(d / "maps.glb").find("normalTexture"), std::string::npos);

  for (const char* extra : {"--mode solid", "--exemplar-wrap tile", "-e models/exemplars/brick.png",
                            "--maps height=models/exemplars/brick.png"}) {
    SCOPED_TRACE(extra);
    const texfab::test::CliResult o = texture(common() << extra << "-o" << d / "bad.glb");
    EXPECT_NE(o.status, 0);
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_FALSE(fs::exists(d / "bad.glb"));
  }
  // 512-pixel exemplars pack into more than surface coordinates address: refused before the analysis.
  texfab::writeImage(texfab::Image(512, 512, 3), d / "big.png");
  std::ofstream(d / "big.json") << R"({"exemplars": [{"name": "big", "image": ")" << (d / "big.png").string() << R"("}]})";
  const texfab::test::CliResult big = texture(Args() << kModel << "--graph" << d / "big.json" << "-q -o" << d / "bad.glb");
  EXPECT_NE(big.status, 0);
  EXPECT_NE(big.err.find("at most 4096 a side"), std::string::npos) << big.err;
  EXPECT_FALSE(fs::exists(d / "bad.glb"));
}
