// SPDX-License-Identifier: GPL-3.0-or-later
// Procedural solids with a known answer, for the solid texture benchmarks (issue 33): each is a
// colour per voxel, periodic with period 128 on every axis, built to look alike on every
// axis-aligned slice. A 128^2 slice serves as the exemplar; the solid's other slices are what a
// perfect solid synthesis from that exemplar could show at best, so measures of them bound what any
// solid method can reach.
#pragma once

#include "core/image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace texfab::test {

class ProceduralSolid {
public:
  static constexpr int kPeriod = 128;
  static const std::vector<std::string>& names() {
    static const std::vector<std::string> n{"clouds", "marble", "spots", "granite", "wood", "sand"};
    return n;
  }
  explicit ProceduralSolid(std::string kind) : kind_(std::move(kind)) {}
  bool valid() const {
    for (const std::string& n : names())
      if (n == kind_) return true;
    return false;
  }
  const std::string& kind() const { return kind_; }

  /// The exemplar: the side x side corner of the slice z = 0 (side <= kPeriod).
  Image exemplar(int side = kPeriod) const {
    side = std::min(side, kPeriod);
    Image out(side, side, 3);
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        const auto c = color(x, y, 0);
        for (int k = 0; k < 3; ++k) out.at(x, y, k) = c[size_t(k)];
      }
    return out;
  }

  std::array<float, 3> color(int64_t x, int64_t y, int64_t z) const {
    const std::array<double, 3> p{double(wrap(x)) + 0.5, double(wrap(y)) + 0.5, double(wrap(z)) + 0.5};
    if (kind_ == "clouds") {
      const double f = fbm(p, 32, 4);
      return ramp(f, {0.30, 0.22, 0.15}, {0.62, 0.50, 0.36}, {0.88, 0.80, 0.66});
    }
    if (kind_ == "marble") {  // veins across the diagonal, so that every axis sees them alike
      const double t = 2 * M_PI * (p[0] + p[1] + p[2]) / 64 + 7 * fbm(p, 32, 4);
      const double v = std::pow(std::fabs(std::sin(t)), 0.25);
      return ramp(v, {0.35, 0.30, 0.32}, {0.75, 0.70, 0.70}, {0.95, 0.93, 0.90});
    }
    if (kind_ == "spots") {  // balls of several sizes, darker rims, on a mottled ground
      const auto [d, r, id] = worley(p, 16);
      (void)id;
      const double g = 0.85 + 0.3 * (fbm(p, 16, 3) - 0.5);
      if (d < r * 0.7) return {float(0.25 * g), float(0.17 * g), float(0.08 * g)};
      if (d < r) return {float(0.12 * g), float(0.08 * g), float(0.05 * g)};
      return {float(0.85 * g), float(0.60 * g), float(0.28 * g)};
    }
    if (kind_ == "granite") {  // grains of three minerals
      const uint32_t id = worley(p, 8).id;
      const double b = 0.8 + 0.4 * fbm(p, 4, 2);
      static constexpr double mineral[3][3] = {{0.85, 0.80, 0.78}, {0.55, 0.35, 0.33}, {0.12, 0.12, 0.13}};
      const double* m = mineral[id % 3];
      return {float(m[0] * b), float(m[1] * b), float(m[2] * b)};
    }
    if (kind_ == "wood") {  // rings around axes along the diagonal
      const double r = distanceToDiagonalAxes(p);
      const double t = std::fabs(std::sin(2 * M_PI * r / 9 + 3 * fbm(p, 32, 3)));
      return ramp(std::pow(t, 3), {0.55, 0.35, 0.18}, {0.70, 0.48, 0.27}, {0.38, 0.22, 0.10});
    }
    const double f = fbm(p, 4, 2);  // sand: fine grains
    const double s = f > 0.62 ? 0.35 : f < 0.38 ? 1.0 : 0.7;
    return {float(0.80 * s), float(0.70 * s), float(0.50 * s)};
  }

