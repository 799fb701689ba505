// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The flags that choose where the synthesis kernels run (synth, solid, texture): --backend
// cpu|vulkan|auto and --device N. Outputs are the same bytes on every backend; only speed differs.

#include "render/image/context.h"

#include <CLI/CLI.hpp>

#include <string>

namespace texfab::cli {

struct BackendFlags {
  Backend backend = Backend::Cpu;
  int device = -1;  ///< -1: $TEXFAB_VULKAN_DEVICE, else the best device
};

/// Adds --backend and --device to `app`, bound to `flags`.
void addBackendFlags(CLI::App& app, BackendFlags& flags);

/// Sets the context's backend and device and opens the device now, so that a missing one is a
/// one-line Error before any work (Vulkan) or a CPU fall-back (Auto). Returns the line that says
/// what runs the kernels ("Vulkan: NAME", "CPU (why)"); empty for the CPU backend.
std::string applyBackend(const BackendFlags& flags, Context& ctx);

} // namespace texfab::cli
