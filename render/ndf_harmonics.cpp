// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/ndf_harmonics.h"

#include "core/error.h"
#include "core/parallel.h"
#include "render/filter_normal_map.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace texfab::render {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxOrder = 16;

int coefficientCount(int order) { return (order + 1) * (order + 1); }

// sqrt((2l + 1) / 4π · (l - m)! / (l + m)!), times sqrt(2) for m > 0 (real harmonics).
double normalization(int l, int m) {
  double ratio = 1;
  for (int k = l - m + 1; k <= l + m; ++k) ratio /= k;
  return std::sqrt((2 * l + 1) / (4 * kPi) * ratio) * (m > 0 ? std::sqrt(2.0) : 1.0);
}

// Sums over a texel's footprint of Y_lm(n), and how many normals.
struct Sums {
  int width = 0, height = 0, count = 0;
  std::vector<double> sum;
  std::vector<int> normals;
};

NdfHarmonicsLevel meansOf(const Sums& s) {
  NdfHarmonicsLevel level{s.width, s.height, s.count, std::vector<float>(s.sum.size())};
  for (size_t t = 0; t < s.normals.size(); ++t)
    for (int i = 0; i < s.count; ++i)
      level.coefficients[t * size_t(s.count) + size_t(i)] = float(s.sum[t * size_t(s.count) + size_t(i)] / s.normals[t]);
  return level;
}

// The next level: each side halves rounding up; a texel sums its (up to) 2x2 children.
Sums coarser(const Sums& fine, const Context& ctx) {
  Sums c{(fine.width + 1) / 2, (fine.height + 1) / 2, fine.count, {}, {}};
  c.sum.assign(size_t(c.width) * size_t(c.height) * size_t(c.count), 0.0);
  c.normals.assign(size_t(c.width) * size_t(c.height), 0);
  parallelFor(0, c.height, ctx, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < c.width; ++x) {
        const size_t t = size_t(y) * size_t(c.width) + size_t(x);
        for (int fy = 2 * y; fy < std::min(2 * y + 2, fine.height); ++fy)
          for (int fx = 2 * x; fx < std::min(2 * x + 2, fine.width); ++fx) {
            const size_t f = size_t(fy) * size_t(fine.width) + size_t(fx);
            for (int i = 0; i < c.count; ++i) c.sum[t * size_t(c.count) + size_t(i)] += fine.sum[f * size_t(c.count) + size_t(i)];
            c.normals[t] += fine.normals[f];
          }
      }
  });
  return c;
}

} // namespace

std::span<const float> NdfHarmonicsLevel::texel(int x, int y) const {
  return {coefficients.data() + (size_t(y) * size_t(width) + size_t(x)) * size_t(coefficientsPerTexel),
          size_t(coefficientsPerTexel)};
}

void sphericalHarmonics(const Eigen::Vector3f& n, int order, std::span<float> out) {
  const double x = n.x(), y = n.y(), z = n.z();
  // (x + iy)^m = sin^m θ e^{imφ}; P_l^m(z) / sin^m θ by the usual recurrences.
  double cm = 1, sm = 0;  // real and imaginary parts of (x + iy)^m
  for (int m = 0; m <= order; ++m) {
    double pmm = 1;  // (2m - 1)!!
    for (int k = 1; k <= m; ++k) pmm *= 2 * k - 1;
    double lower = 0, p = pmm;
    for (int l = m; l <= order; ++l) {
      if (l == m + 1) lower = p, p = z * (2 * m + 1) * pmm;
      else if (l > m + 1) {
        const double next = ((2 * l - 1) * z * p - (l + m - 1) * lower) / (l - m);
        lower = p, p = next;
      }
      const double k = normalization(l, m) * p;
      out[size_t(l * l + l + m)] = float(k * cm);
      if (m > 0) out[size_t(l * l + l - m)] = float(k * sm);
    }
    const double c = cm * x - sm * y, s = cm * y + sm * x;
    cm = c, sm = s;
  }
}

std::vector<double> blinnPhongBands(double exponent, int order) {
  // λ_l = (s + 1) ∫_0^1 t^s P_l(t) dt, by composite Simpson on 4096 intervals.
  constexpr int kIntervals = 4096;
  std::vector<double> bands(size_t(order + 1), 0.0);
  for (int i = 0; i <= kIntervals; ++i) {
    const double t = double(i) / kIntervals, w = (i == 0 || i == kIntervals ? 1 : i % 2 ? 4 : 2) / (3.0 * kIntervals);
    const double f = (exponent + 1) * std::pow(t, exponent) * w;
    double previous = 1, p = t;  // P_0, P_1
    for (int l = 0; l <= order; ++l) {
      const double pl = l == 0 ? 1 : p;
      bands[size_t(l)] += f * pl;
      if (l >= 1) {
        const double next = ((2 * l + 1) * t * p - l * previous) / (l + 1);
        previous = p, p = next;
      }
    }
  }
  return bands;
}

double shadeBlinnPhongHarmonics(std::span<const float> coefficients, int order, std::span<const double> bands,
                                const Eigen::Vector3f& light, const Eigen::Vector3f& half) {
  std::vector<float> y(size_t(coefficientCount(order)));
  sphericalHarmonics(half, order, y);
  double lobe = 0;
  for (int l = 0; l <= order; ++l)
    for (int m = -l; m <= l; ++m) lobe += bands[size_t(l)] * coefficients[size_t(l * l + l + m)] * y[size_t(l * l + l + m)];
  if (order < 1 || lobe <= 0) return 0;
  // Band 1 is sqrt(3 / 4π) (y, z, x) of the mean normal.
  const Eigen::Vector3f mean(coefficients[3], coefficients[1], coefficients[2]);
  const float length = mean.norm();
  return length > 0 ? lobe * std::max(0.0f, light.dot(mean) / length) : 0.0;
}

NdfHarmonics ndfHarmonics(const Image& map, const NdfHarmonicsOptions& o, const Context& ctx) {
  if (map.channels < 3 || map.width < 1 || map.height < 1)
    throw Error("normal-map filtering: a normal map has three channels (got " + std::to_string(map.channels) + ")");
  if (o.order < 0 || o.order > kMaxOrder) throw Error("normal-map filtering: the SH order must be in [0, 16]");
  Stage stage(ctx, "NDF harmonics");
  const int count = coefficientCount(o.order);
  Sums sums{map.width, map.height, count, std::vector<double>(size_t(map.width) * size_t(map.height) * size_t(count)),
            std::vector<int>(size_t(map.width) * size_t(map.height), 1)};
  parallelFor(0, map.height, ctx, [&](int y0, int y1) {
    std::vector<float> y(static_cast<size_t>(count));
    for (int py = y0; py < y1; ++py)
      for (int px = 0; px < map.width; ++px) {
        sphericalHarmonics(decodeNormal(map, px, py), o.order, y);
        std::copy(y.begin(), y.end(), sums.sum.begin() + std::ptrdiff_t((size_t(py) * size_t(map.width) + size_t(px)) * size_t(count)));
      }
  });
  NdfHarmonics out{o.order, {}};
  for (;;) {
    out.levels.push_back(meansOf(sums));
    if (sums.width == 1 && sums.height == 1) break;
    sums = coarser(sums, ctx);
  }
  stage.finish();
  return out;
}

} // namespace texfab::render
