// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Quality measures of a dither, on a dense box of shell voxels: what a print's colour regions
// average to, and how much of the dither's noise a person sees. Volumes hold linear RGB, 3 floats
// per voxel, x fastest, then y, then layer. The reference is what the materials can reproduce
// (MaterialMixer::reproduced), so colours outside the gamut do not count against a dither.

#include "print/dither_layer.h"
#include "print/mix_materials.h"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace texfab::print {

struct DitherBox {
  int width = 0, height = 0, layers = 0;
  Eigen::Vector3d pitchMm{25.4 / 600, 25.4 / 300, 0.027};  ///< voxel size
  size_t voxels() const { return size_t(width) * size_t(height) * size_t(layers); }
};

/// Every voxel of `box` dithered as shell by LayerDitherer (one per layer, rows top first), as the
/// linear colours of the chosen materials. `noise` is needed for DitherMode::BlueNoise.
std::vector<float> ditherBox(const DitherBox& box, std::span<const float> target, const MaterialMixer& mixer,
                             DitherMode mode, const BlueNoiseVolume* noise);

/// The reproducible colours of `target` (MaterialMixer::reproduced per voxel).
std::vector<float> reproducedColors(std::span<const float> target, const MaterialMixer& mixer);

struct BlockColorError {
  double mean = 0, worst = 0;  ///< over whole blocks: |mean dithered - mean reference| (Euclidean)
};
/// Colour error of `block`^3 blocks (the box's whole blocks only).
BlockColorError blockColorError(const DitherBox& box, std::span<const float> dithered, std::span<const float> reference,
                                int block = 16);

/// Visible noise in a plane: the RMS of (dithered - reference) low-passed by a Gaussian of
/// `sigmaMm` (0.1 mm: about one arc minute at 30 cm). `vertical`: the xz section through row
/// `index` (a side wall: many layers); otherwise layer `index`.
double visibleError(const DitherBox& box, std::span<const float> dithered, std::span<const float> reference,
                    bool vertical, int index, double sigmaMm = 0.1);

} // namespace texfab::print
