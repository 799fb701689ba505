// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// One level of lazy solid synthesis on a Vulkan device, as the engine (synthesize_solid.cpp) hands
// it over once the level's masks are known: the device initializes or upsamples every needed voxel,
// then runs the correction steps (solid kernels, solid_kernels.h), and the engine receives the
// final triples chunk by chunk. The masks, their dilation, the parents' blocks and the coarse-level
// cache stay on the CPU.
//
// A level whose chunks do not fit one binding (SolidChunks::maxCount) is computed in parts, each
// with a halo of chunks around it deep enough for its correction steps (2 voxels per step), which
// are computed again by the neighbouring part: a voxel's value does not depend on the part.

#include "core/context.h"
#include "synthesis/chunk_index.h"
#include "synthesis/cpu/solid_kernels.h"
#include "synthesis/vulkan/runtime.h"

#include <cstdint>
#include <functional>

namespace texfab::synthesis::vulkan {

struct SolidLevelInput {
  const ChunkIndex* chunks = nullptr;  ///< the level's 16^3 chunks (position / 16), slots as the engine's
  std::function<const int8_t*(uint32_t slot)> last;         ///< a chunk's mask, 4096 values
  std::function<const uint32_t*(uint32_t slot)> parents;    ///< its parents' 8^3 triples; empty at the coarsest level
  uint64_t tablesKey = 0;  ///< a key of the level's tables' content: kept on the device between requests (0: not kept)
  int steps = 0;        ///< correction steps T
  int interleave = 1;
  cpu::SolidInit init;  ///< initialization (coarsest level)
};

/// Receives the final triples of chunk `slot` (4096 * 3 words, of which only those of its voxels
/// with last = steps are set); called from several threads at once.
using SolidChunkSink = std::function<void(uint32_t slot, const uint32_t* triples)>;

/// Synthesizes the level: every chunk holding a voxel with last = steps goes to `finish`.
void synthesizeSolidLevel(Device& device, const cpu::SolidTables& tables, const SolidLevelInput& level,
                          const SolidChunkSink& finish, const Context& ctx);

} // namespace texfab::synthesis::vulkan
