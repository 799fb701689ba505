// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/downsample.h"
#include "core/error.h"
#include "core/hash.h"
#include "core/image_io.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_graph.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"
#include "synthesis/synthesize_graph.h"

#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <complex>
#include <filesystem>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

namespace texfab::synthesis {
namespace {

// A side x side RGB exemplar of blobs and stripes from `seed`.
Image patterned(int side, uint32_t seed) {
  Image image(side, side, 3);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      for (int c = 0; c < 3; ++c)
        image.pixel(x, y)[c] = float((texelHash(seed, 0, x / 3, y / 2, uint32_t(c)) >> 24) % 200) / 255.0f +
                               0.2f * float((x + 2 * y + int(seed)) % 7 == 0);
  return image;
}

ExemplarGraph twoNodes(int side, int octaves) {
  ExemplarGraph g;
  g.names = {"coarse", "fine"};
  g.exemplars = {patterned(side, 1), patterned(side, 2)};
  g.edges = {{0, 1, octaves}};
  return g;
}

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

Image photo(const char* name) {
  return readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models" / "exemplars" / "photos" / name);
}

// The two-node graph: rock regions detailed by stone grain at 1/16 the scale.
ExemplarGraph rockAndStone() {
  ExemplarGraph g;
  g.names = {"rock", "stone"};
  g.exemplars = {photo("rock.png"), photo("stone.png")};
  g.edges = {{0, 1, 4}};
  return g;
}

TEST(ExemplarGraph, RefusesBadGraphsWithOneLine) {
  auto refused = [](ExemplarGraph g) { return refusal([&] { g.validate(); }); };
  ExemplarGraph g = twoNodes(32, 2);
  EXPECT_EQ(refused(g), "(accepted)");
  ExemplarGraph bad = g;
  bad.exemplars[1] = patterned(16, 3);
  EXPECT_NE(refused(bad).find("every exemplar of a graph has the same size"), std::string::npos) << refused(bad);
  bad = g;
  bad.exemplars[1] = Image(32, 24, 3);
  EXPECT_NE(refused(bad).find("must be square, with a power-of-two side"), std::string::npos) << refused(bad);
  bad = g;
  bad.edges[0].octaves = 0;
  EXPECT_NE(refused(bad).find("scale ratio must be greater than 1"), std::string::npos) << refused(bad);
  bad = g;
  bad.edges[0].octaves = 6;  // 64 > 32 pixels
  EXPECT_NE(refused(bad).find("the whole destination would fit in one pixel"), std::string::npos) << refused(bad);
  bad = g;
  bad.edges.push_back(g.edges[0]);
  EXPECT_NE(refused(bad).find("is given twice"), std::string::npos) << refused(bad);
  bad = g;
  bad.edges.clear();
  EXPECT_NE(refused(bad).find("'fine' is not reached from the root 'coarse'"), std::string::npos) << refused(bad);
  bad = g;
  bad.exemplars[0].pixels[5] = std::nanf("");
  EXPECT_NE(refused(bad).find("not finite"), std::string::npos) << refused(bad);
  // Valid, but too deep for 32-pixel exemplars: 8 texels of 'fine' need 2^(3+3) pixels.
  bad = twoNodes(32, 3);
  EXPECT_NE(refusal([&] { analyzeGraph(bad); }).find("use exemplars of at least 64 pixels or a smaller scale"),
            std::string::npos);
}

TEST(ExemplarGraph, DeepestLevelFollowsTheLongestPathAndCyclesAreInfinite) {
  ExemplarGraph g = twoNodes(16, 2);  // L = 4
  g.names.push_back("finer");
  g.exemplars.push_back(patterned(16, 4));
  g.edges.push_back({1, 2, 1});
  g.edges.push_back({0, 2, 1});
  EXPECT_EQ(g.deepestLevel(), 4 + 2 + 1);
  g.edges.push_back({2, 2, 1});  // self-similar: zooms forever
  EXPECT_EQ(g.deepestLevel(), -1);
}

// Han's admissible sets (thesis §5.2.1.2): candidates of a level lie in the level itself (where a
// texel may stay) or in an edge's destination at k - r, never in the finest level of an exemplar
// with edges out, never above the entry level.
TEST(ExemplarGraph, CandidatesLieInAdmissibleLevels) {
  const GraphAnalysis a = analyzeGraph(twoNodes(64, 2));  // L = 6, entry level 3
  ASSERT_EQ(a.levels, 7);
  EXPECT_EQ(a.k, 1 + 2 * 2);
  const int m = a.side;
  const size_t aw = size_t(a.atlasWidth());
  EXPECT_FALSE(a.selfAdmissible[size_t(a.finestLevel() * m)]);                 // the root's finest level
  EXPECT_TRUE(a.selfAdmissible[size_t(m) * aw + size_t(a.finestLevel() * m)]);  // the leaf's
  int crossings = 0;
  for (int y = 0; y < a.atlasHeight(); ++y)
    for (int x = 0; x < a.atlasWidth(); ++x) {
      const int node = y / m, level = x / m;
      for (int i = 0; i < a.k; ++i) {
        const uint32_t c = a.candidates[(size_t(y) * a.atlasWidth() + x) * size_t(a.k) + size_t(i)];
        const int cNode = int(coordV(c)) / m, cLevel = int(coordU(c)) / m;
        const bool same = cNode == node && cLevel == level;
        const bool edge = node == 0 && cNode == 1 && cLevel == level - 2 && cLevel >= 3;
        ASSERT_TRUE((same && a.selfAdmissible[size_t(y) * aw + size_t(x)]) || edge)
            << "texel (" << x << ", " << y << ") candidate " << i << " in node " << cNode << " level " << cLevel;
        crossings += edge;
      }
    }
  EXPECT_GT(crossings, 0);
}

// The cached analysis is the computed one; a truncated or foreign file is recomputed, never trusted.
TEST(ExemplarGraph, CachedAnalysesAreTheComputedOnesAndDamagedFilesAreRecomputed) {
  test::TempDir dir;
  const ExemplarGraph g = twoNodes(32, 1);
  const AnalysisCacheSettings cache{dir.path(), uint64_t(1) << 30};
  bool cached = true;
  const GraphAnalysis first = analyzeGraph(g, {}, cache, {}, &cached);
  EXPECT_FALSE(cached);
  const GraphAnalysis second = analyzeGraph(g, {}, cache, {}, &cached);
  EXPECT_TRUE(cached);
  EXPECT_EQ(second.colors.pixels, first.colors.pixels);
  EXPECT_EQ(second.appearance, first.appearance);
  EXPECT_EQ(second.neighborhood, first.neighborhood);
  EXPECT_EQ(second.candidates, first.candidates);
  EXPECT_EQ(second.selfAdmissible, first.selfAdmissible);
  EXPECT_EQ(second.entryLevel, first.entryLevel);
  const std::filesystem::path file = std::filesystem::directory_iterator(dir.path())->path();
  EXPECT_FALSE(readGraphAnalysis(file, first.key + 1)) << "a foreign key was trusted";
  std::filesystem::resize_file(file, std::filesystem::file_size(file) / 2);
  EXPECT_FALSE(readGraphAnalysis(file, first.key));
  const GraphAnalysis third = analyzeGraph(g, {}, cache, {}, &cached);
  EXPECT_FALSE(cached);
  EXPECT_EQ(third.candidates, first.candidates);
  EXPECT_EQ(second.transfers, first.transfers);
  EXPECT_EQ(second.transferAppearance, first.transferAppearance);
}

// Thesis §5.3's convention: coarser exemplars decide the colours of finer levels. A fine exemplar
// that is the coarse one's pattern made 0.25 darker keeps, zoomed in, the coarse one's mean colour
// with transfers, and shows its own without them. Within an exemplar a transfer is 0.
TEST(SynthesizeGraph, TransfersKeepTheCoarseExemplarsColours) {
  ExemplarGraph g = twoNodes(64, 2);
  for (float& v : g.exemplars[0].pixels) v = 0.3f + 0.7f * v;
  g.exemplars[1] = g.exemplars[0];
  for (float& v : g.exemplars[1].pixels) v -= 0.25f;
  const auto mean = [](const Image& image) {
    double sum = 0;
    for (float v : image.pixels) sum += v;
    return sum / double(image.pixels.size());
  };
  ExemplarGraph own = g;
  own.coarseColors = false;
  const GraphAnalysis a = analyzeGraph(g), b = analyzeGraph(own);
  EXPECT_NE(a.key, b.key);
  EXPECT_TRUE(b.transfers.empty());
  ASSERT_EQ(a.transfers.size(), a.candidates.size() * 3);
  for (size_t slot = 0; slot < a.candidates.size(); ++slot) {
    const size_t node = slot / size_t(a.k) / size_t(a.atlasWidth()) / size_t(a.side);
    if (coordV(a.candidates[slot]) / uint32_t(a.side) != node) continue;
    for (int c = 0; c < 3; ++c) ASSERT_EQ(a.transfers[slot * 3 + size_t(c)], 0) << "slot " << slot;
  }
  GraphSynthesisOptions options;
  options.zoomOctaves = 5;  // the fine exemplar at its finest level
  const Window w{0, 0, 96, 96};
  const SynthesisResult corrected = synthesizeGraph(a, w, options), plain = synthesizeGraph(b, w, options);
  for (uint32_t c : corrected.coords.coords) ASSERT_EQ(coordV(c) / uint32_t(a.side), 1u) << "all texels in the fine exemplar";
  const double coarse = mean(g.exemplars[0]);
  EXPECT_NEAR(mean(graphColors(corrected, a)), coarse, 0.03);
  EXPECT_NEAR(mean(graphColors(plain, b)), coarse - 0.25, 0.03);
}

// Every output texel is a function of its position: windows agree with larger requests, at any
// thread count, at every zoom.
TEST(SynthesizeGraph, WindowsAgreeWithLargerRequestsAndThreadCounts) {
  const GraphAnalysis a = analyzeGraph(twoNodes(64, 2));
  for (int zoom : {-1, 0, 2, 3}) {
    GraphSynthesisOptions options;
    options.zoomOctaves = zoom;
    options.seed = 7;
    const Window outer{-21, -13, 80, 70};
    const SynthesisResult big = synthesizeGraph(a, outer, options, Context{.threads = 2});
    ASSERT_FALSE(big.colorOffsets.empty()) << "the two exemplars differ in colour: transfers are expected";
    for (const Window inner : {Window{-21, -13, 80, 70}, Window{-5, 4, 31, 17}, Window{40, 30, 19, 27}}) {
      const SynthesisResult part = synthesizeGraph(a, inner, options, Context{.threads = 1});
      for (int y = 0; y < inner.height; ++y)
        for (int x = 0; x < inner.width; ++x) {
          const int bx = int(inner.x - outer.x) + x, by = int(inner.y - outer.y) + y;
          ASSERT_EQ(part.coords.at(x, y), big.coords.at(bx, by))
              << "zoom 2^" << zoom << " texel (" << inner.x + x << ", " << inner.y + y << ")";
          for (int c = 0; c < 3; ++c)
            ASSERT_EQ(part.colorOffsets.at(x, y, c), big.colorOffsets.at(bx, by, c))
                << "zoom 2^" << zoom << " offset at (" << inner.x + x << ", " << inner.y + y << ")";
        }
    }
    options.seed = 8;
    EXPECT_NE(synthesizeGraph(a, outer, options).coords.coords, big.coords.coords) << "the seed changes nothing";
  }
}

// --tileable: the output repeats at its period, at every zoom, whether the period tiles every level
// (a multiple of interleave * 2^level) or only the finer ones (the coarser are read wrapped).
TEST(SynthesizeGraph, TileableOutputsRepeatAtTheirPeriod) {
  const GraphAnalysis a = analyzeGraph(twoNodes(64, 2));  // L = 6
  for (const auto& [zoom, period] : {std::pair{0, 128}, std::pair{0, 48}, std::pair{2, 40}, std::pair{-1, 64}}) {
    GraphSynthesisOptions options;
    options.zoomOctaves = zoom;
    options.seed = 3;
    options.periodX = options.periodY = period;
    SCOPED_TRACE("zoom 2^" + std::to_string(zoom) + ", period " + std::to_string(period) + ", periodic from level " +
                 std::to_string(graphFirstPeriodicLevel(a, options)));
    const Window w{-period / 2, -7, 2 * period + 5, 2 * period + 3};
    const SynthesisResult result = synthesizeGraph(a, w, options);
    const CoordMap& out = result.coords;
    const Image colors = graphColors(result, a);
    for (int y = 0; y < w.height; ++y)
      for (int x = 0; x < w.width; ++x) {
        if (x + period < w.width) {
          ASSERT_EQ(out.at(x, y), out.at(x + period, y)) << "texel (" << x << ", " << y << ")";
          ASSERT_EQ(colors.at(x, y, 1), colors.at(x + period, y, 1)) << "colour at (" << x << ", " << y << ")";
        }
        if (y + period < w.height) {
          ASSERT_EQ(out.at(x, y), out.at(x, y + period)) << "texel (" << x << ", " << y << ")";
          ASSERT_EQ(colors.at(x, y, 1), colors.at(x, y + period, 1)) << "colour at (" << x << ", " << y << ")";
        }
      }
    // The tile is not one exemplar texel repeated.
    std::vector<uint32_t> distinct(out.coords.begin(), out.coords.end());
    std::sort(distinct.begin(), distinct.end());
    EXPECT_GT(std::unique(distinct.begin(), distinct.end()) - distinct.begin(), period * period / 8);
  }
  GraphSynthesisOptions odd;
  odd.periodX = odd.periodY = 47;
  EXPECT_NE(refusal([&] { synthesizeGraph(a, {0, 0, 47, 47}, odd); }).find("must be a multiple of the interleave"),
            std::string::npos);
}

// The two-node target on photographs: a coarse exemplar (rock) detailed by a fine one
// (stone) at 1/16 the scale. At every zoom from 1 to 16 the output's 7x7 fidelity to the exemplar
// that governs it is within 1.3x a single-exemplar synthesis' seen the same way: at zoom 1 the
// rock, at zoom z > 1 the stone box-filtered by 16 / z (against a single synthesis 16 / z times
// as large, box-filtered alike). The stone is shown with the rock's colours (thesis §5.3's
// transfers), so it is measured by structure, each neighbourhood's mean removed; the rock by
// colour too.
TEST(SynthesizeGraph, EachScaleIsAsFaithfulAsASingleExemplarSynthesis) {
  const ExemplarGraph g = rockAndStone();
  const GraphAnalysis a = analyzeGraph(g);
  const int side = 192;
  FidelityOptions colour, structure;
  structure.removeMean = true;
  for (int zoom = 0; zoom <= 4; ++zoom) {
    const int node = zoom == 0 ? 0 : 1, factor = zoom == 0 ? 1 : 1 << (4 - zoom);
    const Image& exemplar = g.exemplars[size_t(node)];
    GraphSynthesisOptions options;
    options.zoomOctaves = zoom;
    const Image graph = graphColors(synthesizeGraph(a, {0, 0, side, side}, options), a);
    AnalysisOptions single;
    single.wrap = detectExemplarWrap(exemplar);
    const Window large{0, 0, side * factor, side * factor};
    const Image alone =
        downsample(applyCoords(synthesize2d(analyzeExemplar(exemplar, single), large, {}).coords, exemplar), factor);
    const Image governing = downsample(exemplar, factor);
    for (const FidelityOptions& f : zoom == 0 ? std::vector{colour, structure} : std::vector{structure}) {
      const double ratio = neighborhoodFidelity(graph, governing, f) / neighborhoodFidelity(alone, governing, f);
      const std::string what = g.names[size_t(node)] + (f.removeMean ? " structure" : " colour") + " at zoom " +
                               std::to_string(1 << zoom);
      EXPECT_LE(ratio, 1.3) << what;
      RecordProperty(what, std::to_string(ratio));
    }
  }
}

// Edge regions: a root of two regions (warm and cool stripes 16 pixels wide, textured), each
// detailed by its own exemplar at 1/16 the scale. Zoomed 16x, a texel lies in the exemplar of the
// region its ancestor was in at zoom 1/2 (root level L - 1, before any edge can be taken).
TEST(SynthesizeGraph, EdgeRegionsDecideWhichExemplarDetailsWhere) {
  ExemplarGraph g;
  g.names = {"regions", "stone", "rock"};
  Image regions(128, 128, 3);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const float grain = float(texelHash(3, 0, x / 4, y / 4, 0) >> 24) / 255.0f * 0.2f;
      const bool warm = (x / 16) % 2 == 0;
      regions.at(x, y, 0) = (warm ? 0.7f : 0.2f) + grain;
      regions.at(x, y, 1) = 0.4f + grain;
      regions.at(x, y, 2) = (warm ? 0.2f : 0.7f) + grain;
    }
  g.exemplars = {regions, photo("stone.png"), photo("rock.png")};
  GraphEdge toStone{0, 1, 4}, toRock{0, 2, 4};
  toStone.region.assign(128 * 128, 0);
  toRock.region.assign(128 * 128, 0);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) ((x / 16) % 2 == 0 ? toStone : toRock).region[size_t(y) * 128 + x] = 1;
  g.edges = {toStone, toRock};
  const GraphAnalysis a = analyzeGraph(g);

