// SPDX-License-Identifier: GPL-3.0-or-later
// The parts of the slice job: the run-length PNG encoder read back by OpenImageIO and zlib, the
// materials file, the material mixer reproducing colours, and the blue-noise array's spread.
#include "core/error.h"
#include "core/image_io.h"
#include "core/mip_pyramid.h"
#include "print/blue_noise.h"
#include "print/color_difference.h"
#include "print/dither_measures.h"
#include "print/mix_materials.h"
#include "print/png_row_encoder.h"
#include "print/print_materials.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

namespace texfab::print {
namespace {

using test::TempDir;

std::string errorOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Rows of runs and noise, `channels` bytes per pixel, values below `levels`.
std::vector<uint8_t> runsAndNoise(int w, int h, int channels, int levels, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> pixels(size_t(w) * size_t(h) * size_t(channels));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w;) {
      const int run = rng() % 3 == 0 ? 1 : int(rng() % 300) + 1;
      uint8_t pixel[4];
      for (int c = 0; c < channels; ++c) pixel[c] = uint8_t(rng() % uint32_t(levels));
      for (int i = 0; i < run && x < w; ++i, ++x)
        std::copy(pixel, pixel + channels, &pixels[(size_t(y) * size_t(w) + size_t(x)) * size_t(channels)]);
    }
  return pixels;
}

std::vector<uint8_t> encode(const std::vector<uint8_t>& pixels, int w, int h, int channels, std::span<const Rgba8> palette) {
  PngRowEncoder encoder(w, h, channels, palette);
  for (int y = 0; y < h; ++y) encoder.addRow(&pixels[size_t(y) * size_t(w) * size_t(channels)]);
  return encoder.finish();
}

TEST(PngRowEncoder, OpenImageIOReadsBackEveryPixel) {
  const int w = 613, h = 97;  // odd sizes, runs longer than deflate's 258-byte copies
  for (int channels : {3, 4}) {
    const std::vector<uint8_t> pixels = runsAndNoise(w, h, channels, 256, uint32_t(channels));
    const std::vector<uint8_t> png = encode(pixels, w, h, channels, {});
    const Image back = decodeImage(png, "encoded.png");
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.channels, channels);
    for (size_t i = 0; i < pixels.size(); ++i) ASSERT_EQ(std::lround(back.pixels[i] * 255.0f), pixels[i]) << i;
    EXPECT_LT(png.size(), pixels.size() * 9 / 8 + 1024);  // never much larger than raw
  }
}

TEST(PngRowEncoder, IndexedImagesKeepPaletteAndTransparency) {
  const int w = 1000, h = 40;
  const std::vector<Rgba8> palette = {{0, 0, 0, 0}, {0, 255, 255, 255}, {255, 0, 255, 255}, {20, 30, 40, 255}};
  const std::vector<uint8_t> pixels = runsAndNoise(w, h, 1, 4, 7);
  const Image back = decodeImage(encode(pixels, w, h, 1, palette), "indexed.png");
  ASSERT_EQ(back.channels, 4);  // palette + tRNS expand to RGBA
  for (size_t i = 0; i < pixels.size(); ++i)
    for (int c = 0; c < 4; ++c) ASSERT_EQ(std::lround(back.pixels[4 * i + size_t(c)] * 255.0f), palette[pixels[i]][size_t(c)]);
}

// Print layers say their pixel size (pHYs, pixels per metre): 600 x 300 dpi here. The chunk comes
// before the image data and the image still decodes.
TEST(PngRowEncoder, WritesThePixelSize) {
  const std::vector<Rgba8> palette = {{0, 0, 0, 0}, {255, 255, 255, 255}};
  const std::vector<uint8_t> pixels = runsAndNoise(50, 4, 1, 2, 3);
  PngRowEncoder encoder(50, 4, 1, palette, {23622, 11811});
  for (int y = 0; y < 4; ++y) encoder.addRow(&pixels[size_t(y) * 50]);
  const std::vector<uint8_t> png = encoder.finish();
  const std::string bytes(png.begin(), png.end());
  const size_t at = bytes.find("pHYs");
  ASSERT_NE(at, std::string::npos);
  EXPECT_LT(at, bytes.find("IDAT"));
  // Length 9, the type, x = 23622 = 0x5c46 and y = 11811 = 0x2e23 pixels per metre, unit 1 (metre).
  const uint8_t expected[17] = {0, 0, 0, 9, 'p', 'H', 'Y', 's', 0, 0, 0x5c, 0x46, 0, 0, 0x2e, 0x23, 1};
  EXPECT_TRUE(std::equal(expected, expected + 17, png.begin() + std::ptrdiff_t(at) - 4));
  EXPECT_EQ(decodeImage(png, "phys.png").width, 50);
  const std::vector<uint8_t> plain = encode(pixels, 50, 4, 1, palette);
  EXPECT_EQ(std::string(plain.begin(), plain.end()).find("pHYs"), std::string::npos);
}

