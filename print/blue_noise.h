// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A 3-D blue-noise threshold array: a rank for every cell of an n^3 torus such that the cells of
// any rank range are spread evenly, with no low-frequency clumps, in every direction. Thresholding
// a colour's material fractions against it (a 3-D ordered dither) gives a dither that is a
// function of position alone, so any set of layers dithers alone exactly as in a full run.
//
// Based on: R. Ulichney. The void-and-cluster method for dither array generation. SPIE 1913,
//   1993 (initial pattern, its relaxation by moving the tightest cluster to the largest void, then
//   ranks by removing clusters and filling voids).
// Deviations: in 3-D, with distances measured in millimetres (voxels are anisotropic, e.g.
//   0.042 x 0.085 x 0.027 mm); the energy of a cell sums three filters: over its layer (2-D),
//   over its column (1-D), and a quarter of the 3-D filter over other layers, so that every layer
//   alone is blue, not only the volume (a slice of 3-D blue noise is nearly white in 2-D; the
//   separate layer and column energies follow spatiotemporal blue noise, A. Wolfe et al., EGSR
//   2022, §3); the energy filter is the
//   rational kernel (1 + d^2 / (2 s^2))^-2, evaluated in double and rounded to 32-bit integers,
//   instead of a Gaussian, so the array is bit-identical on every platform (no libm); the
//   initial pattern comes from a counter-based hash; ties go to the lowest cell index; the third
//   phase fills voids of the 1 pattern, which is the same as Ulichney's clusters of the inverted
//   pattern because the two energies sum to a constant.

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace texfab::print {

struct BlueNoiseVolume {
  int size = 0;                  ///< cells per side (the array repeats with this period)
  std::vector<uint32_t> rank;    ///< size^3 ranks, a permutation of [0, size^3); x fastest

  /// The threshold of cell (x, y, z) (any integers; wraps), in (0, 1).
  float threshold(int64_t x, int64_t y, int64_t z) const {
    const int64_t s = size;
    const int64_t i = ((x % s + s) % s) + s * (((y % s + s) % s) + s * ((z % s + s) % s));
    return (float(rank[size_t(i)]) + 0.5f) / float(rank.size());
  }
};

/// The array for cells of `pitch` (any unit; only ratios matter). `size` in [4, 64]. Takes about
/// 0.5 s of CPU at size 32.
BlueNoiseVolume blueNoiseVolume(int size, const Eigen::Vector3d& pitch);

} // namespace texfab::print
