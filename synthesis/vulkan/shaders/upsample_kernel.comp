// SPDX-License-Identifier: GPL-3.0-or-later
// upsampleKernel (synthesis/cpu/synthesis_kernels.cpp), one texel per invocation.
#version 460
#include "dispatch.glsl"
#include "coord_map.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { UpsampleParams p; };
READ_WORDS(0, parent);
WORDS(1, coords);

// The child coordinate of a non-toroidal parent coordinate, one axis: b + spacing * bit,
// b = min(parent, hi - spacing) (lo if that is below lo), at most hi.
uint clampedChild(uint parent, int bit, int lo, int hi) {
  const int base = max(min(int(parent), hi - p.spacing), lo);
  return uint(min(base + bit * p.spacing, hi));
}

// S_l[q] = S_{l-1}[floor(q/2)] + spacing * (q mod 2), wrapped (errata §20.2), or kept inside the
// valid region (the two children distinct).
void upsampleKernel(uint index) {
  const uint w = uint(p.grid.width), ew = uint(p.exemplarWidth), eh = uint(p.exemplarHeight);
  const int64_t qx = p.grid.x0 + int(index % w), qy = p.grid.y0 + int(index / w);
  const uint py = uint(floorShift(qy, 1) - p.parentGrid.y0), px = uint(floorShift(qx, 1) - p.parentGrid.x0);
  const uint s = parent.words[py * uint(p.parentGrid.width) + px];
  if (p.region.clamp != 0) {
    coords.words[index] = packCoord(clampedChild(coordU(s), int(qx & 1), p.region.x0, p.region.x1),
                                    clampedChild(coordV(s), int(qy & 1), p.region.y0, p.region.y1));
    return;
  }
  const uint dx = (qx & 1) != 0 ? uint(p.spacing) % ew : 0u;
  const uint dy = (qy & 1) != 0 ? uint(p.spacing) % eh : 0u;
  coords.words[index] = packCoord(wrapAdd(coordU(s), dx, ew), wrapAdd(coordV(s), dy, eh));
}

void main() {
  const uint index = invocationIndex();
  if (index < uint(p.grid.width) * uint(p.grid.height)) upsampleKernel(index);
}
