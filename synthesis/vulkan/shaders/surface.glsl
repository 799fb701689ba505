// SPDX-License-Identifier: GPL-3.0-or-later
// What the surface kernels share: the GLSL twin of the helpers of synthesis/cpu/surface_kernels.cpp
// and of synthesis/synthesize_surface.h's constants. Every float product and sum is `precise`
// (no fused multiply-add, no reassociation), as the CPU build's -ffp-contract=off. Offsets and
// exemplar sizes in subpixels are 32-bit here (they stay below 2^27): Mesa 22.3's lavapipe
// miscompiles the sign of 64-bit integers converted from floats (int64_t(int(floor(x))) >= 0 held
// for negative x), and 32-bit arithmetic gives the CPU's int64 results exactly.
#ifndef TEXFAB_SURFACE_GLSL
#define TEXFAB_SURFACE_GLSL

#include "coord_map.glsl"
#include "kernel_params.h"

const int kSubpixelBits = 4;
const int kOne = 1 << kSubpixelBits;  // one exemplar pixel in subpixel units

// The 8 unit steps, in neighbor order (kSurfaceStepX/Y), and the neighbor index of step (dx, dy)
// at [dy + 1][dx + 1] (-1 for (0, 0)).
const int kSurfaceStepX[8] = {1, 1, 0, -1, -1, -1, 0, 1};
const int kSurfaceStepY[8] = {0, 1, 1, 1, 0, -1, -1, -1};
const int kStepIndex[9] = {5, 6, 7, 4, -1, 0, 3, 2, 1};

int roundToInt(float v) {
  precise const float t = v + 0.5;
  return int(floor(t));
}

// round(J * (vx, vy)) in subpixel units: two products, then their sum, each rounded to float.
ivec2 applyJ(const float j[4], float vx, float vy) {
  precise const float ax = j[0] * vx, bx = j[1] * vy;
  precise const float ay = j[2] * vx, by = j[3] * vy;
  precise const float sx = (ax + bx) * float(kOne), sy = (ay + by) * float(kOne);
  return ivec2(roundToInt(sx), roundToInt(sy));
}

// c + (dx, dy) subpixels, wrapped to the exemplar (sizes in subpixels).
uint shifted(uint c, int dx, int dy, int w, int h) {
  return packCoord(uint(floorMod(int(coordU(c)) + dx, w)), uint(floorMod(int(coordV(c)) + dy, h)));
}

// The same, or reflected into the valid region (whole pixels) when the exemplar does not tile.
uint shifted(uint c, int dx, int dy, int w, int h, RegionParams region) {
  if (region.clamp == 0) return shifted(c, dx, dy, w, h);
  return packCoord(uint(reflectInto(int(coordU(c)) + dx, region.x0 * kOne, region.x1 * kOne)),
                   uint(reflectInto(int(coordV(c)) + dy, region.y0 * kOne, region.y1 * kOne)));
}

// The unit step (one of 8) closest in direction to (fx, fy) (sectors of 45 degrees around each).
int stepToward(float fx, float fy) {
  const float kTan22_5 = 0.41421356;
  const float ax = abs(fx), ay = abs(fy);
  precise const float tx = kTan22_5 * ay, ty = kTan22_5 * ax;
  const int dx = ax > tx ? (fx > 0 ? 1 : -1) : 0;
  const int dy = ay > ty ? (fy > 0 ? 1 : -1) : 0;
  return kStepIndex[(dy + 1) * 3 + dx + 1];
}

// The Jacobian of a site from its binding (4 floats per site).
#define JACOBIAN_AT(buf, s, j) \
  for (uint jj = 0; jj < 4; ++jj) j[jj] = uintBitsToFloat((buf).words[(s) * 4u + jj])

#endif
