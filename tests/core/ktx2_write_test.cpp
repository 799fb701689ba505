// SPDX-License-Identifier: GPL-3.0-or-later
// The UASTC block encoder and the KTX2 writer, read back by a real reader: three.js's Basis
// Universal transcoder (tests/core/ktx2_transcode.mjs, the npm package three installed by
// scripts/install-deps.sh into .tools/, or found through $TEXFAB_THREE = a node_modules folder).
// Those tests skip cleanly without node or three.
#include "core/error.h"
#include "core/ktx2_write.h"
#include "core/uastc_encode.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <zstd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace texfab {
namespace {

using test::TempDir;

/// A MIP chain whose every level is drawn directly from fn(u, v, level, channel) at its own size
/// (as texfab's filtered chains are: not box averages of the level above).
std::vector<Image> chain(int width, int height, int count, const std::function<float(float, float, int, int)>& fn) {
  std::vector<Image> levels;
  for (int i = 0; i < count; ++i) {
    Image image(std::max(1, width >> i), std::max(1, height >> i), 3);
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        for (int c = 0; c < 3; ++c)
          image.at(x, y, c) = fn((float(x) + 0.5f) / float(image.width), (float(y) + 0.5f) / float(image.height), i, c);
    levels.push_back(std::move(image));
  }
  return levels;
}

// metallicRoughness data: R unused (0), G (roughness) and B (metallic) smooth, unrelated fields
// whose features span the whole image at every level.
float smooth(float u, float v, int level, int c) {
  const float l = 0.05f * float(level);  // levels differ a little, as widened roughness does
  switch (c) {
  case 0: return 0.0f;
  case 1: return std::min(1.0f, 0.15f + l + 0.6f * u * u * (3.0f - 2.0f * u) + 0.1f * v);
  default: return 0.2f + 0.6f * (0.5f + 0.5f * std::cos(3.0f * u + 2.0f * v));
  }
}

float noise(float u, float v, int level, int c) {
  uint32_t h = uint32_t(u * 65536.0f) * 73856093u ^ uint32_t(v * 65536.0f) * 19349663u ^ uint32_t(level * 3 + c) * 83492791u;
  h ^= h >> 13, h *= 0x5bd1e995u, h ^= h >> 15;
  return float(h & 0xFFFF) / 65535.0f;
}

uint8_t unorm8(float v) { return uint8_t(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); }

/// The pixels our own decoder gives for a level.
std::vector<uint8_t> decodeOwn(const Image& level) {
  return uastc::decodeImage(uastc::encodeImage(level), level.width, level.height);
}

struct LevelError {
  double mean = 0;  ///< mean absolute error over R, G, B, in 8-bit steps
  int max = 0;
};

LevelError compare(const Image& source, const std::string& rgba) {
  LevelError e;
  for (int y = 0; y < source.height; ++y)
    for (int x = 0; x < source.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const int d = std::abs(int(uint8_t(rgba[(size_t(y) * size_t(source.width) + size_t(x)) * 4 + size_t(c)])) - int(unorm8(source.at(x, y, c))));
        e.mean += d, e.max = std::max(e.max, d);
      }
  e.mean /= double(source.width) * source.height * 3;
  return e;
}

/// Writes the chain as KTX2, transcodes it with three, and checks every level: its size, alpha
/// 255, the same pixels as our decoder, and the error against the source within bound(level).
void readBackWithThree(const std::string& name, const std::vector<Image>& levels, const std::function<LevelError(const Image&)>& bound,
                       const Ktx2Options& options = {}) {
  TempDir dir("texfab-ktx2");
  const std::filesystem::path file = dir / (name + ".ktx2");
  const std::vector<uint8_t> bytes = encodeKtx2Uastc(levels, options);
  {
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(file.c_str(), "wb"), &std::fclose);
    ASSERT_TRUE(f);
    ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), f.get()), bytes.size());
  }
  const std::string report = test::transcode(file, dir / "level");
  std::string expected = "\"ok\":true,\"uastc\":true,\"hasAlpha\":false,\"width\":" + std::to_string(levels[0].width) +
                         ",\"height\":" + std::to_string(levels[0].height) + ",\"levels\":[";
  for (size_t i = 0; i < levels.size(); ++i)
    expected += std::string(i ? "," : "") + "{\"width\":" + std::to_string(levels[i].width) + ",\"height\":" + std::to_string(levels[i].height) +
                ",\"bytes\":" + std::to_string(levels[i].width * levels[i].height * 4) + "}";
  ASSERT_NE(report.find(expected), std::string::npos) << "expected " << expected << "\ngot " << report.substr(report.size() - std::min<size_t>(report.size(), 2000));
  for (size_t i = 0; i < levels.size(); ++i) {
    SCOPED_TRACE(name + " level " + std::to_string(i));
    const std::string rgba = test::readFile(dir / ("level" + std::to_string(i) + ".rgba"));
    ASSERT_EQ(rgba.size(), size_t(levels[i].width) * size_t(levels[i].height) * 4);
    const std::vector<uint8_t> own = decodeOwn(levels[i]);
    ASSERT_EQ(0, std::memcmp(own.data(), rgba.data(), own.size())) << "three's transcoder and decodeBlock disagree";
    for (size_t p = 3; p < rgba.size(); p += 4) ASSERT_EQ(uint8_t(rgba[p]), 255);
    const LevelError e = compare(levels[i], rgba);
    std::cout << "[ ktx2     ] " << name << " level " << i << " " << levels[i].width << "x" << levels[i].height << ": mean abs error "
              << e.mean << ", max " << e.max << " (8-bit steps)\n";
    EXPECT_LE(e.mean, bound(levels[i]).mean);
    EXPECT_LE(e.max, bound(levels[i]).max);
  }
}

