// SPDX-License-Identifier: GPL-3.0-or-later
// correctSurfaceKernel (synthesis/cpu/surface_kernels.cpp): one correction sub-pass, one site per
// invocation (sites of other classes are copied).
#version 460
#include "dispatch.glsl"
#include "surface.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { CorrectSurfaceParams p; };
READ_WORDS(0, siteX);       // from site `first` on
READ_WORDS(1, siteY);
READ_WORDS(2, jacobian);
READ_WORDS(3, neighbors);   // 8 site indices per site, -1 = none
READ_WORDS(4, coordsIn);    // the whole level
WORDS(5, coordsOut);
READ_WORDS(6, appearance);    // 8 int8 (2 words) per exemplar pixel
READ_WORDS(7, neighborhood);  // 32 int8 (8 words) per exemplar pixel
READ_WORDS(8, candidates);    // k packed pixel coordinates per exemplar pixel

const int kDiagonalX[4] = {-1, 1, -1, 1};
const int kDiagonalY[4] = {-1, -1, 1, 1};

// v reduced into [0, m).
uint reduce(int v, uint m) { return uint(v < 0 || v >= int(m) ? floorMod(v, int(m)) : v); }

// The exemplar pixel nearest subpixel coordinate c.
uint pixelIndex(uint c) {
  uint u = (coordU(c) + kOne / 2) >> kSubpixelBits, v = (coordV(c) + kOne / 2) >> kSubpixelBits;
  if (u == uint(p.exemplarWidth)) u = 0;
  if (v == uint(p.exemplarHeight)) v = 0;
  return v * uint(p.exemplarWidth) + u;
}

// c + (dx, dy) subpixels: wrapped, or clamped to the valid region (whole pixels) when the
// exemplar does not tile (a predicted neighborhood sample).
uint predictedAt(uint c, int dx, int dy) {
  if (p.region.clamp != 0)
    return packCoord(uint(min(max(int(coordU(c)) + dx, p.region.x0 * kOne), p.region.x1 * kOne)),
                     uint(min(max(int(coordV(c)) + dy, p.region.y0 * kOne), p.region.y1 * kOne)));
  const uint sw = uint(p.exemplarWidth) * kOne, sh = uint(p.exemplarHeight) * kOne;
  return packCoord(wrapAdd(coordU(c), reduce(dx, sw), sw), wrapAdd(coordV(c), reduce(dy, sh), sh));
}

int appearanceAt(uint pixel, int c) { return INT8_AT(appearance, pixel * 8u + uint(c)); }

int neighborhoodDistance(const uint target[8], uint pixel) {
  int sum = 0;
  for (uint i = 0; i < 8; ++i) sum += ssd4(target[i], neighborhood.words[pixel * 8u + i]);
  return sum;
}

// Sample i of the synthesized neighborhood (4 bytes of each of two words of `target`), predicted
// from immediate neighbors (LH06 §5): the mean of the estimates through the two unit steps
// closest in direction to J^-1 Delta.
void predictSample(int i, const float j[4], const ivec2 back[8], uint s, uint current, inout uint target[8]) {
  const int dx = p.spacing * kDiagonalX[i], dy = p.spacing * kDiagonalY[i];
  precise const float det = j[0] * j[3] - j[1] * j[2];
  const float sgn = det < 0 ? -1.0 : 1.0;
  precise const float fx = sgn * (j[3] * float(dx) - j[1] * float(dy)), fy = sgn * (j[0] * float(dy) - j[2] * float(dx));
  const float gx = det != 0.0 ? fx : float(dx), gy = det != 0.0 ? fy : float(dy);
  const int d1 = stepToward(gx, gy);
  precise const float side = float(kSurfaceStepX[d1]) * gy - float(kSurfaceStepY[d1]) * gx;
  const int d2 = (d1 + (side > 0 ? 1 : 7)) % 8;
  uint estimates[2];
  int count = 0;
  for (int k = 0; k < 2; ++k) {
    const int d = k == 0 ? d1 : d2;
    const int n = int(neighbors.words[s * 8u + uint(d)]);
    if (n < 0) continue;
    estimates[count++] = pixelIndex(predictedAt(coordsIn.words[n], dx * kOne + back[d].x, dy * kOne + back[d].y));
  }
  if (count == 0)  // no neighbor on that side (an open boundary): from the site itself
    estimates[count++] = pixelIndex(predictedAt(current, dx * kOne, dy * kOne));
  for (int c = 0; c < 8; ++c) {
    const int a = appearanceAt(estimates[0], c);
    const int v = count == 1 ? a : (a + appearanceAt(estimates[1], c)) >> 1;
    const uint w = uint(2 * i + c / 4);
    target[w] = bitfieldInsert(target[w], uint(v), (c % 4) * 8, 8);
  }
}

