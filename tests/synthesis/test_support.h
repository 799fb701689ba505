// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Small helpers shared by the synthesis tests (plus tests/test_support.h).

#include "core/hash.h"
#include "core/image.h"
#include "tests/test_support.h"

#include <filesystem>

namespace texfab::test {

/// A w x h RGB image of hashed noise: every pixel different, no structure.
inline Image noiseImage(int w, int h, uint32_t seed = 7) {
  Image image(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        image.at(x, y, c) = float(texelHash(seed, uint32_t(c), x, y, 0) & 255u) / 255.0f;
  return image;
}


} // namespace texfab::test
