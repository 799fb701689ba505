// SPDX-License-Identifier: GPL-3.0-or-later
// solidGatherKernel: the triples of the listed voxels, packed, so that a level hands back to the
// host only the values it reads (a thin request's voxels fill a few layers of each chunk). No CPU
// twin: the CPU engine reads its chunks in place.
#version 460
#include "dispatch.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { GatherParams p; };
READ_WORDS(0, listed);   // voxel index in the chunk set (chunk * 4096 + local)
READ_WORDS(1, triples);  // 3 words per voxel of the chunk set
WORDS(2, packed);        // 3 words per listed voxel

void main() {
  const uint i = invocationIndex();
  if (i >= p.count) return;
  const uint g = listed.words[i];
  for (uint e = 0; e < 3; ++e) packed.words[3u * i + e] = triples.words[3u * g + e];
}
