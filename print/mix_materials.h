// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Which mix of printer materials reproduces a colour: the fractions f of the opaque materials
// (f >= 0, sum 1) whose area-weighted mean colour, in linear light (the eye mixes a fine dither
// linearly), looks closest to the colour c, and among mixes that look equally close the one whose
// materials are closest in lightness to it, so the dither's noise is as faint as it can be:
//   minimize ΔE2000(c, M f)^2 + lambda * sum_i f_i (L*_i - L*_c)^2,
// solved as least squares in CIELAB linearized at the mix p (J_p = d CIELAB / d linear RGB) and
// weighted by CIEDE2000's local metric W at c: |W (Lab(p) + J_p (M f - p) - Lab(c))|^2, p = c first,
// then the mix found (Gauss-Newton, a few passes; the pass with the least true cost is kept, the
// linear-RGB mix being a candidate too). A colour the materials can mix is mixed exactly (the first
// term vanishes); one they cannot is mapped to the mix with the smallest perceptual error rather
// than the smallest linear-RGB error (which lets dark and saturated colours drift in hue and
// lightness). MixSpace::LinearRgb keeps the former choice, |M f - c|^2 + lambda' sum_i f_i
// (Y_i - Y_c)^2, as a baseline.
// With an ICC output profile, c is the colour the profile says the printer reproduces for the
// requested one (IccProfile::reproduced: the profile maker's gamut mapping), not the request.
// A dither then gives each voxel material i with probability f_i (threshold against the cumulative
// fractions), and a region's mean colour is M f.
//
// Based on: D. Shaked, N. Arad, A. Fitzhugh, I. Sobel. Color Diffusion: Error-Diffusion for Color
//   Halftones. HP Labs HPL-96-128R1, 1999 (minimal brightness variation quadruples: render a colour
//   with the materials closest to it in brightness); CIE 15:2004 (CIELAB); G. Sharma, W. Wu,
//   E. N. Dalal, The CIEDE2000 color-difference formula, Color Res. Appl. 30(1), 2005 (the metric
//   W, its rotation term left out).
// Deviations: any set of material colours, not the eight Neugebauer primaries of CMY printing;
//   the quadruple is the support of the solution of the least-squares problem above (solved
//   exactly by enumerating supports of at most four materials, the most a colour in 3-D needs),
//   tabulated on a 33^3 lattice of requested linear RGB and interpolated trilinearly (17^3 before
//   the perceptual choice: its mixes change faster between lattice colours outside the gamut).

#include "print/icc_profile.h"
#include "print/print_materials.h"

#include <array>
#include <cstdint>
#include <vector>

namespace texfab::print {

/// The space a mix's colour error is measured in.
enum class MixSpace { Perceptual, LinearRgb };

struct MaterialMixerOptions {
  MixSpace space = MixSpace::Perceptual;
  /// The printer's ICC output profile: mixes aim at the colour it reproduces; none (nullptr) aims
  /// at the requested colour. Only used while the mixer is built.
  const IccProfile* profile = nullptr;
};

class MaterialMixer {
public:
  /// Throws texfab::Error unless validatePrintMaterials accepts `materials` and at most 16 are
  /// opaque.
  explicit MaterialMixer(const std::vector<PrintMaterial>& materials, const MaterialMixerOptions& options = {});

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

  /// The linear colour of rgb's mix (rgb itself when the materials can reproduce it and no profile
  /// changes it).
  std::array<float, 3> reproduced(const float rgb[3]) const;

  /// The opaque material whose linear colour is nearest to rgb (Euclidean), for error diffusion.
  int nearest(const float rgb[3]) const;

  /// Fractions of rgb's mix per opaque material (in `opaque()` order), interpolated from the table.
  void fractions(const float rgb[3], float* out) const;

  const std::vector<int>& opaque() const { return opaque_; }
  /// Linear colour of material i.
  const std::array<float, 3>& linearColor(int i) const { return linear_[size_t(i)]; }

private:
  static constexpr int kLattice = 33;
  std::vector<int> opaque_;                    // indices of the opaque materials
  int translucent_ = -1;                       // the first translucent material, or -1
  std::vector<std::array<float, 3>> linear_;   // per material
  std::vector<float> table_;                   // kLattice^3 x opaque_.size() fractions
};

} // namespace texfab::print
