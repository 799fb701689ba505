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

/// The share of this machine's memory work may plan to use when no limit is given.
inline constexpr double kDefaultMemoryShare = 0.8;

/// Throws texfab::Error unless `bytes` fits in `limit` bytes (0: kDefaultMemoryShare of this
/// machine's memory): "<what> needs about 12.5 GiB of memory, more than the 6.4 GiB allowed (80 %
/// of this machine's 8.0 GiB)".
void checkMemory(double bytes, const std::string& what, uint64_t limit = 0);

} // namespace texfab