class ThreeTranscoder : public ::testing::Test {
protected:
  void SetUp() override {
    if (const std::string missing = test::threeMissing(); !missing.empty()) GTEST_SKIP() << missing;
  }
};

// Smooth data is what UASTC's one-subset modes are for. The error follows how much the fields
// change across one 4x4 block: where a block spans at most 1/8 of the features (levels 32 pixels
// wide and more) the mean stays under 2/255 and no value is off by more than 8 (measured: mean
// 0.05 to 0.87, max 2 to 7). On the coarse levels a block spans much of the field, and G and B
// vary unrelatedly inside it: mode 0 fits a line, dual-plane mode 6 only 4 weight levels per
// plane (measured: mean up to 5.2, max 18); bound 6 and 24.
LevelError smoothBound(const Image& level) { return level.width >= 32 ? LevelError{2.0, 8} : LevelError{6.0, 24}; }

TEST_F(ThreeTranscoder, SmoothChainDecodesCloseToTheSource) {
  readBackWithThree("smooth", chain(256, 128, 9, smooth), smoothBound);
  // Not a power of two: levels 20x12, 10x6, 5x3, 2x1, 1x1 (partial blocks padded).
  readBackWithThree("smooth-odd", chain(20, 12, 5, smooth), smoothBound);
  // Zstandard supercompression: the transcoder inflates each level to the same blocks.
  readBackWithThree("smooth-zstd", chain(256, 128, 9, smooth), smoothBound, Ktx2Options{.zstdLevel = 9});
}

// White noise is the worst case for one line (or two planes) per 4x4 block: the decode must still
// match ours bit for bit; the error is only bounded loosely (measured: mean 24 to 27, max 153).
TEST_F(ThreeTranscoder, NoisyChainDecodesExactlyAsOurDecoder) {
  readBackWithThree("noise", chain(64, 64, 7, noise), [](const Image&) { return LevelError{40.0, 255}; });
}

TEST(Uastc, SolidBlocksAreExact) {
  for (int v : {0, 1, 77, 128, 254, 255}) {
    uastc::Texels t{};
    for (size_t i = 0; i < 16; ++i) t[4 * i] = uint8_t(v), t[4 * i + 1] = uint8_t(255 - v), t[4 * i + 2] = uint8_t(v / 3), t[4 * i + 3] = 255;
    const uastc::Block b = uastc::encodeBlock(t);
    EXPECT_EQ(uastc::blockMode(b), 8);
    uastc::Texels d{};
    ASSERT_TRUE(uastc::decodeBlock(b, d));
    EXPECT_EQ(d, t);
  }
}

TEST(Uastc, DecodingAnImageCropsItsBlocksAndChecksThem) {
  std::vector<uint8_t> black(5 * 3 * 4, 0);
  for (size_t p = 3; p < black.size(); p += 4) black[p] = 255;
  const std::vector<uint8_t> blocks = uastc::encodeImage(Image(5, 3, 3));
  EXPECT_EQ(uastc::decodeImage(blocks, 5, 3), black);
  EXPECT_THROW(uastc::decodeImage(blocks, 9, 3), Error);
  std::vector<uint8_t> reserved(blocks.size(), 0xFF);
  EXPECT_THROW(uastc::decodeImage(reserved, 5, 3), Error);
}

