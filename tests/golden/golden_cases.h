// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The fixed cases whose output bytes the golden tests hash. Each returns the FNV-1a 64 hashes of
// what texfab computes, stage by stage (analysis, atlas, fields, synthesis, colour, bake, encode:
// those the case passes through), so that a failure names the first stage whose values changed.
// Inputs are small bundled data so that the whole suite runs in seconds. The cases that synthesize
// take the backend of their kernels (the Vulkan tests run them on the device: same hashes).

#include "core/crop.h"
#include "core/image_io.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/solid_tiles.h"
#include "synthesis/synthesize_2d.h"
#include "synthesis/synthesize_solid.h"
#ifndef TEXFAB_GOLDEN_SYNTHESIS_ONLY
#include "atlas/generate_atlas.h"
#include "core/ktx2_write.h"
#include "geometry/io/mesh_io.h"
#include "print/print_job.h"
#include "render/break/break_model.h"
#include "render/filter_normal_map.h"
#include "render/material_mips.h"
#include "render/texture_mesh.h"
#include "tests/render/test_normal_maps.h"
#include "tests/test_support.h"
#endif

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <gtest/gtest.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <vector>

namespace texfab::golden {

/// One stage's expected hash (hex).
struct Stage {
  const char* name;
  const char* hash;
};

/// The expected hashes (hex), stage by stage. A deliberate change of output updates them here, with
/// its reason in the commit message.
inline constexpr Stage kWindow2d[] = {{"analysis", "ec0cf9cad759bed8"}, {"synthesis", "72908d5d3414dcbb"}};
inline constexpr Stage kWindow2dClamp[] = {{"analysis", "27abfbbcef11983d"}, {"synthesis", "f938a9dcaf008e4f"}};
inline constexpr Stage kSolidVolume[] = {
    {"analysis", "39c22a9410faab61"}, {"synthesis", "3e8d8d343adfd9c7"}, {"colour", "9d43c1e1bbb36ea4"}};
inline constexpr Stage kSolidObliquePlane[] = {{"analysis", "39c22a9410faab61"}, {"synthesis", "1024f66e6d415b7d"}};
inline constexpr Stage kSolidClampVolume[] = {{"analysis", "376954e8afa4e8c9"}, {"synthesis", "b014e0dd69a65782"}};
inline constexpr Stage kSolidTiles[] = {
    {"analysis", "39c22a9410faab61"}, {"tiles", "7337d839b4718cad"}, {"evaluation", "2f72b1d90329728e"}};
inline constexpr Stage kSolidTilesTwoLevels[] = {
    {"analysis", "39c22a9410faab61"}, {"tiles", "f0a5fb5ed1c460ef"}, {"evaluation", "a42983dc2d0a23e4"}};
inline constexpr Stage kSolidClampTiles[] = {
    {"analysis", "376954e8afa4e8c9"}, {"tiles", "a8c43503106029d9"}, {"evaluation", "037924fbbd000eb6"}};
inline constexpr Stage kAtlasTexelUvs[] = {{"atlas", "66752b2be1750fd4"}};
inline constexpr Stage kSurfaceTexture[] = {{"analysis", "ec0cf9cad759bed8"},
                                            {"atlas", "427d4aeff5f1272e"},
                                            {"fields", "389e0a7c229b0a0c"},
                                            {"synthesis", "6fab6e5feafcd789"},
                                            {"bake", "42430333584d8224"}};
inline constexpr Stage kSolidTexture[] = {
    {"analysis", "39c22a9410faab61"}, {"atlas", "427d4aeff5f1272e"}, {"bake", "c008a90264b61740"}};
inline constexpr Stage kGlbBytes[] = {{"bake", "42430333584d8224"}, {"encode", "dcf64f875ac17e39"}};
inline constexpr Stage kFracture[] = {
    {"pieces", "d99fa5719320cec1"}, {"interior atlas", "a588d099a162a50b"}, {"interior bake", "a6a15d52f562e627"},
    {"encode", "4b1659ed76db330b"}};
inline constexpr Stage kNdfMipChain[] = {{"normal map", "03b3e7c5302dd5d4"},
                                         {"lobes", "2efa9dab245331e8"},
                                         {"roughness MIPs", "6f586acca2e2a63f"},
                                         {"ktx2", "8c73c145e1c7555b"},
                                         {"brushed normal map", "8c9e1118e0490c67"},
                                         {"brushed roughness MIPs", "34a735f83075dc69"},
                                         {"anisotropy MIPs", "3ab0d8257d84cd76"},
                                         {"anisotropy ktx2", "f7a7dcadb8ddac60"}};
inline constexpr Stage kSliceLayers[] = {{"layers", "dbd4250112e4a0bc"}, {"manifest", "c60d509d95f159fa"}};

/// FNV-1a over bytes, continued from `h`.
inline uint64_t fnv1a(const void* data, size_t size, uint64_t h = 0xcbf29ce484222325ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}
template <class T>
uint64_t hashOf(const std::vector<T>& values, uint64_t h = 0xcbf29ce484222325ull) {
  return fnv1a(values.data(), values.size() * sizeof(T), h);
}
/// An image as the 8-bit values a PNG of it holds.
inline uint64_t hashOf8Bit(const Image& image) {
  std::vector<uint8_t> bytes(image.pixels.size());
  for (size_t i = 0; i < bytes.size(); ++i) {
    const float v = image.pixels[i] < 0 ? 0.0f : image.pixels[i] > 1 ? 1.0f : image.pixels[i];
    bytes[i] = uint8_t(v * 255.0f + 0.5f);
  }
  return hashOf(bytes);
}
inline std::string hex(uint64_t h) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
  return s;
}

