// SPDX-License-Identifier: GPL-3.0-or-later
// The slice job on small prints: a cube with a colour per face (colours before dithering, and
// dithered 16^3 blocks averaging to them), solid colours equal to the solid synthesizer's, and
// shards, thread counts and batch sizes that do not change a byte.
#include "core/image_io.h"
#include "core/mip_pyramid.h"
#include "print/print_grid.h"
#include "print/slice_model.h"
#include "print/voxel_colors.h"
#include "print/voxelize_layers.h"
#include "tests/geometry/solid_meshes.h"
#include "tests/golden/golden_cases.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <fstream>

namespace texfab::print {
namespace {

namespace fs = std::filesystem;
using test::TempDir;
using print::LayerSpans;
using print::LayerVoxelizer;
using print::PrintGrid;

// Linear colours of the six faces (-x, +x, -y, +y, -z, +z): mixes of the default materials, so
// printable exactly.
const Eigen::Vector3f kFaceColors[6] = {{0.4f, 1, 1}, {0.5f, 0, 0.5f}, {0.7f, 1, 0.3f},
                                        {0.6f, 0.6f, 0.6f}, {1, 0.5f, 0.5f}, {0.8f, 0.7f, 1}};

// A 4 mm cube (model units = mm) whose faces carry the colours above (makeBox's face order).
geometry::Mesh faceColoredCube() {
  geometry::Mesh m = test::makeBox({0, 0, 0}, {4, 4, 4});
  for (int f = 0; f < 6; ++f) {
    geometry::Material material;
    material.name = "face" + std::to_string(f);
    material.baseColorFactor << kFaceColors[f], 1.0f;
    m.materials.push_back(material);
    m.faceMaterials.insert(m.faceMaterials.end(), 2, uint32_t(f));
  }
  return m;
}

PrintGrid gridFor(const geometry::Mesh& mesh, double pitchMm) {
  print::PrintGridOptions o;
  o.mmPerUnit = 1;
  o.dpiX = o.dpiY = 25.4 / pitchMm;
  o.layerMm = pitchMm;
  return print::printGrid(geometry::boundingBox(mesh), o);
}

std::vector<uint8_t> readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Every file of two folders, byte for byte.
void expectSameFolders(const fs::path& a, const fs::path& b) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(a)) names.push_back(e.path().filename().string());
  size_t countB = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(b)) ++countB;
  ASSERT_EQ(names.size(), countB);
  for (const std::string& name : names) EXPECT_EQ(readBytes(a / name), readBytes(b / name)) << name;
}

TEST(SliceModel, FaceColorsBeforeDithering) {
  const geometry::Mesh cube = faceColoredCube();
  const PrintGrid grid = gridFor(cube, 0.1);
  const LayerVoxelizer voxelizer(cube, grid);
  const SurfaceVoxelColors colors(cube, grid, 1.0);
  int checked = 0;
  for (int layer : {3, 20, 37}) {
    const LayerSpans spans = voxelizer.voxelize(layer);
    for (int r = 0; r < spans.rows(); ++r)
      for (const print::VoxelSpan& s : spans.row(r)) {
        if (!s.shell) continue;
        std::vector<float> rgba(4 * size_t(s.end - s.begin));
        const int y = grid.height - 1 - r;
        colors.colors(layer, y, s.begin, s.end, rgba.data());
        for (int x = s.begin; x < s.end; ++x) {
          const Eigen::Vector3d p = grid.center(x, y, layer);
          const double d[6] = {p.x(), 4 - p.x(), p.y(), 4 - p.y(), p.z(), 4 - p.z()};
          const int face = int(std::min_element(d, d + 6) - d);
          if (std::count_if(d, d + 6, [&](double v) { return v < d[face] + 0.05; }) > 1) continue;  // near an edge
          for (int c = 0; c < 3; ++c) ASSERT_EQ(rgba[4 * size_t(x - s.begin) + size_t(c)], kFaceColors[face][c]);
          ++checked;
        }
      }
  }
  EXPECT_GT(checked, 3000);
}

