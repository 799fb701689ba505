// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Colour as a person sees it: CIELAB from linear sRGB, measured CIELAB (D50, as print
// spectrophotometers and ICC profiles give it) to linear sRGB, and the CIEDE2000 colour difference.
//
// Based on: G. Sharma, W. Wu, E. N. Dalal. The CIEDE2000 color-difference formula: implementation
//   notes, supplementary test data, and mathematical observations. Color Research & Application
//   30(1), 2005 (equations 1-23; their test pairs check the implementation).
//   IEC 61966-2-1 (sRGB primaries, D65 white); CIE 15:2004 (CIELAB); the Bradford chromatic
//   adaptation from D50 to D65 (as in ICC.1:2010 Annex E).

#include <array>

namespace texfab::print {

using Lab = std::array<double, 3>;  ///< L*, a*, b*

/// CIELAB (D65 white) of a linear sRGB colour.
Lab labFromLinearSrgb(const std::array<double, 3>& rgb);

/// CIELAB (D50 white, as ICC profiles and print measurements use) of a linear sRGB colour: sRGB's
/// D65 adapted to D50 by Bradford (ICC.1:2010 Annex E). The inverse of linearSrgbFromLabD50.
Lab labD50FromLinearSrgb(const std::array<double, 3>& rgb);

/// d CIELAB (D65) / d linear sRGB at `rgb` (row-major 3 x 3; rgb may lie outside [0, 1]).
std::array<double, 9> labJacobian(const std::array<double, 3>& rgb);

/// Linear sRGB of a CIELAB colour measured under D50 (adapted to sRGB's D65 by Bradford); may lie
/// outside [0, 1] for colours outside sRGB's gamut.
std::array<double, 3> linearSrgbFromLabD50(const Lab& lab);

/// The local metric of CIEDE2000 at `at`: W (row-major 3 x 3) with |W d| = ΔE2000(at, at + d) to
/// first order in the CIELAB difference d, its rotation term R_T left out (it only tilts the
/// metric for blues near hue 275°). Rows: ΔL'/S_L, ΔC'/S_C, ΔH'/S_H (Sharma et al. eqs. 2-22 with
/// the pair's means taken at `at`).
std::array<double, 9> deltaE2000Metric(const Lab& at);

/// CIEDE2000 (kL = kC = kH = 1): about 1 is the smallest difference a person notices side by side.
double deltaE2000(const Lab& a, const Lab& b);

} // namespace texfab::print
