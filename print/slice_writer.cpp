// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/slice_writer.h"

#include "core/error.h"
#include "core/files.h"

#include <openssl/evp.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>

namespace texfab::print {
namespace fs = std::filesystem;

namespace {

constexpr const char* kManifest = "slices.json";

void writeBytes(const fs::path& path, std::span<const uint8_t> bytes) {
  std::ofstream out(path, std::ios::binary);
  if (out) out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (out) out.close();
  if (!out) throw Error(path.filename().string() + ": cannot write the file (disk full?)");
}

std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot read");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

nlohmann::ordered_json manifestOf(const nlohmann::ordered_json& print, int first, int count, int total,
                                  const std::vector<SliceFile>& files) {
  nlohmann::ordered_json m;
  m["format"] = "texfab-slices";
  m["version"] = 1;
  m["print"] = print;
  m["layers"] = {{"first", first}, {"count", count}, {"total", total}};
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const SliceFile& f : files)
    list.push_back({{"layer", f.layer}, {"file", f.file}, {"bytes", f.bytes}, {"sha256", f.sha256}});
  m["files"] = std::move(list);
  return m;
}

bool isString(const nlohmann::ordered_json& m, const char* key) { return m.contains(key) && m[key].is_string(); }
bool isInteger(const nlohmann::ordered_json& m, const char* key) { return m.contains(key) && m[key].is_number_integer(); }

// Throws unless `m` has every field that readers of manifests use, of its type, with a layer range
// inside the print: what a manifest's reader may take for granted.
void checkManifest(const nlohmann::ordered_json& m, const std::string& where) {
  if (!m.is_object() || !isString(m, "format") || m["format"] != "texfab-slices")
    throw Error(where + ": not a texfab slice manifest");
  if (!m.contains("print") || !m["print"].is_object()) throw Error(where + ": no \"print\" block");
  const nlohmann::ordered_json* layers = m.contains("layers") ? &m["layers"] : nullptr;
  if (!layers || !layers->is_object() || !isInteger(*layers, "first") || !isInteger(*layers, "count") ||
      !isInteger(*layers, "total"))
    throw Error(where + ": \"layers\" must hold the integers first, count and total");
  const int64_t first = (*layers)["first"], count = (*layers)["count"], total = (*layers)["total"];
  if (first < 0 || count < 0 || total < 0 || total > int64_t(1) << 30 || first > total - count)
    throw Error(where + ": layers " + std::to_string(first) + " + " + std::to_string(count) + " lie outside the print's " +
                std::to_string(total));
  if (!m.contains("files") || !m["files"].is_array()) throw Error(where + ": no \"files\" list");
  const nlohmann::ordered_json& files = m["files"];
  if (int64_t(files.size()) != count)
    throw Error(where + ": " + std::to_string(files.size()) + " files for " + std::to_string(count) + " layers");
  for (size_t i = 0; i < files.size(); ++i) {
    const auto& f = files[i];
    if (!f.is_object() || !isInteger(f, "layer") || !isString(f, "file") || !f.contains("bytes") ||
        !f["bytes"].is_number_unsigned() || !isString(f, "sha256"))
      throw Error(where + ": a file entry needs layer, file, bytes and sha256: " + f.dump());
    const std::string name = f["file"];
    if (f["layer"] != first + int64_t(i) || name.empty() || name == "." || name == ".." ||
        name.find('/') != std::string::npos)
      throw Error(where + ": file entry " + std::to_string(i) + " is not layer " + std::to_string(first + int64_t(i)) +
                  " in a file of the folder: " + f.dump());
  }
}

} // namespace

std::string sliceFileName(int layer, int totalLayers) {
  const int digits = std::max(5, int(std::to_string(std::max(0, totalLayers - 1)).size()));
  char name[64];
  std::snprintf(name, sizeof name, "slice_%0*d.png", digits, layer);
  return name;
}

std::string sha256Hex(std::span<const uint8_t> bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (!EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr))
    throw Error("SHA-256 failed (OpenSSL)");
  static const char* const hex = "0123456789abcdef";
  std::string out;
  for (unsigned i = 0; i < length; ++i) out += {hex[digest[i] >> 4], hex[digest[i] & 15]};
  return out;
}

SliceWriter::SliceWriter(fs::path folder, bool force) : folder_(std::move(folder)) {
  if (folder_.filename().empty()) folder_ = folder_.parent_path();  // "out/" names "out"
  std::error_code ec;
  if (fs::exists(folder_, ec)) {
    if (!fs::is_directory(folder_, ec)) throw Error(folder_.string() + ": exists and is not a folder");
    if (!fs::is_empty(folder_, ec) && !force)
      throw Error(folder_.string() + ": the folder exists and is not empty (give --force to replace it)");
  }
  const fs::path parent = folder_.has_parent_path() ? folder_.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec)) throw Error(parent.string() + ": no such folder");
  staging_ = temporaryPathFor(folder_);
  if (!fs::create_directory(staging_, ec) || ec)
    throw Error(folder_.string() + ": cannot create a temporary folder beside it: " + ec.message());
}

SliceWriter::~SliceWriter() {
  std::error_code ec;
  if (!committed_) fs::remove_all(staging_, ec);
}

