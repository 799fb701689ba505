// SPDX-License-Identifier: GPL-3.0-or-later
// Chart packing: each chart turned to its minimal-area rectangle and rasterized at a density
// (chart_mask.h), placed by the skyline packer with hole filling (skyline_packer.h), at the largest
// density found to fit by a secant search on the used height.
#include "atlas/pack_charts.h"

#include "atlas/chart_mask.h"
#include "atlas/skyline_packer.h"
#include "core/error.h"
#include "core/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

namespace texfab::atlas {

void PackChartsOptions::validate() const {
  auto pow2 = [](int v) { return v > 0 && (v & (v - 1)) == 0; };
  const bool autoSize = width == 0 && height == 0 && texelsPerUnit > 0;
  if (!autoSize && (width < kMinSide || width > kMaxSide || height < kMinSide || height > kMaxSide))
    throw Error("atlas size must be " + std::to_string(kMinSide) + " to " + std::to_string(kMaxSide) + " texels per side, got " + std::to_string(width) + "x" +
                std::to_string(height));
  if (!autoSize && powerOfTwo && (!pow2(width) || !pow2(height)))
    throw Error("atlas size must be a power of two, got " + std::to_string(width) + "x" + std::to_string(height));
  if (gutter < 0 || gutter > kMaxGutter)
    throw Error("gutter must be 0 to " + std::to_string(kMaxGutter) + " texels, got " + std::to_string(gutter));
  if (!(texelsPerUnit >= 0) || !std::isfinite(texelsPerUnit)) throw Error("texelsPerUnit must be >= 0");
  if (maxPasses < 1) throw Error("maxPasses must be >= 1");
}

namespace {

/// One packing pass: every chart at one density into a strip of width W.
struct Pass {
  double density = 0;
  int used = -1; ///< used height; -1 when a chart is wider than the strip in every turn
  std::vector<ChartPlacement> placements;
  std::vector<ChartMask> masks;

  size_t maskTexels() const {
    size_t n = 0;
    for (const ChartMask& m : masks) n += m.texels();
    return n;
  }
};

Pass packAt(const std::vector<OrientedChart>& charts, double density, int W, int pad, double rounding,
            const SkylinePackerOptions& packer, const Context& ctx) {
  Pass pass;
  pass.density = density;
  pass.masks.assign(charts.size(), ChartMask{});
  parallelFor(0, int(charts.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) pass.masks[size_t(i)] = rasterizeChartMask(charts[size_t(i)], density, pad, rounding);
  });
  std::vector<size_t> order(charts.size());
  std::iota(order.begin(), order.end(), size_t(0));
  // Largest shorter side first (measured on CGAL meshes: 1-4 % better fill than by area, by
  // longer side, or by perimeter).
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::min(pass.masks[a].w, pass.masks[a].h) > std::min(pass.masks[b].w, pass.masks[b].h);
  });
  SkylinePacker strip(W, packer);
  pass.placements.assign(charts.size(), ChartPlacement{});
  for (size_t idx : order) {
    const std::optional<ChartPlacement> p = strip.place(pass.masks[idx]);
    if (!p) return pass;
    pass.placements[idx] = *p;
  }
  pass.used = strip.usedHeight();
  return pass;
}

/// The density search. The used height grows about like the square of the density (the width is
/// fixed), so each round predicts the density that fills the height from the packed pass nearest
/// to it (a secant step on sqrt(used)), and packs a pair of candidates around the prediction at
/// once (one per core). Which candidates are packed depends only on earlier results, never on the
/// thread count, so the atlas does not either.
class DensitySearch {
 public:
  DensitySearch(const std::vector<OrientedChart>& charts, double totalArea, double rounding,
                const SkylinePackerOptions& packer, const Context& ctx)
      : charts_(charts), totalArea_(totalArea), rounding_(rounding), packer_(packer), ctx_(ctx) {}

