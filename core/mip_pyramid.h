// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Mip pyramids of textures and filtered lookups into them: 2x2 box-filtered levels in linear
// light, bilinear sampling within a level, trilinear between levels [Williams 1983, "Pyramidal
// Parametrics"]. Used by the preview renderer and the print colours; lookups wrap (glTF's default REPEAT).

#include "core/image.h"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace texfab {

struct MipPyramid {
  /// Level 0 is the full-size texture; each next level halves each side (rounding up) down to 1x1.
  /// Every level has 4 float channels (grey and grey+alpha expanded; alpha 1 when absent).
  std::vector<Image> levels;
  bool empty() const { return levels.empty(); }
};

/// Builds the pyramid. When `srgb` (colour textures), values are decoded from sRGB to linear first
/// so that averaging happens in linear light; alpha is always linear.
MipPyramid buildMipPyramid(const Image& image, bool srgb);

/// The pyramid of a texture's own MIP chain (levels[0] the finest), each level expanded as
/// buildMipPyramid expands the base.
MipPyramid mipPyramidOf(std::span<const Image> levels, bool srgb);

/// Bilinear lookup in one level at (u, v) with v up (v = 0 is the bottom row), wrapping.
Eigen::Vector4f sampleBilinear(const Image& level, float u, float v);

/// Trilinear lookup: `lod` is the level of detail (0 = finest; fractional values blend two levels,
/// values beyond the coarsest clamp).
Eigen::Vector4f sampleTrilinear(const MipPyramid& pyramid, float u, float v, float lod);

/// sRGB transfer functions (IEC 61966-2-1).
float srgbToLinear(float c);
float linearToSrgb(float c);

} // namespace texfab
