// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/io/model_path.h"

#include "core/error.h"

#include <algorithm>
#include <cctype>

namespace texfab::geometry {
namespace fs = std::filesystem;

std::string decodeUriPath(const std::string& uri) {
  std::string out;
  out.reserve(uri.size());
  auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] != '%') {
      out += uri[i];
      continue;
    }
    if (i + 2 >= uri.size() || hex(uri[i + 1]) < 0 || hex(uri[i + 2]) < 0)
      throw Error("malformed %-escape in URI '" + uri + "'");
    out += char(hex(uri[i + 1]) * 16 + hex(uri[i + 2]));
    i += 2;
  }
  return out;
}

fs::path resolveModelReference(const fs::path& model, const std::string& reference, bool uriEncoded) {
  const std::string where = model.string() + ": reference '" + reference + "'";
  if (reference.empty()) throw Error(where + " is empty");
  std::string ref = reference;
  if (uriEncoded) {
    try {
      ref = decodeUriPath(reference);
    } catch (const Error&) {
      throw Error(where + " has a malformed %-escape");
    }
  }
  if (ref.find('\0') != std::string::npos) throw Error(where + " contains a NUL character");
  for (char& c : ref)
    if (c == '\\') c = '/';
  if (ref.front() == '/') throw Error(where + " is an absolute path; only files inside the model's folder may be used");
  // A scheme is letters/digits/+/-/. before the first ':' (this also catches "C:" drive letters).
  const size_t colon = ref.find(':');
  if (colon != std::string::npos) {
    bool scheme = colon > 0 && std::isalpha(static_cast<unsigned char>(ref[0]));
    for (size_t i = 0; i < colon && scheme; ++i) {
      const unsigned char c = static_cast<unsigned char>(ref[i]);
      scheme = std::isalnum(c) || c == '+' || c == '-' || c == '.';
    }
    if (scheme) throw Error(where + " has a URI scheme or drive; only files inside the model's folder may be used");
  }
  size_t begin = 0;
  while (begin <= ref.size()) {
    const size_t end = std::min(ref.find('/', begin), ref.size());
    if (ref.compare(begin, end - begin, "..") == 0 && end - begin == 2)
      throw Error(where + " goes up with '..'; only files inside the model's folder may be used");
    begin = end + 1;
  }
  const fs::path folder = model.parent_path().empty() ? fs::path(".") : model.parent_path();
  const fs::path resolved = folder / fs::path(ref);
  // Symbolic links could still lead out: compare the canonical forms.
  std::error_code ec;
  const fs::path canonicalFolder = fs::weakly_canonical(folder, ec);
  const fs::path canonicalTarget = ec ? fs::path() : fs::weakly_canonical(resolved, ec);
  if (ec) throw Error(where + ": cannot resolve the path (" + ec.message() + ")");
  const auto [f, t] = std::mismatch(canonicalFolder.begin(), canonicalFolder.end(), canonicalTarget.begin(),
                                    canonicalTarget.end());
  if (f != canonicalFolder.end()) throw Error(where + " leads outside the model's folder (through a symbolic link)");
  return resolved;
}

} // namespace texfab::geometry