/// What a case computed, stage by stage, in pipeline order.
struct Stages {
  std::vector<std::pair<std::string, uint64_t>> hashes;
  Stages& add(const std::string& stage, uint64_t hash) {
    hashes.emplace_back(stage, hash);
    return *this;
  }
};

/// Fails the current test unless `got` has the expected stages and hashes; the message names the
/// first stage whose values changed (the later ones follow from it) and lists every new hash.
inline void expectStages(const Stages& got, std::span<const Stage> expected) {
  std::string firstChanged, all;
  bool sameStages = got.hashes.size() == expected.size();
  for (size_t i = 0; i < got.hashes.size(); ++i) {
    const auto& [name, hash] = got.hashes[i];
    sameStages = sameStages && name == expected[i].name;
    const bool same = sameStages && hex(hash) == expected[i].hash;
    if (!same && firstChanged.empty()) firstChanged = name;
    all += (all.empty() ? "" : ", ") + name + " " + hex(hash) + (same ? "" : " (changed)");
  }
  if (!sameStages) ADD_FAILURE() << "the case's stages differ from the expected list: " << all;
  else if (!firstChanged.empty())
    ADD_FAILURE() << "values changed first at the " << firstChanged << " stage: " << all;
}

/// Hashes of the analyses' outputs (every table synthesis reads).
inline uint64_t hashOf(const synthesis::ExemplarAnalysis& a) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (const synthesis::AnalysisLevel& l : a.levels) {
    h = hashOf(l.appearance, h);
    h = hashOf(l.neighborhood, h);
    h = hashOf(l.candidates, h);
  }
  return h;
}
inline uint64_t hashOf(const synthesis::SolidProjection& p, uint64_t h) {
  h = hashOf(p.mean, hashOf(p.basis, h));
  return fnv1a(&p.divisor, sizeof p.divisor, h);
}
inline uint64_t hashOf(const synthesis::SolidAnalysis& a) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (const synthesis::SolidLevel& l : a.levels) {
    for (int e = 0; e < 3; ++e) {
      h = hashOf(l.colors[size_t(e)], h);
      h = hashOf(l.candidates2d[size_t(e)], h);
      h = hashOf(l.descriptors2d[size_t(e)], h);
      h = hashOf(l.triples[size_t(e)], h);
      h = hashOf(l.descriptors3d[size_t(e)], h);
      h = fnv1a(l.searchColors[size_t(e)].data(), sizeof l.searchColors[size_t(e)], h);
    }
    h = hashOf(l.projection3d, hashOf(l.projection2d, h));
  }
  return h;
}
/// Triples, flattened.
inline uint64_t hashOf(const std::vector<synthesis::Triple>& triples) {
  std::vector<uint32_t> flat;
  for (const synthesis::Triple& t : triples) flat.insert(flat.end(), t.begin(), t.end());
  return hashOf(flat);
}