// Mean linear colour of a dithered block of voxels [x0, x0+16) x [y0, y0+16) x the folder's layers.
Eigen::Vector3f blockMean(const fs::path& folder, int x0, int y0, int height) {
  Eigen::Vector3f sum(0, 0, 0);
  int n = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".png") continue;
    const Image layer = readImage(entry.path());
    for (int y = y0; y < y0 + 16; ++y)
      for (int x = x0; x < x0 + 16; ++x, ++n)
        for (int c = 0; c < 3; ++c) sum[c] += srgbToLinear(layer.at(x, height - 1 - y, c));
  }
  EXPECT_EQ(n, 16 * 16 * 16);
  return sum / float(n);
}

TEST(SliceModel, DitheredBlocksAverageToTheFaceColors) {
  // 0.05 mm voxels, 1 mm shell (20 voxels): a 16^3 block against each side face is all shell.
  const geometry::Mesh cube = faceColoredCube();
  const PrintGrid grid = gridFor(cube, 0.05);  // 80^3
  const LayerVoxelizer voxelizer(cube, grid);
  SurfaceVoxelColors colors(cube, grid, 1.0);
  for (DitherMode dither : {DitherMode::BlueNoise, DitherMode::FloydSteinberg}) {
    TempDir dir;
    SliceOptions o;
    o.dither = dither;
    o.firstLayer = 32;
    o.layerCount = 16;
    SliceWriter writer(dir / "out", false);
    sliceModel(voxelizer, colors, o, writer, {});
    writer.publish();
    // Blocks against faces -x, +x, -y, +y, in the middle of each.
    const int blocks[4][2] = {{0, 32}, {64, 32}, {32, 0}, {32, 64}};
    for (int f = 0; f < 4; ++f) {
      const Eigen::Vector3f mean = blockMean(dir / "out", blocks[f][0], blocks[f][1], grid.height);
      EXPECT_LT((mean - kFaceColors[f]).cwiseAbs().maxCoeff(), 0.03f)
          << (dither == DitherMode::BlueNoise ? "blue noise" : "Floyd-Steinberg") << ", face " << f << ": "
          << mean.transpose() << " for " << kFaceColors[f].transpose();
    }
  }
}

TEST(SliceModel, SolidColorsAreTheSynthesizersColors) {
  const geometry::Mesh sphere = test::makeIcoSphere(2.0f, 3);
  const PrintGrid grid = gridFor(sphere, 0.1);
  const LayerVoxelizer voxelizer(sphere, grid);
  const double scale = 12.0;  // solid voxels per mm: 1.2 per print voxel, each takes its own
  const synthesis::SolidSynthesisOptions options;
  SolidVoxelColors colors(golden::solidAnalysis32(), golden::marble32(), golden::marble32(), golden::marble32(), options,
                          scale, grid);
  const std::vector<LayerSpans> layers = {voxelizer.voxelize(20), voxelizer.voxelize(21)};
  colors.prepare(layers, {});
  int checked = 0;
  for (const LayerSpans& spans : layers)
    for (int r = 0; r < spans.rows(); r += 7)
      for (const print::VoxelSpan& s : spans.row(r)) {
        if (!s.shell) continue;
        const int y = grid.height - 1 - r;
        std::vector<float> rgba(4 * size_t(s.end - s.begin));
        colors.colors(spans.layer, y, s.begin, s.end, rgba.data());
        for (int x = s.begin; x < s.end; x += 3, ++checked) {
          const Eigen::Vector3d p = grid.center(x, y, spans.layer) * scale;
          const synthesis::Voxel v{int64_t(std::floor(p.x())), int64_t(std::floor(p.y())), int64_t(std::floor(p.z()))};
          const synthesis::SolidSynthesisResult alone = synthesis::synthesizeSolid(golden::solidAnalysis32(), {&v, 1}, options);
          std::vector<float> color;
          synthesis::solidColors(alone.triples, golden::marble32(), golden::marble32(), golden::marble32(), color);
          const size_t channels = color.size();  // 1 for grey exemplars, else 3
          for (size_t c = 0; c < 3; ++c)
            ASSERT_EQ(rgba[4 * size_t(x - s.begin) + c], srgbToLinear(color[channels == 1 ? 0 : c]));
        }
      }
  EXPECT_GT(checked, 50);
}

