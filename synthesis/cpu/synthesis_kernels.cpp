// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3;
//           S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §4.
#include "synthesis/cpu/synthesis_kernels.h"

#include "core/hash.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"

#include <algorithm>
#include <cstddef>

namespace texfab::synthesis::cpu {

namespace {

inline uint32_t wrapAdd(uint32_t a, uint32_t b, uint32_t m) {  // (a + b) mod m for a, b < m
  const uint32_t s = a + b;
  return s >= m ? s - m : s;
}

} // namespace

void initKernel(uint32_t* out, const LevelGrid& grid, int spacing, int exemplarWidth,
                int exemplarHeight, int64_t periodX, int64_t periodY, int rowBegin, int rowEnd,
                const ValidRegion* clampTo) {
  for (int y = rowBegin; y < rowEnd; ++y) {
    int64_t qy = grid.y0 + y;
    if (periodY > 0) qy = floorMod(qy, periodY);
    int64_t v = floorMod(qy * spacing, exemplarHeight);
    if (clampTo) v = reflectInto(v, clampTo->y0, clampTo->y1);
    for (int x = 0; x < grid.width; ++x) {
      int64_t qx = grid.x0 + x;
      if (periodX > 0) qx = floorMod(qx, periodX);
      int64_t u = floorMod(qx * spacing, exemplarWidth);
      if (clampTo) u = reflectInto(u, clampTo->x0, clampTo->x1);
      out[size_t(y) * grid.width + x] = packCoord(uint32_t(u), uint32_t(v));
    }
  }
}

namespace {

// The clamped child coordinate of upsampleKernel, one axis.
inline uint32_t clampedChild(uint32_t parent, int spacing, int64_t bit, int lo, int hi) {
  int64_t base = std::min<int64_t>(parent, int64_t(hi) - spacing);
  if (base < lo) base = lo;
  return uint32_t(std::min<int64_t>(base + bit * spacing, hi));
}

} // namespace

void upsampleKernel(const uint32_t* parent, const LevelGrid& parentGrid, uint32_t* out,
                    const LevelGrid& grid, int spacing, int exemplarWidth, int exemplarHeight,
                    int rowBegin, int rowEnd, const ValidRegion* clampTo) {
  if (clampTo) {
    for (int y = rowBegin; y < rowEnd; ++y) {
      const int64_t qy = grid.y0 + y;
      const uint32_t* parentRow = parent + size_t(floorShift(qy, 1) - parentGrid.y0) * parentGrid.width;
      for (int x = 0; x < grid.width; ++x) {
        const int64_t qx = grid.x0 + x;
        const uint32_t s = parentRow[floorShift(qx, 1) - parentGrid.x0];
        out[size_t(y) * grid.width + x] = packCoord(clampedChild(coordU(s), spacing, qx & 1, clampTo->x0, clampTo->x1),
                                                    clampedChild(coordV(s), spacing, qy & 1, clampTo->y0, clampTo->y1));
      }
    }
    return;
  }
  const auto offX = uint32_t(spacing % exemplarWidth);
  const auto offY = uint32_t(spacing % exemplarHeight);
  for (int y = rowBegin; y < rowEnd; ++y) {
    const int64_t qy = grid.y0 + y;
    const int64_t py = floorShift(qy, 1) - parentGrid.y0;
    const uint32_t dy = (qy & 1) ? offY : 0;
    const uint32_t* parentRow = parent + size_t(py) * parentGrid.width;
    for (int x = 0; x < grid.width; ++x) {
      const int64_t qx = grid.x0 + x;
      const uint32_t s = parentRow[floorShift(qx, 1) - parentGrid.x0];
      const uint32_t dx = (qx & 1) ? offX : 0;
      out[size_t(y) * grid.width + x] = packCoord(wrapAdd(coordU(s), dx, uint32_t(exemplarWidth)),
                                                  wrapAdd(coordV(s), dy, uint32_t(exemplarHeight)));
    }
  }
}

void jitterKernel(uint32_t* coords, const LevelGrid& grid, uint32_t seed, int level,
                  int64_t amplitude256, int64_t periodX, int64_t periodY, int exemplarWidth,
                  int exemplarHeight, int rowBegin, int rowEnd, const ValidRegion* clampTo) {
  if (amplitude256 == 0) return;
  for (int y = rowBegin; y < rowEnd; ++y) {
    int64_t qy = grid.y0 + y;
    if (periodY > 0) qy = floorMod(qy, periodY);
    for (int x = 0; x < grid.width; ++x) {
      int64_t qx = grid.x0 + x;
      if (periodX > 0) qx = floorMod(qx, periodX);
      // H in [-1, 1) as a 16-bit fraction; offset = floor(amplitude * H + 1/2), all in integers.
      const int64_t hx = int64_t(texelHash(seed, uint32_t(level), int32_t(qx), int32_t(qy), 0) >> 16) - 32768;
      const int64_t hy = int64_t(texelHash(seed, uint32_t(level), int32_t(qx), int32_t(qy), 1) >> 16) - 32768;
      const int64_t jx = (amplitude256 * hx + (int64_t(1) << 22)) >> 23;
      const int64_t jy = (amplitude256 * hy + (int64_t(1) << 22)) >> 23;
      uint32_t& s = coords[size_t(y) * grid.width + x];
      if (clampTo)
        s = packCoord(uint32_t(reflectInto(int64_t(coordU(s)) + jx, clampTo->x0, clampTo->x1)),
                      uint32_t(reflectInto(int64_t(coordV(s)) + jy, clampTo->y0, clampTo->y1)));
      else
        s = packCoord(uint32_t(floorMod(int64_t(coordU(s)) + jx, exemplarWidth)),
                      uint32_t(floorMod(int64_t(coordV(s)) + jy, exemplarHeight)));
    }
  }
}

void correctKernel(const uint32_t* in, uint32_t* out, const LevelGrid& grid, const LevelTables& t,
                   int interleave, int classX, int classY, int ax0, int ax1, int rowBegin, int rowEnd) {
  const auto ew = uint32_t(t.exemplarWidth);
  const auto eh = uint32_t(t.exemplarHeight);
  // -spacing*D mod exemplar size, for D = -1, 0, 1.
  const uint32_t backX[3] = {uint32_t(floorMod(t.spacing, ew)), 0, uint32_t(floorMod(-int64_t(t.spacing), ew))};
  const uint32_t backY[3] = {uint32_t(floorMod(t.spacing, eh)), 0, uint32_t(floorMod(-int64_t(t.spacing), eh))};
  const auto w = size_t(grid.width);
  // First buffer column whose level position is in the class.
  const int firstX = ax0 + int(floorMod(classX - (grid.x0 + ax0), interleave));

  for (int y = rowBegin; y < rowEnd; ++y) {
    const uint32_t* row = in + size_t(y) * w;
    uint32_t* outRow = out + size_t(y) * w;
    for (int x = ax0; x < ax1; ++x) outRow[x] = row[x];
    if (floorMod(grid.y0 + y - classY, interleave) != 0) continue;

    for (int x = firstX; x < ax1; x += interleave) {
      // The synthesized neighborhood: appearance vectors at the 4 diagonal neighbors.
      alignas(32) int8_t target[kNeighborhoodDims];
      for (int i = 0; i < kNeighborhoodSamples; ++i) {
        const uint32_t s = in[size_t(y + kDiagonalY[i]) * w + size_t(x + kDiagonalX[i])];
        const int8_t* a = t.appearance + (size_t(coordV(s)) * ew + coordU(s)) * kAppearanceDims;
        for (int d = 0; d < kAppearanceDims; ++d) target[i * kAppearanceDims + d] = a[d];
      }

      const uint32_t current = row[x];
      uint32_t best = current;
      int32_t bestDistance =
          neighborhoodDistance(target, t.neighborhood + (size_t(coordV(current)) * ew + coordU(current)) * kNeighborhoodDims);

      for (int dy = -1; dy <= 1; ++dy) {
        const uint32_t* nrow = in + size_t(y + dy) * w;
        for (int dx = -1; dx <= 1; ++dx) {
          const uint32_t s = nrow[x + dx];
          const uint32_t* cand = t.candidates + (size_t(coordV(s)) * ew + coordU(s)) * size_t(t.k);
          for (int i = 0; i < t.k; ++i) {
            uint32_t c;
            if (t.clampTo) {  // no wrap: C_i - spacing*D must stay in the valid region
              const int64_t u = int64_t(coordU(cand[i])) - int64_t(t.spacing) * dx;
              const int64_t v = int64_t(coordV(cand[i])) - int64_t(t.spacing) * dy;
              if (!t.clampTo->contains(u, v)) continue;
              c = packCoord(uint32_t(u), uint32_t(v));
            } else {
              c = packCoord(wrapAdd(coordU(cand[i]), backX[dx + 1], ew), wrapAdd(coordV(cand[i]), backY[dy + 1], eh));
            }
            if (c == best) continue;
            const int32_t d = neighborhoodDistance(
                target, t.neighborhood + (size_t(coordV(c)) * ew + coordU(c)) * kNeighborhoodDims);
            // Order-independent minimum of (distance, c != current, c).
            if (d < bestDistance || (d == bestDistance && best != current && c < best)) {
              bestDistance = d;
              best = c;
            }
          }
        }
      }
      outRow[x] = best;
    }
  }
}

} // namespace texfab::synthesis::cpu
