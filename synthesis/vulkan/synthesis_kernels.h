// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The per-texel kernels of parallel synthesis on a Vulkan device: each records one dispatch of the
// GLSL twin (shaders/<name>.comp) of the CPU kernel of the same name in
// synthesis/cpu/synthesis_kernels.h, over the whole buffer rather than a range of rows, and gives
// the same bytes. Level buffers hold grid.width * grid.height packed coordinates and must fit one
// binding (Device::maxRangeBytes). As there, `clampTo` (a non-toroidal exemplar's valid region at
// the level; null: the exemplar tiles) keeps coordinates inside the region instead of wrapping.

#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/vulkan/runtime.h"
#include "synthesis/vulkan/shaders/kernel_params.h"

#include <cstdint>

namespace texfab::synthesis::vulkan {

/// What the correction kernels read about one exemplar level (cpu::LevelTables), on the device.
struct LevelTables {
  int exemplarWidth = 0;
  int exemplarHeight = 0;
  int spacing = 1;
  int k = 1;
  Buffer appearance;    ///< 8 int8 per exemplar pixel
  Buffer neighborhood;  ///< 32 int8 per exemplar pixel
  Buffer candidates;    ///< k packed coordinates per exemplar pixel
  RegionParams region{};  ///< the level's valid region (clamp 0: the exemplar tiles)
};

/// The push-constant form of `clampTo` (clamp 0 when null).
RegionParams regionParams(const ValidRegion* clampTo);

/// Uploads `tables`. Throws Error when a table exceeds the device's binding range.
LevelTables uploadTables(Commands& commands, const cpu::LevelTables& tables);

/// A buffer for the packed coordinates of `grid`. Throws Error when it exceeds a binding range.
Buffer levelBuffer(Device& device, const cpu::LevelGrid& grid);

void initKernel(Commands& commands, const Buffer& out, const cpu::LevelGrid& grid, int spacing, int exemplarWidth,
                int exemplarHeight, int64_t periodX, int64_t periodY, const ValidRegion* clampTo = nullptr);

void upsampleKernel(Commands& commands, const Buffer& parent, const cpu::LevelGrid& parentGrid, const Buffer& out,
                    const cpu::LevelGrid& grid, int spacing, int exemplarWidth, int exemplarHeight,
                    const ValidRegion* clampTo = nullptr);

void jitterKernel(Commands& commands, const Buffer& coords, const cpu::LevelGrid& grid, uint32_t seed, int level,
                  int64_t amplitude256, int64_t periodX, int64_t periodY, int exemplarWidth, int exemplarHeight,
                  const ValidRegion* clampTo = nullptr);

/// One correction sub-pass over the buffer rectangle [ax0, ax1) x [ay0, ay1) (rows ay0..ay1 of the
/// CPU kernel); texels of `out` outside it are left as they are.
void correctKernel(Commands& commands, const Buffer& in, const Buffer& out, const cpu::LevelGrid& grid,
                   const LevelTables& tables, int interleave, int classX, int classY, int ax0, int ax1, int ay0,
                   int ay1);

} // namespace texfab::synthesis::vulkan
