// SPDX-License-Identifier: GPL-3.0-or-later
// Every 2-D and surface kernel on a Vulkan device against its CPU twin, on random inputs, byte for
// byte, for a toroidal exemplar and for a non-toroidal one (a valid region); the surface kernels
// also through binding windows smaller than their arrays.
#include "synthesis/cpu/surface_kernels.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/vulkan/surface_kernels.h"
#include "synthesis/vulkan/synthesis_kernels.h"
#include "tests/vulkan/vulkan_test_support.h"

#include <gtest/gtest.h>

namespace texfab::synthesis {
namespace {

using test::Random;
using test::VulkanDevice;

// Random tables of an exemplar level.
struct HostTables {
  std::vector<int8_t> appearance, neighborhood;
  std::vector<uint32_t> candidates;
  cpu::LevelTables view;

  HostTables(Random& r, int w, int h, int spacing, int k)
      : appearance(r.values<int8_t>(size_t(w) * h * kAppearanceDims, -128, 127)),
        neighborhood(r.values<int8_t>(size_t(w) * h * kNeighborhoodDims, -128, 127)),
        candidates(r.coords(size_t(w) * h * k, w, h)),
        view{w, h, spacing, k, appearance.data(), neighborhood.data(), candidates.data()} {}
};

// A valid region of a w x h exemplar: any rectangle, sometimes one pixel wide or high.
ValidRegion randomRegion(Random& r, int w, int h) {
  const int x0 = int(r.between(0, w / 2)), y0 = int(r.between(0, h / 2));
  return {x0, y0, int(r.between(x0, w - 1)), int(r.between(y0, h - 1))};
}

// Grids far from the origin, with and without tiling periods; half of the rounds for an exemplar
// that does not tile (a random valid region).
TEST(VulkanKernels, TwoDimensionalKernelsEqualTheCpu) {
  VulkanDevice d;
  TEXFAB_REQUIRE_VULKAN(d);
  vulkan::Device& device = *d.device;
  Random r(11);
  for (int round = 0; round < 12; ++round) {
    const int ew = int(r.between(5, 70)), eh = int(r.between(5, 70)), spacing = 1 << r.between(0, 6);
    const cpu::LevelGrid grid{r.between(-(int64_t(1) << 40), int64_t(1) << 40), r.between(-1000, 1000),
                              int(r.between(8, 90)), int(r.between(8, 60))};
    const size_t n = size_t(grid.width) * size_t(grid.height);
    const int64_t periodX = round % 2 ? r.between(1, 300) : 0, periodY = round % 3 ? r.between(1, 300) : 0;
    const ValidRegion region = randomRegion(r, ew, eh);
    const ValidRegion* clampTo = round % 4 < 2 ? nullptr : &region;
    SCOPED_TRACE("round " + std::to_string(round) + (clampTo ? ", clamped" : ""));

    std::vector<uint32_t> cpuInit(n);
    cpu::initKernel(cpuInit.data(), grid, spacing, ew, eh, periodX, periodY, 0, grid.height, clampTo);
    const vulkan::Buffer init = vulkan::levelBuffer(device, grid);
    const cpu::LevelGrid parentGrid{cpu::floorShift(grid.x0, 1) - 1, cpu::floorShift(grid.y0, 1),
                                    grid.width / 2 + 3, grid.height / 2 + 2};
    const std::vector<uint32_t> parent = r.coords(size_t(parentGrid.width) * parentGrid.height, ew, eh);
    std::vector<uint32_t> cpuUp(n);
    cpu::upsampleKernel(parent.data(), parentGrid, cpuUp.data(), grid, spacing, ew, eh, 0, grid.height, clampTo);
    const int64_t amplitude = r.between(0, 256 * 64);
    std::vector<uint32_t> cpuJitter = cpuUp;
    cpu::jitterKernel(cpuJitter.data(), grid, 77, round, amplitude, periodX, periodY, ew, eh, 0, grid.height, clampTo);

    const int k = int(r.between(1, 4)), interleave = int(r.between(1, 3));
    const int cx = int(r.between(0, interleave - 1)), cy = int(r.between(0, interleave - 1));
    HostTables tables(r, ew, eh, spacing, k);
    tables.view.clampTo = clampTo;
    const std::vector<uint32_t> in = r.coords(n, ew, eh), before = r.coords(n, ew, eh);
    std::vector<uint32_t> cpuCorrect = before;
    const int ax0 = 1 + int(r.between(0, 3)), ax1 = grid.width - 1 - int(r.between(0, 3));
    const int ay0 = 1 + int(r.between(0, 3)), ay1 = grid.height - 1 - int(r.between(0, 3));
    cpu::correctKernel(in.data(), cpuCorrect.data(), grid, tables.view, interleave, cx, cy, ax0, ax1, ay0, ay1);

    vulkan::Commands commands(device);
    const vulkan::Buffer parentBuffer = commands.uploaded(std::span<const uint32_t>(parent));
    const vulkan::Buffer up = vulkan::levelBuffer(device, grid);
    const vulkan::Buffer inBuffer = commands.uploaded(std::span<const uint32_t>(in));
    const vulkan::Buffer out = commands.uploaded(std::span<const uint32_t>(before));
    const vulkan::LevelTables deviceTables = vulkan::uploadTables(commands, tables.view);
    vulkan::initKernel(commands, init, grid, spacing, ew, eh, periodX, periodY, clampTo);
    vulkan::upsampleKernel(commands, parentBuffer, parentGrid, up, grid, spacing, ew, eh, clampTo);
    std::vector<uint32_t> gpuInit(n), gpuUp(n), gpuJitter(n), gpuCorrect(n);
    commands.download(up, 0, gpuUp.data(), n * 4);
    vulkan::jitterKernel(commands, up, grid, 77, round, amplitude, periodX, periodY, ew, eh, clampTo);
    vulkan::correctKernel(commands, inBuffer, out, grid, deviceTables, interleave, cx, cy, ax0, ax1, ay0, ay1);
    commands.download(init, 0, gpuInit.data(), n * 4);
    commands.download(up, 0, gpuJitter.data(), n * 4);
    commands.download(out, 0, gpuCorrect.data(), n * 4);
    commands.submit();
    EXPECT_EQ(gpuInit, cpuInit);
    EXPECT_EQ(gpuUp, cpuUp);
    EXPECT_EQ(gpuJitter, cpuJitter);
    EXPECT_EQ(gpuCorrect, cpuCorrect);
  }
}

// A random level of an atlas pyramid: sites on a grid, Jacobians of every orientation and scale,
// neighbors anywhere (or none), parents in a coarser level of `parents` sites.
SurfaceLevel randomLevel(Random& r, size_t sites, size_t parents) {
  SurfaceLevel l;
  l.width = 300;
  l.height = 200;
  for (size_t s = 0; s < sites; ++s) {
    l.x.push_back(int32_t(r.between(0, l.width - 1)));
    l.y.push_back(int32_t(r.between(0, l.height - 1)));
    l.chart.push_back(int32_t(r.between(0, 40)));
    const float scale = r.real(0.2f, 6.0f), angle = r.real(-3.2f, 3.2f), shear = r.real(-0.5f, 0.5f);
    const float flip = r.between(0, 1) ? -1.0f : 1.0f;
    l.jacobian.push_back({scale * std::cos(angle), scale * (shear - std::sin(angle)), flip * scale * std::sin(angle),
                          flip * scale * std::cos(angle)});
    std::array<int32_t, 8> nb{};
    for (int32_t& n : nb) n = r.between(0, 9) == 0 ? -1 : int32_t(r.between(0, int64_t(sites) - 1));
    l.neighbors.push_back(nb);
    l.parent.push_back(int32_t(r.between(0, int64_t(parents) - 1)));
  }
  return l;
}

// With the device's binding range, and with a 64 KiB one: windows of 2048 sites; rounds 1 and 3 for
// an exemplar that does not tile (a random valid region).
TEST(VulkanKernels, SurfaceKernelsEqualTheCpu) {
  for (const uint64_t range : {uint64_t(0), uint64_t(65536)}) {
    VulkanDevice d({range});
    TEXFAB_REQUIRE_VULKAN(d);
    vulkan::Device& device = *d.device;
    Random r(23);
    for (int round = 0; round < 4; ++round) {
      const int ew = int(r.between(5, 40)), eh = int(r.between(5, 45)), spacing = 1 << r.between(0, 5);
      const size_t n = size_t(r.between(2500, 5000)), parents = 700;
      const ValidRegion region = randomRegion(r, ew, eh);
      const ValidRegion* clampTo = round % 2 ? &region : nullptr;
      SCOPED_TRACE("round " + std::to_string(round) + ", range " + std::to_string(range) +
                   (clampTo ? ", clamped" : ""));
      const SurfaceLevel level = randomLevel(r, n, parents);
      const std::vector<uint32_t> parent = r.coords(parents, ew, eh, 1 << kSubpixelBits);
      const std::vector<uint32_t> in = r.coords(n, ew, eh, 1 << kSubpixelBits);
      HostTables tables(r, ew, eh, spacing, int(r.between(1, 4)));
      tables.view.clampTo = clampTo;
      const int64_t amplitude = r.between(1, 256 * 32);
      const int cls = int(r.between(0, 3));

      std::vector<uint32_t> cpuInit(n), cpuUp(n), cpuCorrect(n);
      cpu::initSurfaceKernel(level, cpuInit.data(), ew, eh, 0, n, clampTo);
      cpu::upsampleSurfaceKernel(level, parent.data(), cpuUp.data(), ew, eh, 0, n, clampTo);
      std::vector<uint32_t> cpuJitter = cpuUp;
      cpu::jitterSurfaceKernel(level, cpuJitter.data(), 5, round, amplitude, ew, eh, 0, n, clampTo);
      cpu::correctSurfaceKernel(level, in.data(), cpuCorrect.data(), tables.view, cls, 0, n);

      vulkan::Commands commands(device);
      const vulkan::SurfaceSites sites = vulkan::uploadSites(commands, level);
      const vulkan::Buffer parentBuffer = commands.uploaded(std::span<const uint32_t>(parent));
      const vulkan::Buffer inBuffer = commands.uploaded(std::span<const uint32_t>(in));
      const vulkan::LevelTables deviceTables = vulkan::uploadTables(commands, tables.view);
      const vulkan::Buffer init = vulkan::coordBuffer(device, sites), up = vulkan::coordBuffer(device, sites),
                           out = vulkan::coordBuffer(device, sites);
      std::vector<uint32_t> gpuInit(n), gpuUp(n), gpuJitter(n), gpuCorrect(n);
      vulkan::initSurfaceKernel(commands, sites, init, ew, eh, clampTo);
      vulkan::upsampleSurfaceKernel(commands, sites, parentBuffer, up, ew, eh, clampTo);
      commands.download(up, 0, gpuUp.data(), n * 4);
      vulkan::jitterSurfaceKernel(commands, sites, up, 5, round, amplitude, ew, eh, clampTo);
      vulkan::correctSurfaceKernel(commands, sites, inBuffer, out, deviceTables, cls);
      commands.download(init, 0, gpuInit.data(), n * 4);
      commands.download(up, 0, gpuJitter.data(), n * 4);
      commands.download(out, 0, gpuCorrect.data(), n * 4);
      commands.submit();
      EXPECT_EQ(gpuInit, cpuInit);
      EXPECT_EQ(gpuUp, cpuUp);
      EXPECT_EQ(gpuJitter, cpuJitter);
      EXPECT_EQ(gpuCorrect, cpuCorrect);
    }
  }
}

} // namespace
} // namespace texfab::synthesis
