// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Pieces the benchmark programs share.

#include "render/image/image_io.h"

#include <sys/resource.h>

#include <filesystem>

namespace texfab::bench {

/// GIMP's marble1 (128^2, bundled as models/exemplars/marble.png), or its top-left side x side crop.
inline Image marbleExemplar(int side) {
  static const Image marble = readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/exemplars/marble.png");
  Image out(side, side, marble.channels, marble.format);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      for (int c = 0; c < marble.channels; ++c) out.at(x, y, c) = marble.at(x, y, c);
  return out;
}

/// Peak resident memory of this process so far, in MiB (Linux reports KiB).
inline double peakMemoryMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

} // namespace texfab::bench
