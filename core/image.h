// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// texfab's one image type: interleaved float channels, row-major, top row first.
// Values are the file's normalized values (0..1 for 8/16-bit files; as stored for float files),
// with no colour-space conversion. `format` remembers the precision an image came from, so that
// writing it back keeps 16-bit height maps 16-bit and 8-bit photos 8-bit.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace texfab {

enum class PixelFormat : uint8_t { UInt8, UInt16, Float };

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  PixelFormat format = PixelFormat::UInt8;
  std::vector<float> pixels; ///< width * height * channels values

  Image() = default;
  Image(int w, int h, int c, PixelFormat f = PixelFormat::UInt8)
      : width(w), height(h), channels(c), format(f),
        pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(c), 0.0f) {}

  bool empty() const { return pixels.empty(); }
  size_t index(int x, int y) const {
    return (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) *
           static_cast<size_t>(channels);
  }
  float* pixel(int x, int y) { return pixels.data() + index(x, y); }
  const float* pixel(int x, int y) const { return pixels.data() + index(x, y); }
  float& at(int x, int y, int c) { return pixels[index(x, y) + static_cast<size_t>(c)]; }
  float at(int x, int y, int c) const { return pixels[index(x, y) + static_cast<size_t>(c)]; }
};

} // namespace texfab
