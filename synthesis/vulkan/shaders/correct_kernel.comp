// SPDX-License-Identifier: GPL-3.0-or-later
// correctKernel (synthesis/cpu/synthesis_kernels.cpp): one correction sub-pass, one texel of the
// rectangle [ax0, ax1) x [ay0, ay1) per invocation (texels of other classes are copied).
#version 460
#include "dispatch.glsl"
#include "coord_map.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { CorrectParams p; };
READ_WORDS(0, coordsIn);
WORDS(1, coordsOut);
READ_WORDS(2, appearance);    // 8 int8 (2 words) per exemplar pixel
READ_WORDS(3, neighborhood);  // 32 int8 (8 words) per exemplar pixel
READ_WORDS(4, candidates);    // k packed coordinates per exemplar pixel

const int kDiagonalX[4] = {-1, 1, -1, 1};
const int kDiagonalY[4] = {-1, -1, 1, 1};

// Integer SSD of two runtime neighborhoods (neighborhoodDistance).
int neighborhoodDistance(const uint target[8], uint pixel) {
  int sum = 0;
  for (uint i = 0; i < 8; ++i) sum += ssd4(target[i], neighborhood.words[pixel * 8u + i]);
  return sum;
}

void correctKernel(uint x, uint y) {
  const uint w = uint(p.grid.width), ew = uint(p.exemplarWidth), eh = uint(p.exemplarHeight);
  const uint current = coordsIn.words[y * w + x];
  // -spacing*D mod exemplar size, for D = -1, 0, 1.
  const uint backX[3] = {uint(floorMod(p.spacing, p.exemplarWidth)), 0u, uint(floorMod(-p.spacing, p.exemplarWidth))};
  const uint backY[3] = {uint(floorMod(p.spacing, p.exemplarHeight)), 0u, uint(floorMod(-p.spacing, p.exemplarHeight))};

  // The synthesized neighborhood: appearance vectors at the 4 diagonal neighbors.
  uint target[8];
  for (int i = 0; i < 4; ++i) {
    const uint s = coordsIn.words[(y + kDiagonalY[i]) * w + x + kDiagonalX[i]];
    const uint pixel = coordV(s) * ew + coordU(s);
    target[2 * i] = appearance.words[pixel * 2u];
    target[2 * i + 1] = appearance.words[pixel * 2u + 1u];
  }

  uint best = current;
  int bestDistance = neighborhoodDistance(target, coordV(current) * ew + coordU(current));
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const uint s = coordsIn.words[(y + dy) * w + x + dx];
      const uint cand = (coordV(s) * ew + coordU(s)) * uint(p.k);
      for (uint i = 0; i < uint(p.k); ++i) {
        const uint ci = candidates.words[cand + i];
        uint c;
        if (p.region.clamp != 0) {  // no wrap: C_i - spacing*D must stay in the valid region
          const int u = int(coordU(ci)) - p.spacing * dx, v = int(coordV(ci)) - p.spacing * dy;
          if (u < p.region.x0 || u > p.region.x1 || v < p.region.y0 || v > p.region.y1) continue;
          c = packCoord(uint(u), uint(v));
        } else {
          c = packCoord(wrapAdd(coordU(ci), backX[dx + 1], ew), wrapAdd(coordV(ci), backY[dy + 1], eh));
        }
        if (c == best) continue;
        const int d = neighborhoodDistance(target, coordV(c) * ew + coordU(c));
        // Order-independent minimum of (distance, c != current, c).
        if (d < bestDistance || (d == bestDistance && best != current && c < best)) {
          bestDistance = d;
          best = c;
        }
      }
    }
  coordsOut.words[y * w + x] = best;
}

void main() {
  const uint index = invocationIndex(), rw = uint(p.ax1 - p.ax0);
  if (index >= rw * uint(p.ay1 - p.ay0)) return;
  const uint x = uint(p.ax0) + index % rw, y = uint(p.ay0) + index / rw;
  if (floorMod(p.grid.x0 + x - p.classX, int64_t(p.interleave)) == 0 &&
      floorMod(p.grid.y0 + y - p.classY, int64_t(p.interleave)) == 0)
    correctKernel(x, y);
  else
    coordsOut.words[y * uint(p.grid.width) + x] = coordsIn.words[y * uint(p.grid.width) + x];
}
