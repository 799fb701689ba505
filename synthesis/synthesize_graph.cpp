// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: C. Han et al. Multiscale texture synthesis. SIGGRAPH 2008 (thesis §5.2);
//           S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3.
#include "synthesis/synthesize_graph.h"

#include "core/error.h"
#include "core/hash.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "synthesis/cpu/graph_atlas.h"
#include "synthesis/cpu/synthesis_kernels.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace texfab::synthesis {

namespace {

using cpu::GraphAtlas;
using cpu::GraphLevelState;
using cpu::kRowGrain;
using cpu::LevelGrid;
using cpu::TexelTransfer;
using cpu::Transfer;

// Position q on a level of period p (0: none).
int64_t wrap(int64_t q, int64_t p) { return p > 0 ? cpu::floorMod(q, p) : q; }

// Upsampling: a texel at level k < L of its exemplar becomes four at level k+1, h_{k+1} apart
// (the thesis' ⌊h Δ⌋ with the child's spacing, notes §3.2 erratum); at the finest level, magnified.
// Children at positions wrapped by (px, py): the first periodic level reads its parent so.
void upsample(const GraphAtlas& a, const uint32_t* parent, const LevelGrid& pg, uint32_t* out, const LevelGrid& g,
              int64_t px, int64_t py, int r0, int r1) {
  for (int y = r0; y < r1; ++y) {
    const int64_t qy = wrap(g.y0 + y, py);
    const uint32_t* prow = parent + size_t((qy >> 1) - pg.y0) * size_t(pg.width);
    for (int x = 0; x < g.width; ++x) {
      const int64_t qx = wrap(g.x0 + x, px);
      const uint32_t s = prow[(qx >> 1) - pg.x0];
      if (a.level(s) == a.finest) {
        out[size_t(y) * g.width + x] = s;
        continue;
      }
      const uint32_t next = packCoord(coordU(s) + (1u << a.shift), coordV(s));  // same place, one level finer
      const int h = a.spacing(next);
      out[size_t(y) * g.width + x] = a.move(next, (qx & 1) * h, (qy & 1) * h);
    }
  }
}

// Thesis §5.3's upsampling of transfers: each child's R interpolates its four nearest parents
// bilinearly (weights 9, 3, 3, 1 / 16), the neighbours found as the parents of the children two
// texels away, wrapped by (px, py) like the children. Integer, rounding half up.
void upsampleTransfers(const GraphAtlas& a, const TexelTransfer* parent, const LevelGrid& pg, TexelTransfer* out,
                       const LevelGrid& g, int64_t px, int64_t py, int r0, int r1) {
  const auto at = [&](int64_t qx, int64_t qy) -> const Transfer& {
    return parent[size_t((wrap(qy, py) >> 1) - pg.y0) * size_t(pg.width) + size_t((wrap(qx, px) >> 1) - pg.x0)].r;
  };
  for (int y = r0; y < r1; ++y) {
    const int64_t qy = g.y0 + y, ny = qy + ((qy & 1) ? 2 : -2);
    for (int x = 0; x < g.width; ++x) {
      const int64_t qx = g.x0 + x, nx = qx + ((qx & 1) ? 2 : -2);
      out[size_t(y) * g.width + x] =
          a.texelTransfer(cpu::upsampledTransfer(at(qx, qy), at(nx, qy), at(qx, ny), at(nx, ny)));
    }
  }
}

// Jitter: S[q] += round(strength h_k H(q)), H uniform in [-1, 1)^2 from texelHash(seed, t, q), the
// strength and h_k those of the tile S[q] points to; in integers as cpu::jitterKernel. q wrapped by
// the level's periods (px, py).
void jitter(const GraphAtlas& a, uint32_t* coords, const LevelGrid& g, uint32_t seed, int t,
            const std::vector<int64_t>& amplitude256, int64_t px, int64_t py, int r0, int r1) {
  for (int y = r0; y < r1; ++y)
    for (int x = 0; x < g.width; ++x) {
      uint32_t& s = coords[size_t(y) * g.width + x];
      const int64_t amp = amplitude256[size_t(a.tile(s))];
      if (amp == 0) continue;
      const int64_t qx = wrap(g.x0 + x, px), qy = wrap(g.y0 + y, py);
      const int64_t hx = int64_t(texelHash(seed, uint32_t(t), int32_t(qx), int32_t(qy), 0) >> 16) - 32768;
      const int64_t hy = int64_t(texelHash(seed, uint32_t(t), int32_t(qx), int32_t(qy), 1) >> 16) - 32768;
      s = a.move(s, (amp * hx + (int64_t(1) << 22)) >> 23, (amp * hy + (int64_t(1) << 22)) >> 23);
    }
}

// One correction sub-pass (cpu::correctKernel's rules): each texel of the class takes the best of
// { C_i(S[q+D]) - h D } (h of each candidate's level, wrapped in its tile) in a node S[q] may move
// to (GraphAnalysis::moves), and S[q] itself where it may stay, or at the output level (nothing
// finer is synthesized, so a finest level may stay: the root shows its own pixels at zoom 1); ties
// to S[q], then to the smallest coordinate. With transfers, neighbourhoods compare as seen and a
// choice carries its transfer (cpu::GraphTransferChoice).
template <bool kTransfers>
void correct(const GraphAtlas& a, GraphLevelState in, GraphLevelState out, const LevelGrid& g, bool outputLevel,
             int interleave, int cx, int cy, int x0, int x1, int r0, int r1) {
  const auto w = size_t(g.width);
  const int firstX = x0 + int(cpu::floorMod(cx - (g.x0 + x0), interleave));
  for (int y = r0; y < r1; ++y) {
    const size_t row = size_t(y) * w;
    std::copy(in.coords + row + x0, in.coords + row + x1, out.coords + row + x0);
    if constexpr (kTransfers) std::copy(in.transfers + row + x0, in.transfers + row + x1, out.transfers + row + x0);
    if (cpu::floorMod(g.y0 + y - cy, interleave) != 0) continue;
    for (int x = firstX; x < x1; x += interleave) {
      const auto at = [&](int dx, int dy) { return size_t(y + dy) * w + size_t(x + dx); };
      // The candidates of the 3x3 neighbours, each moved to align with this texel.
      const auto offerCandidates = [&](auto& choice) {
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const size_t q = at(dx, dy);
            const uint32_t* cand = a.candidates + a.texel(in.coords[q]) * size_t(a.k);
            [[maybe_unused]] const int16_t* b = kTransfers ? a.transfersOf(in.coords[q]) : nullptr;
            if constexpr (kTransfers) choice.frame(in.transfers[q]);
            for (int i = 0; i < a.k; ++i) {
              const int h = a.spacing(cand[i]);
              const uint32_t moved = a.move(cand[i], -int64_t(h) * dx, -int64_t(h) * dy);
              if constexpr (kTransfers) choice.offer(moved, b + 3 * i);
              else choice.offer(moved);
            }
          }
      };
      if constexpr (kTransfers) {
        int16_t target[kNeighborhoodDims];  // as seen: each appearance vector moved by A R
        for (int i = 0; i < kNeighborhoodSamples; ++i) {
          const size_t q = at(kDiagonalX[i], kDiagonalY[i]);
          const int8_t* v = a.appearance + a.texel(in.coords[q]) * kAppearanceDims;
          for (int d = 0; d < kAppearanceDims; ++d)
            target[i * kAppearanceDims + d] = int16_t(v[d] + in.transfers[q].shift[size_t(d)]);
        }
        cpu::GraphTransferChoice choice(a, target, in.coords[row + x], in.transfers[row + x], outputLevel);
        offerCandidates(choice);
        out.coords[row + x] = choice.best();
        out.transfers[row + x] = a.texelTransfer(choice.transfer());
      } else {
        alignas(32) int8_t target[kNeighborhoodDims];
        for (int i = 0; i < kNeighborhoodSamples; ++i)
          std::copy_n(a.appearance + a.texel(in.coords[at(kDiagonalX[i], kDiagonalY[i])]) * kAppearanceDims,
                      kAppearanceDims, target + i * kAppearanceDims);
        cpu::GraphChoice choice(a, target, in.coords[row + x], outputLevel);
        offerCandidates(choice);
        out.coords[row + x] = choice.best();
      }
    }
  }
}


} // namespace