  GraphSynthesisOptions options;
  options.zoomOctaves = -1;
  const int side = 512;
  const Image coarse = graphColors(synthesizeGraph(a, {0, 0, side / 32, side / 32}, options), a);
  options.zoomOctaves = 4;
  const CoordMap fine = synthesizeGraph(a, {0, 0, side, side}, options).coords;
  int agree = 0, stone = 0;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const bool warm = coarse.at(x >> 5, y >> 5, 0) > coarse.at(x >> 5, y >> 5, 2);
      const int node = int(coordV(fine.coords[size_t(y) * side + x])) / a.side;
      agree += node == (warm ? 1 : 2);
      stone += node == 1;
    }
  const double agreement = agree / double(side * side), stoneShare = stone / double(side * side);
  RecordProperty("agreement", std::to_string(agreement));
  std::cout << "regions: " << agreement << " of texels in their region's exemplar, stone " << stoneShare << "\n";
  EXPECT_GE(agreement, 0.9);
  EXPECT_GT(stoneShare, 0.1);
  EXPECT_LT(stoneShare, 0.9);
  // Without regions the same graph has no reason to follow them.
  g.edges[0].region.clear();
  g.edges[1].region.clear();
  EXPECT_NE(analyzeGraph(g).key, a.key);
}

// Radially averaged power spectrum of a square power-of-two image's luminance (mean removed), in
// octave bands [2^b, 2^(b+1)) cycles per side, b = 0 .. log2(side) - 2, as shares of the total.
std::vector<double> octaveSpectrum(const Image& image) {
  const int n = image.width;
  std::vector<std::complex<double>> lum(size_t(n) * size_t(n)), rows(lum.size());
  double mean = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const float* p = image.pixel(x, y);
      lum[size_t(y) * n + x] = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
      mean += lum[size_t(y) * n + x].real() / (double(n) * n);
    }
  std::vector<std::complex<double>> twiddle(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) twiddle[size_t(k)] = std::polar(1.0, -2 * M_PI * k / n);
  const auto dft = [&](auto at, auto put) {  // one separable pass: out[u] = sum_x in[x] w^(ux)
    for (int line = 0; line < n; ++line)
      for (int u = 0; u < n; ++u) {
        std::complex<double> sum = 0;
        for (int x = 0; x < n; ++x) sum += at(line, x) * twiddle[size_t((u * x) % n)];
        put(line, u, sum);
      }
  };
  dft([&](int y, int x) { return lum[size_t(y) * n + x] - mean; }, [&](int y, int u, auto v) { rows[size_t(y) * n + u] = v; });
  dft([&](int u, int y) { return rows[size_t(y) * n + u]; }, [&](int u, int v, auto c) { lum[size_t(v) * n + u] = c; });
  const int bands = std::countr_zero(unsigned(n)) - 1;
  std::vector<double> power(size_t(bands), 0.0);
  for (int v = 0; v < n; ++v)
    for (int u = 0; u < n; ++u) {
      const int fu = std::min(u, n - u), fv = std::min(v, n - v);
      const double r = std::sqrt(double(fu * fu + fv * fv));
      if (r < 1 || r >= n / 2) continue;
      power[size_t(std::floor(std::log2(r)))] += std::norm(lum[size_t(v) * n + u]);
    }
  double total = 0;
  for (double p : power) total += p;
  for (double& p : power) p /= total;
  return power;
}