  /// The largest density whose pass fits W×H with mask padding `pad` (its pass in best();
  /// density 0 if none). A coarse search on a 4× smaller grid (16× cheaper) finds the density to
  /// within a few percent (its masks are fatter: the fine density is 0-10 % higher); calibrated by
  /// the mask areas, one or more rounds of full-resolution pairs finish it (until 98.5 % of the
  /// height).
  void fit(int W, int H, int pad, int maxPasses) {
    double start = std::sqrt(0.72 * double(W) * double(H) / totalArea_);
    const int k = (W >= 512 && H >= 512) ? 4 : 1;
    const int rounds = std::max(1, maxPasses / 2);
    bool calibrated = false;
    if (k > 1) {
      const double coarse =
          run(W / k, H / k, (pad + k - 1) / k, start / k, std::min(rounds, 3), std::min(rounds, 3), {0.97, 1.03}, false);
      if (coarse > 0) {
        start = coarse * k;
        // Calibration: the fine masks at k times the coarse density are thinner than k² coarse
        // masks (gutters and texel rounding are relatively smaller). At the same packing
        // efficiency the fine pass would use k·used·ρ rows (ρ: the ratio of the mask areas); the
        // area grows like the square of the density, which gives the fine density to try.
        std::vector<size_t> fine(charts_.size(), 0);
        parallelFor(0, int(charts_.size()), ctx_, [&](int b, int e) {
          for (int i = b; i < e; ++i) fine[size_t(i)] = rasterizeChartMask(charts_[size_t(i)], start, pad, rounding_).texels();
        });
        const double fineTexels = double(std::accumulate(fine.begin(), fine.end(), size_t(0)));
        if (lastMaskTexels_ > 0 && lastUsed_ > 0 && fineTexels > 0) {
          const double rho = fineTexels / (double(k) * double(k) * double(lastMaskTexels_));
          const double rows = double(k) * double(lastUsed_) * rho;
          start *= std::clamp(std::sqrt(double(H) / rows), 1.0, 1.15);
          calibrated = true;
        }
      }
    }
    if (calibrated) run(W, H, pad, start, 1, rounds, {0.99, 1.0}, true);
    else if (k > 1) run(W, H, pad, start, std::min(rounds, 2), rounds, {1.0, 1.08}, true);
    else run(W, H, pad, start, rounds, rounds, {0.97, 1.03}, true);
  }

  Pass& best() { return best_; }
  int passes() const { return passes_; }

 private:
  /// Returns the best fitting density found (0 if none) for a w×h atlas with mask padding p; keeps
  /// its pass in best() when `keep`. The first round packs start·first[0..1]; later rounds pack the
  /// prediction ·0.99 and ·0.997 (just under it: the used height is not quite monotonic in the
  /// density). Rounds beyond `rounds` (up to `maxRounds`) are packed while the best pass fills
  /// less than 98.5 % of the height: a prediction that lands just over the height would otherwise
  /// waste the search.
  double run(int w, int h, int p, double start, int rounds, int maxRounds, std::array<double, 2> first, bool keep) {
    double lo = 0, hi = std::numeric_limits<double>::infinity();
    int loUsed = 0;
    std::array<Pass, 2> pair;
    std::array<double, 2> factors = first;
    double density = start;
    for (int round = 0;
         round < rounds || (lo == 0 && round < rounds + 16) || (loUsed < 0.985 * h && round < maxRounds); ++round) {
      parallelFor(0, 2, ctx_, [&](int b, int e) {
        for (int i = b; i < e; ++i)
          pair[size_t(i)] = packAt(charts_, density * factors[size_t(i)], w, p, rounding_, packer_, ctx_);
      });
      passes_ += 2;
      factors = {0.99, 0.997};
      // Prediction from the pass nearest to the target height.
      double estimate = 0, nearest = std::numeric_limits<double>::infinity();
      for (Pass& r : pair) {
        if (r.used >= 0 && r.used <= h) {
          if (r.density > lo) {
            lo = r.density, loUsed = r.used;
            lastUsed_ = r.used, lastMaskTexels_ = r.maskTexels();
            if (keep) best_ = std::move(r);
          }
        } else {
          hi = std::min(hi, r.density);
        }
        if (r.used > 0 && std::abs(std::log(double(r.used) / h)) < nearest) {
          nearest = std::abs(std::log(double(r.used) / h));
          estimate = r.density * std::clamp(std::sqrt(double(h) / double(r.used)), 0.5, 1.6);
        }
      }
      if (estimate == 0) estimate = density * 0.5; // nothing packed: charts wider than the atlas
      if (std::isfinite(hi)) estimate = std::min(estimate, hi);
      if (lo > 0 && estimate * factors[1] <= lo * 1.001) break; // no candidate above the best left
      density = estimate;
      if (density * std::sqrt(totalArea_) < 1e-6) break;
    }
    return lo;
  }