inline std::filesystem::path bundled(const std::string& relative) {
  return std::filesystem::path(TEXFAB_SOURCE_DIR) / "models" / relative;
}

/// The side x side crop at (x0, y0) of a bundled image.
inline Image bundledCrop(const std::string& relative, int x0, int y0, int side) {
  return crop(readImage(bundled(relative)), x0, y0, side, side);
}

/// A 32x32 crop of the bundled marble: a solid analysis in a second or two.
inline const Image& marble32() {
  static const Image crop = bundledCrop("exemplars/marble.png", 40, 24, 32);
  return crop;
}

inline const synthesis::SolidAnalysis& solidAnalysis32() {
  static const synthesis::SolidAnalysis a = synthesis::analyzeSolid(marble32(), marble32(), marble32(), {}, Context{.threads = 2});
  return a;
}

/// A 40x40 crop of the bundled photograph rock.png (it does not tile), analysed with wrap Clamp.
inline const Image& rock40() {
  static const Image crop = bundledCrop("exemplars/photos/rock.png", 70, 9, 40);
  return crop;
}
inline const synthesis::SolidAnalysis& solidClampAnalysis40() {
  static const synthesis::SolidAnalysis a = [] {
    synthesis::SolidAnalysisOptions options;
    options.wrap = synthesis::ExemplarWrap::Clamp;
    return synthesis::analyzeSolid(rock40(), rock40(), rock40(), options, Context{.threads = 2});
  }();
  return a;
}

/// The context of the synthesis of a case.
inline Context synthesisContext(Backend backend) { return Context{.threads = 2, .backend = backend}; }

/// The bundled brick's analysis.
inline const synthesis::ExemplarAnalysis& brickAnalysis() {
  static const synthesis::ExemplarAnalysis a =
      synthesis::analyzeExemplar(readImage(bundled("exemplars/brick.png")), {}, Context{.threads = 2});
  return a;
}

/// A 2-D window away from the origin, bundled brick, seed 7.
inline Stages window2d(Backend backend = Backend::Cpu) {
  synthesis::SynthesisOptions options;
  options.seed = 7;
  const synthesis::SynthesisResult r =
      synthesis::synthesize2d(brickAnalysis(), {-37, 11, 96, 80}, options, synthesisContext(backend));
  return Stages().add("analysis", hashOf(brickAnalysis())).add("synthesis", hashOf(r.coords.coords));
}

/// A 64x64 crop of the bundled stone photograph, which does not tile.
inline const Image& stone64() {
  static const Image crop = bundledCrop("exemplars/photos/stone.png", 30, 40, 64);
  return crop;
}

/// stone64 analysed as an exemplar that does not tile (ExemplarWrap::Clamp).
inline const synthesis::ExemplarAnalysis& clampAnalysis64() {
  static const synthesis::ExemplarAnalysis a =
      synthesis::analyzeExemplar(stone64(), {.wrap = synthesis::ExemplarWrap::Clamp}, Context{.threads = 2});
  return a;
}

/// A 2-D window away from the origin from clampAnalysis64, seed 5.
inline Stages window2dClamp(Backend backend = Backend::Cpu) {
  synthesis::SynthesisOptions options;
  options.seed = 5;
  const synthesis::SynthesisResult r =
      synthesis::synthesize2d(clampAnalysis64(), {-1000003, 77, 80, 72}, options, synthesisContext(backend));
  return Stages().add("analysis", hashOf(clampAnalysis64())).add("synthesis", hashOf(r.coords.coords));
}

