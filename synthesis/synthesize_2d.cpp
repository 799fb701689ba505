// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3.
#include "synthesis/synthesize_2d.h"

#include "render/image/error.h"
#include "render/image/image_io.h"
#include "render/image/parallel.h"
#include "synthesis/cpu/synthesis_kernels.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <string>

namespace texfab::synthesis {

namespace {

using cpu::LevelGrid;

// Rows per task: enough work to amortize scheduling, small enough to balance two cores.
constexpr int kRowGrain = 8;

LevelGrid expand(const LevelGrid& g, int by) {
  return {g.x0 - by, g.y0 - by, g.width + 2 * by, g.height + 2 * by};
}

// The parent-level rectangle that upsampling `g` reads.
LevelGrid parentOf(const LevelGrid& g) {
  const int64_t x0 = cpu::floorShift(g.x0, 1), y0 = cpu::floorShift(g.y0, 1);
  const int64_t x1 = cpu::floorShift(g.x0 + g.width - 1, 1), y1 = cpu::floorShift(g.y0 + g.height - 1, 1);
  return {x0, y0, int(x1 - x0 + 1), int(y1 - y0 + 1)};
}

cpu::LevelTables tablesOf(const ExemplarAnalysis& a, int level) {
  const AnalysisLevel& l = a.levels[size_t(level)];
  return {a.width, a.height, l.spacing, a.k, l.appearance.data(), l.neighborhood.data(), l.candidates.data()};
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

SynthesisResult synthesize2d(const ExemplarAnalysis& analysis, const Window& window,
                             const SynthesisOptions& options, const Context& ctx) {
  options.validate();
  if (window.width <= 0 || window.height <= 0 || window.width > kMaxImageSide || window.height > kMaxImageSide)
    throw Error("output size " + std::to_string(window.width) + "x" + std::to_string(window.height) +
                " is out of range (1 to " + std::to_string(kMaxImageSide) + " per side)");
  constexpr int64_t kMaxPosition = int64_t(1) << 40;
  if (std::abs(window.x) > kMaxPosition || std::abs(window.y) > kMaxPosition)
    throw Error("window position is out of range (|x|, |y| <= 2^40)");
  if (analysis.levels.empty()) throw Error("exemplar analysis is empty");

  const int finest = analysis.finestLevel();
  const int first = firstSynthesisLevel(finest + 1, options);
  std::vector<float> jitter = options.jitter.empty() ? defaultJitter(finest + 1) : options.jitter;
  jitter.resize(size_t(finest + 1), jitter.back());
  // Skipped coarse levels hand their variation to the first synthesized one, so that a tile too
  // small for the whole stack is still randomized rather than a plain tiling.
  jitter[size_t(first)] = *std::max_element(jitter.begin(), jitter.begin() + first + 1);

  const int subpasses = options.correct ? options.passes * options.interleave * options.interleave : 0;
  // Backward: the rectangle each level must produce (valid[l]) and the padded one it computes.
  std::vector<LevelGrid> valid(size_t(finest + 1)), padded(size_t(finest + 1));
  valid[size_t(finest)] = {window.x, window.y, window.width, window.height};
  for (int l = finest; l >= first; --l) {
    padded[size_t(l)] = expand(valid[size_t(l)], subpasses);
    if (l > first) valid[size_t(l) - 1] = parentOf(padded[size_t(l)]);
  }

  SynthesisResult result;
  std::vector<uint32_t> previous, current, scratch;
  for (int l = first; l <= finest; ++l) {
    const auto start = std::chrono::steady_clock::now();
    const LevelGrid& grid = padded[size_t(l)];
    const int shift = finest - l;
    const int spacing = 1 << shift;
    const int64_t periodX = options.periodX > 0 ? options.periodX >> shift : 0;
    const int64_t periodY = options.periodY > 0 ? options.periodY >> shift : 0;
    current.assign(size_t(grid.width) * size_t(grid.height), 0);

    if (l == first) {
      parallelFor(0, grid.height, ctx, [&](int r0, int r1) {
        cpu::initKernel(current.data(), grid, spacing, analysis.width, analysis.height, periodX, periodY, r0, r1);
      }, kRowGrain);
    } else {
      const LevelGrid& parentGrid = padded[size_t(l) - 1];
      parallelFor(0, grid.height, ctx, [&](int r0, int r1) {
        cpu::upsampleKernel(previous.data(), parentGrid, current.data(), grid, spacing, analysis.width,
                            analysis.height, r0, r1);
      }, kRowGrain);
    }
    const auto amplitude256 = int64_t(std::lrint(double(jitter[size_t(l)]) * spacing * 256.0));
    parallelFor(0, grid.height, ctx, [&](int r0, int r1) {
      cpu::jitterKernel(current.data(), grid, options.seed, l, amplitude256, periodX, periodY, analysis.width,
                        analysis.height, r0, r1);
    }, kRowGrain);

    // Correction: each sub-pass reads `current` and writes `scratch` over a rectangle one texel
    // smaller on every side than the last, so the texels it writes depend only on valid texels.
    const cpu::LevelTables tables = tablesOf(analysis, l);
    scratch.assign(current.size(), 0);
    int inset = 0;
    for (int pass = 0; pass < (options.correct ? options.passes : 0); ++pass)
      for (int cy = 0; cy < options.interleave; ++cy)
        for (int cx = 0; cx < options.interleave; ++cx) {
          ++inset;
          parallelFor(inset, grid.height - inset, ctx, [&](int r0, int r1) {
            cpu::correctKernel(current.data(), scratch.data(), grid, tables, options.interleave, cx, cy, inset,
                               grid.width - inset, r0, r1);
          }, kRowGrain);
          current.swap(scratch);
        }
    previous.swap(current);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.levels.push_back({l, int64_t(grid.width) * grid.height, seconds});
  }

  // `previous` holds the finest padded level; the window sits `subpasses` texels inside it.
  const LevelGrid& grid = padded[size_t(finest)];
  CoordMap& out = result.coords;
  out.width = window.width;
  out.height = window.height;
  out.exemplarWidth = analysis.width;
  out.exemplarHeight = analysis.height;
  out.coords.resize(size_t(window.width) * size_t(window.height));
  for (int y = 0; y < window.height; ++y)
    std::copy_n(previous.begin() + std::ptrdiff_t(size_t(y + subpasses) * grid.width + size_t(subpasses)),
                window.width, out.coords.begin() + std::ptrdiff_t(size_t(y) * window.width));
  return result;
}

} // namespace texfab::synthesis