  const std::vector<OrientedChart>& charts_;
  double totalArea_, rounding_;
  SkylinePackerOptions packer_;
  const Context& ctx_;
  Pass best_;
  int passes_ = 0, lastUsed_ = 0;  // and the used height and mask texels of the last run()'s best pass
  size_t lastMaskTexels_ = 0;
};

/// Each chart's placement and its faces' texel coordinates from the chosen pass.
void placeCharts(const std::vector<OrientedChart>& charts, const Pass& pass, Atlas& atlas, PackChartsReport& report) {
  for (size_t c = 0; c < atlas.charts.size(); ++c) {
    Chart& chart = atlas.charts[c];
    const OrientedChart& p = charts[c];
    const ChartMask& m = pass.masks[c];
    const ChartPlacement& pl = pass.placements[c];
    chart.x = pl.x, chart.y = pl.y, chart.quarterTurns = pl.q;
    chart.maskWidth = m.width[size_t(pl.q)];
    chart.maskHeight = m.heightAt(pl.q);
    if (std::max(p.extent.x(), p.extent.y()) * pass.density < 1) ++report.chartsBelowOneTexel;
    for (size_t i = 0; i < chart.faces.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d& uv = p.corners[3 * i + size_t(k)];
        double x = m.origin + uv.x() * pass.density, y = m.origin + (p.extent.y() - uv.y()) * pass.density;
        double w = m.w, h = m.h;
        for (int q = 0; q < pl.q; ++q) {
          const double nx = h - y, ny = x;
          x = nx, y = ny;
          std::swap(w, h);
        }
        atlas.texelUvs[3 * size_t(chart.faces[i]) + size_t(k)] = Eigen::Vector2f(float(pl.x + x), float(pl.y + y));
      }
  }
}

/// Degenerate triangles (in no chart): all three corners at the atlas position of one of their
/// vertices.
void placeDegenerateTriangles(const geometry::Mesh& mesh, Atlas& atlas) {
  std::vector<Eigen::Vector2f> vertexUv(mesh.vertexCount(), Eigen::Vector2f(-1, -1));
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    if (atlas.faceChart[t] >= 0)
      for (int k = 0; k < 3; ++k)
        if (vertexUv[mesh.triangles[t][size_t(k)]].x() < 0) vertexUv[mesh.triangles[t][size_t(k)]] = atlas.texelUvs[3 * t + size_t(k)];
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    if (atlas.faceChart[t] >= 0) continue;
    Eigen::Vector2f p(0.5f, 0.5f);
    for (int k = 0; k < 3; ++k)
      if (vertexUv[mesh.triangles[t][size_t(k)]].x() >= 0) {
        p = vertexUv[mesh.triangles[t][size_t(k)]];
        break;
      }
    for (int k = 0; k < 3; ++k) atlas.texelUvs[3 * t + size_t(k)] = p;
  }
}

// Lays out smaller the thin charts (at least 4 times as long as wide: slivers, strips) longer than
// `side` texels at `density`: each is scaled to that length. Returns how many.
size_t shrinkLongCharts(std::vector<OrientedChart>& charts, double density, double side) {
  size_t shrunk = 0;
  for (OrientedChart& c : charts) {
    const double longer = std::max(c.extent.x(), c.extent.y()), shorter = std::min(c.extent.x(), c.extent.y());
    const double length = longer * density;
    if (!(length > side) || !(longer >= 4 * shorter)) continue;
    const double s = side / length;
    for (Eigen::Vector2d& p : c.corners) p *= s;
    c.extent *= s;
    ++shrunk;
  }
  return shrunk;
}

