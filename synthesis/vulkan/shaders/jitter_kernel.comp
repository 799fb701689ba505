// SPDX-License-Identifier: GPL-3.0-or-later
// jitterKernel (synthesis/cpu/synthesis_kernels.cpp), one texel per invocation, in place.
#version 460
#include "dispatch.glsl"
#include "coord_map.glsl"
#include "hash.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { JitterParams p; };
WORDS(0, coords);

// S[q] += round(amplitude/256 * H(q)), H uniform in [-1, 1)^2 from texelHash(seed, level, q mod period);
// wrapped, or reflected into the valid region.
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
  const int64_t u = int64_t(coordU(s)) + jx, v = int64_t(coordV(s)) + jy;
  if (p.region.clamp != 0)
    coords.words[index] = packCoord(uint(reflectInto(int(u), p.region.x0, p.region.x1)),
                                    uint(reflectInto(int(v), p.region.y0, p.region.y1)));
  else
    coords.words[index] = packCoord(uint(floorMod(u, int64_t(p.exemplarWidth))),
                                    uint(floorMod(v, int64_t(p.exemplarHeight))));
}

void main() {
  const uint index = invocationIndex();
  if (p.amplitude256 != 0 && index < uint(p.grid.width) * uint(p.grid.height)) jitterKernel(index);
}
