// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// TexelField<T>: one value per atlas texel, contiguous and row-major (row 0 = top of the atlas
// image, as in texfab::Image), restricted to trivially copyable T so that a field can be copied to
// a GPU buffer as-is.

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace texfab::atlas {

template <class T>
struct TexelField {
  static_assert(std::is_trivially_copyable_v<T>, "TexelField<T> needs a trivially copyable T");
  int width = 0;
  int height = 0;
  std::vector<T> values; ///< width * height, row-major

  TexelField() = default;
  TexelField(int w, int h, const T& fill = T{})
      : width(w), height(h), values(static_cast<size_t>(w) * static_cast<size_t>(h), fill) {}

  size_t index(int x, int y) const { return static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x); }
  bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  T& at(int x, int y) { return values[index(x, y)]; }
  const T& at(int x, int y) const { return values[index(x, y)]; }
  bool empty() const { return values.empty(); }
};

/// 3 floats, trivially copyable (Eigen types are kept out of texel fields).
struct Float3 {
  float x = 0, y = 0, z = 0;
};

/// Where a texel center lies on the surface: triangle id and barycentrics (b0 = 1 - b1 - b2
/// belongs to the triangle's first corner). chart = -1 marks an empty texel (gutter or unused).
struct SurfaceSample {
  int32_t chart = -1;
  uint32_t triangle = 0;
  float b1 = 0, b2 = 0;
};

} // namespace texfab::atlas
