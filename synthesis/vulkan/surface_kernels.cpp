// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6.
#include "synthesis/vulkan/surface_kernels.h"

#include "core/error.h"
#include "synthesis/vulkan/shaders/kernel_params.h"

#include <algorithm>
#include <string>

namespace texfab::synthesis::vulkan {

namespace {

constexpr uint32_t kInitSpirv[] =
#include "synthesis/vulkan/shaders/init_surface_kernel.spv.inc"
    ;
constexpr uint32_t kUpsampleSpirv[] =
#include "synthesis/vulkan/shaders/upsample_surface_kernel.spv.inc"
    ;
constexpr uint32_t kJitterSpirv[] =
#include "synthesis/vulkan/shaders/jitter_surface_kernel.spv.inc"
    ;
constexpr uint32_t kCorrectSpirv[] =
#include "synthesis/vulkan/shaders/correct_surface_kernel.spv.inc"
    ;

const Kernel kInit{"initSurfaceKernel", kInitSpirv, {1, 1, 1, 1}, sizeof(SurfaceParams)};
const Kernel kUpsample{"upsampleSurfaceKernel", kUpsampleSpirv, {1, 1, 1, 1, 1, 1}, sizeof(SurfaceParams)};
const Kernel kJitter{"jitterSurfaceKernel", kJitterSpirv, {1, 1, 1, 1}, sizeof(SurfaceParams)};
const Kernel kCorrect{"correctSurfaceKernel", kCorrectSpirv, {1, 1, 1, 1, 1, 1, 1, 1, 1}, sizeof(CorrectSurfaceParams)};

constexpr uint64_t kAlign = 256;  // binding offsets
constexpr uint64_t kWidestSite = 32;  // bytes per site of the widest array (neighbors)

uint64_t aligned(uint64_t bytes) { return (bytes + kAlign - 1) / kAlign * kAlign; }

// Calls fn(first, count) for windows of sites whose arrays each fit a binding; `first` is a
// multiple of 64 sites, so that every array's window starts at a multiple of 256 bytes.
template <class Fn> void forWindows(const Device& device, uint32_t sites, Fn&& fn) {
  const uint64_t window = std::max<uint64_t>(device.maxRangeBytes() / kWidestSite / 64 * 64, 64);
  for (uint64_t first = 0; first < sites; first += window)
    fn(uint32_t(first), uint32_t(std::min<uint64_t>(window, sites - first)));
}

// The window of array `offset` (`width` bytes per site) for sites [first, first + count).
Range window(const SurfaceSites& s, uint64_t offset, uint64_t width, uint32_t first, uint32_t count) {
  return Range(s.arrays, offset + first * width, count * width);
}

} // namespace

SurfaceSites uploadSites(Commands& commands, const SurfaceLevel& level) {
  SurfaceSites s;
  s.count = uint32_t(level.size());
  if (uint64_t(s.count) * 4 > commands.device().maxRangeBytes())
    throw Error("a surface level of " + std::to_string(s.count) + " sites exceeds the Vulkan device's storage-buffer range");
  const uint64_t words = aligned(uint64_t(s.count) * 4);
  s.y = words;
  s.chart = 2 * words;
  s.parent = 3 * words;
  s.jacobian = 4 * words;
  s.neighbors = s.jacobian + aligned(uint64_t(s.count) * 16);
  s.arrays = Buffer(commands.device(), s.neighbors + aligned(uint64_t(s.count) * kWidestSite));
  commands.upload(s.arrays, s.x, level.x.data(), s.count * 4);
  commands.upload(s.arrays, s.y, level.y.data(), s.count * 4);
  commands.upload(s.arrays, s.chart, level.chart.data(), s.count * 4);
  commands.upload(s.arrays, s.parent, level.parent.data(), s.count * 4);
  commands.upload(s.arrays, s.jacobian, level.jacobian.data(), s.count * 16);
  commands.upload(s.arrays, s.neighbors, level.neighbors.data(), s.count * kWidestSite);
  return s;
}

Buffer coordBuffer(Device& device, const SurfaceSites& sites) {
  return Buffer(device, std::max<uint64_t>(uint64_t(sites.count) * 4, 4));
}

void initSurfaceKernel(Commands& commands, const SurfaceSites& s, const Buffer& out, int ew, int eh,
                       const ValidRegion* clampTo) {
  forWindows(commands.device(), s.count, [&](uint32_t first, uint32_t count) {
    const SurfaceParams p{0, first, count, ew, eh, 0, 0, regionParams(clampTo), 0};
    commands.dispatch(kInit, p,
                      {window(s, s.x, 4, first, count), window(s, s.y, 4, first, count),
                       window(s, s.jacobian, 16, first, count), out},
                      count);
  });
}

void upsampleSurfaceKernel(Commands& commands, const SurfaceSites& s, const Buffer& parent, const Buffer& out, int ew,
                           int eh, const ValidRegion* clampTo) {
  forWindows(commands.device(), s.count, [&](uint32_t first, uint32_t count) {
    const SurfaceParams p{0, first, count, ew, eh, 0, 0, regionParams(clampTo), 0};
    commands.dispatch(kUpsample, p,
                      {window(s, s.x, 4, first, count), window(s, s.y, 4, first, count),
                       window(s, s.jacobian, 16, first, count), window(s, s.parent, 4, first, count), parent, out},
                      count);
  });
}

void jitterSurfaceKernel(Commands& commands, const SurfaceSites& s, const Buffer& coords, uint32_t seed, int atlasLevel,
                         int64_t amplitude256, int ew, int eh, const ValidRegion* clampTo) {
  if (amplitude256 == 0) return;
  forWindows(commands.device(), s.count, [&](uint32_t first, uint32_t count) {
    const SurfaceParams p{amplitude256, first, count, ew, eh, seed, atlasLevel, regionParams(clampTo), 0};
    commands.dispatch(kJitter, p,
                      {window(s, s.x, 4, first, count), window(s, s.y, 4, first, count),
                       window(s, s.chart, 4, first, count), coords},
                      count);
  });
}

void correctSurfaceKernel(Commands& commands, const SurfaceSites& s, const Buffer& in, const Buffer& out,
                          const LevelTables& t, int cls) {
  forWindows(commands.device(), s.count, [&](uint32_t first, uint32_t count) {
    const CorrectSurfaceParams p{first, count, cls, t.spacing, t.exemplarWidth, t.exemplarHeight, t.k, t.region};
    commands.dispatch(kCorrect, p,
                      {window(s, s.x, 4, first, count), window(s, s.y, 4, first, count),
                       window(s, s.jacobian, 16, first, count), window(s, s.neighbors, kWidestSite, first, count), in,
                       out, t.appearance, t.neighborhood, t.candidates},
                      count);
  });
}

} // namespace texfab::synthesis::vulkan
