// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/image/image_io.h"

#include "render/image/error.h"
#include "render/image/files.h"
#include "render/image/memory.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <mutex>
#include <cstring>
#include <iterator>
#include <system_error>

namespace texfab {
namespace fs = std::filesystem;

namespace {

// OIIO error texts can span several lines, often repeating one another ("Read error: hit end of
// file", then "PNG read error: IDAT: Read error: hit end of file"); texfab errors are one line:
// the lines no other line contains, joined by "; ".
std::string oneLine(const std::string& text) {
  std::vector<std::string> lines;
  for (size_t begin = 0; begin < text.size();) {
    const size_t end = std::min(text.find('\n', begin), text.size());
    std::string line = text.substr(begin, end - begin);
    while (!line.empty() && line.back() == ' ') line.pop_back();
    if (!line.empty()) lines.push_back(std::move(line));
    begin = end + 1;
  }
  std::string joined;
  for (size_t i = 0; i < lines.size(); ++i) {
    bool repeated = false;
    for (size_t j = 0; j < lines.size() && !repeated; ++j)
      repeated = j != i && lines[j].find(lines[i]) != std::string::npos && (lines[j] != lines[i] || j < i);
    if (!repeated) joined += (joined.empty() ? "" : "; ") + lines[i];
  }
  return joined.empty() ? std::string("unknown error") : joined;
}

// Image libraries under OIIO print their own diagnostics on stderr ("libpng error: ..."); texfab
// says what went wrong in its one-line error. While an image is decoded, stderr goes to /dev/null
// (one decode at a time: the redirection is process-wide).
class QuietStderr {
public:
  QuietStderr() : lock_(mutex()) {
    std::fflush(stderr);
    saved_ = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    std::fflush(stderr);
    if (saved_ >= 0) {
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  int saved_ = -1;
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

uint32_t readBigEndian32(const uint8_t* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}

void checkSize(int64_t width, int64_t height, const std::string& name) {
  if (width <= 0 || height <= 0)
    throw Error(name + ": image has no pixels (" + std::to_string(width) + "x" +
                std::to_string(height) + ")");
  if (width > kMaxImageSide || height > kMaxImageSide)
    throw Error(name + ": image is " + std::to_string(width) + "x" + std::to_string(height) +
                ", larger than the supported " + std::to_string(kMaxImageSide) + " per side");
}

Image readPatFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open file");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decodePat(bytes, path.string());
}

PixelFormat formatOf(OIIO::TypeDesc type) {
  switch (type.basetype) {
  case OIIO::TypeDesc::UINT8:
  case OIIO::TypeDesc::INT8: return PixelFormat::UInt8;
  case OIIO::TypeDesc::UINT16:
  case OIIO::TypeDesc::INT16: return PixelFormat::UInt16;
  default: return PixelFormat::Float;
  }
}

} // namespace

Image decodePat(std::span<const uint8_t> bytes, const std::string& name) {
  // GIMP pattern, version 1: six big-endian uint32 (header size, version, width, height,
  // bytes per pixel, magic "GPAT"), a NUL-terminated name filling the header, then raw pixels.
  constexpr size_t kFixedHeader = 24;
  if (bytes.size() < kFixedHeader) throw Error(name + ": not a GIMP pattern (file too short)");
  const uint32_t headerSize = readBigEndian32(bytes.data());
  const uint32_t version = readBigEndian32(bytes.data() + 4);
  const uint32_t width = readBigEndian32(bytes.data() + 8);
  const uint32_t height = readBigEndian32(bytes.data() + 12);
  const uint32_t depth = readBigEndian32(bytes.data() + 16);
  if (std::memcmp(bytes.data() + 20, "GPAT", 4) != 0)
    throw Error(name + ": not a GIMP pattern (no GPAT magic)");
  if (version != 1) throw Error(name + ": unsupported GIMP pattern version " + std::to_string(version));
  if (depth < 1 || depth > 4)
    throw Error(name + ": GIMP pattern has " + std::to_string(depth) + " bytes per pixel (expected 1-4)");
  if (headerSize < kFixedHeader || headerSize > bytes.size())
    throw Error(name + ": corrupt GIMP pattern header (header size " + std::to_string(headerSize) + ")");
  checkSize(width, height, name);
  const size_t expected = size_t(width) * height * depth;
  const size_t available = bytes.size() - headerSize;
  if (available < expected)
    throw Error(name + ": truncated pattern data (expected " + std::to_string(expected) +
                " bytes, found " + std::to_string(available) + ")");
  Image image(int(width), int(height), int(depth), PixelFormat::UInt8);
  const uint8_t* data = bytes.data() + headerSize;
  // The same conversion as OpenImageIO's, so a pattern and its PNG copy give identical values.
  for (size_t i = 0; i < expected; ++i) image.pixels[i] = float(data[i]) * (1.0f / 255.0f);
  return image;
}

namespace {

// Texture data: alpha kept unassociated (as stored), never premultiplied.
OIIO::ImageSpec readConfig() {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  return config;
}

Image decode(OIIO::ImageInput& in, const std::string& name) {
  const OIIO::ImageSpec& spec = in.spec();
  checkSize(spec.width, spec.height, name);
  if (spec.depth > 1) throw Error(name + ": volume images are not supported");
  if (spec.nchannels < 1) throw Error(name + ": image has no channels");
  const uint64_t bytes = uint64_t(spec.width) * uint64_t(spec.height) * uint64_t(spec.nchannels) * sizeof(float);
  if (bytes > physicalMemoryBytes() / 2)
    throw Error(name + ": image is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                ", too large to load in this machine's memory");
  Image image(spec.width, spec.height, spec.nchannels, formatOf(spec.format));
  if (!in.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()))
    throw Error(name + ": cannot decode image: " + oneLine(in.geterror()));
  return image;
}

} // namespace

std::optional<ImageCodec> imageCodecOf(std::span<const uint8_t> b) {
  auto starts = [&](std::initializer_list<uint8_t> magic) {
    return b.size() >= magic.size() && std::equal(magic.begin(), magic.end(), b.begin());
  };
  if (starts({0x89, 'P', 'N', 'G'})) return ImageCodec::Png;
  if (starts({0xff, 0xd8, 0xff})) return ImageCodec::Jpeg;
  if (b.size() >= 12 && starts({'R', 'I', 'F', 'F'}) && std::equal(b.begin() + 8, b.begin() + 12, "WEBP")) return ImageCodec::Webp;
  return std::nullopt;
}

const char* mimeTypeOf(ImageCodec codec) {
  switch (codec) {
  case ImageCodec::Png: return "image/png";
  case ImageCodec::Jpeg: return "image/jpeg";
  case ImageCodec::Webp: return "image/webp";
  }
  return "";
}

const char* extensionOf(ImageCodec codec) {
  switch (codec) {
  case ImageCodec::Png: return ".png";
  case ImageCodec::Jpeg: return ".jpg";
  case ImageCodec::Webp: return ".webp";
  }
  return "";
}

Image readImage(const fs::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(name + ": no such file");
  if (fs::is_directory(path, ec)) throw Error(name + ": is a directory, not an image");
  if (lower(path.extension().string()) == ".pat") return readPatFile(path);
  const OIIO::ImageSpec config = readConfig();
  const QuietStderr quiet;
  auto in = OIIO::ImageInput::open(name, &config);
  if (!in) throw Error(name + ": cannot read image: " + oneLine(OIIO::geterror()));
  return decode(*in, name);
}

Image decodeImage(std::span<const uint8_t> bytes, const std::string& name) {
  const std::optional<ImageCodec> codec = imageCodecOf(bytes);
  if (!codec) throw Error(name + ": not a PNG, JPEG or WebP image");
  OIIO::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
  const std::string pseudoName = std::string("memory") + extensionOf(*codec);
  OIIO::ImageSpec config = readConfig();
  // OIIO 2.4 ignores open()'s proxy argument when a configuration is given; the hint carries it.
  void* proxyPointer = &proxy;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxyPointer);
  const QuietStderr quiet;
  auto in = OIIO::ImageInput::open(pseudoName, &config, &proxy);
  if (!in) throw Error(name + ": cannot decode image: " + oneLine(OIIO::geterror()));
  return decode(*in, name);
}

void checkImageWritable(const fs::path& path) {
  const std::string name = path.string();
  if (path.filename().empty() || path.extension().empty())
    throw Error(name + ": output needs a file name with an image extension (.png, .exr, ...)");
  if (!OIIO::ImageOutput::create(name)) throw Error(name + ": no image writer for this file extension");
  checkOutputLocation(path);
}

void writeImage(const Image& image, const fs::path& path) {
  const std::string name = path.string();
  checkSize(image.width, image.height, name);
  if (image.channels < 1 || image.pixels.size() != image.index(0, image.height))
    throw Error(name + ": refusing to write an inconsistent image buffer");
  auto out = OIIO::ImageOutput::create(name);
  if (!out) throw Error(name + ": no image writer for this file extension");
  checkOutputLocation(path);  // says why a folder cannot be written (OIIO does not)

  const std::string ext = lower(path.extension().string());
  OIIO::TypeDesc type = OIIO::TypeDesc::UINT8;
  if (ext == ".exr" || ext == ".hdr") type = OIIO::TypeDesc::FLOAT;
  else if (image.format != PixelFormat::UInt8 && (ext == ".png" || ext == ".tif" || ext == ".tiff"))
    type = OIIO::TypeDesc::UINT16;
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
  if (ext == ".png") spec.attribute("png:compressionLevel", 6);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // our alpha is not premultiplied

  const fs::path tmp = temporaryPathFor(path);
  if (!out->open(tmp.string(), spec))
    throw Error(name + ": cannot create file: " + oneLine(out->geterror()));
  const bool written = out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
  const bool closed = out->close();
  if (!written || !closed) {
    discardTemporary(tmp);
    throw Error(name + ": cannot write image: " + oneLine(out->geterror()));
  }
  commitFile(tmp, path);
}

std::vector<uint8_t> encodeImage(const Image& image, ImageCodec codec, int quality) {
  const char* format = codec == ImageCodec::Png ? "PNG" : codec == ImageCodec::Jpeg ? "JPEG" : "WebP";
  if (image.empty() || image.channels < 1 || image.channels > 4 || image.pixels.size() != image.index(0, image.height))
    throw Error("cannot encode an image with " + std::to_string(image.channels) + " channels as " + format);
  checkSize(image.width, image.height, format);
  if (codec == ImageCodec::Webp && image.channels < 3) {  // WebP is RGB(A) only: grey becomes RGB
    Image color(image.width, image.height, image.channels + 2, image.format);
    for (size_t i = 0, n = size_t(image.width) * size_t(image.height); i < n; ++i) {
      const float* from = image.pixels.data() + i * size_t(image.channels);
      float* to = color.pixels.data() + i * size_t(color.channels);
      to[0] = to[1] = to[2] = from[0];
      if (image.channels == 2) to[3] = from[1];
    }
    return encodeImage(color, codec, quality);
  }
  // JPEG: no alpha (grey+alpha -> grey, RGBA -> RGB).
  const int channels = codec == ImageCodec::Jpeg && (image.channels == 2 || image.channels == 4) ? image.channels - 1
                                                                                                   : image.channels;
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  const std::string pseudoName = std::string("memory") + extensionOf(codec);
  auto out = OIIO::ImageOutput::create(pseudoName, &proxy);
  if (!out) throw Error(std::string(format) + " encoding is not available");
  OIIO::ImageSpec spec(image.width, image.height, channels, OIIO::TypeDesc::UINT8);
  if (codec == ImageCodec::Png) spec.attribute("png:compressionLevel", 6);
  else spec.attribute("CompressionQuality", std::clamp(quality, 1, 100));
  spec.attribute("oiio:UnassociatedAlpha", 1);
  void* proxyPointer = &proxy;
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxyPointer);
  const OIIO::stride_t pixelStride = OIIO::stride_t(image.channels * sizeof(float));
  if (!out->open(pseudoName, spec) ||
      !out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data(), pixelStride) || !out->close())
    throw Error(std::string(format) + " encoding failed: " + oneLine(out->geterror()));
  if (bytes.empty()) throw Error(std::string(format) + " encoding produced no bytes");
  return {bytes.begin(), bytes.end()};
}

} // namespace texfab
