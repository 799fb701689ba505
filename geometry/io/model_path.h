// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Resolving the references a model file makes to other files (MTL libraries, textures, glTF
// buffers and images) without ever leaving the model's folder.

#include <filesystem>
#include <string>

namespace texfab::geometry {

/// Resolves `reference`, found in the model file `model`, to a path inside model's folder.
/// Throws texfab::Error ("<model>: reference '<ref>' ...") when the reference is empty, absolute
/// ("/x", "\\x", "C:x"), has a URI scheme ("http:", "file:", ...), contains a ".." component, or
/// resolves (following symbolic links) outside the folder. When `uriEncoded` (glTF), %XX escapes
/// are decoded first, so "%2E%2E/" is refused too. Backslashes count as separators.
std::filesystem::path resolveModelReference(const std::filesystem::path& model, const std::string& reference,
                                            bool uriEncoded = false);

/// Percent-decodes a URI path ("a%20b.png" -> "a b.png"); malformed escapes throw texfab::Error.
std::string decodeUriPath(const std::string& uri);

} // namespace texfab::geometry