void correctSurfaceKernel(uint i) {
  const uint s = p.first + i, sw = uint(p.exemplarWidth) * kOne, sh = uint(p.exemplarHeight) * kOne;
  float j[4];
  JACOBIAN_AT(jacobian, i, j);
  const uint current = coordsIn.words[s];
  // -J(p)delta for the 8 unit steps, rounded once (subpixels, signed).
  ivec2 back[8];
  for (int d = 0; d < 8; ++d) back[d] = -applyJ(j, float(kSurfaceStepX[d]), float(kSurfaceStepY[d]));
  uint target[8];
  for (int k = 0; k < 8; ++k) target[k] = 0u;
  for (int k = 0; k < 4; ++k) predictSample(k, j, back, i, current, target);

  uint best = current;
  int bestDistance = neighborhoodDistance(target, pixelIndex(current));
  for (int d = 0; d <= 8; ++d) {
    const int n = d < 8 ? int(neighbors.words[i * 8u + uint(d)]) : int(s);
    if (n < 0) continue;
    const uint base = coordsIn.words[n];
    // C_i(S[n]) - J(p)delta, keeping S[n]'s subpixel offset from its nearest pixel.
    const int fracX = int((coordU(base) + kOne / 2) & (kOne - 1)) - kOne / 2;
    const int fracY = int((coordV(base) + kOne / 2) & (kOne - 1)) - kOne / 2;
    const uint ox = reduce(fracX + (d < 8 ? back[d].x : 0), sw);
    const uint oy = reduce(fracY + (d < 8 ? back[d].y : 0), sh);
    const uint cand = pixelIndex(base) * uint(p.k);
    for (uint k = 0; k < uint(p.k); ++k) {
      const uint ck = candidates.words[cand + k];
      uint c;
      if (p.region.clamp != 0) {  // C_i(S[n]) - J(p)delta unwrapped; skipped outside the valid region
        const int u = int(coordU(ck)) * kOne + fracX + (d < 8 ? back[d].x : 0);
        const int v = int(coordV(ck)) * kOne + fracY + (d < 8 ? back[d].y : 0);
        if (u < p.region.x0 * kOne || u > p.region.x1 * kOne || v < p.region.y0 * kOne || v > p.region.y1 * kOne)
          continue;
        c = packCoord(uint(u), uint(v));
      } else {
        c = packCoord(wrapAdd(coordU(ck) * kOne, ox, sw), wrapAdd(coordV(ck) * kOne, oy, sh));
      }
      if (c == best) continue;
      const int dist = neighborhoodDistance(target, pixelIndex(c));
      if (dist < bestDistance || (dist == bestDistance && best != current && c < best)) {
        bestDistance = dist;
        best = c;
      }
    }
  }
  coordsOut.words[s] = best;
}

void main() {
  const uint i = invocationIndex();
  if (i >= p.count) return;
  if (int((siteX.words[i] & 1u) | ((siteY.words[i] & 1u) << 1)) == p.cls) correctSurfaceKernel(i);
  else coordsOut.words[p.first + i] = coordsIn.words[p.first + i];
}
