// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3.
#include "synthesis/synthesize_2d.h"

#include "core/error.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "synthesis/backend.h"
#include "synthesis/cpu/synthesis_kernels.h"
#if TEXFAB_HAS_VULKAN
#include "synthesis/vulkan/synthesis_kernels.h"
#endif

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <string>

namespace texfab::synthesis {

namespace {

using cpu::kRowGrain;
using cpu::LevelGrid;

using cpu::expand;
using cpu::parentOf;

// The region a level's coordinates must stay in, for a non-toroidal exemplar; null when it tiles.
const ValidRegion* clampOf(const ExemplarAnalysis& a, int level) {
  return a.wrap == ExemplarWrap::Clamp ? &a.levels[size_t(level)].valid : nullptr;
}

cpu::LevelTables tablesOf(const ExemplarAnalysis& a, int level) {
  const AnalysisLevel& l = a.levels[size_t(level)];
  return {a.width, a.height, l.spacing, a.k, l.appearance.data(), l.neighborhood.data(), l.candidates.data(),
          clampOf(a, level)};
}


using Clock = std::chrono::steady_clock;


// What synthesize2d derives before running a kernel: the levels it synthesizes, the padded
// rectangle each computes (the dependency closure of the window), and each level's parameters.
struct Plan {
  Window window;
  int first = 0, finest = 0;
  int subpasses = 0;              // correction sub-passes per level (each insets by one texel)
  std::vector<LevelGrid> padded;  // per level
  std::vector<float> jitter;      // per level

