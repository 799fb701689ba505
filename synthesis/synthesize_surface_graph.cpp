// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: C. Han et al. Multiscale texture synthesis. SIGGRAPH 2008 (thesis §5.2);
//           S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6.
#include "synthesis/synthesize_surface_graph.h"

#include "core/error.h"
#include "synthesis/backend.h"
#include "synthesis/cpu/graph_atlas.h"
#include "synthesis/cpu/surface_kernels.h"
#include "synthesis/synthesize_graph.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>
#include <type_traits>

namespace texfab::synthesis {

namespace {

using cpu::applyJ;
using cpu::forSites;
using cpu::GraphAtlas;
using cpu::GraphLevelState;
using cpu::Offset;
using cpu::TexelTransfer;
using cpu::Transfer;
constexpr int kOne = cpu::kSubpixelOne;
constexpr int kMaxSurfaceAtlasSide = 65536 / kOne;  // packCoord's 16 bits, in pixels

// One atlas level's view: its sites, its synthesis level t and, per tile (node i, stack level k),
// the factor that takes J(p) (root pixels) to pixels of that tile's exemplar: 2^(t-k) where the
// pointer is in step with t (k < L), 2^min(t-L, depth_i) at a finest level (past it, magnified).
struct LevelView {
  const SurfaceLevel& sites;
  int atlasLevel = 0, t = 0;
  std::vector<float> toTile;

