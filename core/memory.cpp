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

void checkMemory(double bytes, const std::string& what) {
  const double available = double(physicalMemoryBytes());
  if (bytes <= 0.8 * available) return;
  char text[160];
  std::snprintf(text, sizeof text, " needs about %.1f GiB of memory, more than this machine's %.1f GiB allow", bytes / 1073741824.0,
                available / 1073741824.0);
  throw Error(what + text);
}

} // namespace texfab
