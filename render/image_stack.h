// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A stack of images (the slices of a volume, the layers of a print) written into a new folder as
// slice_00000.png, slice_00001.png, ... and, optionally, all of them in order as one raw file of
// 8-bit RGB. The folder and the raw file are outputs of an OutputSet: they appear, with the job's
// other outputs, only once the whole stack is written, and never in part.

#include "core/files.h"
#include "core/image.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace texfab::render {

struct ImageStackOptions {
  std::string prefix = "slice_";   ///< file names: prefix + index (zero-padded) + extension
  int digits = 5;                  ///< zero-padding of the index
  std::string extension = ".png";  ///< any format writeImage writes
  /// Also write every image, in order, as raw 8-bit RGB (x fastest, then y, then image); grey
  /// images are repeated over R, G and B. Empty: no raw file.
  std::filesystem::path raw;
};

class ImageStackWriter {
public:
  /// Reserves `folder` (new, or empty) and the raw file in `outputs`, checking both now.
  ImageStackWriter(OutputSet& outputs, const std::filesystem::path& folder, ImageStackOptions options = {});
  /// Writes the next image of the stack; all must have the same size.
  void write(const Image& image);
  /// Completes the raw file (throws texfab::Error naming it on a failed write). Call before
  /// committing the outputs.
  void finish();
  int count() const { return count_; }

private:
  ImageStackOptions options_;
  std::filesystem::path folder_;
  std::ofstream raw_;
  int count_ = 0, width_ = 0, height_ = 0;
};

} // namespace texfab::render
