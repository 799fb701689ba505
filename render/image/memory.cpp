// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/image/memory.h"

#include <unistd.h>

namespace texfab {

uint64_t physicalMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && pageSize > 0 ? uint64_t(pages) * uint64_t(pageSize) : uint64_t(8) << 30;
}

} // namespace texfab