// A print finer than its solid texture (0.2 solid voxels per print voxel): each print voxel blends
// the 8 solid voxels whose centres surround it, so that no blocks show.
TEST(SliceModel, MagnifiedSolidColorsBlendTheirVoxelsTrilinearly) {
  const geometry::Mesh sphere = test::makeIcoSphere(2.0f, 3);
  const PrintGrid grid = gridFor(sphere, 0.1);
  const LayerVoxelizer voxelizer(sphere, grid);
  const double scale = 2.0;
  const synthesis::SolidSynthesisOptions options;
  const Image& marble = golden::marble32();
  SolidVoxelColors colors(golden::solidAnalysis32(), marble, marble, marble, options, scale, grid);
  ASSERT_EQ(colors.sampling(), SolidSampling::Trilinear);
  const std::vector<LayerSpans> layers = {voxelizer.voxelize(20)};
  colors.prepare(layers, {});
  // The synthesizer's colour of one voxel, in linear light.
  const auto voxelColor = [&](const synthesis::Voxel& v) {
    const synthesis::SolidSynthesisResult alone = synthesis::synthesizeSolid(golden::solidAnalysis32(), {&v, 1}, options);
    std::vector<float> color;
    synthesis::solidColors(alone.triples, marble, marble, marble, color);
    Eigen::Vector3f out;
    for (int c = 0; c < 3; ++c) out[c] = srgbToLinear(color[color.size() == 1 ? 0 : size_t(c)]);
    return out;
  };
  double stepAcross = 0, stepWithin = 0;
  int across = 0, within = 0, equal = 0, checked = 0;
  for (const LayerSpans& spans : layers)
    for (int r = 0; r < spans.rows(); r += 5)
      for (const print::VoxelSpan& s : spans.row(r)) {
        if (!s.shell || s.end - s.begin < 2) continue;
        const int y = grid.height - 1 - r;
        std::vector<float> rgba(4 * size_t(s.end - s.begin));
        colors.colors(spans.layer, y, s.begin, s.end, rgba.data());
        const auto at = [&](int x) { return Eigen::Vector3f(&rgba[4 * size_t(x - s.begin)]); };
        for (int x = s.begin; x + 1 < s.end; ++x) {
          const double step = (at(x + 1) - at(x)).norm();
          const bool boundary = std::floor(grid.centerX(x) * scale) != std::floor(grid.centerX(x + 1) * scale);
          (boundary ? stepAcross : stepWithin) += step;
          ++(boundary ? across : within);
          equal += step == 0;
        }
        for (int x = s.begin; x < s.end && checked < 200; x += 4, ++checked) {
          const Eigen::Vector3d q = grid.center(x, y, spans.layer) * scale - Eigen::Vector3d::Constant(0.5);
          const Eigen::Vector3d base = q.array().floor(), f = q - base;
          Eigen::Vector3f expected = Eigen::Vector3f::Zero();
          for (int k = 0; k < 8; ++k) {
            const synthesis::Voxel v{int64_t(base.x()) + (k & 1), int64_t(base.y()) + (k >> 1 & 1), int64_t(base.z()) + (k >> 2)};
            const double w = ((k & 1) ? f.x() : 1 - f.x()) * ((k & 2) ? f.y() : 1 - f.y()) * ((k & 4) ? f.z() : 1 - f.z());
            expected += float(w) * voxelColor(v);
          }
          ASSERT_LT((at(x) - expected).cwiseAbs().maxCoeff(), 1e-5f) << "print voxel " << x << ", " << y;
        }
      }
  ASSERT_GT(across, 20);
  ASSERT_GE(checked, 40);
  // With the nearest voxel, 4 of 5 neighbours would be equal and every step would cross a boundary.
  EXPECT_LT(equal, (across + within) / 20);
  EXPECT_LT(stepAcross / across, 1.5 * stepWithin / within);
}

