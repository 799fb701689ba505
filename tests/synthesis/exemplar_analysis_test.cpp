// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/error.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace texfab::synthesis {
namespace {

using test::TempDir;

TEST(ExemplarAnalysis, StackHasOneLevelPerOctave) {
  EXPECT_EQ(stackLevelCount(64, 64), 7);
  EXPECT_EQ(stackLevelCount(96, 96), 8);
  EXPECT_EQ(stackLevelCount(128, 40), 8);
  EXPECT_EQ(stackLevelCount(5, 5), 4);
}

TEST(ExemplarAnalysis, GaussianStackPreservesMeanAndSmooths) {
  const Image noise = test::noiseImage(32, 32);
  const std::vector<Image> stack = gaussianStack(noise);
  ASSERT_EQ(stack.size(), 6u);
  auto meanAndVariance = [](const Image& img) {
    double s = 0, s2 = 0;
    for (float v : img.pixels) s += v, s2 += double(v) * v;
    const double n = double(img.pixels.size());
    return std::pair{s / n, s2 / n - (s / n) * (s / n)};
  };
  const auto [mean, variance] = meanAndVariance(noise);
  double previousVariance = variance + 1;
  for (int l = int(stack.size()) - 1; l >= 0; --l) {
    const auto [m, v] = meanAndVariance(stack[size_t(l)]);
    EXPECT_NEAR(m, mean, 1e-4) << "level " << l;      // the toroidal filter keeps the mean
    EXPECT_LT(v, previousVariance) << "level " << l;  // and removes detail level by level
    previousVariance = v;
  }
  EXPECT_EQ(stack.back().pixels, noise.pixels);
}

TEST(ExemplarAnalysis, CandidatesStartWithThePixelAndAreSpreadApart) {
  const Image image = test::noiseImage(40, 40);
  AnalysisOptions options;
  options.k = 4;
  const ExemplarAnalysis a = analyzeExemplar(image, options);
  ASSERT_EQ(a.levels.size(), size_t(stackLevelCount(40, 40)));
  const int minDistance = std::max(2, int(std::lround(options.minSpread * 40)));
  for (const AnalysisLevel& level : a.levels) {
    ASSERT_EQ(level.candidates.size(), 40u * 40u * 4u);
    ASSERT_EQ(level.appearance.size(), 40u * 40u * kAppearanceDims);
    for (int p = 0; p < 40 * 40; ++p) {
      const uint32_t* c = &level.candidates[size_t(p) * 4];
      ASSERT_EQ(c[0], packCoord(uint32_t(p % 40), uint32_t(p / 40)));
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          if (c[j] == c[0]) continue;  // a repeated pixel fills slots with no spread candidate
          int dx = std::abs(int(coordU(c[i])) - int(coordU(c[j]))), dy = std::abs(int(coordV(c[i])) - int(coordV(c[j])));
          dx = std::min(dx, 40 - dx);
          dy = std::min(dy, 40 - dy);
          ASSERT_GE(dx * dx + dy * dy, minDistance * minDistance);
        }
    }
  }
}

TEST(ExemplarAnalysis, CandidatesAreNearestNeighborsInAppearanceSpace) {
  // A pattern with exact repeats: the best non-self candidate of a pixel is its repeat one period
  // away, which has the same appearance vector.
  Image image(48, 48, 3);
  const Image tile = test::noiseImage(16, 16);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x)
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = tile.at(x % 16, y % 16, c);
  AnalysisOptions options;
  options.featureWeight = 0;
  const ExemplarAnalysis a = analyzeExemplar(image, options);
  const AnalysisLevel& finest = a.levels.back();
  int repeats = 0;
  for (int p = 0; p < 48 * 48; ++p) {
    const uint32_t c = finest.candidates[size_t(p) * 2 + 1];
    const int dx = int(coordU(c)) - p % 48, dy = int(coordV(c)) - p / 48;
    repeats += (dx % 16 == 0) && (dy % 16 == 0) && (dx != 0 || dy != 0);
  }
  EXPECT_EQ(repeats, 48 * 48);
}

