// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What this machine can hold, for refusing work that cannot fit before it starts.

#include <cstdint>

namespace texfab {

/// Physical memory of this machine in bytes (8 GiB when the system does not say).
uint64_t physicalMemoryBytes();

} // namespace texfab
