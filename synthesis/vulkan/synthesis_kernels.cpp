// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005, §3;
//           S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §4.
#include "synthesis/vulkan/synthesis_kernels.h"

#include "core/error.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/vulkan/shaders/kernel_params.h"

#include <span>
#include <string>

namespace texfab::synthesis::vulkan {

namespace {

constexpr uint32_t kInitSpirv[] =
#include "synthesis/vulkan/shaders/init_kernel.spv.inc"
    ;
constexpr uint32_t kUpsampleSpirv[] =
#include "synthesis/vulkan/shaders/upsample_kernel.spv.inc"
    ;
constexpr uint32_t kJitterSpirv[] =
#include "synthesis/vulkan/shaders/jitter_kernel.spv.inc"
    ;
constexpr uint32_t kCorrectSpirv[] =
#include "synthesis/vulkan/shaders/correct_kernel.spv.inc"
    ;

const Kernel kInit{"initKernel", kInitSpirv, {1}, sizeof(InitParams)};
const Kernel kUpsample{"upsampleKernel", kUpsampleSpirv, {1, 1}, sizeof(UpsampleParams)};
const Kernel kJitter{"jitterKernel", kJitterSpirv, {1}, sizeof(JitterParams)};
const Kernel kCorrect{"correctKernel", kCorrectSpirv, {1, 1, 1, 1, 1}, sizeof(CorrectParams)};

GridParams gridParams(const cpu::LevelGrid& g) { return {g.x0, g.y0, g.width, g.height}; }

uint64_t texels(const cpu::LevelGrid& g) { return uint64_t(g.width) * uint64_t(g.height); }

template <class T> Buffer table(Commands& commands, const T* values, size_t count, const char* what) {
  const uint64_t bytes = count * sizeof(T);
  if (bytes > commands.device().maxRangeBytes())
    throw Error(std::string("exemplar ") + what + " table (" + std::to_string(bytes >> 20) +
                " MiB) exceeds the Vulkan device's storage-buffer range");
  return commands.uploaded(std::span<const T>(values, count));
}

} // namespace

RegionParams regionParams(const ValidRegion* r) {
  return r ? RegionParams{1, r->x0, r->y0, r->x1, r->y1} : RegionParams{};
}

LevelTables uploadTables(Commands& commands, const cpu::LevelTables& t) {
  const size_t pixels = size_t(t.exemplarWidth) * size_t(t.exemplarHeight);
  LevelTables d;
  d.exemplarWidth = t.exemplarWidth;
  d.exemplarHeight = t.exemplarHeight;
  d.spacing = t.spacing;
  d.k = t.k;
  d.appearance = table(commands, t.appearance, pixels * kAppearanceDims, "appearance");
  d.neighborhood = table(commands, t.neighborhood, pixels * kNeighborhoodDims, "neighborhood");
  d.candidates = table(commands, t.candidates, pixels * size_t(t.k), "candidate");
  d.region = regionParams(t.clampTo);
  return d;
}

Buffer levelBuffer(Device& device, const cpu::LevelGrid& grid) {
  const uint64_t bytes = texels(grid) * 4;
  if (bytes > device.maxRangeBytes())
    throw Error("a synthesis level of " + std::to_string(grid.width) + "x" + std::to_string(grid.height) +
                " texels exceeds the Vulkan device's storage-buffer range");
  return Buffer(device, bytes);
}

void initKernel(Commands& commands, const Buffer& out, const cpu::LevelGrid& grid, int spacing, int exemplarWidth,
                int exemplarHeight, int64_t periodX, int64_t periodY, const ValidRegion* clampTo) {
  const InitParams p{gridParams(grid), periodX, periodY, spacing, exemplarWidth, exemplarHeight, regionParams(clampTo)};
  commands.dispatch(kInit, p, {out}, texels(grid));
}

void upsampleKernel(Commands& commands, const Buffer& parent, const cpu::LevelGrid& parentGrid, const Buffer& out,
                    const cpu::LevelGrid& grid, int spacing, int exemplarWidth, int exemplarHeight,
                    const ValidRegion* clampTo) {
  const UpsampleParams p{gridParams(grid), gridParams(parentGrid), spacing, exemplarWidth, exemplarHeight,
                         regionParams(clampTo)};
  commands.dispatch(kUpsample, p, {parent, out}, texels(grid));
}

void jitterKernel(Commands& commands, const Buffer& coords, const cpu::LevelGrid& grid, uint32_t seed, int level,
                  int64_t amplitude256, int64_t periodX, int64_t periodY, int exemplarWidth, int exemplarHeight,
                  const ValidRegion* clampTo) {
  if (amplitude256 == 0) return;
  const JitterParams p{gridParams(grid), amplitude256, periodX, periodY, seed, level, exemplarWidth, exemplarHeight,
                       regionParams(clampTo), 0};
  commands.dispatch(kJitter, p, {coords}, texels(grid));
}

void correctKernel(Commands& commands, const Buffer& in, const Buffer& out, const cpu::LevelGrid& grid,
                   const LevelTables& t, int interleave, int classX, int classY, int ax0, int ax1, int ay0, int ay1) {
  if (ax1 <= ax0 || ay1 <= ay0) return;
  const CorrectParams p{gridParams(grid), t.spacing, t.exemplarWidth, t.exemplarHeight, t.k, interleave, classX,
                        classY, ax0, ax1, ay0, ay1, t.region};
  commands.dispatch(kCorrect, p, {in, out, t.appearance, t.neighborhood, t.candidates},
                    uint64_t(ax1 - ax0) * uint64_t(ay1 - ay0));
}

} // namespace texfab::synthesis::vulkan