// A scale jump against magnification. In a zoom sweep nested at the origin, view z + 1 shows the
// top-left quarter of view z's region at twice the resolution. The features of that quarter
// persist: they keep their band (cycles per region) in view z + 1, whose finest band is new
// detail. Between consecutive views, the RMS over the quarter's bands of log2 of the ratio of
// their power shares (each normalized over those bands) measures how much the persisting features
// change (a jump); the finest band's share of view z + 1 measures how much detail a zoom adds
// (magnification adds none).
struct ZoomSweepMeasures {
  double largestPersistingStep = 0;
  double leastNewDetail = INFINITY;
};

ZoomSweepMeasures measureZoomSweep(const std::vector<Image>& sweep) {
  ZoomSweepMeasures m;
  for (size_t z = 0; z + 1 < sweep.size(); ++z) {
    const int half = sweep[z].width / 2;
    Image quarter(half, half, sweep[z].channels);
    for (int y = 0; y < half; ++y) std::copy_n(sweep[z].pixel(0, y), size_t(half) * size_t(quarter.channels), quarter.pixel(0, y));
    const std::vector<double> before = octaveSpectrum(quarter), after = octaveSpectrum(sweep[z + 1]);
    double common = 0;
    for (size_t b = 0; b < before.size(); ++b) common += after[b];
    double sum = 0;
    for (size_t b = 0; b < before.size(); ++b) sum += std::pow(std::log2(after[b] / common / before[b]), 2);
    m.largestPersistingStep = std::max(m.largestPersistingStep, std::sqrt(sum / double(before.size())));
    m.leastNewDetail = std::min(m.leastNewDetail, after.back());
  }
  return m;
}

