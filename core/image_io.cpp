// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/image_io.h"

#include "core/error.h"
#include "core/files.h"
#include "core/memory.h"
#include "core/oiio_codec.h"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <system_error>

namespace texfab {
namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

uint32_t readBigEndian32(const uint8_t* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}

// Every image texfab reads is synthesis data (an exemplar, a companion map, coordinates) or is
// compared with it: a pixel that is not a number would spread through every neighbourhood it meets.
Image finiteOnly(Image image, const std::string& name) {
  const auto bad = std::count_if(image.pixels.begin(), image.pixels.end(), [](float v) { return !std::isfinite(v); });
  if (bad > 0)
    throw Error(name + ": " + std::to_string(bad) + " pixel value" + (bad > 1 ? "s are" : " is") +
                " not a finite number (NaN or infinity)");
  return image;
}

Image readPatFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open file");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decodePat(bytes, path.string());
}

// The OpenImageIO module (oiio_codec.h), loaded on first use: from the build tree, else from the
// folder of the running program, else from the folder of the binary that holds this code (the
// installed Python module).
const detail::OiioCodec& oiio() {
  static const detail::OiioCodec* codec = [] {
    const fs::path name = fs::path(TEXFAB_OIIO_MODULE).filename();
    std::vector<std::string> candidates{TEXFAB_OIIO_MODULE};
    std::error_code ec;
    const fs::path program = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) candidates.push_back((program.parent_path() / name).string());
    Dl_info self{};
    if (::dladdr(reinterpret_cast<const void*>(&oiio), &self) != 0 && self.dli_fname)
      candidates.push_back((fs::path(self.dli_fname).parent_path() / name).string());
    std::string why;
    for (const std::string& path : candidates) {
      if (void* module = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) {
        if (void* entry = ::dlsym(module, detail::kOiioCodecSymbol))
          return reinterpret_cast<detail::OiioCodecEntry>(entry)();
        why = path + " has no " + detail::kOiioCodecSymbol;
      } else if (why.empty()) {
        why = ::dlerror();
      }
    }
    throw Error("image support is not available: " + why);
  }();
  return *codec;
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
  detail::checkImageSize(width, height, name);
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
  return finiteOnly(oiio().read(name, physicalMemoryBytes() / 2), name);
}

Image decodeImage(std::span<const uint8_t> bytes, const std::string& name) {
  const std::optional<ImageCodec> codec = imageCodecOf(bytes);
  if (!codec) throw Error(name + ": not a PNG, JPEG or WebP image");
  return finiteOnly(oiio().decode(bytes, std::string("memory") + extensionOf(*codec), name, physicalMemoryBytes() / 2), name);
}

void checkImageWritable(const fs::path& path) {
  const std::string name = path.string();
  if (path.filename().empty() || path.extension().empty())
    throw Error(name + ": output needs a file name with an image extension (.png, .exr, ...)");
  if (!oiio().canWrite(name)) throw Error(name + ": no image writer for this file extension");
  checkOutputLocation(path);
}

void writeImage(const Image& image, const fs::path& path) {
  const std::string name = path.string();
  detail::checkImageSize(image.width, image.height, name);
  if (image.channels < 1 || image.pixels.size() != image.index(0, image.height))
    throw Error(name + ": refusing to write an inconsistent image buffer");
  if (!oiio().canWrite(name)) throw Error(name + ": no image writer for this file extension");
  checkOutputLocation(path);  // says why a folder cannot be written (OIIO does not)
  const fs::path tmp = temporaryPathFor(path);
  try {
    oiio().write(image, tmp.string(), name);
  } catch (...) {
    discardTemporary(tmp);
    throw;
  }
  commitFile(tmp, path);
}

std::vector<uint8_t> encodeImage(const Image& image, ImageCodec codec, int quality) {
  const char* format = codec == ImageCodec::Png ? "PNG" : codec == ImageCodec::Jpeg ? "JPEG" : "WebP";
  if (image.empty() || image.channels < 1 || image.channels > 4 || image.pixels.size() != image.index(0, image.height))
    throw Error("cannot encode an image with " + std::to_string(image.channels) + " channels as " + format);
  detail::checkImageSize(image.width, image.height, format);
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
  return oiio().encode(image, channels, std::string("memory") + extensionOf(codec), quality, format);
}

} // namespace texfab
