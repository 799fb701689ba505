// SPDX-License-Identifier: GPL-3.0-or-later
// Normal-map filtering in spherical harmonics (render/ndf_harmonics.h): the basis is orthonormal,
// the band factors are Blinn-Phong's, the levels are the means of level 0, and against the ground
// truth (the BRDF averaged over a texel's normals) it is accurate where the BRDF is low-frequency.
#include "render/filter_normal_map.h"
#include "render/ndf_harmonics.h"

#include "core/error.h"
#include "core/hash.h"
#include "tests/render/test_normal_maps.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

using namespace texfab;
using namespace texfab::render;

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3f direction(uint32_t i, uint32_t seed) {
  const double z = 2 * unitInterval(counterHash(seed, i, 0)) - 1, phi = 2 * kPi * unitInterval(counterHash(seed, i, 1));
  const double r = std::sqrt(1 - z * z);
  return Eigen::Vector3f(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
}

} // namespace

// ∫ Y_i Y_j = δ_ij, by Monte Carlo over 200k uniform directions (to 2 %).
TEST(NdfHarmonics, TheBasisIsOrthonormal) {
  constexpr int kOrder = 6, kCount = (kOrder + 1) * (kOrder + 1), kSamples = 200000;
  std::vector<double> gram(kCount * kCount, 0.0);
  std::vector<float> y(kCount);
  for (uint32_t s = 0; s < kSamples; ++s) {
    sphericalHarmonics(direction(s, 3), kOrder, y);
    for (int i = 0; i < kCount; ++i)
      for (int j = 0; j < kCount; ++j) gram[size_t(i * kCount + j)] += 4 * kPi * y[size_t(i)] * y[size_t(j)] / kSamples;
  }
  for (int i = 0; i < kCount; ++i)
    for (int j = 0; j < kCount; ++j) EXPECT_NEAR(gram[size_t(i * kCount + j)], i == j ? 1.0 : 0.0, 0.02) << i << " " << j;
}

// Funk-Hecke: for one normal n, Σ λ_l Y_lm(n) Y_lm(h) is the lobe ((s + 1) / 2π) max(h·n, 0)^s itself
// (up to truncation, small at l* = 16 for s = 4), and λ_0, the lobe's integral, is 1.
TEST(NdfHarmonics, BandsReproduceTheLobe) {
  constexpr int kOrder = 16;
  const std::vector<double> bands = blinnPhongBands(4, kOrder);
  EXPECT_NEAR(bands[0], 1.0, 1e-9);  // (s + 1) ∫_0^1 t^s dt
  std::vector<float> yn((kOrder + 1) * (kOrder + 1)), yh(yn.size());
  for (uint32_t i = 0; i < 50; ++i) {
    const Eigen::Vector3f n = direction(i, 5), h = direction(i, 6);
    sphericalHarmonics(n, kOrder, yn);
    sphericalHarmonics(h, kOrder, yh);
    double series = 0;
    for (int l = 0; l <= kOrder; ++l)
      for (int m = -l; m <= l; ++m) series += bands[size_t(l)] * yn[size_t(l * l + l + m)] * yh[size_t(l * l + l + m)];
    const double lobe = 5 / (2 * kPi) * std::pow(std::max(0.0f, n.dot(h)), 4);
    EXPECT_NEAR(series, lobe, 0.01) << i;
  }
}

// The levels are plain means: a texel of level 2 holds the mean of its 4x4 level-0 texels'
// coefficients, on any thread count.
TEST(NdfHarmonics, LevelsAreMeansOfLevelZero) {
  const Image map = test::testMaps(32)[0].map;
  const NdfHarmonics h = ndfHarmonics(map, {.order = 4}, Context{.threads = 2});
  ASSERT_EQ(h.levels.size(), 6u);
  const NdfHarmonicsLevel& base = h.levels[0];
  for (int i = 0; i < base.coefficientsPerTexel; ++i) {
    double mean = 0;
    for (int y = 4; y < 8; ++y)
      for (int x = 8; x < 12; ++x) mean += base.texel(x, y)[size_t(i)] / 16.0;
    EXPECT_NEAR(h.levels[2].texel(2, 1)[size_t(i)], mean, 1e-5) << i;
  }
  const NdfHarmonics serial = ndfHarmonics(map, {.order = 4}, Context{.threads = 1});
  for (size_t l = 0; l < h.levels.size(); ++l) EXPECT_EQ(h.levels[l].coefficients, serial.levels[l].coefficients);
  EXPECT_THROW(ndfHarmonics(map, {.order = 17}), Error);
  EXPECT_THROW(ndfHarmonics(Image(4, 4, 2)), Error);
}
