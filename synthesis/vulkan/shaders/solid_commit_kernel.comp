// SPDX-License-Identifier: GPL-3.0-or-later
// solidCommitKernel (synthesis/cpu/solid_kernels.cpp): copies the voxels corrected at `step`
// (triples and colours), one voxel per invocation.
#version 460
#include "dispatch.glsl"
#include "solid.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SolidParams p; };
READ_WORDS(0, last);  // int8 per voxel
READ_WORDS(1, fromTriples);
READ_WORDS(2, fromColors);
WORDS(3, toTriples);
WORDS(4, toColors);

void solidCommitKernel(uint g) {
  for (uint e = 0; e < 3; ++e) toTriples.words[3u * g + e] = fromTriples.words[3u * g + e];
  for (uint c = 0; c < 2; ++c) toColors.words[2u * g + c] = fromColors.words[2u * g + c];
}

void main() {
  const uint g = invocationIndex();
  if (g < p.chunks * kChunkVoxels && INT8_AT(last, g) >= p.step && inClass(g, p.step, p.interleave))
    solidCommitKernel(g);
}