void GraphSynthesisOptions::validate(const GraphAnalysis& analysis) const {
  if (zoomOctaves < -analysis.finestLevel())
    throw Error("zoom: at most " + std::to_string(analysis.side) + "x out (the root exemplar's whole tile in one texel)");
  if (analysis.finestLevel() + zoomOctaves > 60) throw Error("zoom: at most 2^60");
  for (float j : jitter)
    if (!(j >= 0.0f && j <= 1.0f)) throw Error("jitter values must be in [0, 1]");
  if (passes < 0 || passes > 8) throw Error("passes must be 0 to 8");
  if (interleave < 1 || interleave > 3) throw Error("interleave must be 1 to 3");
  if (periodX < 0 || periodY < 0 || periodX > kMaxImageSide || periodY > kMaxImageSide)
    throw Error("tiling period must be in [0, " + std::to_string(kMaxImageSide) + "]");
  if (periodX % interleave || periodY % interleave)
    throw Error("tiling period " + std::to_string(periodX) + "x" + std::to_string(periodY) +
                " must be a multiple of the interleave (" + std::to_string(interleave) + ")");
}

int graphZoomOctaves(double zoom) {
  const int octaves = std::isfinite(zoom) && zoom > 0 ? int(std::lrint(std::log2(zoom))) : 0;
  if (!(zoom > 0) || std::ldexp(1.0, octaves) != zoom)
    throw Error("zoom: expected a power of two (1, 2, 4, ... or 0.5, 0.25, ...)");
  return octaves;
}

