// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/image_stack.h"

#include "core/error.h"
#include "core/image_io.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <vector>

namespace texfab::render {
namespace fs = std::filesystem;

ImageStackWriter::ImageStackWriter(OutputSet& outputs, const fs::path& folder, ImageStackOptions options)
    : options_(std::move(options)) {
  folder_ = outputs.addFolder(folder);
  checkImageWritable(folder_ / (options_.prefix + options_.extension));
  if (!options_.raw.empty()) {
    const fs::path staged = outputs.add(options_.raw);
    raw_.open(staged, std::ios::binary);
    if (!raw_) throw Error(systemError(options_.raw, "cannot create file", errno));
  }
}

void ImageStackWriter::write(const Image& image) {
  if (count_ == 0) width_ = image.width, height_ = image.height;
  if (image.width != width_ || image.height != height_)
    throw Error("image stack: image " + std::to_string(count_) + " differs in size from the first");
  char index[32];
  std::snprintf(index, sizeof index, "%0*d", options_.digits, count_);
  writeImage(image, folder_ / (options_.prefix + index + options_.extension));
  if (raw_.is_open()) {
    const size_t pixels = size_t(image.width) * size_t(image.height);
    std::vector<uint8_t> bytes(pixels * 3);
    for (size_t i = 0; i < pixels; ++i)
      for (int c = 0; c < 3; ++c) {
        const float v = image.pixels[i * size_t(image.channels) + size_t(std::min(c, image.channels - 1))];
        bytes[i * 3 + size_t(c)] = uint8_t(std::lrint(std::clamp(v, 0.0f, 1.0f) * 255.0f));
      }
    raw_.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  }
  ++count_;
}

void ImageStackWriter::finish() {
  if (!raw_.is_open()) return;
  raw_.flush();
  const bool ok = bool(raw_);
  const int err = errno;
  raw_.close();
  if (!ok) throw Error(systemError(options_.raw, "cannot write file", err));
}

} // namespace texfab::render
