// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The on-disk cache discipline shared by the 2-D exemplar analysis and the solid analysis: a file
// named by the content + parameter key, read when present and valid, otherwise computed and
// stored. A damaged file is recomputed, never trusted; a cache folder that cannot be written costs
// time on the next run, not correctness.

#include "render/image/error.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

namespace texfab::synthesis {

/// `read(path, key)` -> std::optional<T>; `compute()` -> T; `write(value, path)` may throw Error.
template <class Read, class Compute, class Write>
auto loadOrCompute(const std::filesystem::path& cacheDir, uint64_t key, const std::string& extension, Read read,
                   Compute compute, Write write, bool* fromCache) {
  char name[40];
  std::snprintf(name, sizeof name, "%016llx", static_cast<unsigned long long>(key));
  const std::filesystem::path path = cacheDir / (name + extension);
  if (auto cached = read(path, key)) {
    if (fromCache) *fromCache = true;
    return std::move(*cached);
  }
  auto value = compute();
  if (fromCache) *fromCache = false;
  try {
    std::error_code ec;
    std::filesystem::create_directories(cacheDir, ec);
    write(value, path);
  } catch (const Error&) {
    // Unwritable cache folder: keep the computed value (see above).
  }
  return value;
}

} // namespace texfab::synthesis
