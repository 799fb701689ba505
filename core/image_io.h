// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Reading and writing images. Reading goes through OpenImageIO (PNG, JPEG, TGA, TIFF, EXR, and
// whatever else the installed OIIO reads) plus GIMP patterns (.pat), which OIIO does not read.
// Writing: PNG (8 or 16 bit), EXR (half or float), and any other format OIIO writes by extension.
// Every function throws texfab::Error with a one-line message naming the file on failure.

#include "core/image.h"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace texfab {

/// Largest accepted width or height of any image texfab reads or writes.
inline constexpr int kMaxImageSide = 65536;

/// Reads an image. Grey, grey+alpha, RGB and RGBA are kept as 1, 2, 3, 4 channels; more channels
/// are kept as they are. `format` is set from the file's precision. Refuses an image holding a
/// value that is not a finite number (a float image's NaN or infinity).
Image readImage(const std::filesystem::path& path);

/// Decodes a PNG, JPEG or WebP image held in memory (e.g. embedded in a model file); `name` is
/// used in errors.
Image decodeImage(std::span<const uint8_t> bytes, const std::string& name);

/// Decodes a GIMP pattern (.pat, format version 1) held in memory; `name` is used in errors.
Image decodePat(std::span<const uint8_t> bytes, const std::string& name);

/// Writes `image`. The format follows the extension; for PNG the bit depth is 16 when
/// image.format is UInt16 or Float, else 8. Writes to a temporary file in the same folder first,
/// then renames it, so a failed write never leaves a partial file under `path`.
void writeImage(const Image& image, const std::filesystem::path& path);

/// Throws texfab::Error unless an image can be written to `path`: a known image extension and an
/// existing folder. Commands call it before long work so a bad output path fails at once.
void checkImageWritable(const std::filesystem::path& path);

/// The image file formats models embed or reference (glTF core: PNG and JPEG; WebP through
/// EXT_texture_webp).
enum class ImageCodec { Png, Jpeg, Webp };

/// The codec of encoded bytes, from their signature; nothing when they are none of the three.
std::optional<ImageCodec> imageCodecOf(std::span<const uint8_t> bytes);
const char* mimeTypeOf(ImageCodec codec);  ///< "image/png", "image/jpeg", "image/webp"
const char* extensionOf(ImageCodec codec); ///< ".png", ".jpg", ".webp"

/// An image file held in memory, as read (so that it can be written again without re-encoding).
struct EncodedImage {
  std::vector<uint8_t> bytes;
  ImageCodec codec = ImageCodec::Png;
};

/// The image as file bytes, 8 bits per channel: PNG (lossless, zlib level 6), JPEG or WebP at
/// `quality` (1..100). JPEG has no alpha: a second or fourth channel is dropped.
std::vector<uint8_t> encodeImage(const Image& image, ImageCodec codec, int quality = 90);
inline std::vector<uint8_t> encodePng(const Image& image) { return encodeImage(image, ImageCodec::Png); }

} // namespace texfab
