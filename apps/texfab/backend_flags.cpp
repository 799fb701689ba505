// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/backend_flags.h"

#include "render/image/error.h"
#include "synthesis/backend.h"

#include <map>

namespace texfab::cli {

void addBackendFlags(CLI::App& app, BackendFlags& flags) {
  app.add_option_function<std::string>(
         "--backend",
         [&flags](const std::string& name) {
           const std::map<std::string, Backend> names{
               {"cpu", Backend::Cpu}, {"vulkan", Backend::Vulkan}, {"auto", Backend::Auto}};
           const auto it = names.find(name);
           if (it == names.end()) throw CLI::ValidationError("--backend", "expected cpu, vulkan or auto, got '" + name + "'");
           flags.backend = it->second;
         },
         "Where the synthesis kernels run: cpu, vulkan (a Vulkan device; error without one) or auto (a Vulkan "
         "device when there is one, else the CPU); the result does not depend on it")
      ->type_name("cpu|vulkan|auto")
      ->default_str("cpu");
  app.add_option("--device", flags.device,
                 "Vulkan device index (texfab info --devices lists them; default: $TEXFAB_VULKAN_DEVICE, else the "
                 "best device)")
      ->check(CLI::NonNegativeNumber);
}

std::string applyBackend(const BackendFlags& flags, Context& ctx) {
  ctx.backend = flags.backend;
  ctx.device = flags.device;
  if (flags.backend == Backend::Cpu) return {};
  std::string line;
  Context probe = ctx;
  probe.progress = [&line](const ProgressEvent& e) {
    if (e.kind == ProgressEvent::Kind::End && e.stage == "backend") line = e.detail;
  };
  try {
    synthesis::deviceFor(probe);
  } catch (const Cancelled&) {
    throw;
  } catch (const Error& e) {
    throw Error(std::string("--backend vulkan: ") + e.what());
  }
  return line;
}

} // namespace texfab::cli
