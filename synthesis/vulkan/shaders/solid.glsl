// SPDX-License-Identifier: GPL-3.0-or-later
// What the solid kernels share. They work on 16^3 chunks of one level (the lazy engine's chunks),
// one voxel per invocation: invocation g is voxel (g & 4095) of chunk slot (g >> 12), local
// position (x, y, z) = (g & 15, (g >> 4) & 15, g >> 8 & 15). Per voxel, a triples binding holds 3
// packed coordinates (word 3g) and a colours binding 2 words (2g: int16 c0 | c1 << 16, c2), the
// colour records of synthesis/cpu/solid_kernels.h. A chunk's 27 neighbours (itself at 13) are
// slots or -1 (`neighbours`, 27 words per slot, index (dz + 1) * 9 + (dy + 1) * 3 + dx + 1).
// Twin of the helpers of synthesis/cpu/solid_kernels.cpp and solid_search.h.
#ifndef TEXFAB_SOLID_GLSL
#define TEXFAB_SOLID_GLSL

#include "coord_map.glsl"

const int kAxisU[3] = {1, 2, 0};  // E_x (y, z), E_y (z, x), E_z (x, y)
const int kAxisV[3] = {2, 0, 1};
const int kSolidMaxCandidates = 12;
const int kSolid2dDims = 8;
const int kChunkVoxels = 4096;

ivec3 localPosition(uint g) { return ivec3(g & 15u, (g >> 4) & 15u, (g >> 8) & 15u); }

// Coordinates a few taps outside [0, m) (|offset| <= m): one compare instead of a division.
int64_t wrapNear(int64_t a, int64_t m) {
  if (a < 0) a += m;
  else if (a >= m) a -= m;
  return (a >= 0 && a < m) ? a : floorMod(a, m);
}

uint wrapCoord(int64_t u, int64_t v, int w, int h) { return packCoord(uint(wrapNear(u, w)), uint(wrapNear(v, h))); }

// The voxel of the 3x3x3 chunk neighbourhood at offset o (|o| <= 2 per axis) from local position l
// of chunk `slot`, as an invocation index; -1 when its chunk is absent. NEIGHBOURS is the binding.
#define SOLID_VOXEL_AT(NEIGHBOURS)                                                                  \
  int voxelAt(uint slot, ivec3 l, ivec3 o) {                                                        \
    const ivec3 q = l + o, c = q >> 4, m = q & 15;                                                  \
    const int n = int(NEIGHBOURS.words[slot * 27u + uint((c.z + 1) * 9 + (c.y + 1) * 3 + c.x + 1)]); \
    return n < 0 ? -1 : (n << 12) + (m.z << 8) + (m.y << 4) + m.x;                                  \
  }

// Whether voxel g is corrected at `step` with `interleave` (class (step-1) mod 8 of the parities;
// chunk origins are even, so the local parities are the level's).
bool inClass(uint g, int step, int interleave) {
  if (interleave == 1) return true;
  const int cls = (step - 1) % 8;
  const ivec3 l = localPosition(g);
  return (l.x & 1) == (cls & 1) && (l.y & 1) == ((cls >> 1) & 1) && (l.z & 1) == ((cls >> 2) & 1);
}

#endif