// Views of a square image's top-left corner at zoom 2^z, z = 0 .. octaves, each `side` pixels,
// magnified bilinearly: a zoom that adds no detail and changes nothing.
std::vector<Image> magnifiedSweep(const Image& image, int side, int octaves) {
  std::vector<Image> sweep;
  for (int z = 0; z <= octaves; ++z) {
    Image view(side, side, image.channels);
    const double scale = 1.0 / double(1 << z);
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        const double fx = std::max(0.0, (x + 0.5) * scale - 0.5), fy = std::max(0.0, (y + 0.5) * scale - 0.5);
        const int x0 = int(fx), y0 = int(fy), x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
        const double sx = fx - x0, sy = fy - y0;
        for (int c = 0; c < image.channels; ++c)
          view.at(x, y, c) = float((1 - sy) * ((1 - sx) * image.at(x0, y0, c) + sx * image.at(x1, y0, c)) +
                                   sy * ((1 - sx) * image.at(x0, y1, c) + sx * image.at(x1, y1, c)));
      }
    sweep.push_back(std::move(view));
  }
  return sweep;
}

// The zoom sweep through the rock -> stone graph (zoom 1 to 16, a view each octave) and three
// references: a single exemplar's synthesis zoomed by box-filtered views of one large synthesis
// (detail at every zoom, no jump; of the two exemplars, the larger step and the smaller detail),
// the rock magnified (no jump, no new detail) and a sweep that cuts from the magnified rock to a
// stone synthesis halfway (a jump). Computed once for the tests below.
struct ZoomSweeps {
  ZoomSweepMeasures graph, single, magnified, jump;
};

