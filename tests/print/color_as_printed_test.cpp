// SPDX-License-Identifier: GPL-3.0-or-later
// Colour as printed: the mix of materials chosen in CIELAB (against the former linear-RGB choice),
// the printer's ICC output profile (profiles made by LittleCMS in a temporary folder; files that
// are not usable profiles and materials outside the gamut refused), and the preview's layer as the
// eye sees it.
#include "core/error.h"
#include "core/mip_pyramid.h"
#include "print/color_difference.h"
#include "print/icc_profile.h"
#include "print/mix_materials.h"
#include "print/slice_preview.h"
#include "tests/print/icc_test_profiles.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

namespace texfab::print {
namespace {

using test::TempDir;

template <class F> std::string errorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

Lab labOf(const std::array<float, 3>& c) { return labFromLinearSrgb({c[0], c[1], c[2]}); }

// A printer whose materials are far from pure: its gamut leaves out much of sRGB.
std::vector<PrintMaterial> narrowMaterials() {
  return {{"C", {90, 160, 180, 255}}, {"M", {180, 110, 150, 255}}, {"Y", {200, 190, 120, 255}},
          {"K", {60, 60, 60, 255}},   {"W", {230, 230, 230, 255}}};
}

TEST(ColorDifference, JacobianAndD50InverseAgreeWithTheFormulas) {
  const std::vector<std::array<double, 3>> points = {{0.5, 0.2, 0.7}, {0.001, 0.002, 0.0005}, {1, 1, 1}, {1.2, -0.05, 0.3}};
  for (const std::array<double, 3>& c : points) {
    const std::array<double, 9> j = labJacobian(c);
    for (int col = 0; col < 3; ++col) {
      const double h = 1e-6;
      std::array<double, 3> hi = c, lo = c;
      hi[size_t(col)] += h, lo[size_t(col)] -= h;
      const Lab a = labFromLinearSrgb(hi), b = labFromLinearSrgb(lo);
      for (int row = 0; row < 3; ++row)
        EXPECT_NEAR(j[size_t(3 * row + col)], (a[size_t(row)] - b[size_t(row)]) / (2 * h),
                    1e-3 * (1 + std::abs(j[size_t(3 * row + col)])));
    }
    const std::array<double, 3> back = linearSrgbFromLabD50(labD50FromLinearSrgb(c));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[size_t(k)], c[size_t(k)], 1e-5);
  }
  const Lab white = labD50FromLinearSrgb({1, 1, 1});  // D65 white adapts to D50 white
  EXPECT_NEAR(white[0], 100, 1e-3);
  EXPECT_NEAR(white[1], 0, 0.02);
  EXPECT_NEAR(white[2], 0, 0.02);
}

// Outside the gamut the CIELAB choice is nearer the request as CIEDE2000 measures it, on average,
// than the linear-RGB least squares; inside, both reproduce the colour.
TEST(MaterialMixer, PerceptualMixIsNearerOutsideTheGamut) {
  for (const bool narrow : {false, true}) {
    const std::vector<PrintMaterial> materials = narrow ? narrowMaterials() : defaultPrintMaterials();
    const MaterialMixer perceptual(materials), rgb(materials, {MixSpace::LinearRgb});
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    double sumP = 0, sumRgb = 0, worseBy = 0;
    int outside = 0, pWins = 0;
    for (int i = 0; i < 4000; ++i) {
      const float c[3] = {u(rng), u(rng), u(rng)};
      const Lab want = labOf({c[0], c[1], c[2]});
      const double dRgb = deltaE2000(want, labOf(rgb.reproduced(c)));
      const double dP = deltaE2000(want, labOf(perceptual.reproduced(c)));
      if (std::max(dRgb, dP) < 3) continue;  // inside the gamut (up to the table's interpolation)
      ++outside;
      sumP += dP, sumRgb += dRgb;
      pWins += dP < dRgb;
      worseBy = std::max(worseBy, dP - dRgb);
    }
    ASSERT_GT(outside, 300);
    std::printf("%s materials: %d colours outside the gamut, mean ΔE2000 cielab %.2f, linear-rgb %.2f; cielab nearer for "
                "%.0f%%, at worst %.2f farther\n",
                narrow ? "narrow" : "default", outside, sumP / outside, sumRgb / outside, 100.0 * pWins / outside, worseBy);
    EXPECT_LT(sumP / outside, 0.9 * sumRgb / outside);
    EXPECT_GT(pWins, outside * 3 / 4);
    EXPECT_LT(worseBy, 5.0);  // and never much farther
  }
}

TEST(IccProfile, RefusesFilesThatAreNotUsableProfiles) {
  TempDir dir;
  std::ofstream(dir / "garbage.icc") << "this is not an ICC profile, just some text long enough to look like a header...";
  EXPECT_NE(errorOf([&] { IccProfile p(dir / "garbage.icc"); }).find("not an ICC profile"), std::string::npos);
  std::ofstream(dir / "empty.icc");
  EXPECT_NE(errorOf([&] { IccProfile p(dir / "empty.icc"); }).find("not an ICC profile"), std::string::npos);
  EXPECT_NE(errorOf([&] { IccProfile p(dir / "missing.icc"); }).find("cannot open"), std::string::npos);
  EXPECT_NE(errorOf([&] { IccProfile p(dir.path()); }).find("cannot open"), std::string::npos);
  test::writeRgbProfile(dir / "scanner.icc", 0.0, cmsSigInputClass);
  EXPECT_NE(errorOf([&] { IccProfile p(dir / "scanner.icc"); }).find("class 'input'"), std::string::npos);
  test::writeLabProfile(dir / "lab.icc");
  EXPECT_NE(errorOf([&] { IccProfile p(dir / "lab.icc"); }).find("lab.icc"), std::string::npos);
  for (const char* name : {"garbage.icc", "scanner.icc", "lab.icc"}) {
    const std::string e = errorOf([&] { IccProfile p(dir / name); });
    EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 0) << e;
    EXPECT_NE(e.find(name), std::string::npos) << e;
  }
  test::writeRgbProfile(dir / "printer.icc", 0.3, cmsSigOutputClass);
  EXPECT_EQ(IccProfile(dir / "printer.icc").description(), "texfab test RGB");
}

