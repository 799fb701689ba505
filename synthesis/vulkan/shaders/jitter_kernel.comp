// SPDX-License-Identifier: GPL-3.0-or-later
// jitterKernel (synthesis/cpu/synthesis_kernels.cpp), one texel per invocation, in place.
#version 460
#include "dispatch.glsl"
#include "coord_map.glsl"
#include "hash.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { JitterParams p; };
WORDS(0, coords);

// S[q] += round(amplitude/256 * H(q)), H uniform in [-1, 1)^2 from texelHash(seed, level, q mod period).
void jitterKernel(uint index) {
  const uint w = uint(p.grid.width);
  int64_t qx = p.grid.x0 + int(index % w), qy = p.grid.y0 + int(index / w);
  if (p.periodX > 0) qx = floorMod(qx, p.periodX);
  if (p.periodY > 0) qy = floorMod(qy, p.periodY);
  // H in [-1, 1) as a 16-bit fraction; offset = floor(amplitude * H + 1/2), all in integers.
  const int64_t hx = int64_t(texelHash(p.seed, uint(p.level), int(qx), int(qy), 0u) >> 16) - 32768;
  const int64_t hy = int64_t(texelHash(p.seed, uint(p.level), int(qx), int(qy), 1u) >> 16) - 32768;
  const int64_t jx = (p.amplitude256 * hx + (int64_t(1) << 22)) >> 23;
  const int64_t jy = (p.amplitude256 * hy + (int64_t(1) << 22)) >> 23;
  const uint s = coords.words[index];
  coords.words[index] = packCoord(uint(floorMod(int64_t(coordU(s)) + jx, int64_t(p.exemplarWidth))),
                                  uint(floorMod(int64_t(coordV(s)) + jy, int64_t(p.exemplarHeight))));
}

void main() {
  const uint index = invocationIndex();
  if (p.amplitude256 != 0 && index < uint(p.grid.width) * uint(p.grid.height)) jitterKernel(index);
}
