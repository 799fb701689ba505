// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A printer's ICC output profile, as print shops characterize their printers: what colour the
// printer reproduces for a requested sRGB colour (sRGB -> the profile's device space with the
// perceptual intent, the profile maker's gamut mapping, then device -> CIELAB D50), and whether a
// colour lies inside the printer's gamut (CIELAB -> device -> CIELAB, relative colorimetric,
// device values clamped to their range).
//
// Based on: ICC.1:2010 (profile classes, rendering intents, the D50 profile connection space);
//   LittleCMS 2 (M. Maria, littlecms.com), which does the transforms.

#include "print/color_difference.h"
#include "print/print_materials.h"

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace texfab::print {

/// ΔE2000 a material's colour may move in its gamut round trip (CIELAB -> device -> CIELAB) and
/// still count as inside the profile's gamut: above 8-bit quantization and a LUT profile's
/// interpolation error (about 1), well below a visible gamut clip.
inline constexpr double kProfileGamutTolerance = 2.0;

class IccProfile {
public:
  /// Reads an ICC profile: an output (printer), display or colour-space profile with an RGB, CMYK
  /// or other device space that converts both to and from the profile connection space. Throws a
  /// one-line texfab::Error naming the file otherwise.
  explicit IccProfile(const std::filesystem::path& path);
  ~IccProfile();
  IccProfile(IccProfile&&) noexcept;
  IccProfile& operator=(IccProfile&&) noexcept;

  /// The colour the printer reproduces for a requested sRGB colour (non-linear, [0, 1]): CIELAB D50.
  Lab reproduced(const std::array<double, 3>& srgb) const;

  /// CIELAB D50 of `lab` sent to the device and read back (relative colorimetric): `lab` itself,
  /// up to rounding, inside the printer's gamut, and the gamut's nearest colour outside it.
  Lab roundTrip(const Lab& lab) const;

  /// The profile's description tag (its file name when it has none).
  const std::string& description() const { return description_; }

private:
  struct State;
  std::unique_ptr<State> state_;
  std::string description_;
};

/// Throws texfab::Error naming the first opaque material whose colour (CIELAB D50 of its sRGB) lies
/// outside the profile's gamut: its round trip (IccProfile::roundTrip) moves it by more than
/// kProfileGamutTolerance ΔE2000. (A translucent material's colour only names it.)
void checkMaterialsInGamut(const std::vector<PrintMaterial>& materials, const IccProfile& profile,
                           const std::string& profileName);

} // namespace texfab::print
