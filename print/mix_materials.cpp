// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: D. Shaked, N. Arad, A. Fitzhugh, I. Sobel. Color Diffusion: Error-Diffusion for Color
//   Halftones. HP Labs HPL-96-128R1, 1999 (minimal brightness variation).
#include "print/mix_materials.h"

#include "core/error.h"
#include "core/mip_pyramid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace texfab::print {

namespace {

constexpr double kBrightnessWeight = 0.02;  // lambda: how much faint noise may cost in colour accuracy
constexpr int kMaxSupport = 4;              // materials a colour in 3-D needs at most

double luminance(const std::array<float, 3>& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

// Solves the n x n system a x = b in place (Gaussian elimination, partial pivoting); false when
// singular.
bool solve(std::array<std::array<double, kMaxSupport + 1>, kMaxSupport + 1>& a, std::array<double, kMaxSupport + 1>& b,
           int n) {
  for (int col = 0; col < n; ++col) {
    int pivot = col;
    for (int r = col + 1; r < n; ++r)
      if (std::abs(a[size_t(r)][size_t(col)]) > std::abs(a[size_t(pivot)][size_t(col)])) pivot = r;
    if (std::abs(a[size_t(pivot)][size_t(col)]) < 1e-12) return false;
    std::swap(a[size_t(pivot)], a[size_t(col)]);
    std::swap(b[size_t(pivot)], b[size_t(col)]);
    for (int r = col + 1; r < n; ++r) {
      const double f = a[size_t(r)][size_t(col)] / a[size_t(col)][size_t(col)];
      for (int c = col; c < n; ++c) a[size_t(r)][size_t(c)] -= f * a[size_t(col)][size_t(c)];
      b[size_t(r)] -= f * b[size_t(col)];
    }
  }
  for (int r = n - 1; r >= 0; --r) {
    for (int c = r + 1; c < n; ++c) b[size_t(r)] -= a[size_t(r)][size_t(c)] * b[size_t(c)];
    b[size_t(r)] /= a[size_t(r)][size_t(r)];
  }
  return true;
}

// The mix of `colors` for target c: the best over supports of 1-4 materials of the problem
// restricted to the support with sum f = 1 (its KKT system), keeping solutions with f >= 0.
// Supports are tried smallest first, then by mask, and a later one must be strictly better.
std::vector<double> bestMix(const std::vector<std::array<float, 3>>& colors, const std::array<float, 3>& c) {
  const int n = int(colors.size());
  const double yc = luminance(c);
  std::vector<double> spread(static_cast<size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) spread[size_t(i)] = kBrightnessWeight * std::pow(luminance(colors[size_t(i)]) - yc, 2);
  std::vector<double> best(size_t(n), 0.0);
  double bestCost = std::numeric_limits<double>::infinity();
  for (int support = 1; support <= std::min(n, kMaxSupport); ++support)
    for (uint32_t mask = 1; mask < (1u << n); ++mask) {
      if (std::popcount(mask) != support) continue;
      int idx[kMaxSupport], k = 0;
      for (int i = 0; i < n; ++i)
        if (mask >> i & 1) idx[k++] = i;
      std::array<std::array<double, kMaxSupport + 1>, kMaxSupport + 1> a{};
      std::array<double, kMaxSupport + 1> b{};
      for (int r = 0; r < k; ++r) {
        const auto& mr = colors[size_t(idx[r])];
        for (int s = 0; s < k; ++s) {
          const auto& ms = colors[size_t(idx[s])];
          a[size_t(r)][size_t(s)] = 2.0 * (double(mr[0]) * ms[0] + double(mr[1]) * ms[1] + double(mr[2]) * ms[2]);
        }
        a[size_t(r)][size_t(k)] = 1.0;
        a[size_t(k)][size_t(r)] = 1.0;
        b[size_t(r)] = 2.0 * (double(mr[0]) * c[0] + double(mr[1]) * c[1] + double(mr[2]) * c[2]) - spread[size_t(idx[r])];
      }
      b[size_t(k)] = 1.0;
      if (!solve(a, b, k + 1)) continue;
      if (std::any_of(b.begin(), b.begin() + k, [](double f) { return f < -1e-9; })) continue;
      double mixed[3] = {0, 0, 0}, cost = 0;
      for (int r = 0; r < k; ++r) {
        const double f = std::max(0.0, b[size_t(r)]);
        for (int ch = 0; ch < 3; ++ch) mixed[ch] += f * colors[size_t(idx[r])][size_t(ch)];
        cost += f * spread[size_t(idx[r])];
      }
      for (int ch = 0; ch < 3; ++ch) cost += std::pow(mixed[ch] - c[size_t(ch)], 2);
      if (!(cost < bestCost - 1e-12)) continue;
      bestCost = cost;
      std::fill(best.begin(), best.end(), 0.0);
      for (int r = 0; r < k; ++r) best[size_t(idx[r])] = std::max(0.0, b[size_t(r)]);
    }
  double sum = 0;
  for (double f : best) sum += f;
  for (double& f : best) f /= sum;
  return best;
}

} // namespace

MaterialMixer::MaterialMixer(const std::vector<PrintMaterial>& materials) {
  validatePrintMaterials(materials, "materials");
  for (const PrintMaterial& m : materials)
    linear_.push_back({srgbToLinear(m.color[0] / 255.0f), srgbToLinear(m.color[1] / 255.0f), srgbToLinear(m.color[2] / 255.0f)});
  for (int i = 0; i < int(materials.size()); ++i) {
    if (materials[size_t(i)].opaque()) opaque_.push_back(i);
    else if (translucent_ < 0) translucent_ = i;
  }
  if (opaque_.size() > 16)
    throw Error("materials: " + std::to_string(opaque_.size()) + " opaque materials, at most 16 can be mixed");
  std::vector<std::array<float, 3>> colors;
  for (int i : opaque_) colors.push_back(linear_[size_t(i)]);
  const size_t n = opaque_.size();
  table_.resize(size_t(kLattice) * kLattice * kLattice * n);
  for (int b = 0; b < kLattice; ++b)
    for (int g = 0; g < kLattice; ++g)
      for (int r = 0; r < kLattice; ++r) {
        const std::array<float, 3> c{float(r) / (kLattice - 1), float(g) / (kLattice - 1), float(b) / (kLattice - 1)};
        const std::vector<double> f = bestMix(colors, c);
        const size_t at = (size_t(r) + size_t(kLattice) * (size_t(g) + size_t(kLattice) * size_t(b))) * n;
        for (size_t i = 0; i < n; ++i) table_[at + i] = float(f[i]);
      }
}

void MaterialMixer::fractions(const float rgb[3], float* out) const {
  const size_t n = opaque_.size();
  int i0[3];
  float w[3];
  for (int ch = 0; ch < 3; ++ch) {
    const float p = std::clamp(std::isfinite(rgb[ch]) ? rgb[ch] : 0.0f, 0.0f, 1.0f) * float(kLattice - 1);
    i0[ch] = std::min(int(p), kLattice - 2);
    w[ch] = p - float(i0[ch]);
  }
  std::fill(out, out + n, 0.0f);
  for (int corner = 0; corner < 8; ++corner) {
    const int dr = corner & 1, dg = corner >> 1 & 1, db = corner >> 2 & 1;
    const float weight = (dr ? w[0] : 1 - w[0]) * (dg ? w[1] : 1 - w[1]) * (db ? w[2] : 1 - w[2]);
    const size_t at = (size_t(i0[0] + dr) + size_t(kLattice) * (size_t(i0[1] + dg) + size_t(kLattice) * size_t(i0[2] + db))) * n;
    for (size_t i = 0; i < n; ++i) out[i] += weight * table_[at + i];
  }
}

MaterialMixer::Mix MaterialMixer::mix(const float rgba[4]) const {
  Mix m;
  m.alpha = std::clamp(std::isfinite(rgba[3]) ? rgba[3] : 1.0f, 0.0f, 1.0f);
  float f[16];
  fractions(rgba, f);
  float cumulative = 0;
  for (size_t i = 0; i < opaque_.size(); ++i) m.cumulative[i] = cumulative += f[i];
  return m;
}

int MaterialMixer::pick(const Mix& m, float t) const {
  if (translucent_ >= 0) {
    if (t >= m.alpha) return translucent_;
    t /= m.alpha;
  }
  for (size_t i = 0; i + 1 < opaque_.size(); ++i)
    if (t < m.cumulative[i]) return opaque_[i];
  return opaque_.back();
}

int MaterialMixer::pick(const float rgba[4], float t) const { return pick(mix(rgba), t); }

std::array<float, 3> MaterialMixer::reproduced(const float rgb[3]) const {
  float f[16];
  fractions(rgb, f);
  std::array<float, 3> c{0, 0, 0};
  for (size_t i = 0; i < opaque_.size(); ++i)
    for (int ch = 0; ch < 3; ++ch) c[size_t(ch)] += f[i] * linear_[size_t(opaque_[i])][size_t(ch)];
  return c;
}

int MaterialMixer::nearest(const float rgb[3]) const {
  int best = opaque_.front();
  float bestDistance = std::numeric_limits<float>::infinity();
  for (int i : opaque_) {
    const auto& m = linear_[size_t(i)];
    const float d = (m[0] - rgb[0]) * (m[0] - rgb[0]) + (m[1] - rgb[1]) * (m[1] - rgb[1]) + (m[2] - rgb[2]) * (m[2] - rgb[2]);
    if (d < bestDistance) bestDistance = d, best = i;
  }
  return best;
}

} // namespace texfab::print
