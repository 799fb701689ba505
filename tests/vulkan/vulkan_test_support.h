// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What the Vulkan tests share: the device they run on (skipping, with the reason, where there is
// none), and random inputs. ctest runs them under the Khronos validation layer
// ($TEXFAB_VULKAN_VALIDATION=1): any validation message is an Error at the next submit.

#include "core/error.h"
#include "synthesis/vulkan/runtime.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace texfab::test {

/// A Vulkan device for one test, or the reason there is none.
struct VulkanDevice {
  std::unique_ptr<synthesis::vulkan::Device> device;
  std::string missing;

  explicit VulkanDevice(const synthesis::vulkan::DeviceOptions& options = {}) {
    try {
      device = std::make_unique<synthesis::vulkan::Device>(-1, options);
    } catch (const Error& e) {
      missing = e.what();
    }
  }
};

/// Skips the test when there is no Vulkan device.
#define TEXFAB_REQUIRE_VULKAN(d) \
  if (!(d).device) GTEST_SKIP() << "no Vulkan device: " << (d).missing

/// Uniform random values.
class Random {
public:
  explicit Random(uint32_t seed) : engine_(seed) {}
  int64_t between(int64_t lo, int64_t hi) { return std::uniform_int_distribution<int64_t>(lo, hi)(engine_); }
  float real(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(engine_); }
  template <class T> std::vector<T> values(size_t n, int64_t lo, int64_t hi) {
    std::vector<T> v(n);
    for (T& x : v) x = T(between(lo, hi));
    return v;
  }
  /// n packed coordinates in [0, w) x [0, h) (scaled by `unit`, e.g. subpixels).
  std::vector<uint32_t> coords(size_t n, int w, int h, int unit = 1) {
    std::vector<uint32_t> v(n);
    for (uint32_t& c : v) c = uint32_t(between(0, int64_t(w) * unit - 1)) | uint32_t(between(0, int64_t(h) * unit - 1)) << 16;
    return v;
  }

private:
  std::mt19937 engine_;
};

/// Downloads `count` values of T from `buffer` (one submit).
template <class T>
std::vector<T> download(synthesis::vulkan::Device& device, const synthesis::vulkan::Buffer& buffer, size_t count) {
  std::vector<T> out(count);
  synthesis::vulkan::Commands commands(device);
  commands.download(buffer, 0, out.data(), count * sizeof(T));
  commands.submit();
  return out;
}

} // namespace texfab::test