TEST(IccProfile, ReproducesInsideItsGamutAndMapsOutside) {
  TempDir dir;
  test::writeRgbProfile(dir / "srgb.icc", 0.0);
  test::writeRgbProfile(dir / "narrow.icc", 0.4);
  const IccProfile srgb(dir / "srgb.icc"), narrow(dir / "narrow.icc");
  const std::vector<std::array<double, 3>> colors = {{0.5, 0.5, 0.5}, {0.8, 0.3, 0.2}, {1, 0, 0}, {0.1, 0.9, 0.4}};
  for (const std::array<double, 3>& c : colors) {
    std::array<double, 3> linear;
    for (int k = 0; k < 3; ++k) linear[size_t(k)] = srgbToLinear(float(c[size_t(k)]));
    const Lab want = labD50FromLinearSrgb(linear);
    // A profile of sRGB's own primaries reproduces every sRGB colour (its gamma 2.2 differs from
    // sRGB's curve, but device values go both ways through it).
    EXPECT_LT(deltaE2000(want, srgb.reproduced(c)), 1.0) << c[0] << " " << c[1] << " " << c[2];
    EXPECT_LT(deltaE2000(want, srgb.roundTrip(want)), 1.0);
  }
  // The narrow printer: grey stays, pure red comes out less chroma, and a round trip moves red.
  const Lab grey = labD50FromLinearSrgb({0.2, 0.2, 0.2});
  EXPECT_LT(deltaE2000(grey, narrow.reproduced({linearToSrgb(0.2f), linearToSrgb(0.2f), linearToSrgb(0.2f)})), 1.0);
  EXPECT_LT(deltaE2000(grey, narrow.roundTrip(grey)), 0.5);
  const Lab red = labD50FromLinearSrgb({1, 0, 0}), printed = narrow.reproduced({1, 0, 0});
  EXPECT_LT(std::hypot(printed[1], printed[2]), 0.8 * std::hypot(red[1], red[2]));
  EXPECT_GT(deltaE2000(red, narrow.roundTrip(red)), 10);
}

