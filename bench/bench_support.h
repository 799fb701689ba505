// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Pieces the benchmark programs share.

#include "core/crop.h"
#include "core/image_io.h"

#include <sys/resource.h>

#include <algorithm>
#include <filesystem>

namespace texfab::bench {

/// GIMP's marble1 (128^2, bundled as models/exemplars/marble.png), or its top-left side x side crop.
inline Image marbleExemplar(int side) {
  static const Image marble = readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/exemplars/marble.png");
  return crop(marble, 0, 0, side, side);
}

/// `image` magnified (bilinear, pixel centres aligned) to side x side.
inline Image magnified(const Image& image, int side) {
  Image out(side, side, image.channels, image.format);
  const double stepX = double(image.width) / side, stepY = double(image.height) / side;
  for (int y = 0; y < side; ++y) {
    const double v = std::clamp((y + 0.5) * stepY - 0.5, 0.0, double(image.height - 1));
    const int y0 = std::min(int(v), image.height - 2);
    const float fy = float(v - y0);
    for (int x = 0; x < side; ++x) {
      const double u = std::clamp((x + 0.5) * stepX - 0.5, 0.0, double(image.width - 1));
      const int x0 = std::min(int(u), image.width - 2);
      const float fx = float(u - x0);
      for (int c = 0; c < image.channels; ++c)
        out.at(x, y, c) = (1 - fy) * ((1 - fx) * image.at(x0, y0, c) + fx * image.at(x0 + 1, y0, c)) +
                          fy * ((1 - fx) * image.at(x0, y0 + 1, c) + fx * image.at(x0 + 1, y0 + 1, c));
    }
  }
  return out;
}

/// Peak resident memory of this process so far, in MiB (Linux reports KiB).
inline double peakMemoryMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

} // namespace texfab::bench