int graphOutputLevel(const GraphAnalysis& analysis, const GraphSynthesisOptions& options) {
  return analysis.finestLevel() + options.zoomOctaves;
}

int graphFirstPeriodicLevel(const GraphAnalysis& analysis, const GraphSynthesisOptions& options) {
  if (options.periodX == 0 && options.periodY == 0) return 0;
  const int finest = graphOutputLevel(analysis, options);
  const auto periodic = [&](int period, int shift) {
    return period == 0 || (shift < 31 && period % (1 << shift) == 0 && (period >> shift) % options.interleave == 0);
  };
  int first = finest;
  while (first > 0 && periodic(options.periodX, finest - first + 1) && periodic(options.periodY, finest - first + 1))
    --first;
  return first;
}

std::vector<int64_t> graphJitterAmplitudes256(const GraphAnalysis& analysis, const std::vector<float>& jitter) {
  std::vector<float> strength = jitter.empty() ? defaultJitter(analysis.levels) : jitter;
  strength.resize(size_t(analysis.levels), strength.back());
  std::vector<int64_t> amplitude256;
  for (int node = 0; node < analysis.nodes; ++node)
    for (int k = 0; k < analysis.levels; ++k) {
      const int step = std::clamp(k - (node == 0 ? 0 : analysis.entryLevel - 2), 0, analysis.levels - 1);
      amplitude256.push_back(int64_t(std::lrint(double(strength[size_t(step)]) * analysis.spacing(k) * 256.0)));
    }
  return amplitude256;
}

double synthesizeGraphMemoryBytes(const Window& window) {
  // Three coordinate and transfer buffers of the padded finest level, then RGB offsets and colours.
  return double(window.width + 64) * double(window.height + 64) *
         (3 * (sizeof(uint32_t) + sizeof(TexelTransfer)) + 6 * sizeof(float));
}

