// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/crop.h"
#include "core/downsample.h"
#include "core/error.h"
#include "core/image_io.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace texfab {
namespace {

using test::TempDir;

Image gradient(int w, int h, int c, PixelFormat f) {
  Image image(w, h, c, f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k) image.at(x, y, k) = float((x * 7 + y * 13 + k * 29) % 256) / 255.0f;
  return image;
}

void expectNear(const Image& a, const Image& b, float tolerance) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.channels, b.channels);
  for (size_t i = 0; i < a.pixels.size(); ++i) ASSERT_NEAR(a.pixels[i], b.pixels[i], tolerance) << "value " << i;
}

TEST(ImageIo, LosslessFormatsRoundTripEveryChannelCount) {
  TempDir dir;
  for (int channels : {1, 2, 3, 4})
    for (const char* ext : {".png", ".tga", ".tif", ".exr"}) {
      SCOPED_TRACE(std::string(ext) + " with " + std::to_string(channels) + " channels");
      const Image image = gradient(37, 21, channels, PixelFormat::UInt8);
      const auto path = dir / ("img" + std::to_string(channels) + ext);
      writeImage(image, path);
      const Image back = readImage(path);
      expectNear(back, image, 1e-3f);
    }
}

TEST(ImageIo, SixteenBitPngKeepsSixteenBits) {
  TempDir dir;
  Image image(256, 4, 1, PixelFormat::UInt16);
  for (int x = 0; x < 256; ++x)
    for (int y = 0; y < 4; ++y) image.at(x, y, 0) = float(x * 256 + y) / 65535.0f;
  writeImage(image, dir / "h.png");
  const Image back = readImage(dir / "h.png");
  EXPECT_EQ(back.format, PixelFormat::UInt16);
  for (int x = 0; x < 256; ++x)
    for (int y = 0; y < 4; ++y) ASSERT_EQ(std::lround(back.at(x, y, 0) * 65535.0f), x * 256 + y);
}

TEST(ImageIo, FloatExrKeepsValuesOutsideZeroOne) {
  TempDir dir;
  Image image(3, 2, 3, PixelFormat::Float);
  image.pixels = {-1.5f, 0.0f, 2.25f, 1000.0f, 0.125f, 3.0f, 7.0f, 8.0f, 9.0f, 0.5f, 0.25f, 65535.0f,
                  1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f};
  writeImage(image, dir / "f.exr");
  const Image back = readImage(dir / "f.exr");
  EXPECT_EQ(back.format, PixelFormat::Float);
  EXPECT_EQ(back.pixels, image.pixels);
}

// An EXR holding NaN or infinity is refused with one line naming the file and the count;
// synthesis never sees it.
TEST(ImageIo, RefusesValuesThatAreNotFiniteNumbers) {
  TempDir dir;
  Image image(4, 4, 3, PixelFormat::Float);
  for (const char* name : {"nan.exr", "inf.exr"}) {
    image.pixels.assign(image.pixels.size(), 0.5f);
    image.pixels[7] = std::string(name) == "nan.exr" ? NAN : INFINITY;
    image.pixels[9] = -INFINITY;
    writeImage(image, dir / name);
    std::string message;
    try {
      readImage(dir / name);
    } catch (const Error& e) {
      message = e.what();
    }
    EXPECT_NE(message.find((dir / name).string() + ": 2 pixel values are not a finite number"), std::string::npos)
        << message;
  }
}

// A file whose extension names another format than its bytes is read by the format its signature
// names (a JPEG saved as .png), as OpenImageIO's own fallback would, without trying every reader.
TEST(ImageIo, AFileIsReadByItsSignatureWhenItsExtensionLies) {
  TempDir dir;
  Image image(16, 8, 3);
  for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = float(i % 17) / 16.0f;
  writeImage(image, dir / "a.jpg");
  std::filesystem::copy_file(dir / "a.jpg", dir / "a.png");
  EXPECT_EQ(readImage(dir / "a.png").pixels, readImage(dir / "a.jpg").pixels);
  std::ofstream(dir / "b.png", std::ios::binary) << "II*" << std::string(40, '\0');  // a TIFF signature, no TIFF
  EXPECT_THROW(readImage(dir / "b.png"), Error);
}