TEST(PngRowEncoder, RunsCompressAndBadUseIsRefused) {
  std::vector<uint8_t> row(5000, 3);
  PngRowEncoder encoder(5000, 200, 1, std::vector<Rgba8>(4, Rgba8{1, 2, 3, 255}));
  for (int y = 0; y < 200; ++y) encoder.addRow(row.data());
  // 1 MB of one colour: a literal and a copy per row (the filter byte breaks each row's run).
  EXPECT_LT(encoder.finish().size(), 10000u);
  EXPECT_NE(errorOf([] { PngRowEncoder(0, 10, 1, std::vector<Rgba8>(1)); }).find("out of range"), std::string::npos);
  EXPECT_NE(errorOf([] { PngRowEncoder(10, 10, 1, {}); }).find("colours"), std::string::npos);
  PngRowEncoder short_(4, 2, 3);
  const uint8_t pixels[12] = {};
  short_.addRow(pixels);
  EXPECT_NE(errorOf([&] { short_.finish(); }).find("1 of 2 rows"), std::string::npos);
}

TEST(PrintMaterials, FileFormsAndErrors) {
  TempDir dir;
  auto write = [&](const std::string& text) {
    std::ofstream(dir / "m.json") << text;
    return dir / "m.json";
  };
  const auto m = readPrintMaterials(write(R"({"materials": [{"name": "A", "color": "#ff8000"},
                                                            {"name": "B", "color": [0, 10, 20], "opacity": 0.5}]})"));
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].color, (Rgba8{255, 128, 0, 255}));
  EXPECT_EQ(m[1].opacity, 0.5);
  EXPECT_EQ(readPrintMaterials(write(R"([{"name": "W", "color": "#FFFFFF"}])")).size(), 1u);
  auto error = [&](const std::string& text) { return errorOf([&] { readPrintMaterials(write(text)); }); };
  EXPECT_NE(error(R"({"materials": []})").find("no materials"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "color": "#12345"}])").find("#RRGGBB"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "color": [0, 300, 0]}])").find("0-255"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "color": "#000000", "opacity": 2}])").find("opacity"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "color": "#000000"}, {"name": "a", "color": "#FFFFFF"}])").find("twice"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "color": "#000000", "opacity": 0}])").find("no opaque"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "colour": "#000000"}])").find("unknown field"), std::string::npos);
  EXPECT_NE(error("not json").find("not valid JSON"), std::string::npos);
  // Measured CIELAB (D50): white is white, a mid grey is sRGB's mid grey; outside sRGB is refused.
  const auto lab = readPrintMaterials(write(R"([{"name": "W", "lab": [100, 0, 0]}, {"name": "G", "lab": [50, 0, 0]}])"));
  EXPECT_EQ(lab[0].color, (Rgba8{255, 255, 255, 255}));
  EXPECT_EQ(lab[1].color, (Rgba8{119, 119, 119, 255}));
  EXPECT_NE(error(R"([{"name": "A", "lab": [50, 0, 0], "color": "#000000"}])").find("one of the two"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "lab": [60, 100, -120]}])").find("outside sRGB"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "lab": [120, 0, 0]}])").find("L outside"), std::string::npos);
  EXPECT_NE(error(R"([{"name": "A", "lab": [50, 0]}])").find("[L, a, b]"), std::string::npos);
  EXPECT_NE(errorOf([&] { readPrintMaterials(dir / "missing.json"); }).find("cannot open"), std::string::npos);
  EXPECT_EQ(findPrintMaterial(defaultPrintMaterials(), "white"), 4u);
  EXPECT_NE(errorOf([] { findPrintMaterial(defaultPrintMaterials(), "gold"); }).find("VeroCyan"), std::string::npos);
}

TEST(MaterialMixer, ReproducesColorsInsideTheGamut) {
  const std::vector<PrintMaterial> materials = defaultPrintMaterials();
  const MaterialMixer mixer(materials);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    // A random mix of the opaque materials is a colour they can print.
    float f[5], sum = 0, rgb[3] = {0, 0, 0};
    for (float& v : f) sum += (v = u(rng));
    for (int m = 0; m < 5; ++m)
      for (int c = 0; c < 3; ++c) rgb[c] += f[m] / sum * mixer.linearColor(m)[size_t(c)];
    const std::array<float, 3> got = mixer.reproduced(rgb);
    float fractions[16], total = 0;
    mixer.fractions(rgb, fractions);
    for (size_t m = 0; m < mixer.opaque().size(); ++m) {
      EXPECT_GE(fractions[m], -1e-6f);
      total += fractions[m];
    }
    EXPECT_NEAR(total, 1.0f, 1e-4f);
    for (int c = 0; c < 3; ++c) worst = std::max(worst, double(std::abs(got[size_t(c)] - rgb[c])));
  }
  EXPECT_LT(worst, 0.02);  // linear light
  // Greys mix without colour bias; a saturated red is the nearest printable colour (magenta + yellow).
  const float grey[3] = {0.3f, 0.3f, 0.3f};
  const std::array<float, 3> g = mixer.reproduced(grey);
  EXPECT_NEAR(g[0], 0.3f, 0.01f);
  EXPECT_NEAR(g[1], g[2], 0.01f);
  // Thresholds spread over [0, 1) pick each material in proportion to its fraction.
  const float rgba[4] = {0.5f, 0.2f, 0.7f, 1.0f};
  float fractions[16];
  mixer.fractions(rgba, fractions);
  std::vector<int> counts(materials.size(), 0);
  for (int i = 0; i < 10000; ++i) ++counts[size_t(mixer.pick(rgba, (float(i) + 0.5f) / 10000.0f))];
  for (size_t m = 0; m < mixer.opaque().size(); ++m) EXPECT_NEAR(counts[size_t(mixer.opaque()[m])] / 10000.0, fractions[m], 2e-4);
  // Transparent colours take the clear material for the part alpha leaves.
  const float half[4] = {1, 1, 1, 0.25f};
  int clear = 0;
  for (int i = 0; i < 1000; ++i) clear += mixer.pick(half, (float(i) + 0.5f) / 1000.0f) == 5;
  EXPECT_EQ(clear, 750);
}

// The dither the slice job uses (3-D blue noise, a function of position) against in-layer
// Floyd-Steinberg (the baseline) and white-noise thresholds, on a 64 x 48 x 64 block of shell voxels
// at 600 x 300 dpi and 0.027 mm, CMYKW, for a flat colour and a ramp through the printable colours.
TEST(DitherQuality, BlueNoiseBeatsTheBaselinesWhereTheyAreWeak) {
  const MaterialMixer mixer({{"C", {0, 255, 255, 255}}, {"M", {255, 0, 255, 255}}, {"Y", {255, 255, 0, 255}},
                             {"K", {0, 0, 0, 255}}, {"W", {255, 255, 255, 255}}});
  const DitherBox box{64, 48, 64, {25.4 / 600, 25.4 / 300, 0.027}};
  const BlueNoiseVolume noise = blueNoiseVolume(32, box.pitchMm);
  for (int ramp = 0; ramp < 2; ++ramp) {
    std::vector<float> target(3 * box.voxels());
    for (int z = 0; z < box.layers; ++z)
      for (int y = 0; y < box.height; ++y)
        for (int x = 0; x < box.width; ++x) {
          const size_t v = 3 * ((size_t(z) * size_t(box.height) + size_t(y)) * size_t(box.width) + size_t(x));
          const float u = float(x) / float(box.width), w = float(y) / float(box.height), t = float(z) / float(box.layers);
          target[v] = ramp ? 0.15f + 0.8f * u : 0.5f;
          target[v + 1] = ramp ? 0.2f + 0.6f * w : 0.3f;
          target[v + 2] = ramp ? 0.9f - 0.7f * t : 0.2f;
        }
    const std::vector<float> reference = reproducedColors(target, mixer);
    const std::vector<float> blue = ditherBox(box, target, mixer, DitherMode::BlueNoise, &noise);
    const std::vector<float> fs = ditherBox(box, target, mixer, DitherMode::FloydSteinberg, nullptr);
    std::vector<float> white(target.size());
    uint64_t state = 1;
    for (size_t v = 0; v < target.size(); v += 3) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const float rgba[4] = {target[v], target[v + 1], target[v + 2], 1.0f};
      const std::array<float, 3>& c = mixer.linearColor(mixer.pick(rgba, float(state >> 40) / 16777216.0f));
      std::copy(c.begin(), c.end(), &white[v]);
    }
    const BlockColorError blueBlocks = blockColorError(box, blue, reference), fsBlocks = blockColorError(box, fs, reference);
    const double blueXy = visibleError(box, blue, reference, false, 32), whiteXy = visibleError(box, white, reference, false, 32);
    const double blueXz = visibleError(box, blue, reference, true, 24), fsXz = visibleError(box, fs, reference, true, 24);
    std::printf("%s: 16^3 blocks blue %.4f (worst %.4f) FS %.4f (worst %.4f); in a layer blue %.4f white %.4f; "
                "side section blue %.4f FS %.4f\n",
                ramp ? "ramp" : "flat", blueBlocks.mean, blueBlocks.worst, fsBlocks.mean, fsBlocks.worst, blueXy, whiteXy,
                blueXz, fsXz);
    EXPECT_LT(blueBlocks.mean, fsBlocks.mean);    // regions average to their colour better
    EXPECT_LT(blueBlocks.worst, 0.02);            // and no block is far off
    EXPECT_LT(blueXz, 0.7 * fsXz);                // FS's layers are uncorrelated: a side wall shows it
    EXPECT_LT(blueXy, 0.6 * whiteXy);             // a layer alone is blue, not white
  }
}

TEST(BlueNoise, IsAPermutationSpreadEvenlyAndRepeatable) {
  const Eigen::Vector3d pitch(0.0423, 0.0847, 0.027);
  const BlueNoiseVolume a = blueNoiseVolume(16, pitch);
  std::vector<uint32_t> sorted = a.rank;
  std::sort(sorted.begin(), sorted.end());
  for (uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  EXPECT_EQ(blueNoiseVolume(16, pitch).rank, a.rank);
  // The 10 % lowest thresholds: spread evenly, the counts in blocks vary much less than for white
  // noise, in the volume (4^3 blocks) and within each layer (4 x 4 blocks of every layer).
  auto blockSpread = [](auto&& isSet, int blockZ, int layers) {
    double sum = 0, sum2 = 0;
    int blocks = 0;
    for (int bz = 0; bz < layers; bz += blockZ)
      for (int by = 0; by < 16; by += 4)
        for (int bx = 0; bx < 16; bx += 4, ++blocks) {
          int n = 0;
          for (int z = bz; z < bz + blockZ; ++z)
            for (int y = by; y < by + 4; ++y)
              for (int x = bx; x < bx + 4; ++x) n += isSet(x, y, z);
          sum += n;
          sum2 += double(n) * n;
        }
    return std::sqrt(sum2 / blocks - (sum / blocks) * (sum / blocks));
  };
  std::mt19937 rng(1);
  std::vector<uint8_t> white(4096);
  for (uint8_t& v : white) v = rng() % 10 == 0;
  auto blueSet = [&](int x, int y, int z) { return a.threshold(x, y, z) < 0.1f; };
  auto whiteSet = [&](int x, int y, int z) { return white[size_t(x + 16 * (y + 16 * z))] != 0; };
  const double blue3 = blockSpread(blueSet, 4, 16), white3 = blockSpread(whiteSet, 4, 16);
  const double blue2 = blockSpread(blueSet, 1, 16), white2 = blockSpread(whiteSet, 1, 16);
  EXPECT_LT(blue3, 0.65 * white3) << "volume: blue " << blue3 << ", white " << white3;
  EXPECT_LT(blue2, 0.65 * white2) << "layers: blue " << blue2 << ", white " << white2;
  std::printf("spread of the 10 %% lowest: volume blue %.2f white %.2f; layers blue %.2f white %.2f\n", blue3, white3,
              blue2, white2);
  EXPECT_NE(errorOf([&] { blueNoiseVolume(20, pitch); }).find("size"), std::string::npos);
}

} // namespace
} // namespace texfab::print

