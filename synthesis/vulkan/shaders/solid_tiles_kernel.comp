// SPDX-License-Identifier: GPL-3.0-or-later
// solidTilesKernel: the GLSL twin of SolidTileReader (synthesis/solid_tiles.cpp), one voxel of a
// box per invocation: the cell's variants from the placement hash, the voxel's storage element.
#version 460
#include "dispatch.glsl"
#include "hash.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { TilesParams p; };
READ_WORDS(0, elements);  // 3 words (a triple) per element
WORDS(1, triples);        // 3 words per voxel of the box

const uint kPlacementPurpose = 0x504c4345u;  // solid_tiles.cpp

// Placement: the variant of a face (kind 0..2), edge (3..5) or corner (6) of cell (x, y, z).
uint variantOf(int kind, int x, int y, int z) {
  const uint h = voxelHash(p.seed, kPlacementPurpose, x, y, z, uint(kind));
  return kind < 3 ? h % uint(p.variants) : h & 1u;
}

// SolidTileLayout::cellCode.
uint cellCode(int x, int y, int z) {
  const uint v = uint(p.variants);
  uint tile = 0u, weight = 1u;
  const ivec3 next[3] = {ivec3(x + 1, y, z), ivec3(x, y + 1, z), ivec3(x, y, z + 1)};
  for (int a = 0; a < 3; ++a) {
    tile += weight * variantOf(a, x, y, z);
    weight *= v;
    tile += weight * variantOf(a, next[a].x, next[a].y, next[a].z);
    weight *= v;
  }
  uint code = tile;
  for (int a = 0; a < 3; ++a) code |= variantOf(3 + a, x, y, z) << uint(10 + a);
  return code | (variantOf(6, x, y, z) << 13u);
}

// SolidTileLayout::element.
uint element(ivec3 l, uint code) {
  const uint m = uint((1 << p.shift) - 1), tile = code & 1023u;
  const int zeros = int(l.x == 0) + int(l.y == 0) + int(l.z == 0);
  if (zeros == 0) return p.interiors + ((tile * m + uint(l.z - 1)) * m + uint(l.y - 1)) * m + uint(l.x - 1);
  if (zeros == 1) {
    const int a = l.x == 0 ? 0 : l.y == 0 ? 1 : 2, b = (a + 1) % 3, c = (a + 2) % 3;
    uint digit = tile;
    for (int i = 0; i < 2 * a; ++i) digit /= uint(p.variants);
    const uint face = uint(a) * uint(p.variants) + digit % uint(p.variants);
    return p.faces + (face * m + uint(l[c] - 1)) * m + uint(l[b] - 1);
  }
  if (zeros == 2) {
    const int a = l.x != 0 ? 0 : l.y != 0 ? 1 : 2;
    const uint edge = uint(a) * 2u + ((code >> uint(10 + a)) & 1u);
    return 2u + edge * m + uint(l[a] - 1);
  }
  return (code >> 13u) & 1u;
}

void main() {
  const uint g = invocationIndex();
  if (g >= p.count) return;
  const uint row = g / uint(p.nx);
  const ivec3 v = ivec3(p.x0 + int(g % uint(p.nx)), p.y0 + int(row % uint(p.ny)), p.z0 + int(row / uint(p.ny)));
  const ivec3 cell = v >> p.shift;  // arithmetic: floor for negative voxels
  const uint e = element(v & ((1 << p.shift) - 1), cellCode(cell.x, cell.y, cell.z));
  for (uint k = 0u; k < 3u; ++k) triples.words[3u * g + k] = elements.words[3u * e + k];
}