TEST(Uastc, RampsAreNearlyExactAndEveryModeIsUsed) {
  std::array<int, 19> modes{};
  uint32_t seed = 12345;
  const auto next = [&] { return (seed = seed * 1664525u + 1013904223u) >> 24; };
  for (int n = 0; n < 2000; ++n) {
    // A ramp between two random colours, with a little noise on some blocks; or just the two
    // colours (which mode 5's 8-bit endpoints give exactly).
    const int a[3] = {int(next()), int(next()), int(next())}, b[3] = {int(next()), int(next()), int(next())};
    const bool twoColours = n % 4 == 1;
    const int spread = n % 4 < 2 ? 0 : int(next() % 24);
    uastc::Texels t{};
    for (int i = 0; i < 16; ++i) {
      for (int c = 0; c < 3; ++c)
        t[size_t(4 * i + c)] = uint8_t(twoColours ? (i % 3 ? a[c] : b[c])
                                                  : std::clamp(a[c] + (b[c] - a[c]) * i / 15 + (spread ? int(next() % uint32_t(spread)) - spread / 2 : 0), 0, 255));
      t[size_t(4 * i + 3)] = 255;
    }
    const uastc::Block block = uastc::encodeBlock(t);
    ++modes[size_t(uastc::blockMode(block))];
    uastc::Texels d{};
    ASSERT_TRUE(uastc::decodeBlock(block, d));
    int worst = 0;
    for (size_t i = 0; i < 64; ++i) worst = std::max(worst, std::abs(int(d[i]) - int(t[i])));
    EXPECT_LE(worst, twoColours ? 0 : spread ? spread + 12 : 6) << "block " << n;
    EXPECT_EQ(uastc::encodeBlock(t), block);  // deterministic
  }
  EXPECT_GT(modes[0], 0);
  EXPECT_GT(modes[5], 0);
  EXPECT_GT(modes[18], 0);
  EXPECT_GT(modes[6], 0);
}

uint32_t get32(const std::vector<uint8_t>& f, size_t at) {
  return uint32_t(f[at]) | uint32_t(f[at + 1]) << 8 | uint32_t(f[at + 2]) << 16 | uint32_t(f[at + 3]) << 24;
}
uint64_t get64(const std::vector<uint8_t>& f, size_t at) { return get32(f, at) | uint64_t(get32(f, at + 4)) << 32; }

TEST(Ktx2, LayoutFollowsTheSpecification) {
  const std::vector<Image> levels = chain(16, 8, 5, smooth);
  const std::vector<uint8_t> f = encodeKtx2Uastc(levels);
  const uint8_t id[12] = {0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};
  ASSERT_EQ(0, std::memcmp(f.data(), id, 12));
  EXPECT_EQ(get32(f, 12), 0u);   // vkFormat
  EXPECT_EQ(get32(f, 16), 1u);   // typeSize
  EXPECT_EQ(get32(f, 20), 16u);  // width
  EXPECT_EQ(get32(f, 24), 8u);   // height
  EXPECT_EQ(get32(f, 36), 1u);   // faceCount
  EXPECT_EQ(get32(f, 40), 5u);   // levelCount
  EXPECT_EQ(get32(f, 44), 0u);   // supercompression
  const uint32_t dfd = get32(f, 48);
  EXPECT_EQ(dfd, 80u + 5 * 24);
  EXPECT_EQ(get32(f, 52), 44u);
  EXPECT_EQ(get32(f, dfd), 44u);
  EXPECT_EQ(get32(f, dfd + 12) & 0xFFFFFFu, 166u | (0u << 8) | (1u << 16));  // UASTC, unspecified primaries, linear
  EXPECT_EQ(get32(f, dfd + 28) >> 24, 0u);                                    // KHR_DF_CHANNEL_UASTC_RGB
  const uint32_t kvd = get32(f, 56), kvdBytes = get32(f, 60);
  EXPECT_EQ(kvd, dfd + 44);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&f[kvd + 4])), "KTXwriter");
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&f[kvd + 14])), "texfab");
  uint64_t previous = f.size();
  for (size_t i = 0; i < 5; ++i) {
    const uint64_t offset = get64(f, 80 + 24 * i), length = get64(f, 88 + 24 * i);
    const uint64_t blocks = uint64_t((levels[i].width + 3) / 4) * uint64_t((levels[i].height + 3) / 4);
    EXPECT_EQ(offset % 16, 0u);
    EXPECT_GE(offset, kvd + kvdBytes);
    EXPECT_EQ(length, blocks * 16);
    EXPECT_EQ(get64(f, 96 + 24 * i), length);
    EXPECT_LE(offset + length, previous);  // smaller levels come first in the file
    previous = offset;
  }
  EXPECT_EQ(get64(f, 80) + get64(f, 88), f.size());
  Ktx2Options colour;
  colour.srgb = true;
  const std::vector<uint8_t> g = encodeKtx2Uastc(levels, colour);
  EXPECT_EQ(get32(g, dfd + 12) & 0xFFFFFFu, 166u | (1u << 8) | (2u << 16));  // BT.709, sRGB

  // Zstandard: scheme 2, each level's bytes inflate to the uncompressed file's, whose length the
  // index keeps as uncompressedByteLength; levels follow one another without padding.
  const std::vector<uint8_t> z = encodeKtx2Uastc(levels, Ktx2Options{.zstdLevel = 9});
  EXPECT_EQ(get32(z, 44), 2u);
  EXPECT_EQ(get32(z, 52), 44u);
  EXPECT_EQ(get64(z, 72), 0u);  // no supercompression global data
  for (size_t i = 0; i < 5; ++i) {
    const uint64_t offset = get64(z, 80 + 24 * i), length = get64(z, 88 + 24 * i), raw = get64(z, 96 + 24 * i);
    EXPECT_EQ(raw, get64(f, 88 + 24 * i));
    std::vector<uint8_t> inflated(raw);
    ASSERT_EQ(ZSTD_decompress(inflated.data(), inflated.size(), &z[offset], length), raw);
    EXPECT_EQ(0, std::memcmp(inflated.data(), &f[get64(f, 80 + 24 * i)], raw)) << "level " << i;
    if (i > 0) {
      EXPECT_EQ(offset + length, get64(z, 80 + 24 * (i - 1)));
    }
  }
  EXPECT_EQ(get64(z, 80) + get64(z, 88), z.size());
}