  LevelView(const SurfaceLevel& s, int a, int level, const GraphAnalysis& g) : sites(s), atlasLevel(a), t(level) {
    for (int i = 0; i < g.nodes; ++i)
      for (int k = 0; k < g.levels; ++k)
        toTile.push_back(std::ldexp(1.0f, k < g.finestLevel() ? t - k : std::min(t - k, g.depth[size_t(i)])));
  }
  // J(s) scaled for `tile`: exact (a power of two).
  std::array<float, 4> jacobian(size_t s, int tile) const {
    std::array<float, 4> j = sites.jacobian[s];
    for (float& v : j) v *= toTile[size_t(tile)];
    return j;
  }
};

// Top level: the root's stack level min(t, L), tiled by J(p) as initSurfaceKernel.
void init(const GraphAtlas& a, const LevelView& v, uint32_t* out, size_t b, size_t e) {
  const int k = std::min(v.t, a.finest);
  const uint32_t origin = packCoord(uint32_t(k) << a.shift, 0);
  for (size_t s = b; s < e; ++s) {
    const Offset o = applyJ(v.jacobian(s, a.tile(origin)), float(v.sites.x[s]) + 0.5f, float(v.sites.y[s]) + 0.5f);
    out[s] = a.move(origin, o.x, o.y);
  }
}

// Upsampling: the parent's pointer one stack level finer (kept at the finest), moved by the child's
// offset from its parent's centre, 2^(t-k) J(p) ((x, y) mod 2 - 1/2).
void upsample(const GraphAtlas& a, const LevelView& v, const uint32_t* parent, uint32_t* out, size_t b, size_t e) {
  for (size_t s = b; s < e; ++s) {
    uint32_t c = parent[v.sites.parent[s]];
    if (a.level(c) < a.finest) c = packCoord(coordU(c) + (1u << a.shift), coordV(c));
    const Offset o = applyJ(v.jacobian(s, a.tile(c)), float(v.sites.x[s] & 1) - 0.5f, float(v.sites.y[s] & 1) - 0.5f);
    out[s] = a.move(c, o.x, o.y);
  }
}

// Jitter as cpu::jitterSurfaceKernel, with the amplitude of the tile each pointer is in.
void jitter(const GraphAtlas& a, const LevelView& v, uint32_t* coords, uint32_t seed,
            const std::vector<int64_t>& amplitude256, size_t b, size_t e) {
  for (size_t s = b; s < e; ++s) {
    const int64_t amp = amplitude256[size_t(a.tile(coords[s]))];
    if (amp == 0) continue;
    const Offset j = cpu::surfaceJitter(v.sites, s, seed, v.atlasLevel, amp);
    coords[s] = a.move(coords[s], j.x, j.y);
  }
}

// Thesis §5.3's upsampling of transfers: a child's R is bilinear from its four nearest parents,
// its own and the parent's neighbours toward the child's side ((x, y) mod 2); a missing neighbour
// (an open boundary) counts as the parent itself.
void upsampleTransfers(const GraphAtlas& a, const LevelView& v, const SurfaceLevel& parentSites,
                       const TexelTransfer* parent, TexelTransfer* out, size_t b, size_t e) {
  for (size_t s = b; s < e; ++s) {
    const int32_t p = v.sites.parent[s];
    const int sx = (v.sites.x[s] & 1) ? 1 : -1, sy = (v.sites.y[s] & 1) ? 1 : -1;
    const auto toward = [&](int dx, int dy) -> const Transfer& {
      const int32_t n = parentSites.neighbors[size_t(p)][size_t(cpu::stepIndex(dx, dy))];
      return parent[n >= 0 ? n : p].r;
    };
    out[s] = a.texelTransfer(cpu::upsampledTransfer(parent[p].r, toward(sx, 0), toward(0, sy), toward(sx, sy)));
  }
}

// One correction sub-pass over the sites of class `cls` (cpu::correctSurfaceKernel's rules, each
// step scaled to the stack level of the pointer it moves): the target's sample at diagonal Δ is
// the mean appearance of S[n] + h(S[n]) Δ - 2^(t-k) J(p)δ over the two steps δ toward J⁻¹Δ;
// candidates C_i(S[n]) - 2^(t-k) J(p)δ over the 8 neighbours and C_i(S[s]), in nodes S[s] may
// move to (GraphAnalysis::moves); S[s] itself competes where its tile is admissible to itself or
// at the output level (synthesize_graph.cpp's rule). With transfers, each estimate is seen with its
// neighbour's R, and a candidate from S[n]'s list carries R_n composed with its offset
// (cpu::GraphTransferChoice), as in the plane.
template <bool kTransfers>
void correct(const GraphAtlas& a, const LevelView& v, GraphLevelState in, GraphLevelState out, bool outputLevel,
             int cls, size_t b, size_t e) {
  const SurfaceLevel& level = v.sites;
  using Value = std::conditional_t<kTransfers, int16_t, int8_t>;
  for (size_t s = b; s < e; ++s) {
    out.coords[s] = in.coords[s];
    if constexpr (kTransfers) out.transfers[s] = in.transfers[s];
    if (((level.x[s] & 1) | ((level.y[s] & 1) << 1)) != cls) continue;
    const std::array<int32_t, 8>& nb = level.neighbors[s];
    const uint32_t current = in.coords[s];
    const auto back = [&](int tile, int d) {  // -J(p) δ_d in the tile's pixels, subpixels
      const Offset o = applyJ(v.jacobian(s, tile), float(kSurfaceStepX[d]), float(kSurfaceStepY[d]));
      return Offset{-o.x, -o.y};
    };
    // Channel c of the appearance at `at`, as site n shows it.
    const auto estimate = [&](size_t n, uint32_t at, int c) {
      const int8_t value = a.appearance[a.texel(at) * kAppearanceDims + size_t(c)];
      if constexpr (kTransfers) return int16_t(value + in.transfers[n].shift[size_t(c)]);
      else return value;
    };

    alignas(32) Value target[kNeighborhoodDims];
    for (int i = 0; i < kNeighborhoodSamples; ++i) {
      struct { size_t n; uint32_t at; } from[2];
      int count = 0;
      for (int d : cpu::stepsToward(level.jacobian[s], float(kDiagonalX[i]), float(kDiagonalY[i]))) {
        const int32_t n = nb[size_t(d)];
        if (n < 0) continue;
        const uint32_t base = in.coords[n];
        const int64_t h = int64_t(a.spacing(base)) * kOne;
        const Offset o = back(a.tile(base), d);
        from[count++] = {size_t(n), a.move(base, h * kDiagonalX[i] + o.x, h * kDiagonalY[i] + o.y)};
      }
      if (count == 0) {  // an open boundary on that side: from the site itself
        const int64_t h = int64_t(a.spacing(current)) * kOne;
        from[count++] = {s, a.move(current, h * kDiagonalX[i], h * kDiagonalY[i])};
      }
      for (int c = 0; c < kAppearanceDims; ++c) {
        const int e0 = estimate(from[0].n, from[0].at, c);
        target[i * kAppearanceDims + c] =
            count == 1 ? Value(e0) : Value((e0 + estimate(from[1].n, from[1].at, c)) >> 1);
      }
    }

    auto choice = [&] {
      if constexpr (kTransfers) return cpu::GraphTransferChoice(a, target, current, in.transfers[s], outputLevel);
      else return cpu::GraphChoice(a, target, current, outputLevel);
    }();
    for (int d = 0; d <= 8; ++d) {
      const int32_t n = d < 8 ? nb[size_t(d)] : int32_t(s);
      if (n < 0) continue;
      const uint32_t base = in.coords[n];
      // S[n]'s subpixel offset from its nearest pixel, kept.
      const int fracX = int((coordU(base) + kOne / 2) & (kOne - 1)) - kOne / 2;
      const int fracY = int((coordV(base) + kOne / 2) & (kOne - 1)) - kOne / 2;
      const uint32_t* cand = a.candidates + a.texel(base) * size_t(a.k);
      [[maybe_unused]] const int16_t* offsets = kTransfers ? a.transfersOf(base) : nullptr;
      if constexpr (kTransfers) choice.frame(in.transfers[n]);
      for (int i = 0; i < a.k; ++i) {
        const uint32_t c0 = a.fromPixel(cand[i]);
        const Offset o = d < 8 ? back(a.tile(c0), d) : Offset{0, 0};
        const uint32_t moved = a.move(c0, fracX + o.x, fracY + o.y);
        if constexpr (kTransfers) choice.offer(moved, offsets + 3 * i);
        else choice.offer(moved);
      }
    }
    out.coords[s] = choice.best();
    if constexpr (kTransfers) out.transfers[s] = a.texelTransfer(choice.transfer());
  }
}

} // namespace

void checkSurfaceGraphSize(int nodes, int side) {
  const int width = side * (std::countr_zero(unsigned(side)) + 1), height = side * nodes;
  if (width > kMaxSurfaceAtlasSide || height > kMaxSurfaceAtlasSide)
    throw Error("the graph's exemplars pack into " + std::to_string(width) + "x" + std::to_string(height) +
                " pixels; on a surface at most " + std::to_string(kMaxSurfaceAtlasSide) +
                " a side (exemplars of 256 pixels or fewer, at most 16 of them)");
}

int surfaceGraphOutputLevel(const GraphAnalysis& analysis, double pixelsPerTexel) {
  return analysis.finestLevel() - int(std::lround(std::log2(std::max(pixelsPerTexel, 1e-9))));
}

SurfaceSynthesisResult synthesizeSurfaceGraph(const GraphAnalysis& analysis, const SurfaceDomain& domain,
                                              const SurfaceSynthesisOptions& options, const Context& ctx) {
  options.validate();
  checkSurfaceGraphSize(analysis.nodes, analysis.side);
  if (domain.levels.empty() || domain.levels[0].size() == 0) throw Error("the surface has no texels to synthesize");
  if (ctx.backend == Backend::Vulkan) throw Error("graph synthesis on a surface runs on the CPU only (--backend cpu)");

  SurfaceSynthesisResult result;
  result.exemplarPixelsPerTexel = std::max(medianPixelsPerTexel(domain.levels[0]), 1e-6);
  const int output = surfaceGraphOutputLevel(analysis, result.exemplarPixelsPerTexel);
  if (output < 0) throw Error("the scale puts the whole root exemplar inside one texel");
  const int top = std::min(int(domain.levels.size()) - 1, output);  // the coarsest level with t >= 0
  const GraphAtlas atlas(analysis, kSubpixelBits);
  const std::vector<int64_t> amplitude256 = graphJitterAmplitudes256(analysis, options.jitter);
  const int subpasses = options.correct ? options.passes * 4 : 0;

  const bool transfers = atlas.transfers != nullptr;
  std::vector<uint32_t> previous, current, scratch;
  std::vector<TexelTransfer> previousR, currentR, scratchR;  // with transfers only
  for (int a = top; a >= 0; --a) {
    const auto start = std::chrono::steady_clock::now();
    const int t = output - a;
    Stage stage(ctx, "level " + std::to_string(top - a + 1) + "/" + std::to_string(top + 1));
    const LevelView view(domain.levels[size_t(a)], a, t, analysis);
    const auto sites = [&](auto&& kernel) { forSites(view.sites.size(), ctx, kernel); };
    current.assign(view.sites.size(), 0);
    if (transfers) currentR.assign(current.size(), TexelTransfer{});
    if (a == top) {
      sites([&](size_t b, size_t e) { init(atlas, view, current.data(), b, e); });
    } else {
      sites([&](size_t b, size_t e) {
        upsample(atlas, view, previous.data(), current.data(), b, e);
        if (transfers)
          upsampleTransfers(atlas, view, domain.levels[size_t(a + 1)], previousR.data(), currentR.data(), b, e);
      });
    }
    sites([&](size_t b, size_t e) { jitter(atlas, view, current.data(), options.seed, amplitude256, b, e); });
    scratch.resize(current.size());
    scratchR.resize(currentR.size());
    for (int k = 0; k < subpasses; ++k) {
      const GraphLevelState in{current.data(), currentR.data()}, out{scratch.data(), scratchR.data()};
      sites([&](size_t b, size_t e) {
        const auto kernel = transfers ? correct<true> : correct<false>;
        kernel(atlas, view, in, out, a == 0, k % 4, b, e);
      });
      current.swap(scratch);
      currentR.swap(scratchR);
      stage.advance(k + 1, subpasses);
    }
    previous.swap(current);
    previousR.swap(currentR);
    result.levels.push_back({a, int64_t(view.sites.size()), secondsSince(start)});
    stage.finish();
  }
  result.coords = std::move(previous);
  for (const TexelTransfer& t : previousR) result.colorOffsets.push_back(cpu::colorOffset(t.r));
  return result;
}

float sampleSurfaceGraph(const GraphAnalysis& analysis, const Image& atlas, uint32_t coord, int channel) {
  channel = std::min(channel, atlas.channels - 1);
  const int m = analysis.side;
  const int tileX = int(coordU(coord) / uint32_t(m * kOne)) * m, tileY = int(coordV(coord) / uint32_t(m * kOne)) * m;
  const float u = float(coordU(coord)) / float(kOne) - float(tileX), v = float(coordV(coord)) / float(kOne) - float(tileY);
  const auto at = [&](int x, int y) { return atlas.at(tileX + (x & (m - 1)), tileY + (y & (m - 1)), channel); };
  if (tileX / m < analysis.finestLevel()) return at(int(std::floor(u + 0.5f)), int(std::floor(v + 0.5f)));
  const int x0 = int(std::floor(u)), y0 = int(std::floor(v));
  const float fx = u - float(x0), fy = v - float(y0);
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

} // namespace texfab::synthesis