TEST(IccProfile, MaterialsOutsideTheGamutAreNamed) {
  TempDir dir;
  test::writeRgbProfile(dir / "narrow.icc", 0.3);
  const IccProfile narrow(dir / "narrow.icc");
  const std::string e = errorOf([&] { checkMaterialsInGamut(defaultPrintMaterials(), narrow, "narrow.icc"); });
  EXPECT_NE(e.find("material 'VeroCyan'"), std::string::npos) << e;
  EXPECT_NE(e.find("narrow.icc"), std::string::npos) << e;
  EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 0);
  EXPECT_EQ(errorOf([&] { checkMaterialsInGamut(narrowMaterials(), narrow, "narrow.icc"); }), "");
  // A translucent material's colour only names it: not checked.
  std::vector<PrintMaterial> clear = narrowMaterials();
  clear.push_back({"Clear", {0, 255, 0, 255}, 0.0});
  EXPECT_EQ(errorOf([&] { checkMaterialsInGamut(clear, narrow, "narrow.icc"); }), "");
}

// With a profile, the mix aims at the colour the profile says the printer reproduces: the default
// materials (wider than the narrow profile) mix that colour, not the request.
TEST(MaterialMixer, WithAProfileAimsAtWhatTheProfileReproduces) {
  TempDir dir;
  test::writeRgbProfile(dir / "narrow.icc", 0.4);
  const IccProfile narrow(dir / "narrow.icc");
  const std::vector<PrintMaterial> materials = defaultPrintMaterials();
  const MaterialMixer plain(materials), profiled(materials, {MixSpace::Perceptual, &narrow});
  double toProfile = 0, toRequest = 0;
  int n = 0;
  for (int r = 0; r <= 16; r += 4)
    for (int g = 0; g <= 16; g += 4)
      for (int b = 0; b <= 16; b += 4, ++n) {  // lattice colours: no interpolation between targets
        const float c[3] = {float(r) / 16, float(g) / 16, float(b) / 16};
        const Lab target = narrow.reproduced({linearToSrgb(c[0]), linearToSrgb(c[1]), linearToSrgb(c[2])});
        const std::array<float, 3> got = profiled.reproduced(c);
        toProfile += deltaE2000(target, labD50FromLinearSrgb({got[0], got[1], got[2]}));
        const std::array<float, 3> plainGot = plain.reproduced(c);
        toRequest += deltaE2000(target, labD50FromLinearSrgb({plainGot[0], plainGot[1], plainGot[2]}));
      }
  std::printf("ΔE2000 to the profile's colour: with the profile %.2f, without %.2f (mean of %d)\n", toProfile / n,
              toRequest / n, n);
  EXPECT_LT(toProfile / n, 0.5 * toRequest / n);  // not all: CMYKW mixes no saturated red, green or blue
}

// The preview's layers: as dithered, a checkerboard of black and white voxels; as seen, grey.
TEST(SlicePreview, ShowsLayersAsDitheredAndAsSeen) {
  PrintGrid grid;
  grid.width = 48, grid.height = 40, grid.layers = 8;
  grid.pitchMm = {25.4 / 600, 25.4 / 300, 0.027};
  SlicePreview preview(grid, 0, grid.layers, 320);
  std::vector<uint8_t> rgba(4 * size_t(grid.width));
  for (int layer = 0; layer < grid.layers; ++layer)
    for (int r = 0; r < grid.height; ++r) {
      for (int x = 0; x < grid.width; ++x) {
        const uint8_t v = (x + r + layer) % 2 ? 255 : 0;
        rgba[4 * size_t(x)] = rgba[4 * size_t(x) + 1] = rgba[4 * size_t(x) + 2] = v;
        rgba[4 * size_t(x) + 3] = 255;
      }
      const VoxelSpan span{0, grid.width, true};
      preview.addRow(layer, r, {&span, 1}, rgba.data());
    }
  const Image raw = preview.shownLayer(1, false), seen = preview.shownLayer(1, true);
  ASSERT_EQ(raw.width, grid.width);
  double rawSpread = 0, seenWorst = 0;
  for (int y = 8; y < raw.height - 8; ++y)
    for (int x = 8; x < raw.width - 8; ++x) {
      rawSpread += std::abs(raw.at(x, y, 0) - 0.5);
      seenWorst = std::max(seenWorst, double(std::abs(seen.at(x, y, 1) - 0.5f)));
    }
  EXPECT_NEAR(rawSpread / ((raw.height - 16) * (raw.width - 16)), 0.5, 1e-6);  // every voxel black or white
  EXPECT_LT(seenWorst, 0.02);                                                   // their mean, linear grey
  const Image picture = preview.compose();
  EXPECT_GT(picture.height, 2 * raw.height);
}

} // namespace
} // namespace texfab::print
