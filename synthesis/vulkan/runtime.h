// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A small Vulkan compute runtime for the synthesis kernels: devices, storage buffers, and lists of
// commands (uploads, kernel dispatches, downloads) run in order with a barrier between each two.
// No Vulkan type appears here; runtime.cpp holds them.
//
// Kernels are compute shaders compiled to SPIR-V at build time and embedded (kernel.h); every one
// has 64 invocations per workgroup and reads its parameters from push constants. A dispatch binds
// ranges of buffers to bindings 0..n-1 of set 0 (push descriptors). A range never exceeds the
// device's maxStorageBufferRange (128 MiB on lavapipe and some GPUs): callers split larger data
// into several ranges (Device::maxRangeBytes).
//
// Errors: a missing device or driver, device loss, out of device memory and validation messages
// (with $TEXFAB_VULKAN_VALIDATION=1) are texfab::Error with a one-line message. Waits check the
// context's cancel flag; a device that stops answering is reported lost by its driver's watchdog.

#include "core/context.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace texfab::synthesis::vulkan {

/// One physical device as the Vulkan loader reports it.
struct DeviceInfo {
  int index = 0;             ///< position in the loader's list: the value of --device / $TEXFAB_VULKAN_DEVICE
  std::string name;
  std::string type;          ///< "discrete GPU", "integrated GPU", "virtual GPU", "CPU" or "other"
  std::string apiVersion;    ///< e.g. "1.3.230"
  std::string driver;        ///< driver name and version, e.g. "llvmpipe, Mesa 22.3.6"
  uint64_t memoryBytes = 0;  ///< the largest device-local heap
  uint64_t maxRangeBytes = 0;  ///< maxStorageBufferRange
  std::string unusable;      ///< why texfab cannot use it (missing feature), empty if it can
};

/// The devices the Vulkan loader finds, in its order; empty when there is no loader or driver
/// (never throws).
std::vector<DeviceInfo> listDevices();

/// Where a device's time went, summed over every submit since profiling was switched on
/// (Device::setProfiling). Device seconds come from timestamps around each copy and dispatch
/// (zero when the device has none); wall seconds are the host's, from submit to the fence.
struct DeviceProfile {
  double uploadSeconds = 0;    ///< device: host-to-device copies
  double dispatchSeconds = 0;  ///< device: kernels
  double downloadSeconds = 0;  ///< device: device-to-host copies
  double submitSeconds = 0;    ///< host wall time inside submit (queue, wait, copy-out)
  double allocateSeconds = 0;  ///< host wall time creating buffers (device and staging memory)
  uint64_t uploadBytes = 0, downloadBytes = 0;
  uint64_t dispatches = 0, submits = 0, allocations = 0;
};

struct DeviceOptions {
  /// The largest byte range one binding may cover, at most (0 = the device's maxStorageBufferRange).
  /// Tests lower it to exercise the splitting of large data on small inputs.
  uint64_t maxRangeBytes = 0;
};

/// An opened device: instance, logical device, one compute queue, the pipelines built so far.
/// Thread-safe: several threads may record and submit commands at once.
class Device {
public:
  /// Opens device `index`; -1: $TEXFAB_VULKAN_DEVICE when set, else the best usable device
  /// (discrete GPU, integrated, virtual, other, CPU; then the loader's order). Throws Error when
  /// there is none, when the index is out of range, or when the device lacks what texfab needs
  /// (Vulkan 1.1, shaderInt64, push descriptors, a compute queue).
  explicit Device(int index = -1, const DeviceOptions& options = {});
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  const DeviceInfo& info() const;
  /// The largest byte range one binding may cover (a multiple of 256).
  uint64_t maxRangeBytes() const;

  /// Profiling (off by default): every command of every later submit is timed on the device and
  /// summed into profile(). Switching it on resets the sums. For benchmarks.
  void setProfiling(bool on);
  DeviceProfile profile() const;

  /// Data kept on the device between computations, by a key of its content (the tables of one
  /// level of a solid analysis, say): `make` builds it on a miss and returns it with its size in
  /// bytes. The least recently used data goes beyond a budget (an eighth of the device's memory,
  /// at most 512 MiB); data larger than the budget is returned and not kept. Key 0: never kept.
  template <class T, class Make> std::shared_ptr<const T> resident(uint64_t key, Make&& make) {
    return std::static_pointer_cast<const T>(residentData(key, [&]() -> std::pair<std::shared_ptr<const void>, uint64_t> {
      return make();
    }));
  }

  struct Impl;
  Impl& impl() const { return *impl_; }

private:
  std::shared_ptr<const void> residentData(uint64_t key,
                                           const std::function<std::pair<std::shared_ptr<const void>, uint64_t>()>& make);

  std::unique_ptr<Impl> impl_;
};