/// A 12^3 box of the solid texture of marble32 with its colours.
inline Stages solidVolume(Backend backend = Backend::Cpu) {
  synthesis::SolidSynthesisOptions options;
  options.seed = 3;
  const synthesis::SolidSynthesisResult r =
      synthesis::synthesizeSolidBox(solidAnalysis32(), {5, -3, 7, 12, 12, 12}, options, nullptr, synthesisContext(backend));
  std::vector<float> colors;
  synthesis::solidColors(r.triples, marble32(), marble32(), marble32(), colors);
  return Stages()
      .add("analysis", hashOf(solidAnalysis32()))
      .add("synthesis", hashOf(r.triples))
      .add("colour", hashOf(colors, hashOf(r.triples)));
}

/// A 12^3 box of the solid texture of rock40, which does not tile (clamp).
inline Stages solidClampVolume(Backend backend = Backend::Cpu) {
  synthesis::SolidSynthesisOptions options;
  options.seed = 5;
  const synthesis::SolidSynthesisResult r = synthesis::synthesizeSolidBox(
      solidClampAnalysis40(), {-9, 30, 4, 12, 12, 12}, options, nullptr, synthesisContext(backend));
  return Stages().add("analysis", hashOf(solidClampAnalysis40())).add("synthesis", hashOf(r.triples));
}

/// The voxels of an oblique 40x40 plane through the solid texture of marble32.
/// The voxels of a 40x40 oblique plane.
inline std::vector<synthesis::Voxel> obliquePlane() {
  std::vector<synthesis::Voxel> voxels;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      const double x = 3 + 0.8 * i - 0.3 * j, y = -5 + 0.5 * i + 0.7 * j, z = 11 + 0.3 * i + 0.6 * j;
      voxels.push_back({int64_t(std::floor(x)), int64_t(std::floor(y)), int64_t(std::floor(z))});
    }
  return voxels;
}

inline Stages solidPlane(Backend backend = Backend::Cpu) {
  const std::vector<synthesis::Voxel> voxels = obliquePlane();
  const synthesis::SolidSynthesisResult r =
      synthesis::synthesizeSolid(solidAnalysis32(), voxels, {}, nullptr, synthesisContext(backend));
  return Stages().add("analysis", hashOf(solidAnalysis32())).add("synthesis", hashOf(r.triples));
}

/// A tile set of a solid analysis, and the oblique plane read from it with seed 5. 8-voxel tiles are
/// one level (32^3 arrangements); 16-voxel tiles add a coarse level and the upsampling to the finest,
/// at one iteration per level to keep the emulated runs short.
inline Stages solidTiles(const synthesis::SolidAnalysis& analysis, int tileSide = 8) {
  synthesis::SolidTileOptions options;
  options.tileSide = tileSide;
  if (tileSide > 8) options.iterations = options.finestIterations = 1;
  const synthesis::SolidTileSet tiles = synthesis::buildSolidTiles(analysis, options, Context{.threads = 2});
  const std::vector<synthesis::Voxel> voxels = obliquePlane();
  std::vector<synthesis::Triple> triples(voxels.size());
  synthesis::evaluateSolidTiles(tiles, 5, voxels, triples);
  return Stages()
      .add("analysis", hashOf(analysis))
      .add("tiles", hashOf(tiles.elements))
      .add("evaluation", hashOf(triples));
}

#ifndef TEXFAB_GOLDEN_SYNTHESIS_ONLY

/// The bundled knot's atlas at 512^2: every corner's texel position.
inline Stages atlasTexelUvs() {
  const geometry::Mesh mesh = geometry::readMesh(bundled("meshes/knot1.off"));
  atlas::GenerateAtlasOptions options;
  options.pack.width = options.pack.height = 512;
  const atlas::GenerateAtlasResult r = atlas::generateAtlas(mesh, options);
  return Stages().add("atlas", hashOf(r.atlas.texelUvs));
}

