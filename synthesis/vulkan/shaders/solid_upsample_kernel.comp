// SPDX-License-Identifier: GPL-3.0-or-later
// solidUpsampleKernel (synthesis/cpu/solid_kernels.cpp), one voxel per invocation.
#version 460
#include "dispatch.glsl"
#include "solid.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SolidParams p; };
READ_WORDS(0, last);     // int8 per voxel
READ_WORDS(1, parents);  // per chunk, the 8^3 triples of its parents (the parent level's block)
WORDS(2, triples);

// Coordinate inheritance with a stack (§5.1, errata §20.2): the parent's triple plus
// spacing * (bits of the voxel along each exemplar's u and v axes).
void solidUpsampleKernel(uint g) {
  const ivec3 l = localPosition(g);
  const int q[3] = {l.x, l.y, l.z};  // the parities of the level position
  const uint parent = (g >> 12) * 512u + uint(((l.z >> 1) * 8 + (l.y >> 1)) * 8 + (l.x >> 1));
  for (int e = 0; e < 3; ++e) {
    const uint s = parents.words[parent * 3u + uint(e)];
    triples.words[3u * g + uint(e)] = wrapCoord(int64_t(coordU(s)) + p.spacing * (q[kAxisU[e]] & 1),
                                                int64_t(coordV(s)) + p.spacing * (q[kAxisV[e]] & 1),
                                                p.exemplarWidth, p.exemplarHeight);
  }
}

void main() {
  const uint g = invocationIndex();
  if (g < p.chunks * kChunkVoxels && INT8_AT(last, g) >= 0) solidUpsampleKernel(g);
}
