// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6;
//           docs/synthesis-notes.md#atlas-synthesis, #anisometric-step, #anisometric-candidates.
#include "synthesis/cpu/surface_kernels.h"

#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace texfab::synthesis::cpu {

namespace {

constexpr int kOne = kSubpixelOne;

// c + (dx, dy) subpixels, wrapped to the exemplar (sizes in subpixels), or reflected into the
// valid region `clampTo` (whole pixels) when it is given.
inline uint32_t shifted(uint32_t c, int dx, int dy, int64_t w, int64_t h, const ValidRegion* clampTo = nullptr) {
  if (clampTo)
    return packCoord(uint32_t(reflectInto(int64_t(coordU(c)) + dx, int64_t(clampTo->x0) * kOne, int64_t(clampTo->x1) * kOne)),
                     uint32_t(reflectInto(int64_t(coordV(c)) + dy, int64_t(clampTo->y0) * kOne, int64_t(clampTo->y1) * kOne)));
  return packCoord(uint32_t(floorMod(int64_t(coordU(c)) + dx, w)), uint32_t(floorMod(int64_t(coordV(c)) + dy, h)));
}

} // namespace

void initSurfaceKernel(const SurfaceLevel& level, uint32_t* out, int ew, int eh, size_t begin, size_t end,
                       const ValidRegion* clampTo) {
  for (size_t s = begin; s < end; ++s) {
    const Offset o = applyJ(level.jacobian[s], float(level.x[s]) + 0.5f, float(level.y[s]) + 0.5f);
    out[s] = shifted(0, o.x, o.y, int64_t(ew) * kOne, int64_t(eh) * kOne);
    if (clampTo) out[s] = shifted(out[s], 0, 0, 0, 0, clampTo);  // the tiling's value, reflected into the region
  }
}

void upsampleSurfaceKernel(const SurfaceLevel& level, const uint32_t* parent, uint32_t* out, int ew, int eh,
                           size_t begin, size_t end, const ValidRegion* clampTo) {
  for (size_t s = begin; s < end; ++s) {
    const Offset o = applyJ(level.jacobian[s], float(level.x[s] & 1) - 0.5f, float(level.y[s] & 1) - 0.5f);
    out[s] = shifted(parent[level.parent[s]], o.x, o.y, int64_t(ew) * kOne, int64_t(eh) * kOne, clampTo);
  }
}

void jitterSurfaceKernel(const SurfaceLevel& level, uint32_t* coords, uint32_t seed, int atlasLevel,
                         int64_t amplitude256, int ew, int eh, size_t begin, size_t end, const ValidRegion* clampTo) {
  if (amplitude256 == 0) return;
  for (size_t s = begin; s < end; ++s) {
    const Offset j = surfaceJitter(level, s, seed, atlasLevel, amplitude256);
    coords[s] = shifted(coords[s], j.x, j.y, int64_t(ew) * kOne, int64_t(eh) * kOne, clampTo);
  }
}

