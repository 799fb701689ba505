// SPDX-License-Identifier: GPL-3.0-or-later
// upsampleKernel (synthesis/cpu/synthesis_kernels.cpp), one texel per invocation.
#version 460
#include "dispatch.glsl"
#include "coord_map.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { UpsampleParams p; };
READ_WORDS(0, parent);
WORDS(1, coords);

// S_l[q] = S_{l-1}[floor(q/2)] + spacing * (q mod 2), wrapped (errata §20.2).
void upsampleKernel(uint index) {
  const uint w = uint(p.grid.width), ew = uint(p.exemplarWidth), eh = uint(p.exemplarHeight);
  const int64_t qx = p.grid.x0 + int(index % w), qy = p.grid.y0 + int(index / w);
  const uint py = uint(floorShift(qy, 1) - p.parentGrid.y0), px = uint(floorShift(qx, 1) - p.parentGrid.x0);
  const uint s = parent.words[py * uint(p.parentGrid.width) + px];
  const uint dx = (qx & 1) != 0 ? uint(p.spacing) % ew : 0u;
  const uint dy = (qy & 1) != 0 ? uint(p.spacing) % eh : 0u;
  coords.words[index] = packCoord(wrapAdd(coordU(s), dx, ew), wrapAdd(coordV(s), dy, eh));
}

void main() {
  const uint index = invocationIndex();
  if (index < uint(p.grid.width) * uint(p.grid.height)) upsampleKernel(index);
}
