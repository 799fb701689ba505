// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Writing files so that a failure never leaves a partial output: every file is written under a
// temporary name in its own folder, then renamed onto its name (an atomic step on one file
// system). Each function throws texfab::Error naming the file on failure.

#include <filesystem>
#include <functional>
#include <ostream>

namespace texfab {

/// A temporary name next to `path` (same folder, so the final rename is atomic).
std::filesystem::path temporaryPathFor(const std::filesystem::path& path);

/// Renames `tmp` onto `path`, removing `tmp` and throwing texfab::Error on failure.
void commitFile(const std::filesystem::path& tmp, const std::filesystem::path& path);

/// Writes a file through `write(stream)` to a temporary name, then renames it onto `path`. On any
/// failure the temporary file is removed and texfab::Error names `path`.
void writeFileAtomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

} // namespace texfab
