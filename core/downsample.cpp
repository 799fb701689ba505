// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/downsample.h"

#include "core/error.h"

#include <algorithm>
#include <string>

namespace texfab {

Image downsample(const Image& image, int factor) {
  if (factor < 1) throw Error("downsample: factor must be at least 1, got " + std::to_string(factor));
  if (factor == 1) return image;
  const int w = std::max(1, image.width / factor), h = std::max(1, image.height / factor);
  const int fx = std::min(factor, image.width), fy = std::min(factor, image.height);
  Image out(w, h, image.channels, image.format);
  const float norm = 1.0f / float(fx * fy);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* o = out.pixel(x, y);
      for (int j = 0; j < fy; ++j)
        for (int i = 0; i < fx; ++i) {
          const float* p = image.pixel(x * fx + i, y * fy + j);
          for (int c = 0; c < image.channels; ++c) o[c] += p[c];
        }
      for (int c = 0; c < image.channels; ++c) o[c] *= norm;
    }
  return out;
}

} // namespace texfab
