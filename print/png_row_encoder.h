// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A PNG encoder for images made of long runs of identical pixels (print layers: empty space, core
// material, and the dithered shell), fed one row at a time, so that a layer never has to be held
// whole. The general-purpose encoders (zlib through OpenImageIO or libpng, libdeflate) search for
// matches at every byte and spend 30-190 ms on a 1526 x 1509 layer; this one codes each run of
// identical pixels as one literal pixel and a copy at the distance of one pixel (deflate's
// fixed Huffman codes, RFC 1951 §3.2.6), the way a run-length encoder would, in well under 1 ms
// for such a layer. Noise (the dithered shell) is coded as literals (8-9 bits per byte): files are
// larger than zlib's where the shell is thick, never by more than 13 % of the raw size.
//
// Output: a valid PNG (ISO/IEC 15948): IHDR, PLTE and tRNS for indexed images, pHYs when the
// pixel size is given, IDAT chunks of a
// zlib stream (RFC 1950) with filter type 0 on every row, IEND. Bytes depend only on the pixels.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace texfab::print {

using Rgba8 = std::array<uint8_t, 4>;

class PngRowEncoder {
public:
  /// `channels`: 1 (palette indices, with `palette` of 1-256 colours; alpha < 255 is written as
  /// transparency), 3 (RGB) or 4 (RGBA), 8 bits each. Throws texfab::Error for sizes out of range
  /// (1 to 2^24 per side) or a bad palette. `pixelsPerMetre` (x, y), when not zero, is written as
  /// the pixels' physical size (pHYs), so that viewers and printer software know the print's scale.
  PngRowEncoder(int width, int height, int channels, std::span<const Rgba8> palette = {},
                std::array<uint32_t, 2> pixelsPerMetre = {0, 0});

  /// Appends the next row (top first): width * channels bytes. Palette indices must be in range.
  void addRow(const uint8_t* pixels);
  /// The PNG file; all `height` rows must have been added.
  std::vector<uint8_t> finish();

  int width() const { return width_; }
  int height() const { return height_; }

private:
  void put(uint32_t bits, int count);
  void literal(uint8_t byte);
  void copy(int64_t length);  // bytes at distance channels_
  void adlerLiterals(const uint8_t* bytes, int64_t n);
  void adlerRun(const uint8_t* pixel, int64_t n);

  int width_, height_, channels_;
  int rows_ = 0;
  std::vector<uint8_t> header_;   // signature, IHDR, PLTE, tRNS
  std::vector<uint8_t> stream_;   // the zlib stream
  uint64_t bitBuffer_ = 0;
  int bitCount_ = 0;
  uint32_t adlerA_ = 1, adlerB_ = 0;
};

} // namespace texfab::print
