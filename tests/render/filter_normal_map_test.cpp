// SPDX-License-Identifier: GPL-3.0-or-later
// Normal-map filtering (render/filter_normal_map.h): against the ground truth of Han et al.'s
// comparisons, the BRDF averaged over every normal a texel covers (what supersampling converges
// to), the fitted lobes beat normalized MIP-mapping and Toksvig's filtering.
#include "render/filter_normal_map.h"
#include "render/ndf_harmonics.h"

#include "core/error.h"
#include "core/hash.h"
#include "tests/render/test_normal_maps.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

using namespace texfab;
using namespace texfab::render;
using texfab::test::TestMap;
using texfab::test::testMaps;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Light and view pairs whose half vectors lie within 35 degrees of the surface normal, where
// glossy highlights are: 32 of them, from a hash.
std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> lightAndHalfVectors() {
  std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> pairs;
  for (uint32_t i = 0; pairs.size() < 32; ++i) {
    const auto dir = [&](double elevationDeg, double azimuth) {
      const double e = elevationDeg * kPi / 180;
      return Eigen::Vector3f(float(std::cos(e) * std::cos(azimuth)), float(std::cos(e) * std::sin(azimuth)),
                             float(std::sin(e)));
    };
    const Eigen::Vector3f light = dir(15 + 70 * unitInterval(counterHash(9, i, 0)), 2 * kPi * unitInterval(counterHash(9, i, 1)));
    const Eigen::Vector3f half = dir(55 + 35 * unitInterval(counterHash(9, i, 2)), 2 * kPi * unitInterval(counterHash(9, i, 3)));
    const Eigen::Vector3f view = 2 * half.dot(light) * half - light;
    if (view.z() > 0.1f) pairs.push_back({light, half});
  }
  return pairs;
}

struct Errors {
  double vmf = 0, mip = 0, toksvig = 0, sh = 0;
};

// RMS shading errors over every texel of `level` and every light/view pair, against the BRDF
// averaged over the texel's level-0 normals.
Errors shadingErrors(const Image& map, const NdfMipChain& chain, const NdfHarmonics& harmonics, int level, double exponent) {
  const auto pairs = lightAndHalfVectors();
  const std::vector<double> bands = blinnPhongBands(exponent, harmonics.order);
  const int side = 1 << level;
  Errors e;
  size_t n = 0;
  for (int ty = 0; ty < chain.levels[size_t(level)].height; ++ty)
    for (int tx = 0; tx < chain.levels[size_t(level)].width; ++tx) {
      Eigen::Vector3f mean = Eigen::Vector3f::Zero();
      std::vector<Eigen::Vector3f> normals;
      for (int y = ty * side; y < (ty + 1) * side; ++y)
        for (int x = tx * side; x < (tx + 1) * side; ++x) normals.push_back(decodeNormal(map, x, y));
      for (const auto& normal : normals) mean += normal / float(normals.size());
      for (const auto& [light, half] : pairs) {
        double truth = 0;
        for (const auto& normal : normals) truth += blinnPhong(normal, light, half, exponent) / double(normals.size());
        const double vmf = shadeBlinnPhong(chain.texel(level, tx, ty), light, half, exponent);
        const double mip = blinnPhong(Eigen::Vector3f(mean.normalized()), light, half, exponent);
        const double toksvig = shadeToksvig(mean, light, half, exponent);
        const double sh =
            shadeBlinnPhongHarmonics(harmonics.levels[size_t(level)].texel(tx, ty), harmonics.order, bands, light, half);
        e.vmf += (vmf - truth) * (vmf - truth);
        e.sh += (sh - truth) * (sh - truth);
        e.mip += (mip - truth) * (mip - truth);
        e.toksvig += (toksvig - truth) * (toksvig - truth);
        ++n;
      }
    }
  e.vmf = std::sqrt(e.vmf / double(n)), e.mip = std::sqrt(e.mip / double(n)), e.toksvig = std::sqrt(e.toksvig / double(n));
  e.sh = std::sqrt(e.sh / double(n));
  return e;
}

} // namespace

