// SPDX-License-Identifier: GPL-3.0-or-later
// jitterSurfaceKernel (synthesis/cpu/surface_kernels.cpp), one site per invocation, in place.
#version 460
#include "dispatch.glsl"
#include "hash.glsl"
#include "surface.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SurfaceParams p; };
READ_WORDS(0, siteX);  // from site `first` on
READ_WORDS(1, siteY);
READ_WORDS(2, chart);
WORDS(3, coords);      // the whole level

// As jitterKernel, hashed on (seed, chart, level, x, y).
void jitterSurfaceKernel(uint i) {
  const uint chartSeed = p.seed ^ pcgHash(chart.words[i] + 0x9e3779b9u);
  const int x = int(siteX.words[i]), y = int(siteY.words[i]);
  const int64_t hx = int64_t(texelHash(chartSeed, uint(p.atlasLevel), x, y, 0u) >> 16) - 32768;
  const int64_t hy = int64_t(texelHash(chartSeed, uint(p.atlasLevel), x, y, 1u) >> 16) - 32768;
  const int64_t jx = (p.amplitude256 * kOne * hx + (int64_t(1) << 22)) >> 23;  // subpixels
  const int64_t jy = (p.amplitude256 * kOne * hy + (int64_t(1) << 22)) >> 23;
  const uint s = p.first + i;
  coords.words[s] = shifted(coords.words[s], int(jx), int(jy), p.exemplarWidth * kOne,
                            p.exemplarHeight * kOne, p.region);
}

void main() {
  const uint i = invocationIndex();
  if (p.amplitude256 != 0 && i < p.count) jitterSurfaceKernel(i);
}
