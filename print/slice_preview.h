// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A picture of a slice run for a person to check before printing: the print seen from the front
// (looking along +y) and from the side (along +x), each pixel the mean colour of the voxels it
// covers (as the eye averages the dither at a normal viewing distance) shaded by the surface's
// slope, and four layers side by side below: as dithered (one voxel per pixel, the materials) and,
// under them, as the eye sees the mixed print (the materials' colours low-passed by a Gaussian of
// 0.1 mm, about one arc minute at 30 cm), all at print scale (square millimetres).
// Collected while the layers are rendered, in memory proportional to the picture, not the print.

#include "core/image.h"
#include "print/print_grid.h"
#include "print/voxelize_layers.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace texfab::print {

class SlicePreview {
public:
  /// For layers [firstLayer, firstLayer + layerCount) of `grid`; views `width` pixels wide.
  SlicePreview(const print::PrintGrid& grid, int firstLayer, int layerCount, int width = 640);

  /// Image row r of `layer` (rows top first, each layer's rows from one thread in order; layers
  /// may run on different threads): its inside spans and the RGBA8 of all its voxels.
  void addRow(int layer, int r, std::span<const print::VoxelSpan> spans, const uint8_t* rgba);

  /// The picture: front and side views above, four layers below (dithered, then as seen); sRGB
  /// (8 bits) on a grey ground.
  Image compose() const;

  /// Shown layer k (0-3) at one pixel per `thumbStep` voxels, linear RGB on the ground: as
  /// dithered (a voxel per pixel) or, `seen`, as the eye sees the mixed print (the materials'
  /// linear colours low-passed by a Gaussian of 0.1 mm at the print's pitch).
  Image shownLayer(int k, bool seen) const;

  /// The layers shown below the views.
  const std::array<int, 4>& shownLayers() const { return shown_; }

private:
  struct Sample {
    float rgb[3] = {0, 0, 0};
    float depth = -1;  // mm from the view's near side; < 0: nothing there
  };
  Image view(const std::vector<Sample>& samples, int columns, double columnMm) const;

  print::PrintGrid grid_;
  int first_, count_, width_;
  int frontStep_, sideStep_;                 // voxels per stored column
  int frontColumns_, sideColumns_;
  std::vector<Sample> front_, side_;         // count_ x columns
  std::vector<std::vector<Sample>> scratch_; // per layer being rendered: the front row at full width
  std::array<int, 4> shown_{};
  int thumbStep_ = 1, thumbWidth_ = 0, thumbHeight_ = 0;
  std::array<std::vector<float>, 4> thumbs_; // RGB sums per thumbnail pixel (+ count)
  std::array<std::vector<float>, 4> raw_;    // RGB of a thumbnail pixel's first voxel (+ 1 if inside)
};

} // namespace texfab::print
