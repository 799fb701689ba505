// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The fuzz targets: every reader texfab owns, and every entry where it hands a file's bytes to a
// library (tinygltf, Draco, lib3mf, OpenImageIO, LittleCMS, nlohmann::json). A target gives one input
// to its reader the way a user's file reaches it: as a file of that format in a scratch folder, or
// as bytes in memory where texfab decodes from memory (images embedded in models).
//
// Refusing an input with texfab::Error is the expected end of most inputs. Anything else is a
// finding: another exception escaping, a crash, a sanitizer report, a hang, or a reader that accepts
// an input and returns a value breaking its own contract (a mesh validateMesh refuses, an image whose
// pixel count does not match its size); those abort with a message.
//
// libFuzzer runs them (fuzz_main.cpp, scripts/fuzz.sh); the test suite runs every target on its
// seeds and on the inputs of tests/fuzz/regressions/<target>/ (fuzz_regression_test.cpp).

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

namespace texfab::fuzz {

struct FuzzTarget {
  const char* name;  ///< e.g. "mesh_obj"; also the regression folder's name
  const char* what;  ///< one line: the reader and the format
  /// Feeds one input to the reader: true when it loads, false when it is refused with texfab::Error.
  bool (*run)(std::span<const uint8_t> input);
  /// Writes the seed inputs (valid files made from the test models) into `folder`.
  void (*writeSeeds)(const std::filesystem::path& folder);
};

/// All targets, in a fixed order.
std::span<const FuzzTarget> fuzzTargets();

/// The target named `name`, or null.
const FuzzTarget* findFuzzTarget(std::string_view name);

} // namespace texfab::fuzz