const ZoomSweeps& zoomSweeps() {
  static const ZoomSweeps sweeps = [] {
    const ExemplarGraph g = rockAndStone();
    const GraphAnalysis a = analyzeGraph(g);
    const int side = 128, octaves = 4;
    ZoomSweeps m;
    std::vector<Image> graphSweep;
    for (int z = 0; z <= octaves; ++z) {
      GraphSynthesisOptions options;
      options.zoomOctaves = z;
      graphSweep.push_back(graphColors(synthesizeGraph(a, {0, 0, side, side}, options), a));
    }
    m.graph = measureZoomSweep(graphSweep);
    std::vector<Image> alone;  // a side^2 synthesis of each exemplar
    for (const Image& exemplar : g.exemplars) {
      AnalysisOptions o;
      o.wrap = detectExemplarWrap(exemplar);
      const ExemplarAnalysis analysis = analyzeExemplar(exemplar, o);
      const Image large = applyCoords(synthesize2d(analysis, {0, 0, side << octaves, side << octaves}, {}).coords, exemplar);
      std::vector<Image> sweep;
      for (int z = 0; z <= octaves; ++z) {
        const int factor = 1 << (octaves - z);
        Image view(side * factor, side * factor, large.channels);
        for (int y = 0; y < view.height; ++y)
          std::copy_n(large.pixel(0, y), size_t(view.width) * size_t(view.channels), view.pixel(0, y));
        sweep.push_back(downsample(view, factor));
      }
      const ZoomSweepMeasures one = measureZoomSweep(sweep);
      m.single.largestPersistingStep = std::max(m.single.largestPersistingStep, one.largestPersistingStep);
      m.single.leastNewDetail = std::min(m.single.leastNewDetail, one.leastNewDetail);
      alone.push_back(applyCoords(synthesize2d(analysis, {0, 0, side, side}, {}).coords, exemplar));
    }
    std::vector<Image> magnified = magnifiedSweep(alone[0], side, octaves);
    m.magnified = measureZoomSweep(magnified);
    for (int z = octaves / 2 + 1; z <= octaves; ++z) magnified[size_t(z)] = alone[1];
    m.jump = measureZoomSweep(magnified);
    for (const auto& [name, r] : {std::pair{"graph", m.graph}, {"single exemplar", m.single}, {"rock magnified", m.magnified},
                                  {"magnified rock, then stone", m.jump}})
      std::cout << name << ": largest step of persisting features " << r.largestPersistingStep << ", least new detail "
                << r.leastNewDetail << "\n";
    return m;
  }();
  return sweeps;
}