TEST(ExemplarAnalysis, IndependentOfThreadCount) {
  const Image image = test::noiseImage(33, 29);
  const ExemplarAnalysis one = analyzeExemplar(image, {}, Context{.threads = 1});
  const ExemplarAnalysis two = analyzeExemplar(image, {}, Context{.threads = 2});
  ASSERT_EQ(one.levels.size(), two.levels.size());
  for (size_t l = 0; l < one.levels.size(); ++l) {
    EXPECT_EQ(one.levels[l].appearance, two.levels[l].appearance);
    EXPECT_EQ(one.levels[l].candidates, two.levels[l].candidates);
  }
}

TEST(ExemplarAnalysis, CacheRoundTripAndSecondRunHitsCache) {
  TempDir dir;
  const Image image = test::noiseImage(24, 24);
  bool cached = true;
  const ExemplarAnalysis first = analyzeExemplarCached(image, {}, dir.path(), Context{.threads = 0}, &cached);
  EXPECT_FALSE(cached);
  const ExemplarAnalysis second = analyzeExemplarCached(image, {}, dir.path(), Context{.threads = 0}, &cached);
  EXPECT_TRUE(cached);
  EXPECT_EQ(first.key, second.key);
  ASSERT_EQ(first.levels.size(), second.levels.size());
  for (size_t l = 0; l < first.levels.size(); ++l) {
    EXPECT_EQ(first.levels[l].spacing, second.levels[l].spacing);
    EXPECT_EQ(first.levels[l].appearance, second.levels[l].appearance);
    EXPECT_EQ(first.levels[l].neighborhood, second.levels[l].neighborhood);
    EXPECT_EQ(first.levels[l].candidates, second.levels[l].candidates);
  }
  // Other options or other pixels are other keys.
  AnalysisOptions k3;
  k3.k = 3;
  EXPECT_NE(analysisKey(image, k3), first.key);
  EXPECT_NE(analysisKey(test::noiseImage(24, 24, 8), {}), first.key);
}

TEST(ExemplarAnalysis, DamagedCacheIsRecomputedNotTrusted) {
  TempDir dir;
  const Image image = test::noiseImage(20, 20);
  const ExemplarAnalysis fresh = analyzeExemplarCached(image, {}, dir.path());
  std::filesystem::path file;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) file = entry.path();
  ASSERT_FALSE(file.empty());
  std::filesystem::resize_file(file, std::filesystem::file_size(file) / 2);
  EXPECT_FALSE(readAnalysis(file, fresh.key).has_value());
  EXPECT_FALSE(readAnalysis(dir / "missing.analysis", fresh.key).has_value());
  bool cached = true;
  const ExemplarAnalysis again = analyzeExemplarCached(image, {}, dir.path(), Context{.threads = 0}, &cached);
  EXPECT_FALSE(cached);
  EXPECT_EQ(again.levels.back().candidates, fresh.levels.back().candidates);
  EXPECT_TRUE(readAnalysis(file, fresh.key).has_value());  // rewritten whole
  EXPECT_FALSE(readAnalysis(file, fresh.key + 1).has_value());
}

TEST(ExemplarAnalysis, FeatureDistanceOfALine) {
  // One bright vertical line on black: every pixel's distance to the nearest edge is its
  // horizontal (toroidal) distance to the line's two edge columns.
  Image image(32, 16, 1);
  for (int y = 0; y < 16; ++y) image.at(10, y, 0) = 1.0f;
  const Image d = featureDistance(image);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x) {
      int best = 1000;
      for (int edge : {9, 11}) {
        const int dx = std::abs(x - edge);
        best = std::min(best, std::min(dx, 32 - dx));
      }
      ASSERT_FLOAT_EQ(d.at(x, y, 0), float(best)) << x << "," << y;
    }
}

TEST(ExemplarAnalysis, RefusesTinyAndHugeExemplars) {
  EXPECT_THROW(analyzeExemplar(Image(1, 1, 3), {}), Error);
  EXPECT_THROW(analyzeExemplar(Image(4, 64, 3), {}), Error);
  EXPECT_THROW(analyzeExemplar(Image(5000, 8, 3), {}), Error);
  AnalysisOptions bad;
  bad.k = 0;
  EXPECT_THROW(analyzeExemplar(test::noiseImage(8, 8), bad), Error);
  EXPECT_NO_THROW(analyzeExemplar(test::noiseImage(5, 5), {}));
}

} // namespace
} // namespace texfab::synthesis