  int spacing(int l) const { return 1 << (finest - l); }
  int64_t period(int p, int l) const { return p > 0 ? p >> (finest - l) : 0; }
  int64_t amplitude256(int l) const {
    return int64_t(std::lrint(double(jitter[size_t(l)]) * spacing(l) * 256.0));
  }
  const LevelGrid& grid(int l) const { return padded[size_t(l)]; }
};

Plan planFor(const ExemplarAnalysis& analysis, const Window& window, const SynthesisOptions& options) {
  Plan p;
  p.window = window;
  p.finest = analysis.finestLevel();
  p.first = firstSynthesisLevel(p.finest + 1, options);
  p.jitter = options.jitter.empty() ? defaultJitter(p.finest + 1) : options.jitter;
  p.jitter.resize(size_t(p.finest + 1), p.jitter.back());
  // Skipped coarse levels hand their variation to the first synthesized one, so that a tile too
  // small for the whole stack is still randomized rather than a plain tiling.
  p.jitter[size_t(p.first)] = *std::max_element(p.jitter.begin(), p.jitter.begin() + p.first + 1);
  p.subpasses = options.correct ? options.passes * options.interleave * options.interleave : 0;
  // Backward: the rectangle each level must produce (valid) and the padded one it computes.
  p.padded.resize(size_t(p.finest + 1));
  LevelGrid valid{window.x, window.y, window.width, window.height};
  for (int l = p.finest; l >= p.first; --l) {
    p.padded[size_t(l)] = expand(valid, p.subpasses);
    valid = parentOf(p.padded[size_t(l)]);
  }
  return p;
}

// Calls fn(classX, classY, inset) for each correction sub-pass of a level, in order. Each reads the
// last one's output over a rectangle one texel smaller on every side (inset from the padded grid),
// so the texels it writes depend only on valid texels.
template <class Fn> void forSubpasses(const SynthesisOptions& options, Fn&& fn) {
  int inset = 0;
  for (int pass = 0; pass < (options.correct ? options.passes : 0); ++pass)
    for (int cy = 0; cy < options.interleave; ++cy)
      for (int cx = 0; cx < options.interleave; ++cx) fn(cx, cy, ++inset);
}

// The stage of level l as progress reports it: "level k/n", k counted from the first synthesized.
std::string levelStageName(const Plan& plan, int l) {
  return "level " + std::to_string(l - plan.first + 1) + "/" + std::to_string(plan.finest - plan.first + 1);
}

// The finest padded level on the CPU.
std::vector<uint32_t> synthesizeOnCpu(const ExemplarAnalysis& analysis, const Plan& plan,
                                      const SynthesisOptions& options, const Context& ctx,
                                      std::vector<LevelStats>& stats) {
  const int ew = analysis.width, eh = analysis.height;
  std::vector<uint32_t> previous, current, scratch;
  for (int l = plan.first; l <= plan.finest; ++l) {
    const auto start = Clock::now();
    Stage stage(ctx, levelStageName(plan, l));
    const LevelGrid& grid = plan.grid(l);
    const int spacing = plan.spacing(l);
    const int64_t periodX = plan.period(options.periodX, l), periodY = plan.period(options.periodY, l);
    const auto rows = [&](auto&& kernel) { parallelFor(0, grid.height, ctx, kernel, kRowGrain); };
    const ValidRegion* clampTo = clampOf(analysis, l);
    current.assign(size_t(grid.width) * size_t(grid.height), 0);
    if (l == plan.first)
      rows([&](int r0, int r1) {
        cpu::initKernel(current.data(), grid, spacing, ew, eh, periodX, periodY, r0, r1, clampTo);
      });
    else
      rows([&](int r0, int r1) {
        cpu::upsampleKernel(previous.data(), plan.grid(l - 1), current.data(), grid, spacing, ew, eh, r0, r1, clampTo);
      });
    rows([&](int r0, int r1) {
      cpu::jitterKernel(current.data(), grid, options.seed, l, plan.amplitude256(l), periodX, periodY, ew, eh, r0, r1,
                        clampTo);
    });
    const cpu::LevelTables tables = tablesOf(analysis, l);
    scratch.assign(current.size(), 0);
    forSubpasses(options, [&](int cx, int cy, int inset) {
      parallelFor(inset, grid.height - inset, ctx, [&](int r0, int r1) {
        cpu::correctKernel(current.data(), scratch.data(), grid, tables, options.interleave, cx, cy, inset,
                           grid.width - inset, r0, r1);
      }, kRowGrain);
      current.swap(scratch);
      stage.advance(inset, plan.subpasses);
    });
    previous.swap(current);
    stats.push_back({l, int64_t(grid.width) * grid.height, secondsSince(start)});
    stage.finish();
  }
  return previous;
}

#if TEXFAB_HAS_VULKAN
// Whether every level of the plan fits one binding of the device.
bool fitsDevice(const Plan& plan, const vulkan::Device& device) {
  for (int l = plan.first; l <= plan.finest; ++l)
    if (uint64_t(plan.grid(l).width) * uint64_t(plan.grid(l).height) * 4 > device.maxRangeBytes()) return false;
  return true;
}

// The same on a Vulkan device: the levels stay on the device, one submit per level, and the
// window's rows of the finest level come back into `out` at (x0, y0).
void synthesizeOnDevice(vulkan::Device& device, const ExemplarAnalysis& analysis, const Plan& plan,
                        const SynthesisOptions& options, const Context& ctx, std::vector<LevelStats>& stats,
                        CoordMap& out, int x0, int y0) {
  const int ew = analysis.width, eh = analysis.height;
  vulkan::Commands commands(device);
  vulkan::Buffer previous, current, scratch;
  for (int l = plan.first; l <= plan.finest; ++l) {
    const auto start = Clock::now();
    Stage stage(ctx, levelStageName(plan, l));
    const LevelGrid& grid = plan.grid(l);
    const int spacing = plan.spacing(l);
    const int64_t periodX = plan.period(options.periodX, l), periodY = plan.period(options.periodY, l);
    const ValidRegion* clampTo = clampOf(analysis, l);
    current = vulkan::levelBuffer(device, grid);
    scratch = vulkan::levelBuffer(device, grid);
    const vulkan::LevelTables tables = vulkan::uploadTables(commands, tablesOf(analysis, l));
    if (l == plan.first) vulkan::initKernel(commands, current, grid, spacing, ew, eh, periodX, periodY, clampTo);
    else vulkan::upsampleKernel(commands, previous, plan.grid(l - 1), current, grid, spacing, ew, eh, clampTo);
    vulkan::jitterKernel(commands, current, grid, options.seed, l, plan.amplitude256(l), periodX, periodY, ew, eh,
                         clampTo);
    forSubpasses(options, [&](int cx, int cy, int inset) {
      vulkan::correctKernel(commands, current, scratch, grid, tables, options.interleave, cx, cy, inset,
                            grid.width - inset, inset, grid.height - inset);
      std::swap(current, scratch);
    });
    commands.submit(ctx);
    previous = std::move(current);
    stats.push_back({l, int64_t(grid.width) * grid.height, secondsSince(start)});
    stage.finish();
  }
  const LevelGrid& grid = plan.grid(plan.finest);
  std::vector<vulkan::Commands::Region> rows(size_t(plan.window.height));
  for (int y = 0; y < plan.window.height; ++y)
    rows[size_t(y)] = {(uint64_t(y + plan.subpasses) * uint64_t(grid.width) + uint64_t(plan.subpasses)) * 4,
                       (uint64_t(y0 + y) * uint64_t(out.width) + uint64_t(x0)) * 4, uint64_t(plan.window.width) * 4};
  commands.download(previous, rows, out.coords.data());
  commands.submit(ctx);
}
#endif

// The window out of the finest padded level, where it sits `subpasses` texels inside.
void cropWindow(const Plan& plan, const std::vector<uint32_t>& finest, CoordMap& out, int x0, int y0) {
  const LevelGrid& grid = plan.grid(plan.finest);
  for (int y = 0; y < plan.window.height; ++y)
    std::copy_n(finest.begin() + std::ptrdiff_t(size_t(y + plan.subpasses) * size_t(grid.width) + size_t(plan.subpasses)),
                plan.window.width, out.coords.begin() + std::ptrdiff_t(size_t(y0 + y) * size_t(out.width) + size_t(x0)));
}

// Tiles add up their levels.
void addLevels(std::vector<LevelStats>& stats, const std::vector<LevelStats>& tile) {
  if (stats.empty()) stats = tile;
  else
    for (size_t i = 0; i < stats.size() && i < tile.size(); ++i) {
      stats[i].texels += tile[i].texels;
      stats[i].seconds += tile[i].seconds;
    }
}

// Synthesizes `window` into `out` at (x0, y0), on the device when there is one. A window whose
// levels exceed the device's binding range is split in two (a window equals the same texels of
// any larger one, so tiles join without seams).
void synthesizeWindow(const ExemplarAnalysis& analysis, const Window& window, const SynthesisOptions& options,
                      const Context& ctx, vulkan::Device* device, CoordMap& out, int x0, int y0,
                      std::vector<LevelStats>& stats) {
  const Plan plan = planFor(analysis, window, options);
  std::vector<LevelStats> tile;
#if TEXFAB_HAS_VULKAN
  if (device && !fitsDevice(plan, *device)) {
    if (window.width == 1 && window.height == 1) throw Error("the Vulkan device's binding range is too small");
    Window a = window, b = window;
    if (window.width >= window.height) {
      a.width = window.width / 2;
      b.x += a.width;
      b.width -= a.width;
      synthesizeWindow(analysis, a, options, ctx, device, out, x0, y0, stats);
      synthesizeWindow(analysis, b, options, ctx, device, out, x0 + a.width, y0, stats);
    } else {
      a.height = window.height / 2;
      b.y += a.height;
      b.height -= a.height;
      synthesizeWindow(analysis, a, options, ctx, device, out, x0, y0, stats);
      synthesizeWindow(analysis, b, options, ctx, device, out, x0, y0 + a.height, stats);
    }
    return;
  }
  if (device) {
    synthesizeOnDevice(*device, analysis, plan, options, ctx, tile, out, x0, y0);
    return addLevels(stats, tile);
  }
#else
  (void)device;
#endif
  cropWindow(plan, synthesizeOnCpu(analysis, plan, options, ctx, tile), out, x0, y0);
  addLevels(stats, tile);
}

} // namespace

std::vector<float> defaultJitter(int levelCount) {
  // Level l samples the exemplar every 2^(L-l) pixels, i.e. at 2^-l of its size. Full jitter
  // while that spacing is at least a quarter of the exemplar randomizes the large-scale layout;
  // half at an eighth; none below, where correction then grows coherent patches of at least an
  // eighth of the exemplar. Measured on GIMP's patterns, finer jitter costs neighborhood fidelity
  // (visible seams) without reducing repetition further.
  std::vector<float> jitter(size_t(std::max(levelCount, 0)), 0.0f);
  for (int l = 0; l < levelCount && l < 4; ++l) jitter[size_t(l)] = l < 3 ? 1.0f : 0.5f;
  return jitter;
}

void SynthesisOptions::validate() const {
  for (float j : jitter)
    if (!(j >= 0.0f && j <= 1.0f)) throw Error("jitter must be in [0, 1], got " + std::to_string(j));
  if (passes < 0 || passes > 8) throw Error("passes must be in [0, 8], got " + std::to_string(passes));
  if (interleave < 1 || interleave > 3)
    throw Error("interleave must be 1, 2 or 3 (1, 4 or 9 sub-passes), got " + std::to_string(interleave));
  if (periodX < 0 || periodY < 0 || periodX > kMaxImageSide || periodY > kMaxImageSide)
    throw Error("tiling period must be in [0, " + std::to_string(kMaxImageSide) + "]");
}

double synthesize2dMemoryBytes(const Window& window, int resolvedChannels) {
  return double(window.width) * double(window.height) * (12.0 + 4.0 * resolvedChannels);
}

int firstSynthesisLevel(int levelCount, const SynthesisOptions& options) {
  // A tiling period must stay whole, and a multiple of the interleave (so the sub-pass classes
  // repeat with it), at every synthesized level; coarser levels are skipped.
  if (options.periodX == 0 && options.periodY == 0) return 0;
  const int finest = levelCount - 1;
  auto periodic = [&](int period, int shift) {
    return period == 0 || (period % (1 << shift) == 0 && (period >> shift) % options.interleave == 0);
  };
  if (!periodic(options.periodX, 0) || !periodic(options.periodY, 0))
    throw Error("tiling period " + std::to_string(options.periodX) + "x" + std::to_string(options.periodY) +
                " must be a multiple of the interleave (" + std::to_string(options.interleave) + ")");
  int first = finest;
  while (first > 0 && periodic(options.periodX, finest - first + 1) && periodic(options.periodY, finest - first + 1))
    --first;
  return first;
}

void Window::validate() const {
  if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide)
    throw Error("output size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range (1 to " +
                std::to_string(kMaxImageSide) + " per side)");
  constexpr int64_t kMaxPosition = int64_t(1) << 40;
  if (std::abs(x) > kMaxPosition || std::abs(y) > kMaxPosition)
    throw Error("window position is out of range (|x|, |y| <= 2^40)");
}

SynthesisResult synthesize2d(const ExemplarAnalysis& analysis, const Window& window,
                             const SynthesisOptions& options, const Context& ctx) {
  options.validate();
  window.validate();
  if (analysis.levels.empty()) throw Error("exemplar analysis is empty");
  const auto device = deviceFor(ctx);
  SynthesisResult result;
  CoordMap& out = result.coords;
  out.width = window.width;
  out.height = window.height;
  out.exemplarWidth = analysis.width;
  out.exemplarHeight = analysis.height;
  out.coords.resize(size_t(window.width) * size_t(window.height));
  synthesizeWindow(analysis, window, options, ctx, device.get(), out, 0, 0, result.levels);
  return result;
}

} // namespace texfab::synthesis
