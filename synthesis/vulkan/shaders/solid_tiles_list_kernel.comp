// SPDX-License-Identifier: GPL-3.0-or-later
// solidTilesListKernel: the triples of a list of voxels from a tile set, one voxel per invocation
// (solid_tiles.glsl).
#version 460
#include "dispatch.glsl"
#include "hash.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { TilesParams p; };  // the box fields unused
READ_WORDS(0, elements);  // 3 words (a triple) per element
READ_WORDS(1, voxels);    // 3 signed words (x, y, z) per listed voxel
WORDS(2, triples);        // 3 words per listed voxel

#include "solid_tiles.glsl"

void main() {
  const uint g = invocationIndex();
  if (g >= p.count) return;
  const uint e = tileElement(ivec3(voxels.words[3u * g], voxels.words[3u * g + 1u], voxels.words[3u * g + 2u]));
  for (uint k = 0u; k < 3u; ++k) triples.words[3u * g + k] = elements.words[3u * e + k];
}
