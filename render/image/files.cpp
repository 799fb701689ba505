// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/image/files.h"

#include "render/image/error.h"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <string>
#include <system_error>

namespace texfab {
namespace fs = std::filesystem;

fs::path temporaryPathFor(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  // Built by appending: GCC 12 warns falsely (-Wrestrict, PR 105329) on "literal" + string here.
  std::string tmpName(".");
  tmpName.append(path.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  tmpName.append("-").append(std::to_string(counter++));
  return path.parent_path() / tmpName;
}

void commitFile(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(path.string() + ": cannot write file: " + ec.message());
  }
}

void writeFileAtomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  const fs::path tmp = temporaryPathFor(path);
  auto discard = [&] {
    std::error_code ec;
    fs::remove(tmp, ec);
  };
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw Error(path.string() + ": cannot create file");
    try {
      write(out);
    } catch (...) {
      out.close();
      discard();
      throw;
    }
    out.flush();
    if (!out) {
      out.close();
      discard();
      throw Error(path.string() + ": cannot write file (disk full?)");
    }
  }
  commitFile(tmp, path);
}

} // namespace texfab