// A print coarser than its solid texture (3 solid voxels along each print voxel): each print voxel
// is the mean of the solid voxels its box overlaps, weighted by the overlap, so that it shows the
// material prefiltered rather than one aliased voxel.
TEST(SliceModel, MinifiedSolidColorsAverageTheirFootprint) {
  const geometry::Mesh sphere = test::makeIcoSphere(2.0f, 3);
  const PrintGrid grid = gridFor(sphere, 0.1);
  const LayerVoxelizer voxelizer(sphere, grid);
  const double scale = 30.0;
  const Image& marble = golden::marble32();
  SolidVoxelColors colors(golden::solidAnalysis32(), marble, marble, marble, {}, scale, grid);
  ASSERT_EQ(colors.sampling(), SolidSampling::Box);
  const std::vector<LayerSpans> layers = {voxelizer.voxelize(20)};
  colors.prepare(layers, {});
  // Print voxels to check, each with its footprint: per axis the overlapped voxels and weights.
  struct Check {
    Eigen::Vector3f color;
    std::array<std::vector<std::pair<int64_t, double>>, 3> taps;
    int64_t nearest[3];  // the voxel under the centre
  };
  std::vector<Check> checks;
  std::vector<synthesis::Voxel> voxels;
  for (int r = 0; r < layers[0].rows() && checks.size() < 24; r += 9)
    for (const print::VoxelSpan& s : layers[0].row(r)) {
      if (!s.shell) continue;
      const int y = grid.height - 1 - r;
      std::vector<float> rgba(4 * size_t(s.end - s.begin));
      colors.colors(20, y, s.begin, s.end, rgba.data());
      for (int x = s.begin; x < s.end && checks.size() < 24; x += 5) {
        Check c;
        c.color = Eigen::Vector3f(&rgba[4 * size_t(x - s.begin)]);
        const Eigen::Vector3d center = grid.center(x, y, 20);
        for (int a = 0; a < 3; ++a) {
          const double lo = (center[a] - 0.05) * scale, hi = (center[a] + 0.05) * scale;
          for (int64_t v = int64_t(std::floor(lo)); double(v) < hi; ++v)
            c.taps[size_t(a)].push_back({v, (std::min(hi, double(v + 1)) - std::max(lo, double(v))) / (hi - lo)});
          c.nearest[a] = int64_t(std::floor(center[a] * scale));
        }
        for (const auto& [vx, wx] : c.taps[0])
          for (const auto& [vy, wy] : c.taps[1])
            for (const auto& [vz, wz] : c.taps[2]) voxels.push_back({vx, vy, vz});
        voxels.push_back({c.nearest[0], c.nearest[1], c.nearest[2]});
        checks.push_back(c);
      }
    }
  ASSERT_EQ(checks.size(), 24u);
  int different = 0;
  const synthesis::SolidSynthesisResult alone = synthesis::synthesizeSolid(golden::solidAnalysis32(), voxels, {});
  std::vector<float> rgb;
  synthesis::solidColors(alone.triples, marble, marble, marble, rgb);
  const auto colorAt = [&](size_t i) {
    Eigen::Vector3f out;
    for (int ch = 0; ch < 3; ++ch) out[ch] = srgbToLinear(rgb[rgb.size() == voxels.size() ? i : 3 * i + size_t(ch)]);
    return out;
  };
  size_t i = 0;
  for (const Check& c : checks) {
    Eigen::Vector3f expected = Eigen::Vector3f::Zero();
    for (const auto& [vx, wx] : c.taps[0])
      for (const auto& [vy, wy] : c.taps[1])
        for (const auto& [vz, wz] : c.taps[2]) expected += float(wx * wy * wz) * colorAt(i++);
    EXPECT_LT((c.color - expected).cwiseAbs().maxCoeff(), 1e-5f);
    const Eigen::Vector3f nearest = colorAt(i++);
    different += (nearest - expected).cwiseAbs().maxCoeff() > 1e-3f;
  }
  EXPECT_GT(different, 12) << "the footprint's mean is mostly not the voxel under its centre";
}

