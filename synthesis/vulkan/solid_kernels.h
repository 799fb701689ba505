// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The per-voxel kernels of lazy solid synthesis on a Vulkan device: each records one dispatch of
// the GLSL twin (shaders/<name>.comp) of the CPU kernel of the same name in
// synthesis/cpu/solid_kernels.h, and gives the same bytes. Where the CPU kernels read a dense grid,
// these read a set of 16^3 chunks of one level (the lazy engine's chunks) with each chunk's 27
// neighbours; the masks and their dilation stay on the CPU (solidDilateKernel).

#include "synthesis/cpu/solid_kernels.h"
#include "synthesis/solid_tiles.h"
#include "synthesis/vulkan/runtime.h"

#include <array>
#include <cstdint>
#include <span>

namespace texfab::synthesis::vulkan {

inline constexpr int kSolidChunkVoxels = 4096;  ///< 16^3

/// A byte range of a buffer.
struct Slice {
  uint64_t offset = 0;
  uint64_t bytes = 0;
};

/// What the solid kernels read about one level (cpu::SolidTables), on the device.
struct SolidTables {
  int exemplarWidth = 0, exemplarHeight = 0, spacing = 1;
  int dims = 0, k2d = 1, k2dStride = 1, k3d = 1;
  int shift2d = 0, shift3d = 0;
  int clampMargin = 0;
  Buffer data;
  std::array<Slice, 3> colors, candidates2d, candidateDescriptors2d, triples, descriptors3d;
  Slice projection;  ///< int32: offsets 2-D [8], offsets 3-D [16], basis 2-D [8][75], basis 3-D [dims][183]
  Slice searchColors;  ///< int32: [3][766], a voxel's colour record by channel and colour sum (cpu::colorOf)

  Range range(const Slice& s) const { return Range(data, s.offset, s.bytes); }
};

/// Uploads `tables` (their projections prepared). Throws Error when a table exceeds the device's
/// binding range.
SolidTables uploadSolidTables(Commands& commands, const cpu::SolidTables& tables);

/// Chunks of one level on the device. Chunk i: key (its level position / 16, 3 int32), mask
/// (`last`, 4096 int8, x fastest), the slots of its 27 neighbours (-1: absent; index (dz + 1) * 9 +
/// (dy + 1) * 3 + dx + 1, itself at 13) and, above the coarsest level, its parents' triples (the
/// 8^3 block of the parent level at its key, 3 words per voxel).
struct SolidChunks {
  uint32_t count = 0;
  Buffer keys, last, neighbours, parents;
  Buffer triples, colors;              ///< per voxel 3 words / 2 words (colour records as int16)
  Buffer corrected, correctedColors;   ///< a correction's output, until solidCommitKernel

  /// The most chunks one set may hold on `device` (its triples fit one binding).
  static uint32_t maxCount(const Device& device);
};

/// Uploads `count` chunks: keys (3 per chunk), last (4096 per chunk), neighbours (27 per chunk),
/// parents (3 * 512 per chunk, or empty at the coarsest level).
SolidChunks uploadChunks(Commands& commands, uint32_t count, std::span<const int32_t> keys, std::span<const int8_t> last,
                         std::span<const int32_t> neighbours, std::span<const uint32_t> parents);

void solidInitKernel(Commands& commands, const SolidChunks& chunks, const SolidTables& tables,
                     const cpu::SolidInit& init);

/// From `chunks.parents`.
void solidUpsampleKernel(Commands& commands, const SolidChunks& chunks, const SolidTables& tables);

void solidColorKernel(Commands& commands, const SolidChunks& chunks, const SolidTables& tables, int minLast);

/// Reads triples/colors, writes the voxels corrected at `step` to corrected/correctedColors.
/// `contrastGain16` as cpu::SolidTables::contrastGain16 (an option of the request, not of the tables).
void solidCorrectKernel(Commands& commands, const SolidChunks& chunks, const SolidTables& tables, int interleave,
                        int step, int contrastGain16);

/// Copies the voxels corrected at `step` from corrected/correctedColors to triples/colors.
void solidCommitKernel(Commands& commands, const SolidChunks& chunks, int interleave, int step);

/// `packed` (3 words per entry) = the triples of the `count` voxels listed in `listed` (chunk *
/// 4096 + local index): what a level's caller reads, without the rest of the chunks. No CPU twin.
void solidGatherKernel(Commands& commands, const SolidChunks& chunks, const Buffer& listed, uint32_t count,
                       const Buffer& packed);

/// The triples of every voxel of `box` (x fastest, then y, then z) read from `tiles` in the
/// arrangement of `seed`: the GLSL twin of evaluateSolidTilesBox (SolidTileReader), the same bytes,
/// one voxel per invocation, in slabs of whole z layers of at most `slabVoxels` voxels (and one
/// binding range). The tile set stays resident on the device under its key.
void evaluateSolidTilesBox(Device& device, const SolidTileSet& tiles, uint32_t seed, const VoxelBox& box,
                           std::span<Triple> out, const Context& ctx = {}, uint64_t slabVoxels = uint64_t(1) << 26);
/// The triples of `voxels` (|coordinates| <= kMaxSolidPosition), in order: the GLSL twin of
/// evaluateSolidTiles, one voxel per invocation, in batches of at most `batchVoxels`.
void evaluateSolidTiles(Device& device, const SolidTileSet& tiles, uint32_t seed, std::span<const Voxel> voxels,
                        std::span<Triple> out, const Context& ctx = {}, uint64_t batchVoxels = uint64_t(1) << 26);

} // namespace texfab::synthesis::vulkan
