// SPDX-License-Identifier: GPL-3.0-or-later
// solidCorrectKernel (synthesis/cpu/solid_kernels.cpp): the two-step search of §5.1 for the voxels
// of correction sub-pass `step`, one voxel per invocation; writes only those voxels.
#version 460
#include "dispatch.glsl"
#include "solid.glsl"
#include "kernel_params.h"

layout(push_constant) uniform Push { SolidParams p; };
READ_WORDS(0, last);        // int8 per voxel
READ_WORDS(1, neighbours);  // 27 slots per chunk
READ_WORDS(2, inTriples);
READ_WORDS(3, inColors);
WORDS(4, outTriples);
WORDS(5, outColors);
READ_WORD_ARRAYS(6, exemplarColors, 3);          // per exemplar: w * h * 3 bytes
READ_WORD_ARRAYS(7, candidates2d, 3);            // per exemplar: w * h * k2dStride packed coordinates
READ_WORD_ARRAYS(8, candidateDescriptors2d, 3);  // per exemplar: w * h * k2dStride * 8 int8
READ_WORD_ARRAYS(9, candidateTriples, 3);        // per exemplar: w * h * 12 * 3 packed coordinates
READ_WORD_ARRAYS(10, descriptors3d, 3);          // per exemplar: w * h * 12 * dims int8
READ_WORDS(11, projection);  // int32: offsets 2-D [8], offsets 3-D [16], basis 2-D [8][75], basis 3-D [dims][183]
READ_WORDS(12, searchColors);  // int32 [3][kSolidColorSums]: the colour record by colour sum

const int kOffsets3d = 8, kBasis2d = 24, kBasis3d = 24 + 8 * 75;

SOLID_VOXEL_AT(neighbours)

// The colour record (3 int16) of voxel v; zeros when its chunk is absent (never read by a voxel
// whose mask is complete).
ivec3 colorAt(int v) {
  if (v < 0) return ivec3(0);
  const uint a = inColors.words[2u * uint(v)], b = inColors.words[2u * uint(v) + 1u];
  return ivec3(bitfieldExtract(int(a), 0, 16), bitfieldExtract(int(a), 16, 16), bitfieldExtract(int(b), 0, 16));
}

int clampProjected(int sum, int offset, int shift) { return clamp((sum + offset) >> shift, -127, 127); }

// Voxel (a, b) of plane `plane` of the 3-neighborhood: its offset, and false when an earlier plane
// holds it. Planes in the order of solidCrossOffsets: (x, y), (z, x), (y, z): 61 voxels in all.
bool crossOffset(int plane, int a, int b, out ivec3 o) {
  o = plane == 0 ? ivec3(b, a, 0) : plane == 1 ? ivec3(a, 0, b) : ivec3(0, b, a);
  return !((plane == 1 && b == 0) || (plane == 2 && (a == 0 || b == 0)));
}

// cpu::applyContrastGain: the records the search sees, moved away from the 3-neighborhood's mean.
ivec3 gained(ivec3 c, ivec3 mean) {
  if (p.contrastGain16 == 16) return c;
  return clamp(mean + (((c - mean) * p.contrastGain16) >> 4), ivec3(0), ivec3(kSolidColorSums * 2 - 2));
}

ivec3 crossMean(uint slot, ivec3 l) {
  if (p.contrastGain16 == 16) return ivec3(0);
  ivec3 sum = ivec3(0);
  for (int plane = 0; plane < 3; ++plane)
    for (int a = -2; a <= 2; ++a)
      for (int b = -2; b <= 2; ++b) {
        ivec3 o;
        if (crossOffset(plane, a, b, o)) sum += colorAt(voxelAt(slot, l, o));
      }
  return (sum + 30) / 61;
}

// The projected 3-neighborhood (target3d) and its three projected planes (target2d, E_x, E_y,
// E_z), each as int8 in words. Inputs are the colour records' channels in the order of
// solidCrossOffsets: the (x, y) plane, the (z, x) plane off the x axis, the (y, z) plane off both.
void projectTargets(uint g, out uint target3d[4], out uint target2d[3][2]) {
  const uint slot = g >> 12;
  const ivec3 l = localPosition(g);
  const ivec3 mean = crossMean(slot, l);
  int sum[16];
  for (int d = 0; d < 16; ++d) sum[d] = 0;
  int i = 0;
  for (int plane = 0; plane < 3; ++plane)
    for (int a = -2; a <= 2; ++a)
      for (int b = -2; b <= 2; ++b) {
        ivec3 o;
        if (!crossOffset(plane, a, b, o)) continue;
        const ivec3 c = gained(colorAt(voxelAt(slot, l, o)), mean);
        for (int d = 0; d < p.dims; ++d) {
          const uint row = uint(kBasis3d + d * 183 + 3 * i);
          sum[d] += int(projection.words[row]) * c.x + int(projection.words[row + 1u]) * c.y +
                    int(projection.words[row + 2u]) * c.z;
        }
        ++i;
      }
  for (int k = 0; k < 4; ++k) target3d[k] = 0u;
  for (int d = 0; d < p.dims; ++d)
    target3d[d >> 2] = bitfieldInsert(target3d[d >> 2], uint(clampProjected(sum[d], int(projection.words[kOffsets3d + d]), p.shift3d)), (d & 3) * 8, 8);

  for (int e = 0; e < 3; ++e) {
    for (int d = 0; d < 8; ++d) sum[d] = 0;
    for (int k = 0; k < 25; ++k) {
      ivec3 o = ivec3(0);
      o[kAxisU[e]] = k % 5 - 2;
      o[kAxisV[e]] = k / 5 - 2;
      const ivec3 c = gained(colorAt(voxelAt(slot, l, o)), mean);
      for (int d = 0; d < 8; ++d) {
        const uint row = uint(kBasis2d + d * 75 + 3 * k);
        sum[d] += int(projection.words[row]) * c.x + int(projection.words[row + 1u]) * c.y +
                  int(projection.words[row + 2u]) * c.z;
      }
    }
    target2d[e][0] = target2d[e][1] = 0u;
    for (int d = 0; d < 8; ++d)
      target2d[e][d >> 2] = bitfieldInsert(target2d[e][d >> 2], uint(clampProjected(sum[d], int(projection.words[d]), p.shift2d)), (d & 3) * 8, 8);
  }
}