/// Device `index` (as Device's constructor), opened on first use and kept for the process (opening
/// costs ~0.1 s): every computation of the process shares it. A device that was lost is reopened.
/// $TEXFAB_VULKAN_MAX_RANGE (bytes) lowers its binding range (DeviceOptions), for tests.
std::shared_ptr<Device> sharedDevice(int index);

/// Whether a device was asked for by its index: `index` >= 0, or $TEXFAB_VULKAN_DEVICE set.
bool deviceNamed(int index);

/// A storage buffer in device memory. Its contents are undefined until written.
class Buffer {
public:
  Buffer();
  Buffer(Device& device, uint64_t bytes);
  Buffer(Buffer&&) noexcept;
  Buffer& operator=(Buffer&&) noexcept;
  ~Buffer();

  uint64_t bytes() const { return bytes_; }
  explicit operator bool() const { return impl_ != nullptr; }

  struct Impl;
  Impl& impl() const { return *impl_; }

private:
  std::unique_ptr<Impl> impl_;
  uint64_t bytes_ = 0;
};

/// A byte range of a buffer bound to one binding: [offset, offset + bytes), offset a multiple of
/// 256, bytes at most Device::maxRangeBytes().
struct Range {
  const Buffer* buffer = nullptr;
  uint64_t offset = 0;
  uint64_t bytes = 0;

  Range() = default;
  Range(const Buffer& b) : buffer(&b), bytes(b.bytes()) {}  // NOLINT: a whole buffer is a range
  Range(const Buffer& b, uint64_t offset, uint64_t bytes) : buffer(&b), offset(offset), bytes(bytes) {}
};

/// A compute kernel: embedded SPIR-V (main, 64 invocations per workgroup), its number of storage
/// bindings (each an array of `arrays[i]` descriptors; 1 if empty) and the size of its push
/// constants.
struct Kernel {
  const char* name;
  std::span<const uint32_t> spirv;
  std::vector<uint32_t> arrays;  ///< descriptors per binding
  uint32_t paramBytes;
};

/// Work for the device, recorded in order and run by submit(): each command sees the results of
/// those before it. Uploads copy their data when recorded; downloads fill their destination
/// during submit(). With `timed` (or a profiling device), dispatches and copies are timed on the
/// device (kernelSeconds()).
class Commands {
public:
  explicit Commands(Device& device, bool timed = false);
  ~Commands();
  Commands(const Commands&) = delete;
  Commands& operator=(const Commands&) = delete;

  Device& device() const { return device_; }

  void upload(const Buffer& to, uint64_t offset, const void* data, uint64_t bytes);
  template <class T> void upload(const Buffer& to, std::span<const T> data, uint64_t offset = 0) {
    upload(to, offset, data.data(), data.size_bytes());
  }
  /// A new buffer holding `data`, its size rounded up to whole words (at least one, so that empty
  /// tables still bind): shaders read bytes from words.
  template <class T> Buffer uploaded(std::span<const T> data) {
    Buffer b(device_, std::max<uint64_t>((data.size_bytes() + 3) / 4 * 4, 4));
    upload(b, data);
    return b;
  }
  void download(const Buffer& from, uint64_t offset, void* data, uint64_t bytes);
  /// Bytes [from, from + bytes) of the buffer to data + to, for each region (one copy command).
  struct Region {
    uint64_t from = 0, to = 0, bytes = 0;
  };
  void download(const Buffer& from, std::span<const Region> regions, void* data);
  void fill(const Buffer& to, uint32_t value);

  /// Runs `kernel` over `invocations` (its index in [0, invocations), gl_GlobalInvocationID.x plus
  /// gl_WorkGroupID.y rows of 65535 groups beyond 4.19M invocations: see dispatch.glsl), with
  /// `params` as push constants and `bindings` flattened over the kernel's binding arrays.
  template <class Params>
  void dispatch(const Kernel& kernel, const Params& params, std::initializer_list<Range> bindings,
                uint64_t invocations) {
    static_assert(sizeof(Params) <= 128, "push constants are limited to 128 bytes");
    dispatchRaw(kernel, &params, sizeof(Params), bindings, invocations);
  }

  /// Runs everything recorded and waits for it. Throws Error on device loss, out of memory or a
  /// validation message; Cancelled (after the device is done) when ctx's cancel flag is set.
  void submit(const Context& ctx = {});

  /// Device seconds per kernel name over the dispatches of the last submit, and of its copies as
  /// "upload" and "download" (timed commands only).
  const std::map<std::string, double>& kernelSeconds() const { return seconds_; }

  struct Impl;

private:
  void dispatchRaw(const Kernel& kernel, const void* params, size_t paramBytes, std::initializer_list<Range> bindings,
                   uint64_t invocations);
  void addToProfile(double wallSeconds) const;

  Device& device_;
  std::unique_ptr<Impl> impl_;
  std::map<std::string, double> seconds_;
};

/// Invocations per workgroup of every kernel.
inline constexpr uint32_t kWorkgroupSize = 64;

} // namespace texfab::synthesis::vulkan
