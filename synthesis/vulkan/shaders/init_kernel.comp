// SPDX-License-Identifier: GPL-3.0-or-later
// initKernel (synthesis/cpu/synthesis_kernels.cpp), one texel per invocation.
#version 460
#include "dispatch.glsl"
#include "coord_map.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { InitParams p; };
WORDS(0, coords);

// Coarsest level: S[q] = (q' * spacing) mod exemplar size, q' = q mod period (period 0: q' = q);
// non-toroidal: that value reflected into the valid region.
void initKernel(uint index) {
  const uint w = uint(p.grid.width);
  int64_t qx = p.grid.x0 + int(index % w), qy = p.grid.y0 + int(index / w);
  if (p.periodX > 0) qx = floorMod(qx, p.periodX);
  if (p.periodY > 0) qy = floorMod(qy, p.periodY);
  int u = int(floorMod(qx * p.spacing, int64_t(p.exemplarWidth)));
  int v = int(floorMod(qy * p.spacing, int64_t(p.exemplarHeight)));
  if (p.region.clamp != 0) {
    u = reflectInto(u, p.region.x0, p.region.x1);
    v = reflectInto(v, p.region.y0, p.region.y1);
  }
  coords.words[index] = packCoord(uint(u), uint(v));
}

void main() {
  const uint index = invocationIndex();
  if (index < uint(p.grid.width) * uint(p.grid.height)) initKernel(index);
}
