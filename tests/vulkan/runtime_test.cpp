// SPDX-License-Identifier: GPL-3.0-or-later
// The Vulkan runtime's memory: released buffers serve later ones of their size class (a request
// creates tens of buffers, and creating device memory costs ~1 ms each on a GPU), downloads by
// regions land where asked, and data kept resident is made once per key.
#include "synthesis/vulkan/runtime.h"
#include "tests/vulkan/vulkan_test_support.h"

#include <gtest/gtest.h>

#include <numeric>

namespace texfab::synthesis {
namespace {

using test::VulkanDevice;

TEST(VulkanRuntime, ReleasedBuffersServeLaterOnesOfTheirSizeClass) {
  VulkanDevice d;
  TEXFAB_REQUIRE_VULKAN(d);
  vulkan::Device& device = *d.device;
  device.setProfiling(true);
  { const vulkan::Buffer a(device, 1000); }
  { const vulkan::Buffer b(device, 900); }  // the same class as a (4 KiB)
  EXPECT_EQ(device.profile().allocations, 1u);
  const vulkan::Buffer c(device, 3000);
  const vulkan::Buffer e(device, 2000);  // c holds the released one: a new one
  EXPECT_EQ(device.profile().allocations, 2u);
  { const vulkan::Buffer f(device, (9 << 20) + 1); }
  { const vulkan::Buffer g(device, 10 << 20); }  // both round up to 10 MiB (steps of 2 MiB up to 16 MiB)
  EXPECT_EQ(device.profile().allocations, 3u);
  { const vulkan::Buffer h(device, 20 << 20); }
  EXPECT_EQ(device.profile().allocations, 4u);
  device.setProfiling(false);
}

TEST(VulkanRuntime, DownloadRegionsLandWhereAsked) {
  VulkanDevice d;
  TEXFAB_REQUIRE_VULKAN(d);
  std::vector<uint32_t> words(4096);
  std::iota(words.begin(), words.end(), 0u);
  vulkan::Commands commands(*d.device);
  const vulkan::Buffer buffer = commands.uploaded(std::span<const uint32_t>(words));
  // Out of order, one empty, one over another's source.
  const std::vector<vulkan::Commands::Region> regions = {
      {4 * 100, 4 * 10, 4 * 5}, {4 * 0, 4 * 0, 4 * 3}, {4 * 7, 4 * 20, 0}, {4 * 4000, 4 * 30, 4 * 96}, {4 * 102, 4 * 200, 4}};
  std::vector<uint32_t> out(300, 0xdeadbeef);
  commands.download(buffer, regions, out.data());
  commands.submit();
  std::vector<uint32_t> expected(300, 0xdeadbeef);
  for (const auto& r : regions)
    for (uint64_t i = 0; i < r.bytes / 4; ++i) expected[r.to / 4 + i] = words[r.from / 4 + i];
  EXPECT_EQ(out, expected);

  // Rows of a window (they fill most of the range they span: one copy of that range).
  std::vector<vulkan::Commands::Region> rows;
  for (uint64_t y = 0; y < 10; ++y) rows.push_back({4 * (64 * (y + 3) + 2), 4 * 60 * (9 - y), 4 * 60});
  std::vector<uint32_t> window(600, 0xdeadbeef);
  commands.download(buffer, rows, window.data());
  commands.submit();
  for (uint64_t y = 0; y < 10; ++y)
    for (uint64_t x = 0; x < 60; ++x) ASSERT_EQ(window[60 * (9 - y) + x], words[64 * (y + 3) + 2 + x]) << x << "," << y;
}

TEST(VulkanRuntime, ResidentDataIsMadeOncePerKey) {
  VulkanDevice d;
  TEXFAB_REQUIRE_VULKAN(d);
  int made = 0;
  auto make = [&](uint64_t bytes) {
    return [&made, bytes] {
      ++made;
      return std::pair{std::make_shared<const int>(made), bytes};
    };
  };
  const auto a = d.device->resident<int>(7, make(1024));
  const auto b = d.device->resident<int>(7, make(1024));
  EXPECT_EQ(a, b);
  EXPECT_EQ(made, 1);
  d.device->resident<int>(8, make(1024));
  EXPECT_EQ(made, 2);
  d.device->resident<int>(0, make(1024));  // key 0: never kept
  d.device->resident<int>(0, make(1024));
  EXPECT_EQ(made, 4);
  d.device->resident<int>(9, make(uint64_t(1) << 40));  // beyond the budget: not kept
  d.device->resident<int>(9, make(uint64_t(1) << 40));
  EXPECT_EQ(made, 6);
  EXPECT_EQ(*d.device->resident<int>(7, make(1024)), 1);
}

} // namespace
} // namespace texfab::synthesis