// The target: at 1/4, 1/16 and 1/64 of the map's resolution, the RMS error at least 3x
// lower than normalized MIP-mapping's and lower than Toksvig's, on three materials.
TEST(FilterNormalMap, BeatsMipMappingAndToksvigAgainstTheGroundTruth) {
  for (const TestMap& m : testMaps(256)) {
    const NdfMipChain chain = filterNormalMap(m.map);
    ASSERT_EQ(chain.levels.size(), 9u);
    const NdfHarmonics harmonics = ndfHarmonics(m.map);
    for (int level : {2, 4, 6}) {
      const Errors e = shadingErrors(m.map, chain, harmonics, level, 64);
      std::printf("%-14s 1/%-3d RMS vMF %.4f, normalized MIP %.4f (%.1fx), Toksvig %.4f (%.1fx), SH %.4f\n",
                  m.name.c_str(), 1 << level, e.vmf, e.mip, e.mip / e.vmf, e.toksvig, e.toksvig / e.vmf, e.sh);
      EXPECT_LE(3 * e.vmf, e.mip) << m.name << ", level " << level;
      EXPECT_LT(e.vmf, e.toksvig) << m.name << ", level " << level;
    }
  }
}

// The SH form (ndf_harmonics.h, l* = 8) where it fits, low-frequency BRDFs (Blinn-Phong exponents
// 4 to 16): at least 3x less error than normalized MIP-mapping and less than Toksvig's on every
// material and level (measured 3.4-24x and 1.7-3.2x); printed beside the fitted lobes.
TEST(FilterNormalMap, HarmonicsFitLowFrequencyBrdfs) {
  for (const TestMap& m : testMaps(256)) {
    const NdfMipChain chain = filterNormalMap(m.map);
    const NdfHarmonics harmonics = ndfHarmonics(m.map);
    for (double exponent : {4.0, 8.0, 16.0})
      for (int level : {2, 4, 6}) {
        const Errors e = shadingErrors(m.map, chain, harmonics, level, exponent);
        std::printf("%-14s s %2.0f 1/%-3d RMS SH %.4f, vMF %.4f, normalized MIP %.4f (%.1fx SH), Toksvig %.4f (%.1fx SH)\n",
                    m.name.c_str(), exponent, 1 << level, e.sh, e.vmf, e.mip, e.mip / e.sh, e.toksvig, e.toksvig / e.sh);
        EXPECT_LE(3 * e.sh, e.mip) << m.name << ", s " << exponent << ", level " << level;
        EXPECT_LT(e.sh, e.toksvig) << m.name << ", s " << exponent << ", level " << level;
      }
  }
}

TEST(FilterNormalMap, LobesAreADistribution) {
  const Image map = testMaps(64)[0].map;
  const NdfMipChain chain = filterNormalMap(map, {.lobes = 3});
  for (size_t level = 0; level < chain.levels.size(); ++level)
    for (int y = 0; y < chain.levels[level].height; ++y)
      for (int x = 0; x < chain.levels[level].width; ++x) {
        double sum = 0;
        for (const VmfLobe& l : chain.texel(int(level), x, y)) {
          EXPECT_GE(l.weight, 0);
          EXPECT_LE(l.mean.norm(), 1.0f + 1e-5f);
          sum += l.weight;
        }
        EXPECT_NEAR(sum, 1.0, 1e-5) << "level " << level;
      }
  // A flat map: one sharp lobe straight up everywhere.
  Image flat(16, 16, 3);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) flat.at(x, y, 0) = flat.at(x, y, 1) = 0.5f, flat.at(x, y, 2) = 1.0f;
  const NdfMipChain f = filterNormalMap(flat);
  const VmfLobe top = f.texel(int(f.levels.size()) - 1, 0, 0)[0];
  EXPECT_FLOAT_EQ(top.weight, 1.0f);
  EXPECT_GT(top.axis().z(), 0.99999f);
  EXPECT_FLOAT_EQ(top.sharpness(), kMaxVmfSharpness);
}