TEST(Ktx2, SameInputSameBytes) {
  const std::vector<Image> levels = chain(64, 32, 7, noise);
  const std::vector<uint8_t> a = encodeKtx2Uastc(levels), b = encodeKtx2Uastc(levels);
  EXPECT_EQ(a, b);
  uint64_t h = 1469598103934665603ull;  // FNV-1a: any change of the encoder's output shows here
  for (uint8_t v : a) h = (h ^ v) * 1099511628211ull;
  std::cout << "[ ktx2     ] noise 64x32 chain hash " << std::hex << h << std::dec << "\n";
}

std::string refusal(const std::vector<Image>& levels, const Ktx2Options& options = {}) {
  try {
    encodeKtx2Uastc(levels, options);
  } catch (const Error& e) {
    return e.what();
  }
  return "accepted";
}

TEST(Ktx2, BadInputIsRefusedWithAClearError) {
  EXPECT_EQ(refusal({}), "KTX2: no MIP levels");
  EXPECT_EQ(refusal(chain(6, 8, 1, smooth)), "KTX2: base level 6x8 is not a multiple of 4 (KHR_texture_basisu requires it)");
  Ktx2Options free;
  free.gltf = false;
  EXPECT_EQ(refusal(chain(6, 7, 3, smooth), free), "accepted");
  std::vector<Image> skip = chain(16, 16, 3, smooth);
  skip[2] = Image(3, 4, 3);
  EXPECT_EQ(refusal(skip), "KTX2: MIP level 2 is 3x4, expected 4x4");
  std::vector<Image> tooMany = chain(8, 4, 4, smooth);
  tooMany.push_back(tooMany.back());
  EXPECT_EQ(refusal(tooMany), "KTX2: 5 MIP levels for a 8x4 base (at most 4)");
  EXPECT_EQ(refusal(chain(8, 8, 1, smooth), Ktx2Options{.zstdLevel = 99}),
            "KTX2: Zstandard level 99 is out of range (0 to " + std::to_string(ZSTD_maxCLevel()) + ")");
  std::vector<Image> nan = chain(8, 8, 2, smooth);
  nan[1].at(1, 0, 2) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(refusal(nan), "KTX2: MIP level 1: UASTC: non-finite value at pixel 1");
  EXPECT_EQ(refusal({Image(4, 4, 2)}), "KTX2: MIP level 0: UASTC: 2-channel image (1, 3 or 4 channels expected)");
  Image alpha(4, 4, 4);
  for (int i = 0; i < 16; ++i) alpha.at(i % 4, i / 4, 3) = 1.0f;
  alpha.at(2, 1, 3) = 0.5f;
  EXPECT_EQ(refusal({alpha}), "KTX2: MIP level 0: UASTC: alpha below 1 at pixel 6 (only opaque RGB is encoded)");
}

} // namespace
} // namespace texfab
