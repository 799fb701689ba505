// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Where the synthesis kernels of one computation run: on the CPU (synthesis/cpu/) or on a Vulkan
// device (synthesis/vulkan/), as the execution context asks (ctx.backend, ctx.device). Both give
// the same bytes (the determinism contract); only speed differs.

#include "core/context.h"
#include "synthesis/vulkan/runtime.h"

#include <memory>
#include <vector>

namespace texfab::synthesis {

/// The device the context asks for, or null for the CPU.
///   Backend::Cpu: null.
///   Backend::Vulkan: the device (ctx.device, else $TEXFAB_VULKAN_DEVICE, else the best one),
///     opened once per process; Error when there is none or texfab was built without Vulkan.
///   Backend::Auto: the device when one can be opened; otherwise null, and a note through
///     ctx.progress (a stage "backend" whose detail says why the CPU runs instead).
std::shared_ptr<vulkan::Device> deviceFor(const Context& ctx);

/// Whether this texfab was built with the Vulkan backend.
bool vulkanBuilt();

/// The Vulkan devices the loader finds (empty without the backend, a loader or a driver).
std::vector<vulkan::DeviceInfo> vulkanDevices();

} // namespace texfab::synthesis
