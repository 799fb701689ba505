// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Analytic test surfaces for the atlas tests.

#include "geometry/mesh.h"

#include <cmath>
#include <filesystem>

namespace texfab::test {

/// A w×h grid of n×n quads in the z = 0 plane, counter-clockwise seen from +z.
inline geometry::Mesh makePlane(int n, float w = 1, float h = 1) {
  geometry::Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back({w * float(i) / float(n), h * float(j) / float(n), 0.0f});
  auto id = [n](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

/// An open cylinder of radius r around the z axis, height hgt, outward facing.
inline geometry::Mesh makeCylinder(int around, int rows, float r = 1, float hgt = 2) {
  geometry::Mesh m;
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i < around; ++i) {
      const float a = float(2 * M_PI * i / around);
      m.positions.push_back({r * std::cos(a), r * std::sin(a), hgt * float(j) / float(rows)});
    }
  auto id = [around](int i, int j) { return uint32_t(j * around + (i % around)); };
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < around; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

/// A UV sphere of radius r, closed, outward facing.
inline geometry::Mesh makeSphere(int around, int rings, float r = 1) {
  geometry::Mesh m;
  m.positions.push_back({0, 0, r});
  for (int j = 1; j < rings; ++j) {
    const double th = M_PI * j / rings;
    for (int i = 0; i < around; ++i) {
      const double ph = 2 * M_PI * i / around;
      m.positions.push_back({float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)), float(r * std::cos(th))});
    }
  }
  m.positions.push_back({0, 0, -r});
  const uint32_t south = uint32_t(m.positions.size() - 1);
  auto id = [around](int i, int j) { return uint32_t(1 + (j - 1) * around + (i % around)); };
  for (int i = 0; i < around; ++i) m.triangles.push_back({0, id(i, 1), id(i + 1, 1)});
  for (int j = 1; j < rings - 1; ++j)
    for (int i = 0; i < around; ++i) {
      m.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  for (int i = 0; i < around; ++i) m.triangles.push_back({id(i, rings - 1), south, id(i + 1, rings - 1)});
  return m;
}

} // namespace texfab::test
