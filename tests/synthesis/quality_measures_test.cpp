// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/crop.h"
#include "core/error.h"
#include "core/image_io.h"
#include "synthesis/quality_measures.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace texfab::synthesis {
namespace {

CoordMap tiling(int w, int h, int ew, int eh) {
  CoordMap m{w, h, ew, eh, {}};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.coords.push_back(packCoord(uint32_t(x % ew), uint32_t(y % eh)));
  return m;
}

Image constant(int w, int h, float value) {
  Image image(w, h, 3);
  for (float& v : image.pixels) v = value;
  return image;
}

TEST(QualityMeasures, LatticeCorrelationSeesARepeatingPeriod) {
  // Noise, and the same noise's 8 x 8 corner repeated: 1 at period 8, about 0 for the noise.
  Image noise(40, 40, 1), tiled(40, 40, 1);
  uint32_t state = 12345;
  for (float& v : noise.pixels) v = float((state = state * 1664525u + 1013904223u) >> 8) / float(1u << 24);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) tiled.at(x, y, 0) = noise.at(x % 8, y % 8, 0);
  EXPECT_NEAR(latticeCorrelation(tiled, 8), 1.0, 1e-6);
  EXPECT_LT(latticeCorrelation(noise, 8), 0.2);
  EXPECT_EQ(latticeCorrelation(noise, 20), 0.0);  // no multiple below half the side
}

TEST(QualityMeasures, LatticeStepsFindTheStepAtTheLatticePlanes) {
  // A ramp of 0.01 per pixel that falls back at every lattice plane (period 8), pixel 0 at lattice
  // position 3: steps of 0.01 everywhere but the 0.07 into a plane.
  Image im(41, 1, 1);
  for (int x = 0; x < im.width; ++x) im.at(x, 0, 0) = 0.01f * float((3 + x) % 8);
  const LatticeSteps s = latticeSteps(im, 8, 3, 0);
  ASSERT_EQ(s.meanStep.size(), 8u);
  EXPECT_NEAR(s.meanStep[7], 0.07, 1e-6);
  EXPECT_NEAR(s.meanStep[3], 0.01, 1e-6);
  EXPECT_NEAR(s.seamRatio(), (0.07 + 0.01) / 2 / 0.01, 1e-4);
  EXPECT_NEAR(s.peak(), 7.0, 1e-4);
  // Read with another phase, the step is off the planes (at offset 4): the planes are smoother than
  // the mean inside, (5 * 0.01 + 0.07) / 6; the peak is the same.
  const LatticeSteps shifted = latticeSteps(im, 8, 0, 0);
  EXPECT_NEAR(shifted.seamRatio(), 0.01 / 0.02, 1e-4);
  EXPECT_NEAR(shifted.peak(), 7.0, 1e-4);
  EXPECT_THROW(latticeSteps(im, 2, 0, 0), Error);
}

TEST(QualityMeasures, FidelityIsZeroForAnyCropOfTheTiledExemplar) {
  const Image exemplar = test::noiseImage(16, 16);
  const Image tiled = applyCoords(tiling(50, 40, 16, 16), exemplar);
  EXPECT_DOUBLE_EQ(neighborhoodFidelity(tiled, exemplar, {3, 0}), 0.0);
}

TEST(QualityMeasures, FidelityOfAConstantOffsetIsThatOffset) {
  // Every neighborhood of a constant 0.2 image is 0.1 away (RMS) from every neighborhood of a
  // constant 0.3 exemplar: the measure is that distance, up to 8-bit quantization.
  const double f = neighborhoodFidelity(constant(20, 20, 0.2f), constant(8, 8, 0.3f), {3, 0});
  EXPECT_NEAR(f, 0.1, 1.0 / 255.0);
}

TEST(QualityMeasures, StructureFidelityIgnoresAConstantOffset) {
  // The tiled exemplar made 0.2 brighter: its colour fidelity is about 0.2 and its structure
  // fidelity (each neighbourhood's mean removed) about 0, as the tiling's own.
  const Image exemplar = test::noiseImage(16, 16);
  Image brighter = applyCoords(tiling(50, 40, 16, 16), exemplar);
  for (float& v : brighter.pixels) v = v * 0.7f + 0.2f;
  Image dimmer = exemplar;
  for (float& v : dimmer.pixels) v *= 0.7f;
  FidelityOptions structure{3, 0};
  structure.removeMean = true;
  EXPECT_NEAR(neighborhoodFidelity(brighter, dimmer, {3, 0}), 0.2, 1.5 / 255.0);
  EXPECT_LE(neighborhoodFidelity(brighter, dimmer, structure), 1.0 / 255.0);
  // Structure is not blind: noise stays far from the exemplar.
  EXPECT_GT(neighborhoodFidelity(test::noiseImage(40, 40, 9), dimmer, structure), 0.05);
}

TEST(QualityMeasures, FidelityOfNoiseIsWorseThanOfTheTiling) {
  const Image exemplar = test::noiseImage(16, 16);
  const double noise = neighborhoodFidelity(test::noiseImage(40, 40, 99), exemplar, {3, 0});
  EXPECT_GT(noise, 0.2);  // uniform noise: RMS difference of two independent uniforms is ~0.4
}