namespace {

// CIEDE2000 against Sharma, Wu and Dalal's test pairs (2005, table 1), and CIELAB's white points.
TEST(ColorDifference, MatchesSharmasTestPairsAndWhite) {
  using texfab::print::Lab;
  const struct {
    Lab a, b;
    double expected;
  } pairs[] = {
      {{50.0000, 2.6772, -79.7751}, {50.0000, 0.0000, -82.7485}, 2.0425},
      {{50.0000, 0.0000, 0.0000}, {50.0000, -1.0000, 2.0000}, 2.3669},
      {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0009}, 7.1792},
      {{50.0000, 2.5000, 0.0000}, {73.0000, 25.0000, -18.0000}, 27.1492},
      {{60.2574, -34.0099, 36.2677}, {60.4626, -34.1751, 39.4387}, 1.2644},
  };
  for (const auto& p : pairs) {
    EXPECT_NEAR(texfab::print::deltaE2000(p.a, p.b), p.expected, 1e-4);
    EXPECT_NEAR(texfab::print::deltaE2000(p.b, p.a), p.expected, 1e-4);
  }
  const Lab white = texfab::print::labFromLinearSrgb({1, 1, 1});
  EXPECT_NEAR(white[0], 100, 1e-3);
  EXPECT_NEAR(white[1], 0, 1e-2);
  EXPECT_NEAR(white[2], 0, 1e-2);
  for (double c : texfab::print::linearSrgbFromLabD50({100, 0, 0})) EXPECT_NEAR(c, 1.0, 2e-3);
  // A measured mid grey stays grey and keeps its lightness.
  const auto grey = texfab::print::linearSrgbFromLabD50({50, 0, 0});
  EXPECT_NEAR(texfab::print::labFromLinearSrgb(grey)[0], 50, 0.05);
}

} // namespace
