// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Small helpers shared by the synthesis tests.

#include "render/image.h"
#include "synthesis/hash.h"

#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace texfab::test {

/// A fresh, empty folder for one test, removed by the destructor.
class TempDir {
public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("texfab-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter()++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
  static int& counter() {
    static int c = 0;
    return c;
  }
  std::filesystem::path path_;
};

/// A w x h RGB image of hashed noise: every pixel different, no structure.
inline Image noiseImage(int w, int h, uint32_t seed = 7) {
  Image image(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        image.at(x, y, c) = float(synthesis::texelHash(seed, uint32_t(c), x, y, 0) & 255u) / 255.0f;
  return image;
}

/// GIMP's pattern folder (Debian gimp-data).
inline std::filesystem::path gimpPatterns() { return "/usr/share/gimp/2.0/patterns"; }

/// Runs a shell command; returns its exit status.
inline int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

} // namespace texfab::test
