// SPDX-License-Identifier: GPL-3.0-or-later
// initSurfaceKernel (synthesis/cpu/surface_kernels.cpp), one site per invocation.
#version 460
#include "dispatch.glsl"
#include "surface.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SurfaceParams p; };
READ_WORDS(0, siteX);     // from site `first` on
READ_WORDS(1, siteY);
READ_WORDS(2, jacobian);
WORDS(3, coords);         // the whole level

// S[s] = J(s) * (texel centre) mod exemplar size (non-toroidal: reflected into the valid region).
void initSurfaceKernel(uint i) {
  float j[4];
  JACOBIAN_AT(jacobian, i, j);
  precise const float cx = float(int(siteX.words[i])) + 0.5, cy = float(int(siteY.words[i])) + 0.5;
  const ivec2 o = applyJ(j, cx, cy);
  const int sw = p.exemplarWidth * kOne, sh = p.exemplarHeight * kOne;
  coords.words[p.first + i] = shifted(shifted(0u, o.x, o.y, sw, sh), 0, 0, sw, sh, p.region);
}

void main() {
  const uint i = invocationIndex();
  if (i < p.count) initSurfaceKernel(i);
}
