// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What this machine can hold, for refusing work that cannot fit before it starts. Each algorithm
// that can outgrow memory estimates its own peak next to its code (e.g. textureMeshMemoryBytes);
// callers pass the estimate to checkMemory.

#include <cstdint>
#include <string>

namespace texfab {

/// Physical memory of this machine in bytes (8 GiB when the system does not say).
uint64_t physicalMemoryBytes();

/// Throws texfab::Error unless `bytes` fits in 80 % of this machine's memory:
/// "<what> needs about 12.5 GiB of memory, more than this machine's 8.0 GiB allow".
void checkMemory(double bytes, const std::string& what);

} // namespace texfab
