// SPDX-License-Identifier: GPL-3.0-or-later
// upsampleSurfaceKernel (synthesis/cpu/surface_kernels.cpp), one site per invocation.
#version 460
#include "dispatch.glsl"
#include "surface.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SurfaceParams p; };
READ_WORDS(0, siteX);     // from site `first` on
READ_WORDS(1, siteY);
READ_WORDS(2, jacobian);
READ_WORDS(3, parent);
READ_WORDS(4, parentCoords);  // the whole parent level
WORDS(5, coords);             // the whole level

// S[s] = S_parent[parent(s)] + J(s) * ((x mod 2, y mod 2) - 1/2).
void upsampleSurfaceKernel(uint i) {
  float j[4];
  JACOBIAN_AT(jacobian, i, j);
  precise const float vx = float(int(siteX.words[i] & 1u)) - 0.5, vy = float(int(siteY.words[i] & 1u)) - 0.5;
  const ivec2 o = applyJ(j, vx, vy);
  coords.words[p.first + i] = shifted(parentCoords.words[parent.words[i]], o.x, o.y, p.exemplarWidth * kOne,
                                      p.exemplarHeight * kOne, p.region);
}

void main() {
  const uint i = invocationIndex();
  if (i < p.count) upsampleSurfaceKernel(i);
}
