// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6;
//           S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3.
#include "synthesis/synthesize_surface.h"

#include "render/image/error.h"
#include "render/image/parallel.h"
#include "synthesis/cpu/surface_kernels.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace texfab::synthesis {

namespace {

// Sites per task.
constexpr int kSiteGrain = 4096;

template <class Fn>
void forSites(size_t count, const Context& ctx, Fn&& fn) {
  parallelFor(0, int((count + kSiteGrain - 1) / kSiteGrain), ctx, [&](int b, int e) {
    fn(size_t(b) * kSiteGrain, std::min(count, size_t(e) * kSiteGrain));
  });
}

} // namespace

void SurfaceSynthesisOptions::validate() const {
  for (float j : jitter)
    if (!(j >= 0.0f && j <= 1.0f)) throw Error("jitter must be in [0, 1], got " + std::to_string(j));
  if (passes < 0 || passes > 8) throw Error("passes must be in [0, 8], got " + std::to_string(passes));
}

double medianPixelsPerTexel(const SurfaceLevel& level) {
  std::vector<float> scale;
  scale.reserve(level.size());
  for (const auto& j : level.jacobian) {
    const float det = j[0] * j[3] - j[1] * j[2];
    if (std::isfinite(det) && det != 0.0f) scale.push_back(std::sqrt(std::fabs(det)));
  }
  if (scale.empty()) return 0.0;
  std::nth_element(scale.begin(), scale.begin() + std::ptrdiff_t(scale.size() / 2), scale.end());
  return scale[scale.size() / 2];
}

int stackLevelForAtlasLevel(const ExemplarAnalysis& analysis, int atlasLevel, double pixelsPerTexel) {
  const int finest = analysis.finestLevel();
  const double spacing = std::ldexp(pixelsPerTexel, atlasLevel);
  const int octaves = int(std::lround(std::log2(std::max(spacing, 1e-9))));
  return finest - std::clamp(octaves, 0, finest);
}

SurfaceSynthesisResult synthesizeSurface(const ExemplarAnalysis& analysis, const SurfaceDomain& domain,
                                         const SurfaceSynthesisOptions& options, const Context& ctx) {
  options.validate();
  if (analysis.levels.empty()) throw Error("exemplar analysis is empty");
  if (domain.levels.empty() || domain.levels[0].size() == 0) throw Error("the surface has no texels to synthesize");
  for (size_t a = 0; a < domain.levels.size(); ++a) {
    const SurfaceLevel& l = domain.levels[a];
    const size_t n = l.size();
    if (l.y.size() != n || l.chart.size() != n || l.jacobian.size() != n || l.neighbors.size() != n ||
        l.parent.size() != n)
      throw Error("surface domain level " + std::to_string(a) + " has arrays of different lengths");
  }

  SurfaceSynthesisResult result;
  result.exemplarPixelsPerTexel = std::max(medianPixelsPerTexel(domain.levels[0]), 1e-6);
  const double ppt = result.exemplarPixelsPerTexel;
  const int finest = analysis.finestLevel();
  std::vector<float> jitter = options.jitter.empty() ? defaultJitter(finest + 1) : options.jitter;
  jitter.resize(size_t(finest + 1), jitter.back());

  // The coarsest atlas level synthesized: the first that reaches the coarsest stack level.
  int top = int(domain.levels.size()) - 1;
  while (top > 0 && stackLevelForAtlasLevel(analysis, top - 1, ppt) == 0) --top;

  std::vector<uint32_t> previous, current, scratch;
  for (int a = top; a >= 0; --a) {
    const auto start = std::chrono::steady_clock::now();
    const SurfaceLevel& level = domain.levels[size_t(a)];
    const int l = stackLevelForAtlasLevel(analysis, a, ppt);
    const AnalysisLevel& al = analysis.levels[size_t(l)];
    current.assign(level.size(), 0);
    if (a == top)
      forSites(level.size(), ctx, [&](size_t b, size_t e) {
        cpu::initSurfaceKernel(level, current.data(), analysis.width, analysis.height, b, e);
      });
    else
      forSites(level.size(), ctx, [&](size_t b, size_t e) {
        cpu::upsampleSurfaceKernel(level, previous.data(), current.data(), analysis.width, analysis.height, b, e);
      });
    const auto amplitude256 = int64_t(std::lrint(double(jitter[size_t(l)]) * al.spacing * 256.0));
    forSites(level.size(), ctx, [&](size_t b, size_t e) {
      cpu::jitterSurfaceKernel(level, current.data(), options.seed, a, amplitude256, analysis.width, analysis.height,
                               b, e);
    });

    const cpu::LevelTables tables{analysis.width, analysis.height, al.spacing, analysis.k,
                                  al.appearance.data(), al.neighborhood.data(), al.candidates.data()};
    scratch.resize(current.size());
    for (int pass = 0; pass < (options.correct ? options.passes : 0); ++pass)
      for (int cls = 0; cls < 4; ++cls) {
        forSites(level.size(), ctx, [&](size_t b, size_t e) {
          cpu::correctSurfaceKernel(level, current.data(), scratch.data(), tables, cls, b, e);
        });
        current.swap(scratch);
      }
    previous.swap(current);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.levels.push_back({a, int64_t(level.size()), seconds});
  }
  result.coords = std::move(previous);
  return result;
}

} // namespace texfab::synthesis