// Keys (ssd, tie-break) compared as pairs: the lesser wins.
bool less(int ssd, uint tie, int bestSsd, uint bestTie) { return ssd < bestSsd || (ssd == bestSsd && tie < bestTie); }

// Step 1 in direction e: the pixel (v * w + u) of the best of the k2d 2-D candidates of the 9
// pixels C(S[v + P d] - d), d the 3x3 plane neighbours (§5.1).
uint nearest2d(uint g, int e, const uint target[2]) {
  const uint slot = g >> 12, w = uint(p.exemplarWidth), h = uint(p.exemplarHeight);
  const ivec3 l = localPosition(g);
  int bestSsd = 0x7fffffff;
  uint best = 0xffffffffu;
  for (int j = -1; j <= 1; ++j)
    for (int i = -1; i <= 1; ++i) {
      ivec3 o = ivec3(0);
      o[kAxisU[e]] = i;
      o[kAxisV[e]] = j;
      const int v = voxelAt(slot, l, o);
      const uint q = v < 0 ? 0u : inTriples.words[3u * uint(v) + uint(e)];
      const uint bu = coordU(q) + uint(floorMod(-i * p.spacing, p.exemplarWidth));
      const uint bv = coordV(q) + uint(floorMod(-j * p.spacing, p.exemplarHeight));
      const uint base = ((bv >= h ? bv - h : bv) * w + (bu >= w ? bu - w : bu)) * uint(p.k2dStride);
      for (uint k = 0; k < uint(p.k2d); ++k) {
        const uint c = candidates2d[e].words[base + k], at = (base + k) * 2u;
        const int ssd = ssd4(target[0], candidateDescriptors2d[e].words[at]) +
                        ssd4(target[1], candidateDescriptors2d[e].words[at + 1u]);
        if (less(ssd, c, bestSsd, best)) bestSsd = ssd, best = c;
      }
    }
  return coordV(best) * w + coordU(best);
}

// Step 2: the rank e * 12 + k of the best of the k3d 3-D candidates of the three pixels.
uint nearest3d(const uint pixels[3], const uint target[4]) {
  int bestSsd = 0x7fffffff;
  uint best = 0xffffffffu;
  for (int e = 0; e < 3; ++e)
    for (int k = 0; k < p.k3d; ++k) {
      const uint at = (pixels[e] * uint(kSolidMaxCandidates) + uint(k)) * uint(p.dims);
      int ssd = 0;
      for (int d = 0; d < p.dims; ++d) {
        const int diff = bitfieldExtract(int(target[d >> 2]), (d & 3) * 8, 8) - INT8_AT(descriptors3d[e], at + uint(d));
        ssd += diff * diff;
      }
      if (less(ssd, uint(e * kSolidMaxCandidates + k), bestSsd, best)) bestSsd = ssd, best = uint(e * kSolidMaxCandidates + k);
    }
  return best;
}

// Word i of exemplar e's candidate triples, e per invocation: constant indices into the binding
// array (devices need not index descriptor arrays non-uniformly).
uint candidateTripleWord(uint e, uint i) {
  return e == 0u ? candidateTriples[0].words[i] : e == 1u ? candidateTriples[1].words[i] : candidateTriples[2].words[i];
}

void solidCorrectKernel(uint g) {
  uint target3d[4], target2d[3][2], pixels[3];
  projectTargets(g, target3d, target2d);
  for (int e = 0; e < 3; ++e) pixels[e] = nearest2d(g, e, target2d[e]);
  const uint rank = nearest3d(pixels, target3d);
  const uint e = rank / uint(kSolidMaxCandidates), k = rank % uint(kSolidMaxCandidates);
  const uint at = (pixels[e] * uint(kSolidMaxCandidates) + k) * 3u;
  int c[3] = {0, 0, 0};
  for (uint x = 0; x < 3; ++x) {
    const uint s = candidateTripleWord(e, at + x);
    outTriples.words[3u * g + x] = s;
    const uint pixel = (coordV(s) * uint(p.exemplarWidth) + coordU(s)) * 3u;
    for (uint ch = 0; ch < 3; ++ch) c[ch] += int(UINT8_AT(exemplarColors[x], pixel + ch));
  }
  for (int ch = 0; ch < 3; ++ch) c[ch] = int(searchColors.words[ch * kSolidColorSums + c[ch]]);
  outColors.words[2u * g] = uint(c[0]) | (uint(c[1]) << 16);
  outColors.words[2u * g + 1u] = uint(c[2]);
}

void main() {
  const uint g = invocationIndex();
  if (g < p.chunks * kChunkVoxels && INT8_AT(last, g) >= p.step && inClass(g, p.step, p.interleave))
    solidCorrectKernel(g);
}