void SliceWriter::writeLayer(int layer, int totalLayers, std::span<const uint8_t> png) {
  SliceFile file{layer, sliceFileName(layer, totalLayers), png.size(), sha256Hex(png)};
  try {
    writeBytes(staging_ / file.file, png);
  } catch (const Error&) {
    throw Error((folder_ / file.file).string() + ": cannot write the layer (disk full?)");
  }
  std::lock_guard lock(mutex_);
  files_.push_back(std::move(file));
}

void SliceWriter::writeFile(const std::string& name, std::span<const uint8_t> bytes) {
  try {
    writeBytes(staging_ / name, bytes);
  } catch (const Error&) {
    throw Error((folder_ / name).string() + ": cannot write the file (disk full?)");
  }
}

void SliceWriter::addLayerFile(const fs::path& source, const SliceFile& file) {
  std::error_code ec;
  fs::create_hard_link(source, staging_ / file.file, ec);
  if (ec) fs::copy_file(source, staging_ / file.file, ec);
  if (ec) throw Error((folder_ / file.file).string() + ": cannot copy " + source.string() + ": " + ec.message());
  std::lock_guard lock(mutex_);
  files_.push_back(file);
}

void SliceWriter::seal(const nlohmann::ordered_json& print, int firstLayer, int layerCount, int totalLayers) {
  std::sort(files_.begin(), files_.end(), [](const SliceFile& a, const SliceFile& b) { return a.layer < b.layer; });
  if (int(files_.size()) != layerCount)
    throw Error("internal: " + std::to_string(files_.size()) + " layers written, " + std::to_string(layerCount) + " expected");
  for (int i = 0; i < layerCount; ++i)
    if (files_[size_t(i)].layer != firstLayer + i) throw Error("internal: layer " + std::to_string(firstLayer + i) + " missing");
  const std::string text = manifestOf(print, firstLayer, layerCount, totalLayers, files_).dump(2) + "\n";
  writeFile(kManifest, {reinterpret_cast<const uint8_t*>(text.data()), text.size()});
  sealed_ = true;
}

void SliceWriter::publish() {
  if (!sealed_) throw Error("internal: " + folder_.string() + " published before its manifest was written");
  std::error_code ec;
  fs::path replaced;
  if (fs::exists(folder_, ec)) {
    replaced = temporaryPathFor(folder_);
    fs::rename(folder_, replaced, ec);
    if (ec) throw Error(folder_.string() + ": cannot replace the folder: " + ec.message());
  }
  fs::rename(staging_, folder_, ec);
  if (ec) {
    if (!replaced.empty()) fs::rename(replaced, folder_);
    throw Error(folder_.string() + ": cannot move the slices into place: " + ec.message());
  }
  committed_ = true;
  if (!replaced.empty()) fs::remove_all(replaced, ec);
}

nlohmann::ordered_json readSliceManifest(const fs::path& folder) {
  const fs::path path = folder / kManifest;
  std::ifstream in(path);
  if (!in) throw Error(folder.string() + ": no " + std::string(kManifest) + " (not a slice folder, or an unfinished run)");
  nlohmann::ordered_json m;
  try {
    m = nlohmann::ordered_json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(path.string() + ": not valid JSON (" + e.what() + ")");
  }
  checkManifest(m, path.string());
  return m;
}

void mergeSliceFolders(std::span<const fs::path> shards, const fs::path& output, bool force) {
  if (shards.empty()) throw Error("nothing to merge");
  std::map<int, std::pair<fs::path, nlohmann::ordered_json>> byFirst;
  for (const fs::path& shard : shards) {
    nlohmann::ordered_json m = readSliceManifest(shard);
    const int first = m["layers"].value("first", -1);
    if (!byFirst.emplace(first, std::make_pair(shard, std::move(m))).second)
      throw Error(shard.string() + ": another shard also starts at layer " + std::to_string(first));
  }
  const nlohmann::ordered_json& reference = byFirst.begin()->second.second;
  const int total = reference["layers"].value("total", -1);
  int next = 0;
  for (const auto& [first, entry] : byFirst) {
    const auto& [shard, m] = entry;
    if (m["print"] != reference["print"] || m["layers"].value("total", -1) != total)
      throw Error(shard.string() + ": a different print from " + byFirst.begin()->second.first.string());
    if (first != next)
      throw Error(shard.string() + ": starts at layer " + std::to_string(first) + ", expected " + std::to_string(next) +
                  (first > next ? " (a shard is missing)" : " (shards overlap)"));
    next = first + m["layers"].value("count", 0);
  }
  if (next != total) throw Error("the shards end at layer " + std::to_string(next) + " of " + std::to_string(total));
  SliceWriter writer(output, force);
  for (const auto& [first, entry] : byFirst)
    for (const auto& f : entry.second["files"]) {
      const SliceFile file{f.value("layer", -1), f.value("file", ""), f.value("bytes", uint64_t(0)), f.value("sha256", "")};
      const fs::path source = entry.first / file.file;
      if (sha256Hex(readBytes(source)) != file.sha256)
        throw Error(source.string() + ": does not match its checksum in the manifest");
      writer.addLayerFile(source, file);
    }
  writer.commit(reference["print"], 0, total, total);
}

} // namespace texfab::print
