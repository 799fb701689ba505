// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The one error type texfab throws for bad input (files, images, meshes, parameters) and failed
// output. Its message is a single line that names the thing at fault, e.g.
//   "brick.pat: truncated pattern data (expected 49152 bytes, found 1200)".
// The command line prints it as "texfab <command>: error: <message>" and exits non-zero.
// Broken internal invariants are not Errors: they are bugs and assert.

#include <stdexcept>
#include <string>

namespace texfab {

class Error : public std::runtime_error {
public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

} // namespace texfab
