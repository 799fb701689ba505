// SPDX-License-Identifier: GPL-3.0-or-later
// solidTilesKernel: the triples of a box of voxels from a tile set, one voxel per invocation, x
// fastest, with the codes of its cells from solidTilesCellsKernel (solid_tiles.glsl).
#version 460
#include "dispatch.glsl"
#include "hash.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { TilesParams p; };
READ_WORDS(0, elements);  // 3 words (a triple) per element
READ_WORDS(1, codes);     // one word per cell the box touches, x fastest
WORDS(2, triples);        // 3 words per voxel of the box

#include "solid_tiles.glsl"

void main() {
  const uint g = invocationIndex();
  if (g >= p.count) return;
  const uint row = g / uint(p.nx);
  const ivec3 v = ivec3(p.x0 + int(g % uint(p.nx)), p.y0 + int(row % uint(p.ny)), p.z0 + int(row / uint(p.ny)));
  const ivec3 n = cellCounts(), c = (v >> p.shift) - firstCell();
  const uint code = codes.words[(uint(c.z) * uint(n.y) + uint(c.y)) * uint(n.x) + uint(c.x)];
  const uint e = element(v & ((1 << p.shift) - 1), code);
  for (uint k = 0u; k < 3u; ++k) triples.words[3u * g + k] = elements.words[3u * e + k];
}
