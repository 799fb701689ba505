// SPDX-License-Identifier: GPL-3.0-or-later
// solidColorKernel (synthesis/cpu/solid_kernels.cpp), one voxel per invocation.
#version 460
#include "dispatch.glsl"
#include "solid.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SolidParams p; };
READ_WORDS(0, last);     // int8 per voxel
READ_WORDS(1, triples);
WORDS(2, colors);
READ_WORD_ARRAYS(3, exemplarColors, 3);  // per exemplar: w * h * 3 bytes

// The colour record of a triple: 2 x the sum of its three exemplar colours (R, G, B), then 0.
void solidColorKernel(uint g) {
  int c[3] = {0, 0, 0};
  for (int e = 0; e < 3; ++e) {
    const uint s = triples.words[3u * g + uint(e)];
    const uint at = (coordV(s) * uint(p.exemplarWidth) + coordU(s)) * 3u;
    for (uint ch = 0; ch < 3; ++ch) c[ch] += 2 * int(UINT8_AT(exemplarColors[e], at + ch));
  }
  colors.words[2u * g] = uint(c[0]) | (uint(c[1]) << 16);
  colors.words[2u * g + 1u] = uint(c[2]);
}

void main() {
  const uint g = invocationIndex();
  if (g < p.chunks * kChunkVoxels && INT8_AT(last, g) >= p.minLast) solidColorKernel(g);
}