// The measures tell the three references apart (a jump changes persisting features; magnifying
// changes none and adds no detail), and the graph adds detail at every zoom as a single exemplar
// does.
TEST(SynthesizeGraph, AZoomSweepAddsDetailAtEveryZoom) {
  const ZoomSweeps& m = zoomSweeps();
  RecordProperty("graph_persisting_step", std::to_string(m.graph.largestPersistingStep));
  RecordProperty("graph_new_detail", std::to_string(m.graph.leastNewDetail));
  EXPECT_GT(m.jump.largestPersistingStep, 4 * m.single.largestPersistingStep);
  EXPECT_GT(m.jump.largestPersistingStep, 2 * m.magnified.largestPersistingStep);
  EXPECT_LT(m.magnified.leastNewDetail, 0.2 * m.single.leastNewDetail);
  EXPECT_GE(m.graph.leastNewDetail, 0.5 * m.single.leastNewDetail);
}

// The "no visible scale jump": the persisting features change at most twice as much as in
// a single exemplar's zoom. Thesis §5.3's transfers carry the rock's colours into the stone's
// coarse levels (without them: 1.61, near the cut's 2.03).
TEST(SynthesizeGraph, AZoomSweepHasNoScaleJump) {
  const ZoomSweeps& m = zoomSweeps();
  EXPECT_LE(m.graph.largestPersistingStep, 2 * m.single.largestPersistingStep);
}

} // namespace
} // namespace texfab::synthesis