SynthesisResult synthesizeGraph(const GraphAnalysis& analysis, const Window& window,
                                const GraphSynthesisOptions& options, const Context& ctx) {
  options.validate(analysis);
  window.validate();
  const GraphAtlas atlas(analysis);
  const int finest = graphOutputLevel(analysis, options);
  const int subpasses = options.passes * options.interleave * options.interleave;

  // Periods per level (0: none, or a level coarser than the first periodic one).
  const int first = graphFirstPeriodicLevel(analysis, options);
  const auto period = [&](int p, int t) { return t >= first ? int64_t(p >> (finest - t)) : int64_t(0); };

  std::vector<LevelGrid> padded(size_t(finest + 1));
  LevelGrid valid{window.x, window.y, window.width, window.height};
  for (int t = finest; t >= 0; --t) {
    padded[size_t(t)] = cpu::expand(valid, subpasses);
    valid = cpu::expand(cpu::parentOf(padded[size_t(t)]), 1);  // and their neighbours, for transfers
    if (t != first || t == 0) continue;
    // The first periodic level reads its parent at wrapped positions [0, p): parents [0, (p + 1) / 2).
    if (const int64_t p = period(options.periodX, t)) valid.x0 = 0, valid.width = int((p + 1) / 2);
    if (const int64_t p = period(options.periodY, t)) valid.y0 = 0, valid.height = int((p + 1) / 2);
  }
  // The root's schedule starts at its level 0; another exemplar's two steps before the level texels
  // enter it, as the layout above that level came from the exemplar they left (entered at the start
  // of the schedule, it lost fidelity: 1.35x the single exemplar's on rock -> stone at 16x zoom;
  // never jittered, it copied coherent squares).
  const std::vector<int64_t> amplitude256 = graphJitterAmplitudes256(analysis, options.jitter);

  SynthesisResult result;
  std::vector<uint32_t> previous, current, scratch;
  const bool transfers = atlas.transfers != nullptr;
  std::vector<TexelTransfer> previousR, currentR, scratchR;  // with transfers only
  for (int t = 0; t <= finest; ++t) {
    const auto start = std::chrono::steady_clock::now();
    Stage stage(ctx, "level " + std::to_string(t + 1) + "/" + std::to_string(finest + 1));
    const LevelGrid& g = padded[size_t(t)];
    const auto rows = [&](auto&& kernel) { parallelFor(0, g.height, ctx, kernel, kRowGrain); };
    current.assign(size_t(g.width) * size_t(g.height), 0);  // t = 0: the root's coarsest level, at (0, 0)
    const int64_t px = period(options.periodX, t), py = period(options.periodY, t);
    if (transfers) currentR.assign(current.size(), TexelTransfer{});
    const int64_t wx = t == first ? px : 0, wy = t == first ? py : 0;  // wrapped reads of the parent
    if (t > 0)
      rows([&](int r0, int r1) {
        upsample(atlas, previous.data(), padded[size_t(t - 1)], current.data(), g, wx, wy, r0, r1);
        if (transfers)
          upsampleTransfers(atlas, previousR.data(), padded[size_t(t - 1)], currentR.data(), g, wx, wy, r0, r1);
      });
    rows([&](int r0, int r1) { jitter(atlas, current.data(), g, options.seed, t, amplitude256, px, py, r0, r1); });
    scratch.assign(current.size(), 0);
    if (transfers) scratchR.assign(current.size(), TexelTransfer{});
    int inset = 0;
    for (int pass = 0; pass < options.passes; ++pass)
      for (int cy = 0; cy < options.interleave; ++cy)
        for (int cx = 0; cx < options.interleave; ++cx) {
          ++inset;
          const GraphLevelState in{current.data(), currentR.data()}, out{scratch.data(), scratchR.data()};
          parallelFor(inset, g.height - inset, ctx, [&](int r0, int r1) {
            const auto kernel = transfers ? correct<true> : correct<false>;
            kernel(atlas, in, out, g, t == finest, options.interleave, cx, cy, inset, g.width - inset, r0, r1);
          }, kRowGrain);
          current.swap(scratch);
          currentR.swap(scratchR);
          stage.advance(inset, subpasses);
        }
    previous.swap(current);
    previousR.swap(currentR);
    result.levels.push_back({t, int64_t(g.width) * g.height, secondsSince(start)});
    stage.finish();
  }

  CoordMap& out = result.coords;
  out.width = window.width;
  out.height = window.height;
  out.exemplarWidth = analysis.atlasWidth();
  out.exemplarHeight = analysis.atlasHeight();
  out.coords.resize(size_t(window.width) * size_t(window.height));
  const LevelGrid& g = padded[size_t(finest)];
  const auto finalIndex = [&](int x, int y) { return size_t(y + subpasses) * size_t(g.width) + size_t(x + subpasses); };
  for (int y = 0; y < window.height; ++y)
    std::copy_n(&previous[finalIndex(0, y)], window.width, &out.coords[size_t(y) * size_t(window.width)]);
  if (transfers) {
    result.colorOffsets = Image(window.width, window.height, 3, PixelFormat::Float);
    for (int y = 0; y < window.height; ++y)
      for (int x = 0; x < window.width; ++x) {
        const std::array<float, 3> offset = cpu::colorOffset(previousR[finalIndex(x, y)].r);
        std::copy(offset.begin(), offset.end(), result.colorOffsets.pixel(x, y));
      }
  }
  return result;
}

Image graphColors(const SynthesisResult& result, const GraphAnalysis& analysis, const Context& ctx) {
  Image colors = applyCoords(result.coords, analysis.colors, ctx);
  if (result.colorOffsets.empty()) return colors;
  for (size_t i = 0; i < colors.pixels.size(); ++i)
    colors.pixels[i] = transferredColor(colors.pixels[i], result.colorOffsets.pixels[i]);
  return colors;
}

} // namespace texfab::synthesis
