// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: ICC.1:2010 (profile classes, rendering intents); LittleCMS 2 does the transforms.
#include "print/icc_profile.h"

#include "core/error.h"
#include "core/mip_pyramid.h"

#include <lcms2.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <system_error>

namespace texfab::print {

// One LittleCMS context per profile (no global state): its error handler keeps the last message.
struct IccProfile::State {
  cmsContext context = nullptr;
  std::string lastError;
  cmsHPROFILE device = nullptr, srgb = nullptr, lab = nullptr;
  cmsHTRANSFORM toDevice = nullptr;    // sRGB -> device, perceptual
  cmsHTRANSFORM fromDevice = nullptr;  // device -> CIELAB D50, relative colorimetric
  cmsHTRANSFORM labToDevice = nullptr; // CIELAB D50 -> device, relative colorimetric
  size_t channels = 0;

  ~State() {
    for (cmsHTRANSFORM t : {toDevice, fromDevice, labToDevice})
      if (t) cmsDeleteTransform(t);
    for (cmsHPROFILE p : {device, srgb, lab})
      if (p) cmsCloseProfile(p);
    if (context) cmsDeleteContext(context);
  }
};

namespace {

void keepError(cmsContext context, cmsUInt32Number, const char* text) {
  if (auto* message = static_cast<std::string*>(cmsGetContextUserData(context))) *message = text ? text : "";
}

} // namespace

IccProfile::IccProfile(const std::filesystem::path& path) : state_(std::make_unique<State>()) {
  State& s = *state_;
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(name + ": cannot open ICC profile");
  s.context = cmsCreateContext(nullptr, &s.lastError);
  if (!s.context) throw Error(name + ": cannot start LittleCMS");
  cmsSetLogErrorHandlerTHR(s.context, keepError);
  s.device = cmsOpenProfileFromFileTHR(s.context, name.c_str(), "r");
  if (!s.device)
    throw Error(name + ": not an ICC profile" + (s.lastError.empty() ? std::string() : " (" + s.lastError + ")"));
  // Signatures as the integers a file holds: LittleCMS passes any value through its enum types.
  const uint32_t cls = cmsGetDeviceClass(s.device);
  if (cls != cmsSigOutputClass && cls != cmsSigDisplayClass && cls != cmsSigColorSpaceClass)
    throw Error(name + ": an ICC profile of class '" +
                (cls == cmsSigInputClass ? std::string("input") : cls == cmsSigLinkClass ? "device link"
                 : cls == cmsSigAbstractClass ? "abstract" : cls == cmsSigNamedColorClass ? "named colour" : "other") +
                "', not an output, display or colour-space profile of a printer");
  const uint32_t space = cmsGetColorSpace(s.device);
  if (space == cmsSigLabData || space == cmsSigXYZData)
    throw Error(name + ": an ICC profile of the connection space itself, not of a device");
  // Every signature LittleCMS knows is below 2^31 (four ASCII letters); others are no colour space.
  const cmsInt32Number channels = space < 0x80000000u ? cmsChannelsOfColorSpace(cmsColorSpaceSignature(space)) : -1;
  if (channels <= 0) throw Error(name + ": an ICC profile of an unknown colour space");
  s.channels = size_t(channels);
  const cmsUInt32Number deviceFormat = cmsFormatterForColorspaceOfProfile(s.device, 2, FALSE);  // 16 bits: clamped
  s.srgb = cmsCreate_sRGBProfileTHR(s.context);
  s.lab = cmsCreateLab4ProfileTHR(s.context, nullptr);  // D50
  if (!s.srgb || !s.lab || deviceFormat == 0 || s.channels == 0 || s.channels > cmsMAXCHANNELS)
    throw Error(name + ": LittleCMS cannot use this ICC profile's colour space");
  s.toDevice = cmsCreateTransformTHR(s.context, s.srgb, TYPE_RGB_DBL, s.device, deviceFormat, INTENT_PERCEPTUAL, 0);
  s.fromDevice = cmsCreateTransformTHR(s.context, s.device, deviceFormat, s.lab, TYPE_Lab_DBL,
                                       INTENT_RELATIVE_COLORIMETRIC, 0);
  s.labToDevice = cmsCreateTransformTHR(s.context, s.lab, TYPE_Lab_DBL, s.device, deviceFormat,
                                        INTENT_RELATIVE_COLORIMETRIC, 0);
  if (!s.toDevice || !s.fromDevice || !s.labToDevice)
    throw Error(name + ": this ICC profile cannot convert both to and from its device colours" +
                (s.lastError.empty() ? std::string() : " (" + s.lastError + ")"));
  char text[256] = {};
  if (cmsGetProfileInfoASCII(s.device, cmsInfoDescription, "en", "US", text, sizeof text) > 1) description_ = text;
  if (description_.empty()) description_ = path.filename().string();
}

IccProfile::~IccProfile() = default;
IccProfile::IccProfile(IccProfile&&) noexcept = default;
IccProfile& IccProfile::operator=(IccProfile&&) noexcept = default;

Lab IccProfile::reproduced(const std::array<double, 3>& srgb) const {
  double in[3];
  for (int c = 0; c < 3; ++c) in[c] = std::clamp(std::isfinite(srgb[size_t(c)]) ? srgb[size_t(c)] : 0.0, 0.0, 1.0);
  uint16_t device[cmsMAXCHANNELS] = {};
  cmsDoTransform(state_->toDevice, in, device, 1);
  cmsCIELab lab{};
  cmsDoTransform(state_->fromDevice, device, &lab, 1);
  return {lab.L, lab.a, lab.b};
}

Lab IccProfile::roundTrip(const Lab& lab) const {
  const cmsCIELab in{lab[0], lab[1], lab[2]};
  uint16_t device[cmsMAXCHANNELS] = {};
  cmsDoTransform(state_->labToDevice, &in, device, 1);
  cmsCIELab out{};
  cmsDoTransform(state_->fromDevice, device, &out, 1);
  return {out.L, out.a, out.b};
}

void checkMaterialsInGamut(const std::vector<PrintMaterial>& materials, const IccProfile& profile,
                           const std::string& profileName) {
  for (const PrintMaterial& m : materials) {
    if (!m.opaque()) continue;  // a translucent material's colour only names it (print_materials.h)
    const std::array<double, 3> linear{srgbToLinear(m.color[0] / 255.0f), srgbToLinear(m.color[1] / 255.0f),
                                       srgbToLinear(m.color[2] / 255.0f)};
    const Lab lab = labD50FromLinearSrgb(linear);
    const double moved = deltaE2000(lab, profile.roundTrip(lab));
    if (moved > kProfileGamutTolerance) {
      char figure[32];
      std::snprintf(figure, sizeof figure, "%.1f", moved);
      throw Error("material '" + m.name + "' (" + hexColor(m.color) + ") lies outside the gamut of ICC profile " +
                  profileName + " (ΔE2000 " + figure + " to its nearest printable colour, more than " +
                  std::to_string(int(kProfileGamutTolerance)) + ")");
    }
  }
}

} // namespace texfab::print
