// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6;
//           S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3.
#include "synthesis/synthesize_surface.h"

#include "core/error.h"
#include "core/parallel.h"
#include "synthesis/backend.h"
#include "synthesis/cpu/surface_kernels.h"
#if TEXFAB_HAS_VULKAN
#include "synthesis/vulkan/surface_kernels.h"
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace texfab::synthesis {

namespace {

using cpu::forSites;

using Clock = std::chrono::steady_clock;


// The levels synthesized and each one's parameters: atlas levels top..0, each at the exemplar
// stack level closest to its scale.
struct Plan {
  const ExemplarAnalysis& analysis;
  const SurfaceDomain& domain;
  const SurfaceSynthesisOptions& options;
  double pixelsPerTexel = 0;
  int top = 0;
  std::vector<float> jitter;  // per stack level

  int stackLevel(int a) const { return stackLevelForAtlasLevel(analysis, a, pixelsPerTexel); }
  const AnalysisLevel& tables(int a) const { return analysis.levels[size_t(stackLevel(a))]; }
  int64_t amplitude256(int a) const {
    return int64_t(std::lrint(double(jitter[size_t(stackLevel(a))]) * tables(a).spacing * 256.0));
  }
  cpu::LevelTables tableView(int a) const {
    const AnalysisLevel& al = tables(a);
    return {analysis.width, analysis.height, al.spacing, analysis.k, al.appearance.data(), al.neighborhood.data(),
            al.candidates.data(), clampTo(a)};
  }
  // The valid region of atlas level a's stack level, for a non-toroidal exemplar; null when it tiles.
  const ValidRegion* clampTo(int a) const {
    return analysis.wrap == ExemplarWrap::Clamp ? &tables(a).valid : nullptr;
  }
  int subpasses() const { return options.correct ? options.passes * 4 : 0; }
};

Plan planFor(const ExemplarAnalysis& analysis, const SurfaceDomain& domain, const SurfaceSynthesisOptions& options) {
  Plan p{analysis, domain, options, 0, 0, {}};
  p.pixelsPerTexel = std::max(medianPixelsPerTexel(domain.levels[0]), 1e-6);
  const int finest = analysis.finestLevel();
  p.jitter = options.jitter.empty() ? defaultJitter(finest + 1) : options.jitter;
  p.jitter.resize(size_t(finest + 1), p.jitter.back());
  // The coarsest atlas level synthesized: the first that reaches the coarsest stack level.
  p.top = int(domain.levels.size()) - 1;
  while (p.top > 0 && p.stackLevel(p.top - 1) == 0) --p.top;
  return p;
}

std::vector<uint32_t> synthesizeOnCpu(const Plan& plan, const Context& ctx, std::vector<LevelStats>& stats) {
  const int ew = plan.analysis.width, eh = plan.analysis.height;
  std::vector<uint32_t> previous, current, scratch;
  for (int a = plan.top; a >= 0; --a) {
    const auto start = Clock::now();
    const SurfaceLevel& level = plan.domain.levels[size_t(a)];
    const auto sites = [&](auto&& kernel) { forSites(level.size(), ctx, kernel); };
    current.assign(level.size(), 0);
    const ValidRegion* clampTo = plan.clampTo(a);
    if (a == plan.top)
      sites([&](size_t b, size_t e) { cpu::initSurfaceKernel(level, current.data(), ew, eh, b, e, clampTo); });
    else
      sites([&](size_t b, size_t e) {
        cpu::upsampleSurfaceKernel(level, previous.data(), current.data(), ew, eh, b, e, clampTo);
      });
    sites([&](size_t b, size_t e) {
      cpu::jitterSurfaceKernel(level, current.data(), plan.options.seed, a, plan.amplitude256(a), ew, eh, b, e, clampTo);
    });
    const cpu::LevelTables tables = plan.tableView(a);
    scratch.resize(current.size());
    for (int k = 0; k < plan.subpasses(); ++k) {
      sites([&](size_t b, size_t e) { cpu::correctSurfaceKernel(level, current.data(), scratch.data(), tables, k % 4, b, e); });
      current.swap(scratch);
    }
    previous.swap(current);
    stats.push_back({a, int64_t(level.size()), secondsSince(start)});
  }
  return previous;
}

#if TEXFAB_HAS_VULKAN
// The same on a Vulkan device: the levels stay on the device, one submit per level.
std::vector<uint32_t> synthesizeOnDevice(vulkan::Device& device, const Plan& plan, const Context& ctx,
                                         std::vector<LevelStats>& stats) {
  const int ew = plan.analysis.width, eh = plan.analysis.height;
  vulkan::Commands commands(device);
  vulkan::Buffer previous, current, scratch;
  for (int a = plan.top; a >= 0; --a) {
    const auto start = Clock::now();
    const vulkan::SurfaceSites sites = vulkan::uploadSites(commands, plan.domain.levels[size_t(a)]);
    const vulkan::LevelTables tables = vulkan::uploadTables(commands, plan.tableView(a));
    const ValidRegion* clampTo = plan.clampTo(a);
    current = vulkan::coordBuffer(device, sites);
    scratch = vulkan::coordBuffer(device, sites);
    if (a == plan.top) vulkan::initSurfaceKernel(commands, sites, current, ew, eh, clampTo);
    else vulkan::upsampleSurfaceKernel(commands, sites, previous, current, ew, eh, clampTo);
    vulkan::jitterSurfaceKernel(commands, sites, current, plan.options.seed, a, plan.amplitude256(a), ew, eh, clampTo);
    for (int k = 0; k < plan.subpasses(); ++k) {
      vulkan::correctSurfaceKernel(commands, sites, current, scratch, tables, k % 4);
      std::swap(current, scratch);
    }
    commands.submit(ctx);
    previous = std::move(current);
    stats.push_back({a, int64_t(sites.count), secondsSince(start)});
  }
  std::vector<uint32_t> coords(plan.domain.levels[0].size());
  commands.download(previous, 0, coords.data(), coords.size() * 4);
  commands.submit(ctx);
  return coords;
}
#endif

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

  const Plan plan = planFor(analysis, domain, options);
  SurfaceSynthesisResult result;
  result.exemplarPixelsPerTexel = plan.pixelsPerTexel;
#if TEXFAB_HAS_VULKAN
  if (const auto device = deviceFor(ctx)) {
    result.coords = synthesizeOnDevice(*device, plan, ctx, result.levels);
    return result;
  }
#else
  deviceFor(ctx);
#endif
  result.coords = synthesizeOnCpu(plan, ctx, result.levels);
  return result;
}

} // namespace texfab::synthesis
