// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Raw little-endian values and length-prefixed vectors: the format of texfab's own cache files
// (solid analyses, solid tile sets). A reader that meets a short file or an unexpected length
// clears `ok`, and the cache recomputes.

#include <array>
#include <cstdint>
#include <istream>
#include <ostream>
#include <vector>

namespace texfab::synthesis {

struct BinaryWriter {
  std::ostream& out;
  void raw(const void* d, size_t n) { out.write(static_cast<const char*>(d), std::streamsize(n)); }
  template <class T> void value(const T& v) { raw(&v, sizeof v); }
  template <class T> void vec(const std::vector<T>& v) {
    value(uint64_t(v.size()));
    raw(v.data(), v.size() * sizeof(T));
  }
};

struct BinaryReader {
  std::istream& in;
  bool ok = true;
  void raw(void* d, size_t n) { ok = ok && bool(in.read(static_cast<char*>(d), std::streamsize(n))); }
  template <class T> void value(T& v) { raw(&v, sizeof v); }
  /// Reads a vector that must hold `expected` values.
  template <class T> void vec(std::vector<T>& v, size_t expected) { vec(v, {expected, expected}); }
  /// Reads a vector that must hold one of two counts.
  template <class T> void vec(std::vector<T>& v, std::array<size_t, 2> allowed) {
    uint64_t n = 0;
    value(n);
    if (!ok || (n != allowed[0] && n != allowed[1])) {
      ok = false;
      return;
    }
    v.resize(n);
    raw(v.data(), n * sizeof(T));
  }
};

} // namespace texfab::synthesis
