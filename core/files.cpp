// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/files.h"

#include "core/context.h"
#include "core/error.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <system_error>

namespace texfab {
namespace fs = std::filesystem;

namespace {

// The registered temporaries (see files.h).
std::mutex& registryMutex() {
  static std::mutex m;
  return m;
}
std::set<fs::path>& registry() {
  static std::set<fs::path> paths;
  return paths;
}

void registerTemporary(const fs::path& tmp) {
  const std::lock_guard lock(registryMutex());
  registry().insert(tmp);
}

void forgetTemporary(const fs::path& tmp) {
  const std::lock_guard lock(registryMutex());
  registry().erase(tmp);
}

fs::path folderOf(const fs::path& path) { return path.parent_path().empty() ? fs::path(".") : path.parent_path(); }

} // namespace

std::string systemError(const fs::path& path, const std::string& what, int errnum) {
  return path.string() + ": " + what + ": " + std::strerror(errnum);
}

fs::path temporaryPathFor(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  // Built by appending: GCC 12 warns falsely (-Wrestrict, PR 105329) on "literal" + string here.
  std::string tmpName(".");
  tmpName.append(path.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  tmpName.append("-").append(std::to_string(counter++));
  const fs::path tmp = path.parent_path() / tmpName;
  registerTemporary(tmp);
  return tmp;
}

void discardTemporary(const fs::path& tmp) {
  std::error_code ec;
  fs::remove_all(tmp, ec);
  forgetTemporary(tmp);
}

void removeRegisteredTemporaries() {
  const std::lock_guard lock(registryMutex());
  for (const fs::path& tmp : registry()) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
  }
  registry().clear();
}

void commitFile(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    discardTemporary(tmp);
    throw Error(path.string() + ": cannot write file: " + ec.message());
  }
  forgetTemporary(tmp);
}

void writeFileAtomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  const fs::path tmp = temporaryPathFor(path);
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) {
      const int err = errno;
      discardTemporary(tmp);
      throw Error(systemError(path, "cannot create file", err));
    }
    try {
      write(out);
    } catch (...) {
      out.close();
      discardTemporary(tmp);
      throw;
    }
    out.flush();
    if (!out) {
      const int err = errno;
      out.close();
      discardTemporary(tmp);
      throw Error(systemError(path, "cannot write file", err));
    }
  }
  commitFile(tmp, path);
}

void checkOutputLocation(const fs::path& path) {
  if (path.empty() || path.filename().empty() || path.filename() == "." || path.filename() == "..")
    throw Error("'" + path.string() + "': not a file name");
  const fs::path folder = folderOf(path);
  std::error_code ec;
  if (!fs::exists(folder, ec)) throw Error(path.string() + ": folder " + folder.string() + " does not exist");
  if (!fs::is_directory(folder, ec)) throw Error(path.string() + ": " + folder.string() + " is not a folder");
  if (fs::is_directory(path, ec)) throw Error(path.string() + ": is a folder");
  if (::access(folder.c_str(), W_OK | X_OK) != 0) throw Error(systemError(path, "cannot write in " + folder.string(), errno));
}

OutputSet::~OutputSet() {
  if (committed_) return;
  for (const Staging& s : stagings_) discardTemporary(s.staging);
}

std::string withOutputNames(std::string message) {
  static constexpr std::string_view kStaging = ".texfab-output.tmp-";  // temporaryPathFor(folder / "texfab-output")
  for (size_t at = message.find(kStaging); at != std::string::npos; at = message.find(kStaging, at)) {
    size_t end = at + kStaging.size();
    while (end < message.size() && (std::isdigit(static_cast<unsigned char>(message[end])) || message[end] == '-')) ++end;
    if (end < message.size() && message[end] == '/') message.erase(at, end + 1 - at);
    else at = end;
  }
  return message;
}

const OutputSet::Staging& OutputSet::stagingFor(const fs::path& folder) {
  std::error_code ec;
  const fs::path key = fs::weakly_canonical(folder, ec);
  for (const Staging& s : stagings_)
    if (s.folder == key) return s;
  // A hidden folder in the destination folder: creating it is the writability check.
  fs::path staging = temporaryPathFor(folder / "texfab-output");
  if (::mkdir(staging.c_str(), 0777) != 0) {
    const int err = errno;
    forgetTemporary(staging);
    throw Error(systemError(folder, "cannot write in this folder", err));
  }
  stagings_.push_back({key, std::move(staging)});
  return stagings_.back();
}

fs::path OutputSet::reserve(const fs::path& path) {
  std::error_code ec;
  const fs::path final = fs::weakly_canonical(path, ec);
  if (std::find(outputs_.begin(), outputs_.end(), final) != outputs_.end())
    throw Error(path.string() + ": named as two outputs");
  const fs::path staged = stagingFor(folderOf(path)).staging / path.filename();
  outputs_.push_back(final);
  return staged;
}

fs::path OutputSet::add(const fs::path& path) {
  checkOutputLocation(path);
  return reserve(path);
}

fs::path OutputSet::addFolder(const fs::path& path) {
  fs::path folder = path;
  if (folder.filename().empty()) folder = folder.parent_path();  // "dir/" names the folder "dir"
  std::error_code ec;
  if (fs::is_directory(folder, ec)) {
    if (!fs::is_empty(folder, ec)) throw Error(path.string() + ": output folder exists and is not empty");
    if (::access(folderOf(folder).c_str(), W_OK | X_OK) != 0)
      throw Error(systemError(folder, "cannot write in " + folderOf(folder).string(), errno));
  } else {
    checkOutputLocation(folder);
  }
  const fs::path staged = reserve(folder);
  fs::create_directory(staged, ec);
  if (ec) throw Error(path.string() + ": cannot create folder: " + ec.message());
  return staged;
}

void OutputSet::commit(const Context& ctx) {
  ctx.checkCancelled();
  for (const auto& step : steps_) step();
  // Side files first, then the reserved outputs in order: a model never points at missing files.
  for (const Staging& s : stagings_) {
    std::vector<fs::path> entries;
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(s.staging, ec)) entries.push_back(e.path());
    // Rank: side files 0, then reserved outputs by the order they were added.
    auto rank = [&](const fs::path& p) {
      const auto it = std::find(outputs_.begin(), outputs_.end(), s.folder / p.filename());
      return it == outputs_.end() ? 0 : 1 + (it - outputs_.begin());
    };
    std::stable_sort(entries.begin(), entries.end(), [&](const fs::path& a, const fs::path& b) { return rank(a) < rank(b); });
    for (const fs::path& e : entries) {
      const fs::path final = s.folder / e.filename();
      if (fs::is_directory(final, ec) && fs::is_empty(final, ec)) fs::remove(final, ec);
      fs::rename(e, final, ec);
      if (ec) throw Error(final.string() + ": cannot write: " + ec.message());
    }
  }
  committed_ = true;
  for (const Staging& s : stagings_) discardTemporary(s.staging);
}

} // namespace texfab
