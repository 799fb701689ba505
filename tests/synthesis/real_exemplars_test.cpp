// SPDX-License-Identifier: GPL-3.0-or-later
// Synthesis of 1024^2 textures from real exemplars (GIMP's patterns, Debian gimp-data), each
// measured against two baselines: a random-coordinate image (noise made of exemplar pixels) and a
// verbatim tiling.
#include "core/image_io.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace texfab::synthesis {
namespace {

CoordMap randomCoords(int w, int h, int ew, int eh) {
  CoordMap m{w, h, ew, eh, {}};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      m.coords.push_back(packCoord(texelHash(5, 0, x, y, 0) % uint32_t(ew), texelHash(5, 0, x, y, 1) % uint32_t(eh)));
  return m;
}

class RealExemplar : public ::testing::TestWithParam<const char*> {};

TEST_P(RealExemplar, SynthesisBeatsTheBaselines) {
  const auto path = test::gimpPatterns() / GetParam();
  ASSERT_TRUE(std::filesystem::exists(path)) << path << " missing: gimp-data is not installed (scripts/install-deps.sh)";
  const Image exemplar = readImage(path);
  const ExemplarAnalysis analysis = analyzeExemplar(exemplar, {});
  const SynthesisResult result = synthesize2d(analysis, {0, 0, 1024, 1024}, {});
  const Image image = applyCoords(result.coords, exemplar);
  const QualityReport q = measureQuality(image, exemplar, &result.coords);

  const CoordMap noise = randomCoords(1024, 1024, exemplar.width, exemplar.height);
  const double noiseFidelity = neighborhoodFidelity(applyCoords(noise, exemplar), exemplar);
  const double noiseCoherence = coherence(noise);

  RecordProperty("fidelity", std::to_string(q.fidelity));
  RecordProperty("random_fidelity", std::to_string(noiseFidelity));
  std::printf("%-22s fidelity %.4f (random %.4f)  histogram %.4f  coherence %.3f  coverage %.3f  shifted %.3f\n",
              GetParam(), q.fidelity, noiseFidelity, q.histogramDistance, *q.coherence, *q.coverage,
              q.shiftedCorrelation);
  EXPECT_LE(q.fidelity, 0.5 * noiseFidelity);
  EXPECT_LE(q.histogramDistance, 0.05);
  EXPECT_GT(*q.coherence, noiseCoherence);
  EXPECT_LT(*q.coherence, 1.0);
  EXPECT_GE(*q.coverage, 0.5);
  EXPECT_LE(q.shiftedCorrelation, 0.5);
}

// Brick and parquet have strong features (mortar lines, plank edges); the others are stochastic.
INSTANTIATE_TEST_SUITE_P(GimpPatterns, RealExemplar,
                         ::testing::Values("Stone/brick.pat", "Wood/parque1.pat", "Stone/marble1.pat",
                                           "Stone/granite1.pat", "Wood/wood1.pat", "Stone/slate.pat"),
                         [](const auto& info) {
                           std::string name = info.param;
                           name = name.substr(name.find('/') + 1);
                           return name.substr(0, name.find('.'));
                         });

} // namespace
} // namespace texfab::synthesis