inline render::TextureMeshResult textureElephant(render::TextureMode mode, Backend backend) {
  static const geometry::Mesh mesh = geometry::readMesh(bundled("meshes/elephant.off"));
  static const Image brick = readImage(bundled("exemplars/brick.png"));
  render::TextureExemplar ex;
  ex.color = mode == render::TextureMode::Solid ? &marble32() : &brick;
  ex.analysis = &brickAnalysis();
  ex.solidAnalysis = &solidAnalysis32();
  render::TextureMeshOptions options;
  options.mode = mode;
  options.atlas.pack.width = options.atlas.pack.height = 256;
  // The 256^2 atlas's own density: the default (a 2048^2 atlas's) would minify 8x, and in solid mode
  // point-sample one voxel in eight, each with its own dependency chain.
  options.textureScale = render::autoTextureScale(mesh) * 256 / render::kAutoScaleAtlasSide;
  options.measure = false;
  options.surface.seed = options.solid.seed = 5;
  return render::textureMesh(mesh, ex, options, Context{.backend = backend});
}

/// The per-texel Jacobians of the finest surface level (texel -> exemplar pixels).
inline uint64_t hashOfJacobians(const render::TextureMeshResult& r) { return hashOf(r.sites.jacobian); }

/// The bundled elephant textured at 256^2 with the bundled brick: coordinates and base colour.
inline Stages surfaceTexture(Backend backend = Backend::Cpu) {
  const render::TextureMeshResult r = textureElephant(render::TextureMode::Surface, backend);
  return Stages()
      .add("analysis", hashOf(brickAnalysis()))
      .add("atlas", hashOf(r.atlas.atlas.texelUvs))
      .add("fields", hashOfJacobians(r))
      .add("synthesis", hashOf(r.coords))
      .add("bake", hashOf8Bit(*r.baseColor));
}

/// The same in solid mode with marble32.
inline Stages solidTexture(Backend backend = Backend::Cpu) {
  const render::TextureMeshResult r = textureElephant(render::TextureMode::Solid, backend);
  return Stages()
      .add("analysis", hashOf(solidAnalysis32()))
      .add("atlas", hashOf(r.atlas.atlas.texelUvs))
      .add("bake", hashOf8Bit(*r.baseColor));
}

/// The bytes of the GLB of the surface-mode elephant.
inline Stages glbBytes(Backend backend = Backend::Cpu) {
  const test::TempDir dir("texfab-golden");
  const std::filesystem::path path = dir / "elephant.glb";
  const render::TextureMeshResult r = textureElephant(render::TextureMode::Surface, backend);
  geometry::writeMesh(r.mesh, path);
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return Stages().add("bake", hashOf8Bit(*r.baseColor)).add("encode", hashOf(bytes));
}