TEST(QualityMeasures, CompletenessIsZeroForATilingThatHoldsEveryWindow) {
  // A 2x2 tiling holds every toroidal 7x7 window of the exemplar wholly inside it; a single copy
  // misses the windows across the wrap.
  const Image exemplar = test::noiseImage(16, 16);
  EXPECT_DOUBLE_EQ(neighborhoodCompleteness(applyCoords(tiling(32, 32, 16, 16), exemplar), exemplar, {3, 0}), 0.0);
  EXPECT_GT(neighborhoodCompleteness(exemplar, exemplar, {3, 0}), 0.1);
  FidelityOptions inside{3, 0, false};
  EXPECT_DOUBLE_EQ(neighborhoodCompleteness(exemplar, exemplar, inside), 0.0);
}

TEST(QualityMeasures, CompletenessPenalizesWhatFidelityMisses) {
  // A flat image of the exemplar's mean colour matches the exemplar's flat regions: fidelity rates
  // it better than the exemplar's pixels shuffled. Completeness, the reverse direction, finds none
  // of the exemplar's dark or bright windows in it.
  const Image marble = readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/exemplars/marble.png");
  const Image exemplar = crop(marble, 0, 0, 64, 64);
  CoordMap shuffled = tiling(160, 160, 64, 64);
  uint32_t state = 12345;
  for (uint32_t& c : shuffled.coords) {
    state = state * 1664525u + 1013904223u;  // a linear congruential sequence
    c = packCoord((state >> 8) % 64, (state >> 20) % 64);
  }
  Image flat(160, 160, exemplar.channels);
  for (int c = 0; c < exemplar.channels; ++c) {
    double mean = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) mean += exemplar.at(x, y, c) / (64 * 64);
    for (int y = 0; y < 160; ++y)
      for (int x = 0; x < 160; ++x) flat.at(x, y, c) = float(mean);
  }
  const double flatFidelity = neighborhoodFidelity(flat, exemplar);
  EXPECT_LT(flatFidelity, neighborhoodFidelity(applyCoords(shuffled, exemplar), exemplar));
  EXPECT_GT(neighborhoodCompleteness(flat, exemplar), 2 * flatFidelity);
  EXPECT_DOUBLE_EQ(neighborhoodCompleteness(applyCoords(tiling(160, 160, 64, 64), exemplar), exemplar), 0.0);
}

TEST(QualityMeasures, HistogramDistanceIsTheEarthMoversDistance) {
  EXPECT_NEAR(histogramDistance(constant(8, 8, 0.2f), constant(4, 4, 0.7f)), 0.5, 1.0 / 255.0);
  EXPECT_DOUBLE_EQ(histogramDistance(test::noiseImage(16, 16), test::noiseImage(16, 16)), 0.0);
  // Half the mass moved by 0.4: distance 0.2.
  Image half = constant(8, 8, 0.2f);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 0; c < 3; ++c) half.at(x, y, c) = 0.6f;
  EXPECT_NEAR(histogramDistance(half, constant(8, 8, 0.2f)), 0.2, 1.0 / 255.0);
}

TEST(QualityMeasures, ContrastRatioIsTheRatioOfLuminanceDeviations) {
  const Image exemplar = test::noiseImage(16, 16);
  Image halved = exemplar;
  for (float& v : halved.pixels) v = 0.25f + v / 2;  // half the deviation about a shifted mean
  EXPECT_NEAR(contrastRatio(exemplar, exemplar), 1.0, 1e-9);
  EXPECT_NEAR(contrastRatio(halved, exemplar), 0.5, 1e-6);
  EXPECT_NEAR(contrastRatio(exemplar, halved), 2.0, 1e-5);
  EXPECT_EQ(contrastRatio(constant(8, 8, 0.4f), exemplar), 0.0);
  EXPECT_TRUE(std::isnan(contrastRatio(exemplar, constant(8, 8, 0.4f))));
}

TEST(QualityMeasures, CoherenceOfKnownMaps) {
  EXPECT_DOUBLE_EQ(coherence(tiling(30, 20, 8, 8)), 1.0);  // wrapping still counts as adjacent
  // A 2x2 map: (0,0) (1,0) / (5,5) (1,1): pairs: right-top coherent, right-bottom not,
  // down-left not, down-right coherent -> 2 of 4.
  CoordMap m{2, 2, 8, 8, {packCoord(0, 0), packCoord(1, 0), packCoord(5, 5), packCoord(1, 1)}};
  EXPECT_DOUBLE_EQ(coherence(m), 0.5);
}

TEST(QualityMeasures, CoverageCountsUsedExemplarPixels) {
  EXPECT_DOUBLE_EQ(coverage(tiling(8, 8, 8, 8)), 1.0);
  EXPECT_DOUBLE_EQ(coverage(tiling(4, 8, 8, 8)), 0.5);
  CoordMap one{3, 3, 4, 4, std::vector<uint32_t>(9, packCoord(2, 2))};
  EXPECT_DOUBLE_EQ(coverage(one), 1.0 / 16.0);
}

TEST(QualityMeasures, ShiftedCorrelationOfATilingIsOne) {
  const Image exemplar = test::noiseImage(16, 16);
  EXPECT_NEAR(shiftedSelfCorrelation(applyCoords(tiling(64, 64, 16, 16), exemplar), 16, 16), 1.0, 1e-9);
  EXPECT_LT(std::abs(shiftedSelfCorrelation(test::noiseImage(256, 256, 5), 16, 16)), 0.05);
  EXPECT_THROW(shiftedSelfCorrelation(exemplar, 16, 16), Error);
}

} // namespace
} // namespace texfab::synthesis
