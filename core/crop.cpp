// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/crop.h"

#include "core/error.h"

#include <algorithm>
#include <string>

namespace texfab {

Image crop(const Image& image, int x0, int y0, int width, int height) {
  if (width < 1 || height < 1 || x0 < 0 || y0 < 0 || x0 > image.width - width || y0 > image.height - height)
    throw Error("cannot crop " + std::to_string(width) + "x" + std::to_string(height) + " at (" + std::to_string(x0) +
                ", " + std::to_string(y0) + ") from a " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + " image");
  Image out(width, height, image.channels, image.format);
  const size_t row = size_t(width) * size_t(image.channels);
  for (int y = 0; y < height; ++y) std::copy_n(image.pixel(x0, y0 + y), row, out.pixel(0, y));
  return out;
}

} // namespace texfab
