// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The per-site kernels of synthesis in an atlas on a Vulkan device: each records the dispatches of
// the GLSL twin (shaders/<name>.comp) of the CPU kernel of the same name in
// synthesis/cpu/surface_kernels.h over all sites of a level, and gives the same bytes. A level's
// per-site arrays are read through windows of sites, each within a binding's range; its
// coordinate buffers (one word per site) must fit one binding. `clampTo` (and LevelTables::region)
// as there: a non-toroidal exemplar's valid region at the level, null when it tiles.

#include "synthesis/synthesize_surface.h"
#include "synthesis/vulkan/runtime.h"
#include "synthesis/vulkan/synthesis_kernels.h"

#include <cstdint>

namespace texfab::synthesis::vulkan {

/// A SurfaceLevel's per-site arrays on the device.
struct SurfaceSites {
  uint32_t count = 0;
  Buffer arrays;  ///< x, y, chart, parent (1 word per site), jacobian (4), neighbors (8)
  uint64_t x = 0, y = 0, chart = 0, parent = 0, jacobian = 0, neighbors = 0;  ///< byte offsets
};

/// Uploads `level`. Throws Error when its coordinates would exceed a binding's range.
SurfaceSites uploadSites(Commands& commands, const SurfaceLevel& level);

/// A buffer for one coordinate per site of `sites`.
Buffer coordBuffer(Device& device, const SurfaceSites& sites);

void initSurfaceKernel(Commands& commands, const SurfaceSites& sites, const Buffer& out, int exemplarWidth,
                       int exemplarHeight, const ValidRegion* clampTo = nullptr);

void upsampleSurfaceKernel(Commands& commands, const SurfaceSites& sites, const Buffer& parent, const Buffer& out,
                           int exemplarWidth, int exemplarHeight, const ValidRegion* clampTo = nullptr);

void jitterSurfaceKernel(Commands& commands, const SurfaceSites& sites, const Buffer& coords, uint32_t seed,
                         int atlasLevel, int64_t amplitude256, int exemplarWidth, int exemplarHeight,
                         const ValidRegion* clampTo = nullptr);

void correctSurfaceKernel(Commands& commands, const SurfaceSites& sites, const Buffer& in, const Buffer& out,
                          const LevelTables& tables, int cls);

} // namespace texfab::synthesis::vulkan
