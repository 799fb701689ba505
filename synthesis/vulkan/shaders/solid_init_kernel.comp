// SPDX-License-Identifier: GPL-3.0-or-later
// solidInitKernel (synthesis/cpu/solid_kernels.cpp), one voxel per invocation.
#version 460
#include "dispatch.glsl"
#include "hash.glsl"
#include "solid.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SolidParams p; };
READ_WORDS(0, keys);       // 3 int32 per chunk: its position / 16
READ_WORDS(1, last);       // int8 per voxel
READ_WORDS(2, slabTriples);  // E_z's triples: w * h * kSolidMaxCandidates * 3 packed coordinates
WORDS(3, triples);

// The random warp at level position q, added to disp (1/256 voxel): a sum of compactly supported
// bumps on two hashed grids.
void warp(const int64_t q[3], inout int64_t disp[3]) {
  const int kCells[2] = {4, 8};                 // warp grids, voxels
  const int64_t kAmplitude[2] = {384, 256};     // x jitter/256: stronger at the small scale (§5.1)
  for (int octave = 0; octave < 2; ++octave) {
    const int cell = kCells[octave];
    const int64_t amp = p.jitter256 * kAmplitude[octave] / 256;
    const int64_t radius2 = int64_t(cell * 256) * (cell * 256);
    int64_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = q[a] >= 0 ? q[a] / cell : -((-q[a] + cell - 1) / cell);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int cc[3] = {int(c[0] + dx), int(c[1] + dy), int(c[2] + dz)};
          const uint hc = voxelHash(p.seed, uint(octave), cc[0], cc[1], cc[2], 0u);
          const uint hd = pcgHash(hc);
          int64_t r2 = 0;
          int64_t dir[3];
          for (int a = 0; a < 3; ++a) {
            const int64_t frac = int64_t((hc >> (10 * a)) & 0x3ffu);
            const int64_t centre = int64_t(cc[a]) * cell * 256 + ((frac * cell * 256) >> 10);
            const int64_t d = q[a] * 256 - centre;
            r2 += d * d;
            dir[a] = int64_t((hd >> (9 * a)) & 0x1ffu) - 256;
          }
          if (r2 >= radius2) continue;
          const int64_t s = (radius2 - r2) * 65536 / radius2;
          const int64_t weight = (s * s) >> 16;
          for (int a = 0; a < 3; ++a) disp[a] += (amp * dir[a] * weight) >> 24;
        }
  }
}

// The hashed offset of the cell of side p.offsetCells holding q: exemplar pixels (u, v) and slab
// layers.
void cellOffset(const int64_t q[3], out int64_t offset[3]) {
  const int64_t cell = int64_t(p.offsetCells);
  int c[3];
  for (int a = 0; a < 3; ++a) c[a] = int((q[a] - floorMod(q[a], cell)) / cell);
  const uint hu = voxelHash(p.seed, 2u, c[0], c[1], c[2], 0u), hv = pcgHash(hu), hz = pcgHash(hv);
  offset[0] = int64_t(hu % uint(p.exemplarWidth));
  offset[1] = int64_t(hv % uint(p.exemplarHeight));
  offset[2] = int64_t(hz % 5u);
}

// A slab layer's coordinate c along one exemplar axis: wrapped, or reflected into the valid region
// [m, side - 1 - m].
uint layerCoord(int c, int side) {
  const int m = p.clampMargin;
  return uint(m == 0 ? floorMod(c, side) : reflectInto(c, m, side - 1 - m));
}

// The slab (§4.3) at warped position q, shifted by `offset`: the E_z pixel under (x, y), thickened
// along z by its best candidate's E_x and E_y neighborhoods.
void slabTriple(const int64_t q[3], const int64_t offset[3], uint g) {
  const int w = p.exemplarWidth, h = p.exemplarHeight;
  const uint pixel = wrapCoord(q[0] * p.spacing + offset[0], q[1] * p.spacing + offset[1], w, h);
  const int64_t dz = floorMod(q[2] + offset[2], int64_t(5)) - 2;
  const uint best = (coordV(pixel) * uint(w) + coordU(pixel)) * uint(kSolidMaxCandidates) * 3u;
  const uint b0 = slabTriples.words[best], b1 = slabTriples.words[best + 1u];
  triples.words[3u * g] = packCoord(coordU(b0), layerCoord(int(coordV(b0)) + int(dz) * p.spacing, h));
  triples.words[3u * g + 1u] = packCoord(layerCoord(int(coordU(b1)) + int(dz) * p.spacing, w), coordV(b1));
  triples.words[3u * g + 2u] = slabTriples.words[best + 2u];  // the pixel, or its reflection (clamp)
}

// Initialization (§5.1): the candidate slab tiled over the volume, read through the random warp,
// each cell of p.offsetCells voxels (if > 0) at its own offset.
void solidInitKernel(uint g) {
  const uint slot = g >> 12;
  const ivec3 l = localPosition(g);
  const int64_t q[3] = {int64_t(int(keys.words[3u * slot])) * 16 + l.x, int64_t(int(keys.words[3u * slot + 1u])) * 16 + l.y,
                        int64_t(int(keys.words[3u * slot + 2u])) * 16 + l.z};
  int64_t disp[3] = {0, 0, 0};  // 1/256 voxel
  if (p.jitter256 > 0) warp(q, disp);
  int64_t warped[3], offset[3] = {0, 0, 0};
  for (int a = 0; a < 3; ++a) warped[a] = q[a] + ((disp[a] + 128) >> 8);
  if (p.offsetCells > 0) cellOffset(warped, offset);
  slabTriple(warped, offset, g);
}

void main() {
  const uint g = invocationIndex();
  if (g < p.chunks * kChunkVoxels && INT8_AT(last, g) >= 0) solidInitKernel(g);
}
