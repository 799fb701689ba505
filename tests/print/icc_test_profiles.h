// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// ICC profiles for tests, made by LittleCMS itself: RGB display profiles with sRGB's white and
// tone curve and primaries pulled toward the white (a printer-like narrow gamut), and profiles of
// classes texfab must refuse.
#include <lcms2.h>

#include <filesystem>
#include <stdexcept>

namespace texfab::test {

/// Writes an RGB profile of `cls` whose primaries are sRGB's moved `narrow` of the way to its D65
/// white in xy (0: sRGB's gamut), with a gamma 2.2 tone curve.
inline void writeRgbProfile(const std::filesystem::path& path, double narrow,
                            cmsProfileClassSignature cls = cmsSigDisplayClass) {
  const cmsCIExyY white{0.3127, 0.3290, 1.0};
  const auto toward = [&](double x, double y) {
    return cmsCIExyY{x + narrow * (white.x - x), y + narrow * (white.y - y), 1.0};
  };
  const cmsCIExyYTRIPLE primaries{toward(0.64, 0.33), toward(0.30, 0.60), toward(0.15, 0.06)};
  cmsToneCurve* gamma = cmsBuildGamma(nullptr, 2.2);
  cmsToneCurve* curves[3] = {gamma, gamma, gamma};
  cmsHPROFILE profile = cmsCreateRGBProfile(&white, &primaries, curves);
  cmsFreeToneCurve(gamma);
  if (!profile) throw std::runtime_error("cmsCreateRGBProfile failed");
  cmsSetDeviceClass(profile, cls);
  cmsMLU* description = cmsMLUalloc(nullptr, 1);
  cmsMLUsetASCII(description, "en", "US", "texfab test RGB");
  cmsWriteTag(profile, cmsSigProfileDescriptionTag, description);
  cmsMLUfree(description);
  const bool saved = cmsSaveProfileToFile(profile, path.string().c_str());
  cmsCloseProfile(profile);
  if (!saved) throw std::runtime_error("cmsSaveProfileToFile failed");
}

/// Writes LittleCMS's CIELAB (D50) profile: an abstract profile, not a device's.
inline void writeLabProfile(const std::filesystem::path& path) {
  cmsHPROFILE profile = cmsCreateLab4Profile(nullptr);
  const bool saved = profile && cmsSaveProfileToFile(profile, path.string().c_str());
  if (profile) cmsCloseProfile(profile);
  if (!saved) throw std::runtime_error("cmsCreateLab4Profile failed");
}

} // namespace texfab::test
