// SPDX-License-Identifier: GPL-3.0-or-later
// The GLSL twin of SolidTileReader (synthesis/solid_tiles.cpp): the storage element of a voxel of
// the tile arrangement of p.seed. Needs a push constant `p` of TilesParams and hash.glsl.
#ifndef TEXFAB_SOLID_TILES_GLSL
#define TEXFAB_SOLID_TILES_GLSL

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

// The storage element of voxel v.
uint tileElement(ivec3 v) {
  const ivec3 cell = v >> p.shift;  // arithmetic: floor for negative voxels
  return element(v & ((1 << p.shift) - 1), cellCode(cell.x, cell.y, cell.z));
}

// The cells a box (p.x0, p.y0, p.z0) + (p.nx, p.ny, p.nz) touches: the first, and how many per axis.
ivec3 firstCell() { return ivec3(p.x0, p.y0, p.z0) >> p.shift; }
ivec3 cellCounts() { return ((ivec3(p.x0, p.y0, p.z0) + ivec3(p.nx, p.ny, p.nz) - 1) >> p.shift) - firstCell() + 1; }

#endif
