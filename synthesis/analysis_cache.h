// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The on-disk cache discipline shared by the 2-D exemplar analysis and the solid analysis: a file
// named by the content + parameter key, read when present and valid, otherwise computed and
// stored. A damaged file is recomputed, never trusted; a cache folder that cannot be written costs
// time on the next run, not correctness (a warning says so). Reading a file marks it as recently
// used (its modification time), for pruneCache.

#include "core/context.h"
#include "core/error.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

namespace texfab::synthesis {

/// Where analyses are kept between runs.
struct AnalysisCacheSettings {
  /// The cache folder (defaultCacheDir() for the usual one); nullopt: computed every time.
  std::optional<std::filesystem::path> dir;
  /// After each analysis the least recently used files go until the rest take at most this.
  uint64_t maxBytes = uint64_t(1) << 30;
};

/// Removes the least recently used analyses (*.analysis, *.solid, *.tiles, *.ndf, *.graph) of
/// `cacheDir` until the rest take at most `maxBytes`. Other files are left alone; errors are
/// ignored (a cache is optional).
void pruneCache(const std::filesystem::path& cacheDir, uint64_t maxBytes);
/// The same for `cache`'s folder and bound; nothing without a folder.
void pruneCache(const AnalysisCacheSettings& cache);

/// Marks a cache file as just used.
void touchCacheFile(const std::filesystem::path& path);

/// `read(path, key)` -> std::optional<T>; `compute()` -> T; `write(value, path)` may throw Error.
template <class Read, class Compute, class Write>
auto loadOrCompute(const std::filesystem::path& cacheDir, uint64_t key, const std::string& extension, Read read,
                   Compute compute, Write write, bool* fromCache, const Context& ctx) {
  char name[40];
  std::snprintf(name, sizeof name, "%016llx", static_cast<unsigned long long>(key));
  const std::filesystem::path path = cacheDir / (name + extension);
  if (auto cached = read(path, key)) {
    if (fromCache) *fromCache = true;
    touchCacheFile(path);
    return std::move(*cached);
  }
  auto value = compute();
  if (fromCache) *fromCache = false;
  try {
    std::error_code ec;
    std::filesystem::create_directories(cacheDir, ec);
    if (ec) throw Error(cacheDir.string() + ": cannot create folder: " + ec.message());
    write(value, path);
  } catch (const Error& e) {
    ctx.warn("the analysis cache cannot be written (" + std::string(e.what()) + "); the analysis will be computed again");
  }
  return value;
}

} // namespace texfab::synthesis