// The smallest atlas that holds the charts at `density`: a strip about as wide as the square the
// charts' texels fill at the packer's usual 75 %, widened until every chart fits across it, its
// height what the packing used; both rounded up to multiples of 4.
Pass packToFit(std::vector<OrientedChart>& charts, double totalArea, double density, int pad, double rounding,
               const SkylinePackerOptions& packer, const Context& ctx, int& W, int& H, size_t& shrunk) {
  auto up4 = [](double v) { return int(std::ceil(v / 4)) * 4; };
  const double square = std::sqrt(totalArea / 0.75) * density + 2 * pad;
  shrunk = shrinkLongCharts(charts, density, square - 2 * pad - 2);
  W = std::max(PackChartsOptions::kMinSide, up4(square));
  for (;;) {
    Pass pass = packAt(charts, density, W, pad, rounding, packer, ctx);
    if (pass.used >= 0) {
      H = std::max(PackChartsOptions::kMinSide, up4(pass.used));
      if (H <= PackChartsOptions::kMaxSide) return pass;
    }
    if (W >= PackChartsOptions::kMaxSide)
      throw AtlasTooSmall("the charts need more than a " + std::to_string(PackChartsOptions::kMaxSide) + "^2 atlas at " +
                          std::to_string(density) + " texels per unit");
    W = std::min(PackChartsOptions::kMaxSide, up4(1.25 * W));
  }
}

} // namespace

PackChartsReport packCharts(const geometry::Mesh& mesh, Atlas& atlas, const PackChartsOptions& options, const Context& ctx) {
  options.validate();
  int W = options.width, H = options.height;
  const bool autoSize = W == 0 && H == 0;
  const int pad = (options.gutter + 1) / 2;
  // An atlas sized to fit is at most kMaxSide per side: round as that size does.
  const double rounding =
      autoSize ? texelUvRounding(PackChartsOptions::kMaxSide, PackChartsOptions::kMaxSide) : texelUvRounding(W, H);
  std::vector<OrientedChart> charts(atlas.charts.size());
  parallelFor(0, int(charts.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) charts[size_t(i)] = orientChart(atlas, atlas.charts[size_t(i)]);
  });
  double totalArea = 0;
  for (const Chart& c : atlas.charts) totalArea += c.area;
  if (atlas.charts.empty() || !(totalArea > 0)) throw Error("the mesh has no triangle with a non-zero area to map");

  SkylinePackerOptions packer;
  packer.holeBudget = options.holeFilling ? packer.holeBudget : 0;
  PackChartsReport report;
  Pass pass;
  if (autoSize) {
    pass = packToFit(charts, totalArea, options.texelsPerUnit, pad, rounding, packer, ctx, W, H, report.chartsShrunk);
    report.passes = 1;
  } else if (options.texelsPerUnit > 0) {
    pass = packAt(charts, options.texelsPerUnit, W, pad, rounding, packer, ctx);
    report.passes = 1;
    if (pass.used < 0 || pass.used > H)
      throw AtlasTooSmall("the charts do not fit a " + std::to_string(W) + "x" + std::to_string(H) + " atlas at " +
                          std::to_string(options.texelsPerUnit) + " texels per unit");
  } else {
    // A chart that could not lie across the atlas at the density of a perfect packing would hold
    // every chart's density down to its own.
    const double ideal = std::sqrt(double(W) * double(H) / totalArea);
    report.chartsShrunk = shrinkLongCharts(charts, ideal, double(std::min(W, H) - 2 * pad - 2));
    DensitySearch search(charts, totalArea, rounding, packer, ctx);
    search.fit(W, H, pad, options.maxPasses);
    report.passes = search.passes();
    pass = std::move(search.best());
    if (pass.density == 0)
      throw AtlasTooSmall("the " + std::to_string(atlas.charts.size()) + " charts cannot fit a " + std::to_string(W) +
                          "x" + std::to_string(H) + " atlas (each needs at least " + std::to_string(2 * pad + 3) +
                          " texels per side with this gutter)");
  }
  atlas.width = W;
  atlas.height = H;
  atlas.texelsPerUnit = pass.density;
  report.texelsPerUnit = pass.density;
  report.usedHeight = pass.used;
  report.maskTexels = pass.maskTexels();
  atlas.texelUvs.assign(3 * mesh.triangleCount(), Eigen::Vector2f(0.5f, 0.5f));
  placeCharts(charts, pass, atlas, report);
  placeDegenerateTriangles(mesh, atlas);
  return report;
}

} // namespace texfab::atlas
