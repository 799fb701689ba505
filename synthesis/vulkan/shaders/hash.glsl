// SPDX-License-Identifier: GPL-3.0-or-later
// Counter-based randomness: the GLSL twin of synthesis/hash.h (same operations on 32-bit words).
//
// Based on: M. Jarzynski, M. Olano. Hash Functions for GPU Rendering. JCGT 9(3), 2020 (PCG hash).
#ifndef TEXFAB_HASH_GLSL
#define TEXFAB_HASH_GLSL

uint pcgHash(uint v) {
  const uint state = v * 747796405u + 2891336453u;
  const uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

/// A uniformly distributed 32-bit value for one texel, one level and one purpose.
uint texelHash(uint seed, uint level, int x, int y, uint purpose) {
  return pcgHash(seed ^ pcgHash(level ^ pcgHash(uint(x) ^ pcgHash(uint(y) ^ pcgHash(purpose)))));
}

/// A 3-D variant of texelHash: one voxel of one level, for one purpose.
uint voxelHash(uint seed, uint level, int x, int y, int z, uint purpose) {
  return pcgHash(seed ^ pcgHash(level ^ pcgHash(uint(x) ^ pcgHash(uint(y) ^ pcgHash(uint(z) ^ pcgHash(purpose))))));
}

#endif
