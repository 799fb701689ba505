// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Helpers every test suite shares: a scratch folder and running a command.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>

#ifdef TEXFAB_CLI
#include "synthesis/backend.h"

#include <vector>
#endif

namespace texfab::test {

/// GIMP's pattern folder (Debian gimp-data).
inline std::filesystem::path gimpPatterns() { return "/usr/share/gimp/2.0/patterns"; }

/// A fresh, empty folder under the system temp folder for one test, removed by the destructor.
class TempDir {
public:
  explicit TempDir(const std::string& prefix = "texfab-test") {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            (prefix + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
  std::filesystem::path path_;
};

/// Runs a shell command; returns its exit status (128 if it did not exit normally).
inline int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

/// Where CGAL's mesh data set was extracted (models/fetch; $TEXFAB_CGAL_DATA overrides), or empty.
inline std::filesystem::path cgalDataDir() {
  if (const char* env = std::getenv("TEXFAB_CGAL_DATA"); env && *env) return env;
  const std::filesystem::path p = std::filesystem::path(TEXFAB_SOURCE_DIR) / "models" / "cgal";
  return std::filesystem::exists(p / "elephant.off") ? p : std::filesystem::path();
}

/// A file of CGAL's data set, or empty when the data set is absent (tests then skip).
inline std::filesystem::path cgalModel(const std::string& name) {
  const std::filesystem::path dir = cgalDataDir();
  return dir.empty() ? dir : dir / name;
}

/// What a command printed and how it ended.
struct CliResult {
  int status = -1;     ///< exit status; 128 + signal when killed
  std::string out, err;
  /// stderr's lines.
  size_t errLines() const { return size_t(std::count(err.begin(), err.end(), '\n')); }
};

inline std::string readFile(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  std::string text;
  if (!f) return text;
  std::array<char, 4096> buffer{};
  for (size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), f)) > 0;) text.append(buffer.data(), n);
  std::fclose(f);
  return text;
}

#ifdef TEXFAB_CLI
/// Why `texfab ... --backend vulkan --device 0` cannot run here (for GTEST_SKIP), or empty when it
/// can: the CLI suites run the texfab they link against, so they see the devices it sees.
inline std::string vulkanDeviceMissing() {
  const std::vector<synthesis::vulkan::DeviceInfo> devices = synthesis::vulkanDevices();
  if (devices.empty()) return "no Vulkan device";
  if (!devices[0].unusable.empty()) return "no usable Vulkan device (" + devices[0].name + ": " + devices[0].unusable + ")";
  return {};
}

/// Runs the texfab CLI with `args` (already quoted for the shell), capturing stdout and stderr.
inline CliResult runCli(const std::string& args) {
  static std::atomic<int> counter{0};
  const std::filesystem::path base = std::filesystem::temp_directory_path() /
                                     ("texfab-cli-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  const std::string command = std::string(TEXFAB_CLI) + " " + args + " >'" + base.string() + ".out' 2>'" +
                              base.string() + ".err' </dev/null";
  const int status = std::system(command.c_str());
  CliResult r;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  r.out = readFile(base.string() + ".out");
  r.err = readFile(base.string() + ".err");
  std::error_code ec;
  std::filesystem::remove(base.string() + ".out", ec);
  std::filesystem::remove(base.string() + ".err", ec);
  return r;
}
#endif

/// A path quoted for the shell.
inline std::string quote(const std::filesystem::path& path) {
  std::string q = "'";
  for (char c : path.string()) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// The Khronos glTF validator (npm gltf-validator) installed by scripts/install-deps.sh into
/// .tools/, or the node_modules folder named by $TEXFAB_GLTF_VALIDATOR.
inline std::filesystem::path gltfValidatorModules() {
  if (const char* env = std::getenv("TEXFAB_GLTF_VALIDATOR"); env && *env) return env;
  return std::filesystem::path(TEXFAB_SOURCE_DIR) / ".tools" / "node_modules";
}

/// Why the validator cannot run here (for GTEST_SKIP), or empty when it can.
inline std::string gltfValidatorMissing() {
  if (std::system("command -v node >/dev/null 2>&1") != 0) return "node not installed";
  if (!std::filesystem::exists(gltfValidatorModules() / "gltf-validator"))
    return "gltf-validator not installed (run scripts/install-deps.sh)";
  return {};
}

/// Runs the validator on a .glb/.gltf; returns its output, whose first line reads
/// "errors=N warnings=N ...".
inline std::string validateGltf(const std::filesystem::path& file) {
  const std::string command = "node '" + std::string(TEXFAB_SOURCE_DIR) + "/tests/geometry/validate_gltf.js' '" +
                              gltfValidatorModules().string() + "' '" + file.string() + "' 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), &pclose);
  std::string out;
  std::array<char, 4096> buffer{};
  while (pipe && fgets(buffer.data(), int(buffer.size()), pipe.get())) out += buffer.data();
  return out;
}

/// A GLB file's JSON chunk and what follows its binary chunk's header (the buffer, padded).
inline std::pair<std::string, std::string> glbChunks(const std::string& glb) {
  uint32_t jsonLength = 0;
  if (glb.size() >= 20) std::memcpy(&jsonLength, glb.data() + 12, 4);
  const size_t binAt = 20 + size_t(jsonLength) + 8;
  return {glb.substr(std::min<size_t>(20, glb.size()), jsonLength), binAt < glb.size() ? glb.substr(binAt) : std::string()};
}

/// three.js (npm three, for its Basis Universal transcoder) installed by scripts/install-deps.sh
/// into .tools/, or the node_modules folder named by $TEXFAB_THREE.
inline std::filesystem::path threeModules() {
  if (const char* env = std::getenv("TEXFAB_THREE"); env && *env) return env;
  return std::filesystem::path(TEXFAB_SOURCE_DIR) / ".tools" / "node_modules";
}

/// Why three's transcoder cannot run here (for GTEST_SKIP), or empty when it can.
inline std::string threeMissing() {
  if (std::system("command -v node >/dev/null 2>&1") != 0) return "node not installed";
  if (!std::filesystem::exists(threeModules() / "three" / "examples" / "jsm" / "libs" / "basis" / "basis_transcoder.wasm"))
    return "three not installed (run scripts/install-deps.sh)";
  return {};
}

/// Runs tests/core/ktx2_transcode.mjs on a KTX2 file (each level's RGBA8 to <prefix><level>.rgba);
/// returns its output, one JSON line.
inline std::string transcode(const std::filesystem::path& file, const std::filesystem::path& prefix) {
  const std::string command = "node " + quote(std::filesystem::path(TEXFAB_SOURCE_DIR) / "tests/core/ktx2_transcode.mjs") + " " +
                              quote(threeModules()) + " " + quote(file) + " " + quote(prefix) + " 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), &pclose);
  std::string out;
  std::array<char, 4096> buffer{};
  while (pipe && fgets(buffer.data(), int(buffer.size()), pipe.get())) out += buffer.data();
  return out;
}

} // namespace texfab::test
