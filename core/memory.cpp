// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/memory.h"

#include "core/error.h"

#include <unistd.h>

#include <cstdio>

namespace texfab {

uint64_t physicalMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && pageSize > 0 ? uint64_t(pages) * uint64_t(pageSize) : uint64_t(8) << 30;
}

void checkMemory(double bytes, const std::string& what, uint64_t limit) {
  const double machine = double(physicalMemoryBytes());
  const double allowed = limit > 0 ? double(limit) : kDefaultMemoryShare * machine;
  if (bytes <= allowed) return;
  constexpr double kGiB = 1073741824.0;
  char text[200];
  if (limit > 0)
    std::snprintf(text, sizeof text, " needs about %.2f GiB of memory, more than the %.2f GiB allowed (--max-memory)",
                  bytes / kGiB, allowed / kGiB);
  else
    std::snprintf(text, sizeof text,
                  " needs about %.1f GiB of memory, more than the %.1f GiB allowed (%.0f %% of this machine's %.1f GiB)",
                  bytes / kGiB, allowed / kGiB, kDefaultMemoryShare * 100, machine / kGiB);
  throw Error(what + text);
}

} // namespace texfab