TEST(SliceModel, ShardsThreadsAndBatchesDoNotChangeAByte) {
  const geometry::Mesh sphere = test::makeIcoSphere(2.0f, 3, {0.2f, -0.1f, 0.05f});
  const PrintGrid grid = gridFor(sphere, 0.1);
  print::VoxelizeOptions vo;
  vo.shellMm = 0.5;
  const LayerVoxelizer voxelizer(sphere, grid, vo);
  for (DitherMode dither : {DitherMode::BlueNoise, DitherMode::FloydSteinberg}) {
    TempDir dir;
    auto run = [&](const fs::path& out, int first, int count, int threads, int batch) {
      SolidVoxelColors colors(golden::solidAnalysis32(), golden::marble32(), golden::marble32(), golden::marble32(), {},
                              5.0, grid);
      SliceOptions o;
      o.dither = dither;
      o.firstLayer = first;
      o.layerCount = count;
      o.batchLayers = batch;
      SliceWriter writer(out, false);
      PrintSource source;
      source.model = "sphere";
      sliceModel(voxelizer, colors, o, writer, source, Context{.threads = threads});
      writer.publish();
    };
    run(dir / "full", 0, -1, 1, 16);
    const int n = grid.layers;
    run(dir / "a", 0, 7, 2, 3);
    run(dir / "b", 7, n / 2 - 7, 2, 16);
    run(dir / "c", n / 2, n - n / 2, 2, 5);
    const std::vector<fs::path> shards = {dir / "c", dir / "a", dir / "b"};
    mergeSliceFolders(shards, dir / "merged", false);
    expectSameFolders(dir / "full", dir / "merged");
    // A shard's own files equal the full run's too.
    EXPECT_EQ(readBytes(dir / "b" / sliceFileName(9, n)), readBytes(dir / "full" / sliceFileName(9, n)));
  }
}

TEST(SliceModel, MergeRefusesGapsOverlapsAndOtherPrints) {
  const geometry::Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1});
  const PrintGrid grid = gridFor(box, 0.1);
  const LayerVoxelizer voxelizer(box, grid);
  SurfaceVoxelColors colors(box, grid, 1.0);
  TempDir dir;
  auto run = [&](const fs::path& out, int first, int count, DitherMode dither) {
    SliceOptions o;
    o.firstLayer = first;
    o.layerCount = count;
    o.dither = dither;
    SliceWriter writer(out, false);
    sliceModel(voxelizer, colors, o, writer, {});
    writer.publish();
  };
  run(dir / "a", 0, 4, DitherMode::BlueNoise);
  run(dir / "b", 4, 6, DitherMode::BlueNoise);
  run(dir / "c", 3, 7, DitherMode::BlueNoise);
  run(dir / "d", 4, 6, DitherMode::FloydSteinberg);
  auto error = [&](std::vector<fs::path> parts) {
    try {
      mergeSliceFolders(parts, dir / "merged", false);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error({dir / "a"}).find("end at layer 4 of 10"), std::string::npos);
  EXPECT_NE(error({dir / "a", dir / "c"}).find("overlap"), std::string::npos);
  EXPECT_NE(error({dir / "a", dir / "d"}).find("a different print"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "merged"));
  std::ofstream(dir / "b" / sliceFileName(5, 10), std::ios::app) << "x";
  EXPECT_NE(error({dir / "a", dir / "b"}).find("checksum"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "merged"));
}

} // namespace
} // namespace texfab::print
