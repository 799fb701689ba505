// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The output folder of a slice run: one PNG per layer, named so that names sort by layer
// (slice_00000.png, ...), and the manifest slices.json. Everything is written into a temporary
// folder beside the output, renamed onto it only when every layer and the manifest are written:
// a failed run (a full disk, a cancel, bad input found late) leaves no output and no manifest that
// names missing layers.
//
// Manifest (JSON, keys in this order; equal runs give equal bytes):
//   {"format": "texfab-slices", "version": 1,
//    "print": {...what the layers are: grid, materials, options...},
//    "layers": {"first": A, "count": N, "total": T},
//    "files": [{"layer": k, "file": "slice_0000k.png", "bytes": n, "sha256": "..."}, ...]}
// A shard (a layer range of a larger print) is a folder like any other whose "layers" say which
// range it holds; mergeSliceFolders() joins shards into the folder a full run writes.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <span>
#include <string>
#include <vector>

namespace texfab::print {

/// One written layer, as the manifest lists it.
struct SliceFile {
  int layer = 0;
  std::string file;
  uint64_t bytes = 0;
  std::string sha256;  ///< lowercase hex
};

/// "slice_00042.png" (at least 5 digits; more when the print has more layers).
std::string sliceFileName(int layer, int totalLayers);

/// Lowercase hex SHA-256 of the bytes (OpenSSL).
std::string sha256Hex(std::span<const uint8_t> bytes);

class SliceWriter {
public:
  /// Checks `folder` before any work: it must not exist, or be an empty folder, or `force` must be
  /// given (it is then replaced at commit). Creates the temporary folder. Throws texfab::Error.
  SliceWriter(std::filesystem::path folder, bool force);
  /// Removes the temporary folder unless committed.
  ~SliceWriter();
  SliceWriter(const SliceWriter&) = delete;
  SliceWriter& operator=(const SliceWriter&) = delete;

  /// Writes layer `layer`'s PNG (thread-safe) and records it for the manifest. Throws
  /// texfab::Error naming the file when it cannot be written (e.g. the disk is full).
  void writeLayer(int layer, int totalLayers, std::span<const uint8_t> png);
  /// Writes another file into the folder (e.g. the preview), under `name`.
  void writeFile(const std::string& name, std::span<const uint8_t> bytes);
  /// Copies (hard-links when possible) an existing file into the folder as layer `file.layer`.
  void addLayerFile(const std::filesystem::path& source, const SliceFile& file);
  /// The temporary folder (files written there appear in the output at commit).
  const std::filesystem::path& staging() const { return staging_; }

  /// Completes the temporary folder: the manifest from `print` and `layers` with the recorded files
  /// (sorted by layer). Throws texfab::Error when a layer of the range is missing.
  void seal(const nlohmann::ordered_json& print, int firstLayer, int layerCount, int totalLayers);
  /// Renames the sealed temporary folder onto the output (replacing it with `force`). A command
  /// with other outputs does this when it commits them (OutputSet::atCommit), so a job stopped
  /// after its layers leaves no folder either.
  void publish();
  /// seal(), then publish().
  void commit(const nlohmann::ordered_json& print, int firstLayer, int layerCount, int totalLayers) {
    seal(print, firstLayer, layerCount, totalLayers);
    publish();
  }

  const std::vector<SliceFile>& files() const { return files_; }

private:
  std::filesystem::path folder_, staging_;
  bool sealed_ = false, committed_ = false;
  std::mutex mutex_;
  std::vector<SliceFile> files_;
};

/// The manifest of a slice folder, parsed; throws texfab::Error naming the folder when it is
/// missing or malformed.
nlohmann::ordered_json readSliceManifest(const std::filesystem::path& folder);

/// Joins shard folders (any order) into `output`: their "print" blocks must be equal and their
/// layer ranges must tile [0, total) exactly; every file is checked against its checksum. The
/// result is byte-identical to the folder of a full run. Throws texfab::Error naming the shard at
/// fault.
void mergeSliceFolders(std::span<const std::filesystem::path> shards, const std::filesystem::path& output, bool force);

} // namespace texfab::print
