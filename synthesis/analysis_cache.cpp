// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/analysis_cache.h"

#include <algorithm>
#include <vector>

namespace texfab::synthesis {
namespace fs = std::filesystem;

void touchCacheFile(const fs::path& path) {
  std::error_code ec;
  fs::last_write_time(path, fs::file_time_type::clock::now(), ec);
}

void pruneCache(const AnalysisCacheSettings& cache) {
  if (cache.dir) pruneCache(*cache.dir, cache.maxBytes);
}

void pruneCache(const fs::path& cacheDir, uint64_t maxBytes) {
  struct Entry {
    fs::file_time_type used;
    uint64_t bytes;
    fs::path path;
  };
  std::vector<Entry> entries;
  uint64_t total = 0;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(cacheDir, ec)) {
    const std::string ext = e.path().extension().string();
    if ((ext != ".analysis" && ext != ".solid" && ext != ".tiles" && ext != ".ndf" && ext != ".graph") || !e.is_regular_file(ec)) continue;
    const uint64_t bytes = e.file_size(ec);
    if (ec) continue;
    entries.push_back({e.last_write_time(ec), bytes, e.path()});
    total += bytes;
  }
  // Oldest first; ties by name, so the choice does not depend on the directory's order.
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.used != b.used ? a.used < b.used : a.path < b.path; });
  for (const Entry& e : entries) {
    if (total <= maxBytes) break;
    if (fs::remove(e.path, ec)) total -= e.bytes;
  }
}

} // namespace texfab::synthesis