private:
  static int64_t wrap(int64_t v) { return ((v % kPeriod) + kPeriod) % kPeriod; }

  static uint32_t hash(int64_t a, int64_t b, int64_t c, uint32_t salt) {
    uint64_t h = uint64_t(a) * 0x9E3779B97F4A7C15ull ^ uint64_t(b) * 0xC2B2AE3D27D4EB4Full ^
                 uint64_t(c) * 0x165667B19E3779F9ull ^ uint64_t(salt) * 0x27D4EB2F165667C5ull;
    h ^= h >> 31;
    h *= 0x7FB5D329728EA185ull;
    h ^= h >> 27;
    return uint32_t(h >> 32);
  }
  static double unit(uint32_t h) { return double(h) / 4294967296.0; }

  // Value noise on a lattice of `cell` voxels, periodic with kPeriod; quintic interpolation.
  static double noise(const std::array<double, 3>& p, int cell, uint32_t salt) {
    const int64_t n = kPeriod / cell;
    double f[3], w[3];
    int64_t i[3];
    for (int a = 0; a < 3; ++a) {
      const double q = p[size_t(a)] / cell;
      i[a] = int64_t(std::floor(q));
      f[a] = q - double(i[a]);
      w[a] = f[a] * f[a] * f[a] * (f[a] * (f[a] * 6 - 15) + 10);
    }
    double v = 0;
    for (int c = 0; c < 8; ++c) {
      double weight = 1;
      int64_t l[3];
      for (int a = 0; a < 3; ++a) {
        const int bit = (c >> a) & 1;
        l[a] = ((i[a] + bit) % n + n) % n;
        weight *= bit ? w[a] : 1 - w[a];
      }
      v += weight * unit(hash(l[0], l[1], l[2], salt));
    }
    return v;
  }
  static double fbm(const std::array<double, 3>& p, int cell, int octaves) {
    double v = 0, amplitude = 0.5, total = 0;
    for (int o = 0; o < octaves && cell >= 2; ++o, cell /= 2, amplitude *= 0.5) {
      v += amplitude * noise(p, cell, uint32_t(o + 1));
      total += amplitude;
    }
    return v / total;
  }

  // The nearest of one random point per cell of `cell` voxels: its distance, its radius, its id.
  struct Feature {
    double distance, radius;
    uint32_t id;
  };
  static Feature worley(const std::array<double, 3>& p, int cell) {
    const int64_t n = kPeriod / cell;
    double best = 1e30, radius = 0;
    uint32_t id = 0;
    int64_t c0[3];
    for (int a = 0; a < 3; ++a) c0[a] = int64_t(std::floor(p[size_t(a)] / cell));
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int64_t c[3] = {c0[0] + dx, c0[1] + dy, c0[2] + dz};
          const int64_t w[3] = {(c[0] % n + n) % n, (c[1] % n + n) % n, (c[2] % n + n) % n};
          double d2 = 0;
          for (int a = 0; a < 3; ++a) {
            const double q = (double(c[a]) + unit(hash(w[0], w[1], w[2], uint32_t(10 + a)))) * cell;
            d2 += (q - p[size_t(a)]) * (q - p[size_t(a)]);
          }
          if (d2 < best) {
            best = d2;
            const uint32_t h = hash(w[0], w[1], w[2], 20);
            radius = cell * (0.2 + 0.25 * unit(h));
            id = h % 1009;
          }
        }
    return {std::sqrt(best), radius, id};
  }
  static std::array<float, 3> ramp(double t, std::array<double, 3> a, std::array<double, 3> b,
                                   std::array<double, 3> c) {
    t = std::clamp(t, 0.0, 1.0);
    std::array<float, 3> out;
    for (size_t k = 0; k < 3; ++k)
      out[k] = float(t < 0.5 ? a[k] + (b[k] - a[k]) * 2 * t : b[k] + (c[k] - b[k]) * (2 * t - 1));
    return out;
  }
  // Distance to the nearest of the lines along (1,1,1) through the points of (kPeriod/2) Z^3.
  static double distanceToDiagonalAxes(const std::array<double, 3>& p) {
    const double s = kPeriod / 2.0;
    double best = 1e30;
    for (int dz = -1; dz <= 2; ++dz)
      for (int dy = -1; dy <= 2; ++dy)
        for (int dx = -1; dx <= 2; ++dx) {
          const double q[3] = {p[0] - dx * s, p[1] - dy * s, p[2] - dz * s};
          const double t = (q[0] + q[1] + q[2]) / 3;
          double d2 = 0;
          for (double v : q) d2 += (v - t) * (v - t);
          best = std::min(best, d2);
        }
    return std::sqrt(best);
  }

  std::string kind_;
};

} // namespace texfab::test
