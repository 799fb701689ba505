// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Writing files so that a failure never leaves a partial output: every file is written under a
// temporary name in its own folder, then renamed onto its name (an atomic step on one file
// system). Each function throws texfab::Error naming the file, and the system's reason, on failure.
//
// Temporaries are registered while they exist, so that a process stopped by a signal can remove
// them (removeRegisteredTemporaries): the registry is the one piece of process-wide state here.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace texfab {

struct Context;

/// A temporary name next to `path` (same folder, so the final rename is atomic), registered until
/// commitFile() or discardTemporary().
std::filesystem::path temporaryPathFor(const std::filesystem::path& path);

/// Renames `tmp` onto `path`, removing `tmp` and throwing texfab::Error on failure.
void commitFile(const std::filesystem::path& tmp, const std::filesystem::path& path);

/// Removes a temporary (a file or a folder) and forgets it; never throws.
void discardTemporary(const std::filesystem::path& tmp);

/// `message` with OutputSet's staging folders taken out of the paths it names, so that an error in
/// writing a staged output names the output as the user gave it ("out/a.glb", not
/// "out/.texfab-output.tmp-41-0/a.glb").
std::string withOutputNames(std::string message);

/// Removes every registered temporary. For a signal handler's thread, just before the process exits.
void removeRegisteredTemporaries();

/// Writes a file through `write(stream)` to a temporary name, then renames it onto `path`. On any
/// failure the temporary file is removed and texfab::Error names `path`.
void writeFileAtomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

/// Throws texfab::Error unless a file can be created at `path`: its folder exists and is writable,
/// and `path` is not a folder. The message names `path` and the reason ("Permission denied").
void checkOutputLocation(const std::filesystem::path& path);

/// "path: what: reason" from an errno value, e.g. "out/a.png: cannot create file: Permission denied".
std::string systemError(const std::filesystem::path& path, const std::string& what, int errnum);

/// The outputs of one job, written all or nothing. Each output is written under its own file name
/// into a hidden staging folder beside it (same file system); commit() moves everything staged
/// into place once every output is complete. Until then nothing appears under an output's name, and
/// when the set is destroyed uncommitted (an error, a cancel) its staging folders are removed.
/// Files a writer adds beside a staged output (an OBJ's .mtl and textures, a .gltf's .bin) are
/// staged and committed with it.
class OutputSet {
public:
  OutputSet() = default;
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;
  ~OutputSet();

  /// Reserves the output file `path`, checking now that it can be written (checkOutputLocation);
  /// returns where to write it.
  std::filesystem::path add(const std::filesystem::path& path);
  /// Reserves a new output folder `path`, which must not exist or be empty; returns the staged
  /// folder to fill.
  std::filesystem::path addFolder(const std::filesystem::path& path);
  /// Runs `step` at commit, before the staged files move: an output staged by its own writer (a
  /// slice folder) that must appear with the others, or not at all.
  void atCommit(std::function<void()> step) { steps_.push_back(std::move(step)); }
  /// Moves every staged file into place (the atCommit steps, then side files, then reserved outputs
  /// in the order they were added). Throws Cancelled first if `ctx` has been cancelled.
  void commit(const Context& ctx);

private:
  struct Staging {
    std::filesystem::path folder;  ///< the destination folder
    std::filesystem::path staging; ///< the hidden folder inside it
  };
  const Staging& stagingFor(const std::filesystem::path& folder);
  std::filesystem::path reserve(const std::filesystem::path& path);
  std::vector<Staging> stagings_;
  std::vector<std::filesystem::path> outputs_;  ///< the reserved final paths, in order
  std::vector<std::function<void()>> steps_;
  bool committed_ = false;
};

} // namespace texfab