/// The bundled elephant broken into 3 Voronoi pieces (seed 2), its cut faces textured from
/// marble32's solid texture in a 128^2 atlas: the pieces' geometry, the atlas, its colours and the
/// GLB of the pieces.
inline Stages fracture(Backend backend = Backend::Cpu) {
  const geometry::Mesh mesh = geometry::readMesh(bundled("meshes/elephant.off"));
  render::BreakModelOptions options;
  options.fracture.emplace().pieces = 3;
  options.fracture->seed = 2;
  options.interior.atlas.pack.width = options.interior.atlas.pack.height = 128;
  options.interior.textureScale = render::autoTextureScale(mesh) * 128 / render::kAutoScaleAtlasSide;  // see textureElephant
  options.shareTextureSettings(2, {});
  const render::BrokenModel model =
      render::breakModel(mesh, {}, {&marble32(), &solidAnalysis32()}, options, Context{.threads = 2, .backend = backend});
  uint64_t pieces = 0xcbf29ce484222325ull;
  for (const render::Piece& p : model.pieces) {
    pieces = hashOf(p.mesh.positions, pieces);
    pieces = hashOf(p.mesh.triangles, pieces);
    pieces = hashOf(p.mesh.faceTags, pieces);
  }
  const test::TempDir dir("texfab-golden");
  geometry::writeScene(render::sceneOf(model), dir / "pieces.glb");
  std::ifstream in(dir / "pieces.glb", std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return Stages()
      .add("pieces", pieces)
      .add("interior atlas", hashOf(model.interior->atlas.atlas.texelUvs))
      .add("interior bake", hashOf8Bit(*model.interior->baseColor))
      .add("encode", hashOf(bytes));
}

/// Layers 12 to 15 of the bundled elephant printed 6 mm tall at 127 dpi and 0.2 mm layers, its
/// shell coloured from marble32's solid texture and dithered to the default materials: the layer
/// PNGs' bytes and the manifest.
inline Stages sliceLayers(Backend backend = Backend::Cpu) {
  print::PrintJobOptions options;
  options.grid = {.heightMm = 6, .dpiX = 127, .dpiY = 127, .layerMm = 0.2, .up = geometry::UpAxis::Y};
  options.voxelize.shellMm = 0.6;
  options.colors = print::PrintColors::Solid;
  options.textureScale = 120;  // 4 solid voxels along each print voxel: each averages its footprint (box)
  const Context ctx{.threads = 2, .backend = backend};
  const print::PrintJob job(geometry::readMesh(bundled("meshes/elephant.off")), options, ctx);
  const test::TempDir dir("texfab-golden");
  print::SliceWriter writer(dir / "layers", false);
  job.slice({&marble32(), &solidAnalysis32(), nullptr, "marble32"}, 12, 4, writer, "elephant.off", ctx);
  writer.publish();
  uint64_t layers = 0xcbf29ce484222325ull;
  for (const print::SliceFile& f : writer.files()) {
    std::ifstream in(dir / "layers" / f.file, std::ios::binary);
    layers = hashOf(std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()), layers);
  }
  std::ifstream in(dir / "layers" / "slices.json", std::ios::binary);
  const std::vector<char> manifest((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return Stages().add("layers", layers).add("manifest", hashOf(manifest));
}


/// The normal map of the bundled brick's luminance as a height field, and its NDF fitted per texel
/// and MIP level (render/filter_normal_map.h, default options): every lobe of every level; the glTF
/// route's roughness MIP chain for a glossy metal with that map (render/material_mips.h) and its
/// KTX2 file; for the brushed metal of the previews' tests, the route's roughness and anisotropy
/// chains.
inline Stages ndfMipChain() {
  const Image brick = readImage(bundled("exemplars/brick.png"));
  const Image map = test::normalMap(brick.width, 8, [&](int x, int y) {
    return 0.2126 * brick.at(x, y, 0) + 0.7152 * brick.at(x, y, 1) + 0.0722 * brick.at(x, y, 2);
  });
  const render::NdfMipChain chain = render::filterNormalMap(map, {}, Context{.threads = 2});
  uint64_t lobes = 0xcbf29ce484222325ull;
  for (const render::NdfLevel& l : chain.levels) lobes = hashOf(l.lobes, lobes);
  geometry::Material metal;
  metal.roughnessFactor = 0.3f;
  metal.normalTexture.image = std::make_shared<const Image>(map);
  const geometry::Material filtered = render::withFilteredMips(metal, {}, Context{.threads = 2});
  const auto chainHash = [](const std::vector<Image>& chain) {
    uint64_t h = 0xcbf29ce484222325ull;
    for (const Image& level : chain) h = hashOf(level.pixels, h);
    return h;
  };
  const std::vector<Image>& roughness = *filtered.metallicRoughnessTexture.mips;
  // The brushed metal's grooves, whose normals spread one way: an anisotropy chain too.
  metal.normalTexture.image = std::make_shared<const Image>(test::testMaps(128)[1].map);
  const geometry::Material brushed = render::withFilteredMips(metal, {}, Context{.threads = 2});
  if (!brushed.anisotropy) return Stages().add("anisotropic", 0);
  const std::vector<Image>& anisotropy = *brushed.anisotropy.texture.mips;
  return Stages()
      .add("normal map", hashOf(map.pixels))
      .add("lobes", lobes)
      .add("roughness MIPs", chainHash(roughness))
      .add("ktx2", hashOf(encodeKtx2Uastc(roughness)))
      .add("brushed normal map", hashOf(metal.normalTexture.image->pixels))
      .add("brushed roughness MIPs", chainHash(*brushed.metallicRoughnessTexture.mips))
      .add("anisotropy MIPs", chainHash(anisotropy))
      .add("anisotropy ktx2", hashOf(encodeKtx2Uastc(anisotropy)));
}

#endif
} // namespace texfab::golden
