// SPDX-License-Identifier: GPL-3.0-or-later
// solidTilesCellsKernel: the code (SolidTileLayout::cellCode) of every cell a box touches, x
// fastest, one cell per invocation, for solidTilesKernel to read: its voxels then hash nothing.
#version 460
#include "dispatch.glsl"
#include "hash.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { TilesParams p; };  // count: the cells
WORDS(0, codes);  // one word per cell

#include "solid_tiles.glsl"

void main() {
  const uint g = invocationIndex();
  if (g >= p.count) return;
  const ivec3 n = cellCounts();
  const uint row = g / uint(n.x);
  const ivec3 c = firstCell() + ivec3(int(g % uint(n.x)), int(row % uint(n.y)), int(row / uint(n.y)));
  codes.words[g] = cellCode(c.x, c.y, c.z);
}
