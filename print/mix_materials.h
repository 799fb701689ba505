// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Which mix of printer materials reproduces a colour: the fractions f of the opaque materials
// (f >= 0, sum 1) whose area-weighted mean colour, in linear light, is closest to the colour, and
// among mixes that reproduce it equally well the one whose materials are closest in brightness to
// it, so the dither's noise is as faint as it can be:
//   minimize |M f - c|^2 + lambda * sum_i f_i (Y_i - Y_c)^2.
// A dither then gives each voxel material i with probability f_i (threshold against the cumulative
// fractions), and a region's mean colour is M f.
//
// Based on: D. Shaked, N. Arad, A. Fitzhugh, I. Sobel. Color Diffusion: Error-Diffusion for Color
//   Halftones. HP Labs HPL-96-128R1, 1999 (minimal brightness variation quadruples: render a colour
//   with the materials closest to it in brightness).
// Deviations: any set of material colours, not the eight Neugebauer primaries of CMY printing;
//   the quadruple is the support of the solution of the least-squares problem above (solved
//   exactly by enumerating supports of at most four materials, the most a colour in 3-D needs),
//   tabulated on a 17^3 lattice of linear RGB and interpolated trilinearly.

#include "print/print_materials.h"

#include <array>
#include <cstdint>
#include <vector>

namespace texfab::print {

class MaterialMixer {
public:
  /// Throws texfab::Error unless validatePrintMaterials accepts `materials` and at most 16 are
  /// opaque.
  explicit MaterialMixer(const std::vector<PrintMaterial>& materials);

  /// The material (index into the list) for a voxel of linear colour rgba (clamped to [0, 1])
  /// whose dither threshold is t in [0, 1): opaque material i when t falls in the i-th cumulative
  /// fraction of rgba's mix scaled by its alpha; the first translucent material when t >= alpha
  /// (the first opaque one if there is none).
  int pick(const float rgba[4], float t) const;

  /// A colour's mix prepared for many thresholds: pick(mix(rgba), t) == pick(rgba, t).
  struct Mix {
    float alpha = 1;
    float cumulative[16] = {};  ///< running sums of the fractions, opaque() order
  };
  Mix mix(const float rgba[4]) const;
  int pick(const Mix& mix, float t) const;

  /// The linear colour of rgb's mix (rgb itself when the materials can reproduce it).
  std::array<float, 3> reproduced(const float rgb[3]) const;

  /// The opaque material whose linear colour is nearest to rgb (Euclidean), for error diffusion.
  int nearest(const float rgb[3]) const;

  /// Fractions of rgb's mix per opaque material (in `opaque()` order), interpolated from the table.
  void fractions(const float rgb[3], float* out) const;

  const std::vector<int>& opaque() const { return opaque_; }
  /// Linear colour of material i.
  const std::array<float, 3>& linearColor(int i) const { return linear_[size_t(i)]; }

private:
  static constexpr int kLattice = 17;
  std::vector<int> opaque_;                    // indices of the opaque materials
  int translucent_ = -1;                       // the first translucent material, or -1
  std::vector<std::array<float, 3>> linear_;   // per material
  std::vector<float> table_;                   // kLattice^3 x opaque_.size() fractions
};

} // namespace texfab::print