void correctSurfaceKernel(const SurfaceLevel& level, const uint32_t* in, uint32_t* out, const LevelTables& t,
                          int cls, size_t begin, size_t end) {
  const auto ew = uint32_t(t.exemplarWidth), eh = uint32_t(t.exemplarHeight);
  const uint32_t sw = ew * kOne, sh = eh * kOne;  // exemplar size in subpixels
  // Offsets are reduced into [0, size) once per site, so that every shift below is one add and at
  // most one subtract: no division in the inner loops.
  const auto reduce = [](int64_t v, uint32_t m) {
    if (v < 0 || v >= int64_t(m)) v = floorMod(v, m);
    return uint32_t(v);
  };
  const auto add = [](uint32_t a, uint32_t b, uint32_t m) {  // (a + b) mod m for a, b < m
    const uint32_t sum = a + b;
    return sum >= m ? sum - m : sum;
  };
  // Non-toroidal: a predicted neighborhood sample c + (dx, dy) clamped to the valid region (no wrap).
  const ValidRegion* clampTo = t.clampTo;
  const auto clampedShift = [&](uint32_t c, int64_t dx, int64_t dy) {
    return packCoord(uint32_t(std::clamp(int64_t(coordU(c)) + dx, int64_t(clampTo->x0) * kOne, int64_t(clampTo->x1) * kOne)),
                     uint32_t(std::clamp(int64_t(coordV(c)) + dy, int64_t(clampTo->y0) * kOne, int64_t(clampTo->y1) * kOne)));
  };
  const auto pixelIndex = [&](uint32_t c) {  // the exemplar pixel nearest subpixel coordinate c
    uint32_t u = (coordU(c) + kOne / 2) >> kSubpixelBits, v = (coordV(c) + kOne / 2) >> kSubpixelBits;
    if (u == ew) u = 0;
    if (v == eh) v = 0;
    return size_t(v) * ew + u;
  };
  for (size_t s = begin; s < end; ++s) {
    out[s] = in[s];
    if (((level.x[s] & 1) | ((level.y[s] & 1) << 1)) != cls) continue;
    const std::array<float, 4>& j = level.jacobian[s];
    const std::array<int32_t, 8>& nb = level.neighbors[s];
    const uint32_t current = in[s];

    // -J(p)δ for the 8 unit steps, rounded once (subpixels, signed).
    Offset back[8];
    for (int d = 0; d < 8; ++d) {
      const Offset o = applyJ(j, float(kSurfaceStepX[d]), float(kSurfaceStepY[d]));
      back[d] = {-o.x, -o.y};
    }

    // The synthesized neighborhood, predicted from immediate neighbors (LH06 §5).
    alignas(32) int8_t target[kNeighborhoodDims];
    for (int i = 0; i < kNeighborhoodSamples; ++i) {
      const int dx = t.spacing * kDiagonalX[i], dy = t.spacing * kDiagonalY[i];
      const int8_t* estimates[2];
      int count = 0;
      for (int d : stepsToward(j, float(dx), float(dy))) {
        const int32_t n = nb[size_t(d)];
        if (n < 0) continue;
        const uint32_t predicted =
            clampTo ? clampedShift(in[n], int64_t(dx) * kOne + back[d].x, int64_t(dy) * kOne + back[d].y)
                    : packCoord(add(coordU(in[n]), reduce(int64_t(dx) * kOne + back[d].x, sw), sw),
                                add(coordV(in[n]), reduce(int64_t(dy) * kOne + back[d].y, sh), sh));
        estimates[count++] = t.appearance + pixelIndex(predicted) * kAppearanceDims;
      }
      if (count == 0) {  // no neighbor on that side (an open boundary): from the site itself
        const uint32_t predicted = clampTo ? clampedShift(current, int64_t(dx) * kOne, int64_t(dy) * kOne)
                                           : packCoord(add(coordU(current), reduce(int64_t(dx) * kOne, sw), sw),
                                                       add(coordV(current), reduce(int64_t(dy) * kOne, sh), sh));
        estimates[count++] = t.appearance + pixelIndex(predicted) * kAppearanceDims;
      }
      for (int c = 0; c < kAppearanceDims; ++c)
        target[i * kAppearanceDims + c] =
            count == 1 ? estimates[0][c] : int8_t((int(estimates[0][c]) + int(estimates[1][c])) >> 1);
    }

    uint32_t best = current;
    int32_t bestDistance = neighborhoodDistance(target, t.neighborhood + pixelIndex(current) * kNeighborhoodDims);
    for (int d = 0; d <= 8; ++d) {
      const int32_t n = d < 8 ? nb[size_t(d)] : int32_t(s);
      if (n < 0) continue;
      const uint32_t base = in[n];
      const size_t basePixel = pixelIndex(base);
      // C_i(S[n]) - J(p)δ, keeping S[n]'s subpixel offset from its nearest pixel.
      const int fracX = int((coordU(base) + kOne / 2) & (kOne - 1)) - kOne / 2;
      const int fracY = int((coordV(base) + kOne / 2) & (kOne - 1)) - kOne / 2;
      const uint32_t ox = reduce(int64_t(fracX) + (d < 8 ? back[d].x : 0), sw);
      const uint32_t oy = reduce(int64_t(fracY) + (d < 8 ? back[d].y : 0), sh);
      const uint32_t* cand = t.candidates + basePixel * size_t(t.k);
      for (int i = 0; i < t.k; ++i) {
        uint32_t c;
        if (clampTo) {  // C_i(S[n]) - J(p)δ unwrapped; skipped outside the valid region
          const int64_t u = int64_t(coordU(cand[i])) * kOne + fracX + (d < 8 ? back[d].x : 0);
          const int64_t v = int64_t(coordV(cand[i])) * kOne + fracY + (d < 8 ? back[d].y : 0);
          if (u < int64_t(clampTo->x0) * kOne || u > int64_t(clampTo->x1) * kOne || v < int64_t(clampTo->y0) * kOne ||
              v > int64_t(clampTo->y1) * kOne)
            continue;
          c = packCoord(uint32_t(u), uint32_t(v));
        } else {
          c = packCoord(add(coordU(cand[i]) * kOne, ox, sw), add(coordV(cand[i]) * kOne, oy, sh));
        }
        if (c == best) continue;
        const int32_t dist = neighborhoodDistance(target, t.neighborhood + pixelIndex(c) * kNeighborhoodDims);
        if (dist < bestDistance || (dist == bestDistance && best != current && c < best)) {
          bestDistance = dist;
          best = c;
        }
      }
    }
    out[s] = best;
  }
}

} // namespace texfab::synthesis::cpu
