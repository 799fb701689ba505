// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Choosing one printer material per shell voxel from its colour, row by row through a layer.
//
//   BlueNoise (default): a 3-D ordered dither. Voxel (x, y, layer) takes the material whose
//     cumulative fraction in its colour's mix (MaterialMixer) first exceeds the threshold of a
//     3-D blue-noise array (BlueNoiseVolume) at its position. A function of position alone: any
//     layer or row, computed alone, is the same as in a full run.
//   FloydSteinberg: error diffusion confined to the layer (the baseline the measurements compare
//     against): rows in serpentine order, the nearest material to colour + diffused error, the
//     error spread 7/16, 3/16, 5/16, 1/16 to the shell voxels ahead. Also exact for any layer
//     range (a layer depends only on itself), but its patterns are uncorrelated between layers.
//
// Based on: R. Floyd, L. Steinberg. An adaptive algorithm for spatial greyscale. Proc. SID 17(2),
//   1976; R. Ulichney, Digital Halftoning, MIT Press 1987 (serpentine scan).

#include "print/blue_noise.h"
#include "print/mix_materials.h"
#include "print/voxelize_layers.h"

#include <cstdint>
#include <span>
#include <vector>

namespace texfab::print {

enum class DitherMode { BlueNoise, FloydSteinberg, None };

/// Dithers the rows of one layer, top row first. Not thread-safe: one per layer being rendered.
class LayerDitherer {
public:
  /// `noise` is needed for BlueNoise. `width`: voxels per row.
  LayerDitherer(const MaterialMixer& mixer, DitherMode mode, const BlueNoiseVolume* noise, int layer, int width);

  /// Writes material index + 1 into out[x] for each shell voxel x of the row (grid row index y),
  /// whose colours `shellRgba` lists in span order (4 floats per shell voxel). Other entries of
  /// `out` are left alone. Rows must come top first (y descending), each exactly once.
  void ditherRow(int y, std::span<const print::VoxelSpan> row, const float* shellRgba, uint8_t* out);

private:
  void blueNoiseRow(int y, std::span<const print::VoxelSpan> row, const float* rgba, uint8_t* out);
  void diffuseRow(std::span<const print::VoxelSpan> row, const float* rgba, uint8_t* out);

  const MaterialMixer& mixer_;
  DitherMode mode_;
  const BlueNoiseVolume* noise_;
  int layer_, width_;
  int rowsDone_ = 0;
  std::vector<float> error_, nextError_;  // Floyd-Steinberg: diffused error of this row and the next, 3 per voxel
  std::vector<float> target_;             // Floyd-Steinberg: this row's colours by x, 4 per voxel
  std::vector<uint8_t> shell_;            // Floyd-Steinberg: whether voxel x of this row is shell
  std::vector<float> thresholds_;         // blue noise: the thresholds of this row's cells of the array
};

} // namespace texfab::print
