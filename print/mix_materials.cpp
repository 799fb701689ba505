// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: D. Shaked, N. Arad, A. Fitzhugh, I. Sobel. Color Diffusion: Error-Diffusion for Color
//   Halftones. HP Labs HPL-96-128R1, 1999 (minimal brightness variation); CIE 15:2004 (CIELAB).
#include "print/mix_materials.h"

#include "core/error.h"
#include "core/mip_pyramid.h"
#include "print/color_difference.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace texfab::print {

namespace {

// lambda: how much faint noise may cost in colour accuracy. LinearRgb: against |M f - c|^2 with Y
// in [0, 1]. Perceptual: against ΔE2000^2 with L* in [0, 100]; smaller than the same balance would
// give (0.02), since CIEDE2000 discounts chroma by S_C and the term would then pull colours inside
// the gamut off exact (0.002 keeps them within 0.02 of linear light, as LinearRgb's does).
constexpr double kBrightnessWeight = 0.02;
constexpr double kLightnessWeight = 0.002;
constexpr int kGaussNewtonPasses = 4;  // Perceptual: linearizations of CIELAB, the first at the target
constexpr int kMaxSupport = 4;         // materials a colour in 3-D needs at most

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

// The mix of `colors` for target c, with `spread` the cost of each material's noise: the best over
// supports of 1-4 materials of  minimize |M f - c|^2 + sum_i f_i spread_i  restricted to the
// support with sum f = 1 (its KKT system), keeping solutions with f >= 0. Supports are tried
// smallest first, then by mask, and a later one must be strictly better.
std::vector<double> bestMix(const std::vector<std::array<double, 3>>& colors, const std::array<double, 3>& c,
                            const std::vector<double>& spread) {
  const int n = int(colors.size());
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
          a[size_t(r)][size_t(s)] = 2.0 * (mr[0] * ms[0] + mr[1] * ms[1] + mr[2] * ms[2]);
        }
        a[size_t(r)][size_t(k)] = 1.0;
        a[size_t(k)][size_t(r)] = 1.0;
        b[size_t(r)] = 2.0 * (mr[0] * c[0] + mr[1] * c[1] + mr[2] * c[2]) - spread[size_t(idx[r])];
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

// The problem of one lattice colour: the materials' colours and the target, in the space the error
// is measured in, and each material's noise cost. Perceptual: CIELAB linearized at the current mix
// p (J_p) and weighted by CIEDE2000's local metric at the target (W), so that
// |A f - b| = ΔE2000(Lab(c), Lab(p) + J_p (M f - p)) to first order.
struct MixProblem {
  std::vector<std::array<double, 3>> colors;
  std::array<double, 3> target{};
  std::vector<double> spread;
};

using Mat3 = std::array<double, 9>;
std::array<double, 3> times(const Mat3& m, const std::array<double, 3>& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

MixProblem mixProblem(const std::vector<std::array<float, 3>>& materials, const std::array<double, 3>& c,
                      const std::array<double, 3>& p, MixSpace space) {
  MixProblem out;
  if (space == MixSpace::LinearRgb) {
    const double yc = luminance({float(c[0]), float(c[1]), float(c[2])});
    for (const auto& m : materials) {
      out.colors.push_back({m[0], m[1], m[2]});
      out.spread.push_back(kBrightnessWeight * std::pow(luminance(m) - yc, 2));
    }
    out.target = c;
    return out;
  }
  const Lab labC = labFromLinearSrgb(c), labP = labFromLinearSrgb(p);
  const Mat3 w = deltaE2000Metric(labC), j = labJacobian(p);
  Mat3 wj{};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      for (int q = 0; q < 3; ++q) wj[size_t(3 * r + k)] += w[size_t(3 * r + q)] * j[size_t(3 * q + k)];
  for (const auto& m : materials) {
    const std::array<double, 3> md{m[0], m[1], m[2]};
    out.colors.push_back(times(wj, md));
    out.spread.push_back(kLightnessWeight * std::pow(labFromLinearSrgb(md)[0] - labC[0], 2));
  }
  // W (J_p p - (Lab(p) - Lab(c))): the target the linearized mix is measured against.
  const std::array<double, 3> jp = times(j, p);
  out.target = times(w, {jp[0] - (labP[0] - labC[0]), jp[1] - (labP[1] - labC[1]), jp[2] - (labP[2] - labC[2])});
  return out;
}

// The mix for target c. LinearRgb: one solve. Perceptual: Gauss-Newton, CIELAB relinearized at
// each mix found, started at the target; a linearization can overshoot far outside the gamut, so
// every pass's mix and the linear-RGB mix are candidates, and the one with the least true cost,
// ΔE2000(c, M f)^2 + sum_i f_i spread_i, is kept (the first on ties).
std::vector<double> mixFor(const std::vector<std::array<float, 3>>& materials, const std::array<double, 3>& c,
                           MixSpace space) {
  const auto mixed = [&](const std::vector<double>& f) {
    std::array<double, 3> p{0, 0, 0};
    for (size_t i = 0; i < materials.size(); ++i)
      for (size_t ch = 0; ch < 3; ++ch) p[ch] += f[i] * materials[i][ch];
    return p;
  };
  const MixProblem rgb = mixProblem(materials, c, c, MixSpace::LinearRgb);
  std::vector<double> best = bestMix(rgb.colors, rgb.target, rgb.spread);
  if (space == MixSpace::LinearRgb) return best;
  const Lab want = labFromLinearSrgb(c);
  std::vector<double> spread;  // the perceptual problem's, the same at every linearization
  double bestCost = std::numeric_limits<double>::infinity();
  std::array<double, 3> p = c;
  std::vector<double> f;
  for (int pass = 0; pass < kGaussNewtonPasses; ++pass) {
    const MixProblem problem = mixProblem(materials, c, p, space);
    spread = problem.spread;
    if (pass == 0) {  // the linear-RGB mix, as the perceptual cost sees it
      bestCost = std::pow(deltaE2000(want, labFromLinearSrgb(mixed(best))), 2);
      for (size_t i = 0; i < best.size(); ++i) bestCost += best[i] * spread[i];
    }
    std::vector<double> next = bestMix(problem.colors, problem.target, problem.spread);
    if (next == f) break;
    f = std::move(next);
    p = mixed(f);
    double cost = std::pow(deltaE2000(want, labFromLinearSrgb(p)), 2);
    for (size_t i = 0; i < f.size(); ++i) cost += f[i] * spread[i];
    if (cost < bestCost) bestCost = cost, best = f;
  }
  return best;
}

} // namespace

MaterialMixer::MaterialMixer(const std::vector<PrintMaterial>& materials, const MaterialMixerOptions& options) {
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
  constexpr size_t kEntries = size_t(kLattice) * kLattice * kLattice;
  std::vector<std::array<double, 3>> targets(kEntries);
  for (int b = 0; b < kLattice; ++b)
    for (int g = 0; g < kLattice; ++g)
      for (int r = 0; r < kLattice; ++r) {
        std::array<double, 3>& c = targets[size_t(r) + size_t(kLattice) * (size_t(g) + size_t(kLattice) * size_t(b))];
        c = {double(float(r) / (kLattice - 1)), double(float(g) / (kLattice - 1)), double(float(b) / (kLattice - 1))};
        if (options.profile)  // the colour the printer reproduces for c (may lie outside [0, 1])
          c = linearSrgbFromLabD50(options.profile->reproduced(
              {double(linearToSrgb(float(c[0]))), double(linearToSrgb(float(c[1]))), double(linearToSrgb(float(c[2])))}));
      }
  // Each entry alone: the table is the same on any number of threads.
  table_.resize(kEntries * n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, kEntries, 64), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t e = range.begin(); e != range.end(); ++e) {
      const std::vector<double> f = mixFor(colors, targets[e], options.space);
      for (size_t i = 0; i < n; ++i) table_[e * n + i] = float(f[i]);
    }
  });
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