// A few corrupt bytes of EXR header must not make OpenEXR allocate what they claim.
TEST(ImageIo, RefusesAnExrHeaderThatClaimsMoreThanTheFileHolds) {
  TempDir dir;
  writeImage(Image(8, 4, 3), dir / "a.exr");
  std::ifstream in(dir / "a.exr", std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_NO_THROW(readImage(dir / "a.exr"));
  // The message readImage gives once `value` is written at `offset` after the attribute's type.
  auto corrupt = [&](const std::string& attribute, size_t offset, int32_t value) {
    std::string bytes = good;
    const size_t at = bytes.find(attribute + '\0');
    EXPECT_NE(at, std::string::npos) << attribute;
    const size_t sizeField = bytes.find('\0', at + attribute.size() + 1) + 1;
    std::memcpy(&bytes[sizeField + offset], &value, 4);
    std::ofstream(dir / "b.exr", std::ios::binary) << bytes;
    try {
      readImage(dir / "b.exr");
      ADD_FAILURE() << attribute << " corrupted, yet read";
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(corrupt("dataWindow", 4 + 12, 60000).find("corrupt EXR: its header names"), std::string::npos);
  EXPECT_NE(corrupt("channels", 0, 1 << 30).find("corrupt EXR: its attribute 'channels' runs past"), std::string::npos);
  // A data window wider than texfab reads, refused before OpenEXR allocates its line buffers.
  EXPECT_NE(corrupt("dataWindow", 4 + 8, 8388616).find("larger than the supported 65536 per side"), std::string::npos);
}

// The error reading `path` throws; a test failure when it reads.
std::string readError(const std::filesystem::path& path) {
  try {
    readImage(path);
    ADD_FAILURE() << path << " was read";
  } catch (const Error& e) {
    return e.what();
  }
  return {};
}

// A GIF whose header claims a 65535x65535 screen in 40 bytes (named .png: read by its signature) is
// refused before a decoder allocates it (OpenImageIO decodes the first frame when it opens a GIF).
TEST(ImageIo, RefusesAGifThatClaimsMorePixelsThanItsBytesHold) {
  std::string gif = "GIF89a\xff\xff\xff\xff\x80";
  gif.resize(40, '\0');
  TempDir dir;
  std::ofstream(dir / "huge.png", std::ios::binary) << gif;
  const std::string error = readError(dir / "huge.png");
  EXPECT_NE(error.find("corrupt gif: it claims 65535x65535 pixels, more than its 40 bytes"), std::string::npos) << error;
}

// A TIFF whose 122 bytes claim 43x19722 pixels of 769 channels (650 MB, 2.6 GB as floats; found by
// the image_file fuzz target, 6 s and 2.2 GB before) is refused before any decoding; so are strips
// whose positions and sizes disagree in number (a heap corruption in OpenImageIO 2.4) or that lie
// past the file's end.
TEST(ImageIo, RefusesTiffsThatClaimMoreThanTheirBytesHold) {
  std::string tiff = std::string("II*\0", 4) + std::string("\x08\0\0\0", 4);
  const auto put16 = [&](uint32_t v) { tiff += char(v & 0xff), tiff += char(v >> 8); };
  const auto put32 = [&](uint32_t v) { put16(v & 0xffff), put16(v >> 16); };
  // tag, type (3 SHORT, 4 LONG), count, value: one zip-compressed strip of `stripBytes` at byte 122.
  const auto write = [&](uint32_t channels, uint32_t sizesCount, uint32_t stripBytes) {
    tiff.resize(8);
    const std::vector<std::array<uint32_t, 4>> entries = {
        {256, 3, 1, 43}, {257, 3, 1, 19722}, {258, 3, 1, 8},        {259, 3, 1, 8},         {262, 3, 1, 2},
        {273, 4, 1, 122}, {277, 3, 1, channels}, {278, 3, 1, 19722}, {279, 4, sizesCount, stripBytes}};
    put16(uint32_t(entries.size()));
    for (const auto& [tag, type, count, value] : entries) {
      put16(tag), put16(type), put32(count);
      type == 3 ? (put16(value), put16(0)) : put32(value);
    }
    put32(0);  // no next directory
    EXPECT_EQ(tiff.size(), 122u);
    TempDir dir;
    std::ofstream(dir / "t.tif", std::ios::binary) << tiff;
    return readError(dir / "t.tif");
  };
  EXPECT_NE(write(769, 1, 0).find("corrupt tiff: it claims 43x19722 pixels of 769 channels, more than its 122 bytes"),
            std::string::npos);
  EXPECT_NE(write(3, 33, 0).find("corrupt TIFF: it states 1 strip positions but 33 strip sizes"), std::string::npos);
  EXPECT_NE(write(3, 1, 100).find("corrupt TIFF: its strip 1 of 1 lies past the end of the file"), std::string::npos);
}

TEST(ImageIo, JpegReadsBackClose) {
  TempDir dir;
  Image image(64, 64, 3);
  for (float& v : image.pixels) v = 0.5f;
  writeImage(image, dir / "a.jpg");
  expectNear(readImage(dir / "a.jpg"), image, 0.02f);
}

TEST(ImageIo, DecodesGimpPattern) {
  // Header: size 28 (24 + "ab\0" padded to 4), version 1, 2x1, 3 bytes per pixel, "GPAT", "ab\0\0".
  const std::vector<uint8_t> bytes = {0, 0, 0, 28, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0, 3,
                                      'G', 'P', 'A', 'T', 'a', 'b', 0, 0, 255, 0, 0, 0, 51, 255};
  const Image image = decodePat(bytes, "test.pat");
  ASSERT_EQ(image.width, 2);
  ASSERT_EQ(image.height, 1);
  ASSERT_EQ(image.channels, 3);
  const std::vector<float> expected = {1.0f, 0.0f, 0.0f, 0.0f, 0.2f, 1.0f};
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_FLOAT_EQ(image.pixels[i], expected[i]);
}

TEST(ImageIo, ReadsRealGimpPatterns) {
  const auto brick = test::gimpPatterns() / "Stone" / "brick.pat";
  ASSERT_TRUE(std::filesystem::exists(brick)) << "gimp-data is not installed (scripts/install-deps.sh)";
  const Image image = readImage(brick);
  EXPECT_EQ(image.width, 96);
  EXPECT_EQ(image.height, 96);
  EXPECT_EQ(image.channels, 3);
  // The bundled PNG is the same pattern.
  EXPECT_EQ(readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/exemplars/brick.png").pixels,
            image.pixels);
}

TEST(ImageIo, RejectsBrokenPatterns) {
  std::vector<uint8_t> good = {0, 0, 0, 24, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 1,
                               'G', 'P', 'A', 'T', 1, 2, 3, 4};
  EXPECT_NO_THROW(decodePat(good, "ok.pat"));
  auto truncated = good;
  truncated.pop_back();
  EXPECT_THROW(decodePat(truncated, "t.pat"), Error);
  auto badMagic = good;
  badMagic[20] = 'X';
  EXPECT_THROW(decodePat(badMagic, "m.pat"), Error);
  auto zeroSize = good;
  zeroSize[11] = 0;
  EXPECT_THROW(decodePat(zeroSize, "z.pat"), Error);
  auto huge = good;
  huge[9] = 0x10;  // width 2^20 + 2
  EXPECT_THROW(decodePat(huge, "h.pat"), Error);
  auto badHeader = good;
  badHeader[3] = 200;  // header larger than the file
  EXPECT_THROW(decodePat(badHeader, "b.pat"), Error);
  EXPECT_THROW(decodePat(std::vector<uint8_t>(10, 0), "short.pat"), Error);
}

TEST(ImageIo, ErrorsNameTheFile) {
  TempDir dir;
  { std::ofstream(dir / "notimage.png") << "this is not a PNG file"; }
  try {
    readImage(dir / "notimage.png");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("notimage.png"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line: " << e.what();
  }
  EXPECT_THROW(readImage(dir / "missing.png"), Error);
  EXPECT_THROW(readImage(dir.path()), Error);
}

TEST(ImageIo, FailedWriteLeavesNoFile) {
  TempDir dir;
  EXPECT_THROW(writeImage(gradient(4, 4, 3, PixelFormat::UInt8), dir / "no-such-folder" / "x.png"), Error);
  EXPECT_THROW(writeImage(gradient(4, 4, 3, PixelFormat::UInt8), dir / "x.unknownext"), Error);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

// OpenImageIO (and its ~260 libraries) is loaded by the first image read, not at the program's
// start (checked when this is the process's first test, as under ctest).
bool openImageIoLoaded() {
  std::ifstream maps("/proc/self/maps");
  for (std::string line; std::getline(maps, line);)
    if (line.find("libOpenImageIO.so") != std::string::npos) return true;
  return false;
}

TEST(ImageIo, OpenImageIoIsLoadedByTheFirstImageRead) {
  const auto* unit = ::testing::UnitTest::GetInstance();
  // (gtest counts the running test as successful)
  if (unit->successful_test_count() + unit->failed_test_count() + unit->skipped_test_count() > 1)
    GTEST_SKIP() << "not the first test of this process";
  ASSERT_FALSE(openImageIoLoaded());
  TempDir dir;
  const std::filesystem::path png = dir / "x.png";
  { std::ofstream(png) << "not a png"; }
  EXPECT_THROW(readImage(png), Error);
  EXPECT_TRUE(openImageIoLoaded());
}

// A crop copies the rectangle, every channel, and keeps the format; a rectangle outside is refused.
TEST(Crop, CopiesTheRectangleAndRefusesOneOutside) {
  const Image image = gradient(7, 5, 3, PixelFormat::UInt16);
  const Image part = crop(image, 2, 1, 4, 3);
  ASSERT_EQ(part.width, 4);
  ASSERT_EQ(part.height, 3);
  EXPECT_EQ(part.format, PixelFormat::UInt16);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(part.at(x, y, c), image.at(x + 2, y + 1, c));
  EXPECT_EQ(crop(image, 0, 0, 7, 5).pixels, image.pixels);
  EXPECT_THROW(crop(image, 4, 0, 4, 1), Error);
  EXPECT_THROW(crop(image, -1, 0, 2, 2), Error);
  EXPECT_THROW(crop(image, 0, 0, 0, 2), Error);
}

// Each output pixel is the mean of its block, every channel; a remainder row or column is dropped;
// factor 1 is the image itself; factor 0 is refused.
TEST(Downsample, AveragesBlocksAndDropsTheRemainder) {
  Image image(5, 3, 2, PixelFormat::UInt16);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) {
      image.at(x, y, 0) = float(x + 10 * y);
      image.at(x, y, 1) = 1.0f;
    }
  const Image half = downsample(image, 2);
  ASSERT_EQ(half.width, 2);
  ASSERT_EQ(half.height, 1);
  EXPECT_EQ(half.format, PixelFormat::UInt16);
  EXPECT_FLOAT_EQ(half.at(0, 0, 0), (0 + 1 + 10 + 11) / 4.0f);
  EXPECT_FLOAT_EQ(half.at(1, 0, 0), (2 + 3 + 12 + 13) / 4.0f);
  EXPECT_FLOAT_EQ(half.at(1, 0, 1), 1.0f);
  EXPECT_EQ(downsample(image, 1).pixels, image.pixels);
  EXPECT_THROW(downsample(image, 0), Error);
}

} // namespace
} // namespace texfab