// meanReflection against the mean over a vMF lobe's normals (Wood 1994's inversion on a 500 x 400
// grid of the unit square): a lobe straight up, views from overhead to grazing, sharpness from
// nearly uniform to narrow.
TEST(FilterNormalMap, MeanReflectionIsTheMeanOverTheLobesNormals) {
  const Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();
  for (float kappa : {0.5f, 4.0f, 40.0f, 400.0f}) {
    const double length = 1 / std::tanh(double(kappa)) - 1 / double(kappa);  // A(κ)
    for (float degrees : {0.0f, 40.0f, 80.0f}) {
      const float angle = degrees * 3.14159265f / 180;
      const Eigen::Vector3f dir(std::sin(angle), 0.0f, -std::cos(angle));  // toward the surface
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      constexpr int kU = 500, kV = 400, kSamples = kU * kV;
      for (int i = 0; i < kSamples; ++i) {
        const double u = (i / kV + 0.5) / kU, v = (i % kV + 0.5) / kV;
        const double w = 1 + std::log(u + (1 - u) * std::exp(-2.0 * kappa)) / kappa;  // cos θ
        const double r = std::sqrt(std::max(0.0, 1 - w * w)), phi = 2 * 3.14159265358979 * v;
        const Eigen::Vector3f m(float(r * std::cos(phi)), float(r * std::sin(phi)), float(w));
        sum += (dir - 2 * dir.dot(m) * m).cast<double>();
      }
      const Eigen::Vector3f expected = (sum / kSamples).cast<float>();
      const Eigen::Vector3f got = meanReflection(dir, axis, kappa, float(length));
      EXPECT_LT((got - expected).norm(), 0.01f) << "κ " << kappa << ", view " << degrees << "°: " << got.transpose()
                                                << " against " << expected.transpose();
    }
  }
}

TEST(FilterNormalMap, SameLobesOnOneAndTwoThreads) {
  const Image map = testMaps(128)[2].map;
  const NdfMipChain a = filterNormalMap(map, {}, Context{.threads = 1});
  const NdfMipChain b = filterNormalMap(map, {}, Context{.threads = 2});
  ASSERT_EQ(a.levels.size(), b.levels.size());
  for (size_t l = 0; l < a.levels.size(); ++l) {
    ASSERT_EQ(a.levels[l].lobes.size(), b.levels[l].lobes.size());
    EXPECT_EQ(0, std::memcmp(a.levels[l].lobes.data(), b.levels[l].lobes.data(), a.levels[l].lobes.size() * sizeof(VmfLobe)))
        << "level " << l;
  }
}

TEST(FilterNormalMap, RefusesWhatIsNotANormalMap) {
  EXPECT_THROW(filterNormalMap(Image(8, 8, 1)), Error);
  EXPECT_THROW(filterNormalMap(testMaps(64)[0].map, {.lobes = 9}), Error);
  EXPECT_THROW(filterNormalMap(testMaps(64)[0].map, {.iterations = 0}), Error);
}

TEST(FilterNormalMap, CachedChainsAreTheFittedOnesAndDamagedFilesAreRefitted) {
  const Image map = testMaps(64)[1].map;
  const test::TempDir dir("texfab-ndf-cache");
  const synthesis::AnalysisCacheSettings cache{dir.path(), uint64_t(1) << 30};
  const NdfMipChain fitted = filterNormalMap(map);
  const auto equal = [&](const NdfMipChain& c) {
    if (c.levels.size() != fitted.levels.size()) return false;
    for (size_t l = 0; l < c.levels.size(); ++l)
      if (c.levels[l].lobes.size() != fitted.levels[l].lobes.size() ||
          std::memcmp(c.levels[l].lobes.data(), fitted.levels[l].lobes.data(), c.levels[l].lobes.size() * sizeof(VmfLobe)))
        return false;
    return true;
  };
  bool cached = true;
  EXPECT_TRUE(equal(filterNormalMap(map, {}, cache, {}, &cached)));
  EXPECT_FALSE(cached);
  EXPECT_TRUE(equal(filterNormalMap(map, {}, cache, {}, &cached)));
  EXPECT_TRUE(cached);
  // Other options are another file; a truncated file is refitted, never trusted.
  filterNormalMap(map, {.lobes = 2}, cache, {}, &cached);
  EXPECT_FALSE(cached);
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    std::filesystem::resize_file(e.path(), std::filesystem::file_size(e.path()) / 2);
  EXPECT_TRUE(equal(filterNormalMap(map, {}, cache, {}, &cached)));
  EXPECT_FALSE(cached);
}
