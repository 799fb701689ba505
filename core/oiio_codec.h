// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The OpenImageIO half of image IO (image_io.h), built as a module of its own (texfab_oiio) that
// image_io.cpp loads on the first image it reads or writes. OpenImageIO brings ~260 shared
// libraries, and loading them costs ~0.5 s of CPU at every start of a program that links it;
// most runs of texfab (--help, a usage error, a mesh-only command) and most tests decode no image.
// Errors cross the boundary as texfab::Error.

#include "core/error.h"
#include "core/image.h"
#include "core/image_io.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace texfab::detail {

/// The module's entry points (one table, found by the symbol kOiioCodecSymbol).
struct OiioCodec {
  /// The image file `name` (not a GIMP pattern). Refuses an image of more than maxBytes as floats.
  Image (*read)(const std::string& name, uint64_t maxBytes);
  /// Encoded bytes whose file extension is that of `pseudoName` ("memory.png"); `name` in errors.
  Image (*decode)(std::span<const uint8_t> bytes, const std::string& pseudoName, const std::string& name,
                  uint64_t maxBytes);
  /// Whether OIIO has a writer for the extension of `name`.
  bool (*canWrite)(const std::string& name);
  /// Writes `image` to the file `file` (format by the extension of `name`, named in errors).
  void (*write)(const Image& image, const std::string& file, const std::string& name);
  /// The image as 8-bit file bytes in the format of the extension of `pseudoName`, `channels` of
  /// the image's (the first ones); quality for lossy formats (1..100). `format` names it in errors.
  std::vector<uint8_t> (*encode)(const Image& image, int channels, const std::string& pseudoName, int quality,
                                 const std::string& format);
};

inline constexpr const char* kOiioCodecSymbol = "texfab_oiio_codec";
using OiioCodecEntry = const OiioCodec* (*)();

/// Throws texfab::Error unless width x height is a size texfab reads and writes.
inline void checkImageSize(int64_t width, int64_t height, const std::string& name) {
  if (width <= 0 || height <= 0)
    throw Error(name + ": image has no pixels (" + std::to_string(width) + "x" + std::to_string(height) + ")");
  if (width > kMaxImageSide || height > kMaxImageSide)
    throw Error(name + ": image is " + std::to_string(width) + "x" + std::to_string(height) +
                ", larger than the supported " + std::to_string(kMaxImageSide) + " per side");
}

} // namespace texfab::detail
