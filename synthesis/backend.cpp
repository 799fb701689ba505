// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/backend.h"

#include "core/error.h"

namespace texfab::synthesis {

namespace {

// Reports the backend chosen for a computation as a stage with one line of detail.
void note(const Context& ctx, const std::string& detail) {
  Stage stage(ctx, "backend");
  stage.finish(detail);
}

} // namespace

#if TEXFAB_HAS_VULKAN

bool vulkanBuilt() { return true; }

std::vector<vulkan::DeviceInfo> vulkanDevices() { return vulkan::listDevices(); }

std::shared_ptr<vulkan::Device> deviceFor(const Context& ctx) {
  if (ctx.backend == Backend::Cpu) return nullptr;
  try {
    auto device = vulkan::sharedDevice(ctx.device);
    // A device of type CPU (lavapipe, llvmpipe) emulates a GPU on this machine's cores, an order of
    // magnitude slower than the CPU backend: auto takes it only when it was asked for by index.
    if (ctx.backend == Backend::Auto && device->info().type == "CPU" && !vulkan::deviceNamed(ctx.device)) {
      note(ctx, "CPU (the Vulkan device " + device->info().name +
                    " emulates a GPU on the CPU, slower than the CPU backend; --backend vulkan or --device N uses it)");
      return nullptr;
    }
    note(ctx, "Vulkan: " + device->info().name);
    return device;
  } catch (const Cancelled&) {
    throw;
  } catch (const Error& e) {
    if (ctx.backend == Backend::Vulkan) throw;
    note(ctx, std::string("CPU (") + e.what() + ")");
    return nullptr;
  }
}

#else

bool vulkanBuilt() { return false; }

std::vector<vulkan::DeviceInfo> vulkanDevices() { return {}; }

std::shared_ptr<vulkan::Device> deviceFor(const Context& ctx) {
  if (ctx.backend == Backend::Vulkan) throw Error("this texfab was built without the Vulkan backend");
  if (ctx.backend == Backend::Auto) note(ctx, "CPU (texfab was built without the Vulkan backend)");
  return nullptr;
}

#endif

} // namespace texfab::synthesis
