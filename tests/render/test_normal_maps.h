// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Normal maps for the tests of normal-map filtering and of its shading in previews: three materials
// as tiling height fields turned into tangent-space normal maps.
#include "core/hash.h"
#include "core/image.h"

#include <Eigen/Core>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace texfab::test {

// Tiling value noise: bilinear between hashed lattice values `period` texels apart.
inline double valueNoise(uint32_t seed, double x, double y, int periodX, int periodY, int size) {
  const auto lattice = [&](int i, int j) {
    const int nx = size / periodX, ny = size / periodY;
    return unitInterval(counterHash(seed, uint32_t((i % nx + nx) % nx), uint32_t((j % ny + ny) % ny)));
  };
  const double u = x / periodX, v = y / periodY;
  const int i = int(std::floor(u)), j = int(std::floor(v));
  const double s = u - i, t = v - j;
  return (1 - t) * ((1 - s) * lattice(i, j) + s * lattice(i + 1, j)) + t * ((1 - s) * lattice(i, j + 1) + s * lattice(i + 1, j + 1));
}

// A normal map of a tiling height field: n ∝ (-gain dh/dx, -gain dh/dy, 1), encoded as (n + 1) / 2.
inline Image normalMap(int size, double gain, const std::function<double(int, int)>& height) {
  Image map(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double dx = (height((x + 1) % size, y) - height((x + size - 1) % size, y)) / 2;
      const double dy = (height(x, (y + 1) % size) - height(x, (y + size - 1) % size)) / 2;
      const Eigen::Vector3d n = Eigen::Vector3d(-gain * dx, -gain * dy, 1).normalized();
      for (int c = 0; c < 3; ++c) map.at(x, y, c) = float((n[c] + 1) / 2);
    }
  return map;
}

struct TestMap {
  std::string name;
  Image map;
};

// The three materials, as height fields: bumpy stone (noise at two scales), brushed metal
// (grooves along x: noise that changes every row, slowly along it) and fabric (a plain weave).
inline std::vector<TestMap> testMaps(int size) {
  std::vector<TestMap> maps;
  maps.push_back({"stone", normalMap(size, 2.0, [&](int x, int y) {
                    return 6 * valueNoise(1, x, y, 16, 16, size) + 2 * valueNoise(2, x, y, 4, 4, size);
                  })});
  maps.push_back({"brushed metal", normalMap(size, 1.5, [&](int x, int y) {
                    return 1.5 * valueNoise(3, x, y, 32, 1, size);
                  })});
  maps.push_back({"fabric", normalMap(size, 1.0, [&](int x, int y) {
                    const bool warp = ((x / 8) + (y / 8)) % 2 == 0;
                    const double s = std::sin(3.14159265358979323846 * ((warp ? x : y) % 8) / 8.0);
                    return 3 * s * s;
                  })});
  return maps;
}

} // namespace texfab::test
