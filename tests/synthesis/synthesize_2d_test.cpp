// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/error.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>

namespace texfab::synthesis {
namespace {

// A smooth, toroidal, structured exemplar (sums of periodic waves plus a little noise), so
// correction has real decisions to make.
Image wavyExemplar(int w, int h) {
  Image image(w, h, 3);
  const Image noise = test::noiseImage(w, h, 3);
  const double tau = 6.283185307179586;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        image.at(x, y, c) = float(0.5 + 0.25 * std::sin(tau * (x * (c + 1.0) / w + 2.0 * y / h)) +
                                  0.15 * std::cos(tau * 3.0 * y / h) + 0.1 * (noise.at(x, y, c) - 0.5));
  return image;
}

const ExemplarAnalysis& analysis48() {
  static const ExemplarAnalysis a = analyzeExemplar(wavyExemplar(48, 48), {});
  return a;
}

// The texels of `inner` (which must lie inside `outer`) cut out of a synthesized `outer` window.
std::vector<uint32_t> crop(const CoordMap& outer, const Window& o, const Window& inner) {
  std::vector<uint32_t> out;
  for (int y = 0; y < inner.height; ++y)
    for (int x = 0; x < inner.width; ++x)
      out.push_back(outer.at(int(inner.x - o.x) + x, int(inner.y - o.y) + y));
  return out;
}

TEST(Synthesize2d, WindowsAgreeWithAnyLargerWindowAcrossThreadsAndRuns) {
  const ExemplarAnalysis& a = analysis48();
  SynthesisOptions options;
  options.seed = 1234;
  const Window outer{-150, -77, 300, 260};
  const CoordMap big = synthesize2d(a, outer, options, Context{.threads = 2}).coords;
  // The same outer window again, on one thread: identical.
  EXPECT_EQ(synthesize2d(a, outer, options, Context{.threads = 1}).coords.coords, big.coords);

  uint32_t state = 99;
  auto next = [&](int range) { state = pcgHash(state); return int(state % uint32_t(range)); };
  for (int trial = 0; trial < 12; ++trial) {
    const int w = 1 + next(80), h = 1 + next(80);
    const Window inner{outer.x + next(outer.width - w + 1), outer.y + next(outer.height - h + 1), w, h};
    SCOPED_TRACE("window " + std::to_string(inner.x) + "," + std::to_string(inner.y) + "," + std::to_string(w) +
                 "x" + std::to_string(h));
    const int threads = 1 + trial % 2;
    EXPECT_EQ(synthesize2d(a, inner, options, Context{.threads = threads}).coords.coords, crop(big, outer, inner));
  }
}

TEST(Synthesize2d, DistantWindowsAreDeterministicToo) {
  const ExemplarAnalysis& a = analysis48();
  const Window far{-1000000007, 2000000011, 40, 30};
  const Window farInner{far.x + 13, far.y + 7, 9, 11};
  const CoordMap big = synthesize2d(a, far, {}, Context{.threads = 2}).coords;
  EXPECT_EQ(synthesize2d(a, farInner, {}, Context{.threads = 1}).coords.coords, crop(big, far, farInner));
}

TEST(Synthesize2d, InterleaveAndPassesKeepWindowDeterminism) {
  const ExemplarAnalysis& a = analysis48();
  for (int interleave : {1, 3})
    for (int passes : {1, 3}) {
      SynthesisOptions options;
      options.interleave = interleave;
      options.passes = passes;
      const Window outer{-20, 5, 120, 90};
      const Window inner{17, 31, 23, 19};
      EXPECT_EQ(synthesize2d(a, inner, options, Context{.threads = 2}).coords.coords,
                crop(synthesize2d(a, outer, options, Context{.threads = 1}).coords, outer, inner))
          << "interleave " << interleave << " passes " << passes;
    }
}

TEST(Synthesize2d, ZeroJitterIsAnExactTiling) {
  for (const auto& [w, h] : {std::pair{32, 32}, std::pair{48, 40}, std::pair{37, 23}}) {
    const ExemplarAnalysis a = analyzeExemplar(wavyExemplar(w, h), {});
    SynthesisOptions options;
    options.jitter = {0.0f};
    const Window window{-70, -45, 200, 150};
    const CoordMap m = synthesize2d(a, window, options).coords;
    for (int y = 0; y < window.height; ++y)
      for (int x = 0; x < window.width; ++x) {
        const auto u = uint32_t(cpu::floorMod(window.x + x, w)), v = uint32_t(cpu::floorMod(window.y + y, h));
        ASSERT_EQ(m.at(x, y), packCoord(u, v)) << "exemplar " << w << "x" << h << " at " << x << "," << y;
      }
  }
}

TEST(Synthesize2d, TileableOutputWrapsAtItsSize) {
  const ExemplarAnalysis& a = analysis48();
  SynthesisOptions options;
  options.periodX = 96;
  options.periodY = 64;
  const CoordMap m = synthesize2d(a, {0, 0, 192, 128}, options).coords;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 96; ++x) {
      ASSERT_EQ(m.at(x, y), m.at(x + 96, y));
      ASSERT_EQ(m.at(x, y), m.at(x, y + 64));
    }
  // And it is not a plain tiling of the exemplar.
  SynthesisOptions untiled = options;
  untiled.periodX = untiled.periodY = 0;
  EXPECT_NE(m.coords, synthesize2d(a, {0, 0, 192, 128}, untiled).coords.coords);
}

TEST(Synthesize2d, SeedIsTheOnlySourceOfVariation) {
  const ExemplarAnalysis& a = analysis48();
  SynthesisOptions one, two;
  one.seed = 1;
  two.seed = 2;
  const Window window{0, 0, 64, 64};
  const CoordMap m1 = synthesize2d(a, window, one).coords;
  EXPECT_EQ(m1.coords, synthesize2d(a, window, one).coords.coords);
  const CoordMap m2 = synthesize2d(a, window, two).coords;
  size_t differing = 0;
  for (size_t i = 0; i < m1.coords.size(); ++i) differing += m1.coords[i] != m2.coords[i];
  EXPECT_GT(differing, m1.coords.size() / 2);
}

TEST(Synthesize2d, CoordinatesStayInsideTheExemplar) {
  const ExemplarAnalysis a = analyzeExemplar(wavyExemplar(37, 23), {});
  const CoordMap m = synthesize2d(a, {-5, -9, 150, 120}, {}).coords;
  for (uint32_t c : m.coords) {
    ASSERT_LT(coordU(c), 37u);
    ASSERT_LT(coordV(c), 23u);
  }
}

TEST(Synthesize2d, CorrectionImprovesNeighborhoodFidelity) {
  // Upsampled, jittered coordinates without correction leave seams everywhere; correction must
  // bring every 7x7 neighborhood much closer to one of the exemplar.
  const Image exemplar = wavyExemplar(48, 48);
  const ExemplarAnalysis& a = analysis48();
  SynthesisOptions raw;
  raw.correct = false;
  const double before = neighborhoodFidelity(applyCoords(synthesize2d(a, {0, 0, 128, 128}, raw).coords, exemplar), exemplar);
  const double after = neighborhoodFidelity(applyCoords(synthesize2d(a, {0, 0, 128, 128}, {}).coords, exemplar), exemplar);
  EXPECT_LT(after, 0.7 * before);
}

TEST(Synthesize2d, RejectsBadParameters) {
  const ExemplarAnalysis& a = analysis48();
  EXPECT_THROW(synthesize2d(a, {0, 0, 0, 10}, {}), Error);
  EXPECT_THROW(synthesize2d(a, {0, 0, 70000, 10}, {}), Error);
  SynthesisOptions bad;
  bad.jitter = {1.5f};
  EXPECT_THROW(synthesize2d(a, {0, 0, 8, 8}, bad), Error);
  bad = {};
  bad.interleave = 4;
  EXPECT_THROW(synthesize2d(a, {0, 0, 8, 8}, bad), Error);
}

} // namespace
} // namespace texfab::synthesis
