// SPDX-License-Identifier: GPL-3.0-or-later
// Chart packing.
//  - B. Lévy, S. Petitjean, N. Ray, J. Maillot, "Least Squares Conformal Maps for Automatic
//    Texture Atlas Generation", SIGGRAPH 2002, §5: the "Tetris" horizon packer (each chart is
//    dropped where its lower profile wastes the least area under the current horizon).
//  - H. Freeman, R. Shapira, "Determining the minimum-area encasing rectangle for an arbitrary
//    closed curve", CACM 1975 (rotating calipers: charts are first turned to their minimal-area
//    bounding rectangle).
//  - Hole filling as in bottom-left-fill raster packers (xatlas's brute-force placement, and
//    E. Hopper, B. Turton, "An empirical investigation of meta-heuristic and heuristic algorithms
//    for a 2D packing problem", EJOR 2001): before dropping a chart on the horizon, look for the
//    lowest free spot in the space left under earlier charts. Each atlas row keeps its free runs;
//    at a row, the positions where a mask span fits are the long-enough runs of its row, shifted,
//    and the chart fits where those of all its spans intersect (exact, spans taken from far-apart
//    mask rows first so most rows are ruled out after a few; bounded effort).
//  - Masks sample texel centers like the atlas rasterizer (rasterize_atlas.cpp) and are dilated by
//    half the gutter: any two charts' texels end up more than `gutter` texels apart.
#include "atlas/pack_charts.h"

#include "atlas/convex_hull.h"
#include "render/image/error.h"
#include "render/image/parallel.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>

namespace texfab::atlas {

void PackChartsOptions::validate() const {
  auto pow2 = [](int v) { return v > 0 && (v & (v - 1)) == 0; };
  if (width < 16 || width > 16384 || height < 16 || height > 16384)
    throw Error("atlas size must be 16 to 16384 texels per side, got " + std::to_string(width) + "x" +
                std::to_string(height));
  if (powerOfTwo && (!pow2(width) || !pow2(height)))
    throw Error("atlas size must be a power of two, got " + std::to_string(width) + "x" + std::to_string(height));
  if (gutter < 0 || gutter > 64) throw Error("gutter must be 0 to 64 texels, got " + std::to_string(gutter));
  if (!(texelsPerUnit >= 0) || !std::isfinite(texelsPerUnit)) throw Error("texelsPerUnit must be >= 0");
  if (maxPasses < 1) throw Error("maxPasses must be >= 1");
}

namespace {

// The first texel at or after x of a bit row (one bit per texel, 64 a word) that is occupied
// (`occupied`) or free (!occupied); W if none before W.
int nextTexel(const uint64_t* row, int x, int W, bool occupied) {
  while (x < W) {
    const uint64_t word = row[size_t(x) >> 6];
    const uint64_t v = (occupied ? word : ~word) >> (x & 63);  // wanted bits from x
    const int left = std::min(64 - (x & 63), W - x);
    const int skip = v ? std::countr_zero(v) : 64;
    if (skip < left) return x + skip;
    x += left;
  }
  return W;
}

struct PreparedChart {
  std::vector<Eigen::Vector2d> corners; ///< 3 per face, rotated, min at (0,0), v up
  Eigen::Vector2d extent{0, 0};
};

double cross2(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

PreparedChart prepareChart(const Atlas& atlas, const Chart& chart) {
  PreparedChart p;
  std::vector<Eigen::Vector2d> pts;
  for (uint32_t f : chart.faces)
    for (int k = 0; k < 3; ++k) pts.push_back(atlas.chartUvs[3 * size_t(f) + size_t(k)]);
  const std::vector<Eigen::Vector2d> hull = convexHull(pts);
  // Minimal-area rectangle over hull edge directions.
  double bestArea = std::numeric_limits<double>::infinity();
  Eigen::Vector2d bestDir(1, 0);
  forEachHullEdgeRectangle(hull, [&](const Eigen::Vector2d& d, const Eigen::Vector2d& n, double along, double across) {
    const double area = along * across;
    if (area < bestArea * (1 - 1e-9)) {
      bestArea = area;
      bestDir = along >= across ? d : n; // long side along x
    }
  });
  const Eigen::Vector2d n(-bestDir.y(), bestDir.x());
  p.corners.resize(pts.size());
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (size_t i = 0; i < pts.size(); ++i) {
    p.corners[i] = {pts[i].dot(bestDir), pts[i].dot(n)}; // a rotation: orientation kept
    lo = lo.cwiseMin(p.corners[i]);
    hi = hi.cwiseMax(p.corners[i]);
  }
  for (auto& c : p.corners) c -= lo;
  p.extent = hi - lo;
  return p;
}

struct Mask {
  int w = 0, h = 0;
  int origin = 0;
  std::vector<uint8_t> bits; ///< dilated conservative coverage
  // Profiles per quarter turn: top[x] first occupied row, bottom[x] last occupied row + 1.
  std::array<std::vector<int>, 4> top, bottom;
  std::array<int, 4> width{}, maxBottom{};
  /// Occupied spans [a, b) of each row, per quarter turn (for hole filling).
  std::array<std::vector<std::vector<std::pair<int, int>>>, 4> spans;
};

/// Whether the center (x + ½, y + ½) of texel (x, y) lies in the triangle t (any orientation),
/// with a tolerance of `eps` texels: the atlas rasterizer samples texel centers, so these are
/// exactly the texels the chart will own (the tolerance absorbs the float rounding of the atlas
/// coordinates).
constexpr double kCenterEps = 0.02; ///< texels

bool triangleCoversCenter(const Eigen::Vector2d t[3], double x, double y, double eps) {
  const double area = cross2(t[0], t[1], t[2]);
  const double sign = area >= 0 ? 1 : -1;
  const Eigen::Vector2d c(x + 0.5, y + 0.5);
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d& a = t[k];
    const Eigen::Vector2d& b = t[(k + 1) % 3];
    const double len = (b - a).norm();
    if (len == 0) continue;
    if (sign * cross2(a, b, c) < -eps * len) return false;
  }
  return true;
}

Mask rasterizeMask(const PreparedChart& chart, double density, int pad) {
  Mask m;
  m.origin = pad + 1;
  m.w = int(std::ceil(chart.extent.x() * density)) + 2 * m.origin;
  m.h = int(std::ceil(chart.extent.y() * density)) + 2 * m.origin;
  std::vector<uint8_t> cover(size_t(m.w) * size_t(m.h), 0);
  for (size_t f = 0; f < chart.corners.size() / 3; ++f) {
    Eigen::Vector2d t[3];
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d& c = chart.corners[3 * f + size_t(k)];
      t[k] = {m.origin + c.x() * density, m.origin + (chart.extent.y() - c.y()) * density};
      x0 = std::min(x0, t[k].x()), x1 = std::max(x1, t[k].x());
      y0 = std::min(y0, t[k].y()), y1 = std::max(y1, t[k].y());
    }
    // The texels whose centers the atlas rasterizer tests (rasterize_atlas.cpp): a triangle
    // whose area rounds to zero claims all of them there, so it reserves them all here.
    const int ix0 = std::max(0, int(std::floor(x0 - 0.5))), ix1 = std::min(m.w - 1, int(std::ceil(x1 - 0.5)));
    const int iy0 = std::max(0, int(std::floor(y0 - 0.5))), iy1 = std::min(m.h - 1, int(std::ceil(y1 - 0.5)));
    const bool sliver = std::abs(cross2(t[0], t[1], t[2])) < 1e-4;
    for (int y = iy0; y <= iy1; ++y)
      for (int x = ix0; x <= ix1; ++x) {
        uint8_t& c = cover[size_t(y) * size_t(m.w) + size_t(x)];
        if (!c && (sliver || triangleCoversCenter(t, x, y, kCenterEps))) c = 1;
      }
  }
  // A chart too small to hold a texel center still reserves the texel of its first corner, so
  // every chart has a place of its own.
  if (std::find(cover.begin(), cover.end(), uint8_t(1)) == cover.end() && !chart.corners.empty()) {
    const Eigen::Vector2d& c = chart.corners[0];
    const int x = std::clamp(int(m.origin + c.x() * density), 0, m.w - 1);
    const int y = std::clamp(int(m.origin + (chart.extent.y() - c.y()) * density), 0, m.h - 1);
    cover[size_t(y) * size_t(m.w) + size_t(x)] = 1;
  }
  // Chebyshev dilation by pad (separable max filter, sliding counts: O(w·h)).
  const size_t W_ = size_t(m.w);
  std::vector<uint8_t> tmp(cover.size(), 0);
  m.bits.assign(cover.size(), 0);
  for (int y = 0; y < m.h; ++y) {
    const uint8_t* in = cover.data() + size_t(y) * W_;
    uint8_t* out = tmp.data() + size_t(y) * W_;
    int count = 0; // covered texels in [x - pad, x + pad]
    for (int x = 0; x < std::min(pad, m.w); ++x) count += in[x];
    for (int x = 0; x < m.w; ++x) {
      if (x + pad < m.w) count += in[x + pad];
      if (x - pad - 1 >= 0) count -= in[x - pad - 1];
      out[x] = count > 0;
    }
  }
  for (int x = 0; x < m.w; ++x) {
    int count = 0;
    for (int y = 0; y < std::min(pad, m.h); ++y) count += tmp[size_t(y) * W_ + size_t(x)];
    for (int y = 0; y < m.h; ++y) {
      if (y + pad < m.h) count += tmp[size_t(y + pad) * W_ + size_t(x)];
      if (y - pad - 1 >= 0) count -= tmp[size_t(y - pad - 1) * W_ + size_t(x)];
      m.bits[size_t(y) * W_ + size_t(x)] = count > 0;
    }
  }
  // Runs of every row and every column; the four quarter turns are read off them:
  //   q = 1: (x, y) -> (h-1-y, x); q = 2: (x, y) -> (w-1-x, h-1-y); q = 3: (x, y) -> (y, w-1-x).
  using Runs = std::vector<std::pair<int, int>>;
  std::vector<Runs> rowRuns(size_t(m.h)), colRuns(size_t(m.w));
  for (int y = 0; y < m.h; ++y) {
    const uint8_t* row = m.bits.data() + size_t(y) * W_;
    for (int x = 0; x < m.w;) {
      if (!row[x]) {
        ++x;
        continue;
      }
      int e = x;
      while (e < m.w && row[e]) ++e;
      rowRuns[size_t(y)].push_back({x, e});
      x = e;
    }
  }
  std::vector<int> colStart(size_t(m.w), -1); // start of the open run of each column
  for (int y = 0; y <= m.h; ++y)
    for (int x = 0; x < m.w; ++x) {
      const bool on = y < m.h && m.bits[size_t(y) * W_ + size_t(x)];
      int& st = colStart[size_t(x)];
      if (on && st < 0) st = y;
      if (!on && st >= 0) colRuns[size_t(x)].push_back({st, y}), st = -1;
    }
  for (int q = 0; q < 4; ++q) {
    const int rw = (q % 2) ? m.h : m.w, rh = (q % 2) ? m.w : m.h;
    m.width[size_t(q)] = rw;
    // A column with no texel (a chart thinner than the dilation's reach there) constrains nothing.
    m.top[size_t(q)].assign(size_t(rw), rh);
    m.bottom[size_t(q)].assign(size_t(rw), std::numeric_limits<int>::min());
    m.spans[size_t(q)].assign(size_t(rh), {});
  }
  for (int x = 0; x < m.w; ++x) {
    const Runs& c = colRuns[size_t(x)];
    if (c.empty()) continue;
    m.top[0][size_t(x)] = c.front().first, m.bottom[0][size_t(x)] = c.back().second;
    m.top[2][size_t(m.w - 1 - x)] = m.h - c.back().second, m.bottom[2][size_t(m.w - 1 - x)] = m.h - c.front().first;
    auto& s1 = m.spans[1][size_t(x)];
    for (auto it = c.rbegin(); it != c.rend(); ++it) s1.push_back({m.h - it->second, m.h - it->first});
    m.spans[3][size_t(m.w - 1 - x)] = c;
  }
  for (int y = 0; y < m.h; ++y) {
    const Runs& r = rowRuns[size_t(y)];
    if (r.empty()) continue;
    m.top[1][size_t(m.h - 1 - y)] = r.front().first, m.bottom[1][size_t(m.h - 1 - y)] = r.back().second;
    m.top[3][size_t(y)] = m.w - r.back().second, m.bottom[3][size_t(y)] = m.w - r.front().first;
    auto& s2 = m.spans[2][size_t(m.h - 1 - y)];
    for (auto it = r.rbegin(); it != r.rend(); ++it) s2.push_back({m.w - it->second, m.w - it->first});
    m.spans[0][size_t(y)] = r;
  }
  for (int q = 0; q < 4; ++q) {
    int mb = 0;
    for (int b : m.bottom[size_t(q)]) mb = std::max(mb, b);
    m.maxBottom[size_t(q)] = mb;
  }
  return m;
}

struct Placement {
  int x = 0, y = 0, q = 0;
};

/// Packs every chart at `density` into width W (height unbounded). Returns the used height and the
/// placements, or -1 when a chart is wider than the atlas in every orientation.
int packAt(const std::vector<PreparedChart>& charts, double density, int W, int pad, const Context& ctx,
           double heightWeight, long long holeBudget,
           std::vector<Placement>& placements, std::vector<Mask>& masks) {
  masks.assign(charts.size(), Mask{});
  parallelFor(0, int(charts.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) masks[size_t(i)] = rasterizeMask(charts[size_t(i)], density, pad);
  });
  std::vector<size_t> order(charts.size());
  std::iota(order.begin(), order.end(), size_t(0));
  // Largest shorter side first (measured on CGAL meshes: 1-4 % better fill than by area, by
  // longer side, or by perimeter).
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::min(masks[a].w, masks[a].h) > std::min(masks[b].w, masks[b].h);
  });
  std::vector<int> horizon(size_t(W), 0);
  int used = 0;
  // Occupancy as one bit per texel, 64 texels a word, and per row the list of its free runs
  // [start, end) (for hole filling) with the longest one's length.
  const size_t words = size_t(W + 63) / 64;
  std::vector<uint64_t> occ;
  // Runs are kept in three lists by length (all, >= 16, >= 64 texels): a span only looks at the
  // runs that can hold it.
  constexpr std::array<int, 3> kRunClass{0, 16, 64};
  using Runs = std::vector<std::pair<int32_t, int32_t>>;
  std::vector<std::array<Runs, 3>> freeRuns;
  std::vector<int32_t> rowMaxRun;
  auto ensureRows = [&](int rows) {
    if (int(rowMaxRun.size()) < rows) {
      rowMaxRun.resize(size_t(rows), W);
      freeRuns.resize(size_t(rows), {Runs{{0, W}}, Runs{{0, W}}, Runs{{0, W}}});
      occ.resize(size_t(rows) * words, 0);
    }
  };
  auto refreshRuns = [&](int y) {
    const uint64_t* row = occ.data() + size_t(y) * words;
    auto& lists = freeRuns[size_t(y)];
    for (Runs& l : lists) l.clear();
    int32_t longest = 0;
    int x = 0;
    while (x < W) {
      // Skip occupied texels, then measure the free run.
      x = nextTexel(row, x, W, false);
      if (x >= W) break;
      const int start = x;
      x = nextTexel(row, x, W, true);
      for (size_t k = 0; k < kRunClass.size(); ++k)
        if (x - start >= kRunClass[k]) lists[k].push_back({start, x});
      longest = std::max(longest, x - start);
    }
    rowMaxRun[size_t(y)] = longest;
  };
  long long work = 0; // hole-search effort for the current chart (bounded: deterministic, not timed)
  // A span (a, b) of mask row j; hole tests take the widest spans first, which admit the fewest
  // positions, so most rows are ruled out after a few spans.
  struct Span {
    int j, a, b;
  };
  std::vector<Span> spanOrder;
  // Positions X (closed intervals) where every span tested so far lies in free texels.
  std::vector<std::pair<int32_t, int32_t>> cand, next;
  // The lowest X in [0, xMax] where the chart (spanOrder) fits at row Y, or -1. Exact: the
  // allowed positions of each span are the free runs of its row long enough for it, shifted; the
  // chart fits where all of them intersect.
  auto fitRow = [&](int Y, int xMax) {
    cand.assign(1, {0, xMax});
    for (const Span& sp : spanOrder) {
      const int len = sp.b - sp.a;
      const auto& runs = freeRuns[size_t(Y + sp.j)][len >= kRunClass[2] ? 2 : len >= kRunClass[1] ? 1 : 0];
      // Fast path: the span's whole window over the candidates is free (a few word tests).
      {
        const int x0 = cand.front().first + sp.a, x1 = cand.back().second + sp.b;
        if (x1 - x0 <= 256) {
          ++work;
          const uint64_t* row = occ.data() + size_t(Y + sp.j) * words;
          const int w0 = x0 >> 6, w1 = (x1 - 1) >> 6;
          uint64_t any = 0;
          for (int w = w0; w <= w1; ++w) {
            uint64_t v = row[w];
            if (w == w1 && (x1 & 63) != 0) v &= (uint64_t(1) << (x1 & 63)) - 1;
            if (w == w0) v &= ~uint64_t(0) << (x0 & 63);
            any |= v;
          }
          if (!any) continue;
        }
      }
      next.clear();
      size_t c = 0;
      // Only the runs that can hold the span at a candidate position: e0 >= X + b for the first
      // candidate X, s0 <= X + a for the last (binary search, then a walk).
      const int firstEnd = cand.front().first + sp.b, lastStart = cand.back().second + sp.a;
      auto r = std::partition_point(runs.begin(), runs.end(),
                                    [&](const std::pair<int32_t, int32_t>& u) { return u.second < firstEnd; });
      work += long(cand.size()) + 4;
      for (; r != runs.end() && r->first <= lastStart; ++r) {
        const auto [s0, e0] = *r;
        ++work;
        if (e0 - s0 < len) continue;
        const int lo = s0 - sp.a, hi = e0 - sp.b; // allowed X for this run
        while (c < cand.size() && cand[c].second < lo) ++c;
        for (size_t d = c; d < cand.size() && cand[d].first <= hi; ++d) {
          const int l = std::max(lo, cand[d].first), h = std::min(hi, cand[d].second);
          if (l <= h) next.push_back({l, h});
        }
      }
      cand.swap(next);
      if (cand.empty()) return -1;
    }
    return cand.front().first;
  };
  placements.assign(charts.size(), Placement{});
  std::vector<double> prefix(size_t(W) + 1, 0.0); // prefix sums of the horizon
  for (size_t idx : order) {
    const Mask& m = masks[idx];
    // Every column of a (connected, dilated) chart mask is occupied, so the waste under the chart
    // at X is mw·Y + Σtop − Σh[X..X+mw): a window sum. Y(X) >= max(h over the window) − max(top)
    // gives a lower bound on the score that prunes most positions before the exact O(mw) scan.
    double best = std::numeric_limits<double>::infinity();
    int bestQ = -1, bestX = 0, bestY = 0;
    for (int q = 0; q < 4; ++q) {
      const int mw = m.width[size_t(q)];
      if (mw > W) continue;
      const auto& top = m.top[size_t(q)];
      int maxTop = 0;
      double sumTop = 0;
      for (int x = 0; x < mw; ++x) maxTop = std::max(maxTop, top[size_t(x)]), sumTop += top[size_t(x)];
      const int positions = W - mw + 1;
      // Sliding window maximum of the horizon (monotonic deque).
      std::vector<int> dq(static_cast<size_t>(W));
      size_t head = 0, tail = 0;
      for (int X = 0, R = 0; X < positions; ++X) {
        for (; R < X + mw; ++R) {
          while (tail > head && horizon[size_t(dq[tail - 1])] <= horizon[size_t(R)]) --tail;
          dq[tail++] = R;
        }
        while (dq[head] < X) ++head;
        const int windowMax = horizon[size_t(dq[head])];
        const double windowSum = prefix[size_t(X + mw)] - prefix[size_t(X)];
        auto scoreOf = [&](int Y) {
          return double(mw) * Y + sumTop - windowSum + heightWeight * double(W) * std::max(0, Y + m.maxBottom[size_t(q)] - used);
        };
        const int ylb = std::max(0, windowMax - maxTop);
        if (scoreOf(ylb) > best) continue;
        int Y = 0;
        for (int x = 0; x < mw; ++x) Y = std::max(Y, horizon[size_t(X + x)] - top[size_t(x)]);
        const double sc = scoreOf(Y);
        if (sc < best || (sc == best && Y < bestY)) best = sc, bestQ = q, bestX = X, bestY = Y;
      }
    }
    if (bestQ < 0) return -1;
    // Hole filling: the lowest-row position below the horizon placement where the chart fits in
    // the free space left under earlier charts without growing the used height.
    {
      int holeY = -1, holeX = 0, holeQ = 0;
      work = 0;
      const long long budget = holeBudget * W;
      for (int q = 0; q < (holeBudget > 0 ? 4 : 0); ++q) {
        const int rw = m.width[size_t(q)], rh = (q % 2) ? m.w : m.h;
        if (rw > W) continue;
        const int yLimit = std::min(bestY - 1, used - rh);
        const auto& rows = m.spans[size_t(q)];
        std::vector<int> need(rows.size(), 0); // longest span per mask row
        for (size_t j = 0; j < rows.size(); ++j)
          for (const auto& [a, b] : rows[j]) need[j] = std::max(need[j], b - a);
        const int widest = int(std::max_element(need.begin(), need.end()) - need.begin());
        const int minNeed = need.empty() ? 0 : *std::min_element(need.begin(), need.end());
        spanOrder.clear();
        for (size_t j = 0; j < rows.size(); ++j)
          for (const auto& [a, b] : rows[j]) spanOrder.push_back({int(j), a, b});
        // Order: the widest span, then the rows in bit-reversed order (middle, quarters, eighths,
        // ...; each row's widest span first): far-apart rows meet different neighbours, so a
        // position that does not fit is rejected after a few spans.
        std::vector<int> rank(rows.size());
        {
          int bits = 0;
          while ((size_t(1) << bits) < rows.size()) ++bits;
          for (size_t j = 0; j < rows.size(); ++j) {
            size_t r = 0;
            for (int b = 0; b < bits; ++b)
              if (j & (size_t(1) << b)) r |= size_t(1) << (bits - 1 - b);
            rank[j] = int(r);
          }
        }
        std::vector<int> rowOrder(rows.size());
        std::iota(rowOrder.begin(), rowOrder.end(), 0);
        std::sort(rowOrder.begin(), rowOrder.end(), [&](int u, int v) { return rank[size_t(u)] < rank[size_t(v)]; });
        std::stable_sort(spanOrder.begin(), spanOrder.end(), [&](const Span& u, const Span& v) {
          return rank[size_t(u.j)] != rank[size_t(v.j)] ? rank[size_t(u.j)] < rank[size_t(v.j)] : u.b - u.a > v.b - v.a;
        });
        const auto widestSpan = std::min_element(spanOrder.begin(), spanOrder.end(), [](const Span& u, const Span& v) {
          return u.b - u.a > v.b - v.a;
        });
        if (widestSpan != spanOrder.end()) std::rotate(spanOrder.begin(), widestSpan, widestSpan + 1);
        for (int Y = 0; Y <= yLimit && (holeY < 0 || Y < holeY) && work < budget; ++Y) {
          // Rows too full for the chart's span there rule Y out at once (widest mask row first).
          // A row whose longest free run is shorter than every mask row blocks all the positions
          // whose mask covers it: jump past it.
          int blockedAt = -1;
          if (rowMaxRun[size_t(Y + widest)] < need[size_t(widest)]) blockedAt = Y + widest;
          for (size_t i = 0; i < rowOrder.size() && blockedAt < 0; ++i)
            if (rowMaxRun[size_t(Y + rowOrder[i])] < need[size_t(rowOrder[i])]) blockedAt = Y + rowOrder[i];
          work += long(rows.size()) / 8 + 1;
          if (blockedAt >= 0) {
            if (rowMaxRun[size_t(blockedAt)] < minNeed) Y = blockedAt;
            continue;
          }
          const int X = fitRow(Y, W - rw);
          if (X >= 0) {
            if (holeY < 0 || Y < holeY || (Y == holeY && X < holeX)) holeY = Y, holeX = X, holeQ = q;
            break;
          }
        }
      }
      if (holeY >= 0) bestY = holeY, bestX = holeX, bestQ = holeQ;
    }
    const int Y = bestY;
    const auto& bottom = m.bottom[size_t(bestQ)];
    for (int x = 0; x < m.width[size_t(bestQ)]; ++x)
      if (bottom[size_t(x)] > 0) horizon[size_t(bestX + x)] = std::max(horizon[size_t(bestX + x)], Y + bottom[size_t(x)]);
    {
      const auto& rows = m.spans[size_t(bestQ)];
      ensureRows(Y + int(rows.size()));
      for (size_t j = 0; j < rows.size(); ++j) {
        uint64_t* row = occ.data() + (size_t(Y) + j) * words;
        for (const auto& [a, b] : rows[j])
          for (int x = bestX + a; x < bestX + b; ++x) row[size_t(x) >> 6] |= uint64_t(1) << (x & 63);
        refreshRuns(Y + int(j));
      }
    }
    used = std::max(used, Y + m.maxBottom[size_t(bestQ)]);
    for (int x = 0; x < W; ++x) prefix[size_t(x + 1)] = prefix[size_t(x)] + horizon[size_t(x)];
    placements[idx] = {bestX, Y, bestQ};
  }
  return used;
}

} // namespace

PackChartsReport packCharts(const geometry::Mesh& mesh, Atlas& atlas, const PackChartsOptions& options, const Context& ctx) {
  options.validate();
  const int W = options.width, H = options.height;
  const int pad = (options.gutter + 1) / 2;
  std::vector<PreparedChart> prepared(atlas.charts.size());
  parallelFor(0, int(prepared.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) prepared[size_t(i)] = prepareChart(atlas, atlas.charts[size_t(i)]);
  });
  double totalArea = 0;
  for (const Chart& c : atlas.charts) totalArea += c.area;
  if (atlas.charts.empty() || !(totalArea > 0)) throw Error("the mesh has no triangle with a non-zero area to map");

  PackChartsReport report;
  std::vector<Placement> bestPlacements;
  std::vector<Mask> bestMasks;
  double bestDensity = 0;
  int bestUsed = 0;
  // Weight of growing the used height against area wasted under the chart (measured on CGAL
  // meshes: 0.3 packs best; 0 fills one column first, 1 wastes more under overhangs).
  const double hw = 0.3;
  const long long holeBudget = options.holeFilling ? 256 : 0; // span tests per atlas column per chart
  // Density search. The used height grows about like the square of the density (the width is
  // fixed), so each round predicts the density that fills the height from the packed pass nearest
  // to it (a secant step on sqrt(used)), and packs a pair of candidates around the prediction at
  // once (one per core). Which candidates are packed depends only on earlier results, never on
  // the thread count, so the atlas does not either.
  struct Pass {
    double density = 0;
    int used = -1;
    std::vector<Placement> placements;
    std::vector<Mask> masks;
  };
  auto packPair = [&](int w, int p, double d0, double d1, std::array<Pass, 2>& out) {
    out[0].density = d0, out[1].density = d1;
    parallelFor(0, 2, ctx, [&](int b, int e) {
      for (int i = b; i < e; ++i) {
        Pass& r = out[size_t(i)];
        r.used = packAt(prepared, r.density, w, p, ctx, hw, holeBudget, r.placements, r.masks);
      }
    });
    report.passes += 2;
  };
  // Returns the best fitting density found (0 if none); keeps its pass when `keep`. The first
  // round packs start·first[0..1]; later rounds pack the prediction ·0.99 and ·0.997 (just under
  // it: the used height is not quite monotonic in the density).
  int coarseUsed = 0;         // used height and mask texels of the best pass of the last search
  size_t coarseMaskTexels = 0;
  // Rounds beyond `rounds` (up to `maxRounds`) are packed while the best pass fills less than
  // 98.5 % of the height: the used height is not monotonic in the density, and a prediction that
  // lands just over the height would otherwise waste the search.
  auto search = [&](int w, int h, int p, double start, int rounds, int maxRounds, std::array<double, 2> first,
                    bool keep) {
    double lo = 0, hi = std::numeric_limits<double>::infinity();
    int loUsed = 0;
    std::array<Pass, 2> pair;
    std::array<double, 2> factors = first;
    double density = start;
    for (int round = 0; round < rounds || (lo == 0 && round < rounds + 16) ||
                        (loUsed < 0.985 * h && round < maxRounds);
         ++round) {
      packPair(w, p, density * factors[0], density * factors[1], pair);
      factors = {0.99, 0.997};
      // Prediction from the pass nearest to the target height.
      double estimate = 0, nearest = std::numeric_limits<double>::infinity();
      for (Pass& r : pair) {
        if (r.used >= 0 && r.used <= h) {
          if (r.density > lo) {
            lo = r.density, loUsed = r.used;
            coarseUsed = r.used, coarseMaskTexels = 0;
            for (const Mask& m : r.masks)
              for (uint8_t b : m.bits) coarseMaskTexels += b;
            if (keep)
              bestDensity = r.density, bestUsed = r.used, bestPlacements = std::move(r.placements),
              bestMasks = std::move(r.masks);
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
      if (density * std::sqrt(totalArea) < 1e-6) break;
    }
    return lo;
  };
  if (options.texelsPerUnit > 0) {
    std::vector<Placement> placements;
    std::vector<Mask> masks;
    const int used = packAt(prepared, options.texelsPerUnit, W, pad, ctx, hw, holeBudget, placements, masks);
    report.passes = 1;
    if (used < 0 || used > H)
      throw Error("the charts do not fit a " + std::to_string(W) + "x" + std::to_string(H) + " atlas at " +
                  std::to_string(options.texelsPerUnit) + " texels per unit");
    bestDensity = options.texelsPerUnit, bestUsed = used;
    bestPlacements = std::move(placements), bestMasks = std::move(masks);
  } else {
    double start = std::sqrt(0.72 * double(W) * double(H) / totalArea);
    // A coarse search on a 4× smaller grid (16× cheaper) finds the density to within a few
    // percent (its masks are fatter: the fine density is 0-10 % higher); calibrated by the mask
    // areas, one or more rounds of full-resolution pairs finish it (until 98.5 % of the height).
    const int k = (W >= 512 && H >= 512) ? 4 : 1;
    const int rounds = std::max(1, options.maxPasses / 2);
    bool calibrated = false;
    if (k > 1) {
      const double coarse = search(W / k, H / k, (pad + k - 1) / k, start / k, std::min(rounds, 3), std::min(rounds, 3),
                                  {0.97, 1.03}, false);
      if (coarse > 0) {
        start = coarse * k;
        // Calibration: the fine masks at k times the coarse density are thinner than k² coarse
        // masks (gutters and texel rounding are relatively smaller). At the same packing
        // efficiency the fine pass would use k·used·ρ rows (ρ: the ratio of the mask areas);
        // the area grows like the square of the density, which gives the fine density to try.
        std::vector<size_t> fine(prepared.size(), 0);
        parallelFor(0, int(prepared.size()), ctx, [&](int b, int e) {
          for (int i = b; i < e; ++i)
            for (uint8_t bit : rasterizeMask(prepared[size_t(i)], start, pad).bits) fine[size_t(i)] += bit;
        });
        const double fineTexels = double(std::accumulate(fine.begin(), fine.end(), size_t(0)));
        if (coarseMaskTexels > 0 && coarseUsed > 0 && fineTexels > 0) {
          const double rho = fineTexels / (double(k) * double(k) * double(coarseMaskTexels));
          const double rows = double(k) * double(coarseUsed) * rho;
          start *= std::clamp(std::sqrt(double(H) / rows), 1.0, 1.15);
          calibrated = true;
        }
      }
    }
    if (calibrated) search(W, H, pad, start, 1, rounds, {0.99, 1.0}, true);
    else if (k > 1) search(W, H, pad, start, std::min(rounds, 2), rounds, {1.0, 1.08}, true);
    else search(W, H, pad, start, rounds, rounds, {0.97, 1.03}, true);
    if (bestDensity == 0)
      throw Error("the " + std::to_string(atlas.charts.size()) + " charts cannot fit a " + std::to_string(W) + "x" +
                  std::to_string(H) + " atlas (each needs at least " + std::to_string(2 * pad + 3) +
                  " texels per side with this gutter); use a larger --resolution or a simpler mesh");
  }
  atlas.width = W;
  atlas.height = H;
  atlas.texelsPerUnit = bestDensity;
  report.texelsPerUnit = bestDensity;
  report.usedHeight = bestUsed;
  for (const Mask& m : bestMasks)
    for (uint8_t b : m.bits) report.maskTexels += b;
  atlas.texelUvs.assign(3 * mesh.triangleCount(), Eigen::Vector2f(0.5f, 0.5f));
  for (size_t c = 0; c < atlas.charts.size(); ++c) {
    Chart& chart = atlas.charts[c];
    const PreparedChart& p = prepared[c];
    const Mask& m = bestMasks[c];
    const Placement& pl = bestPlacements[c];
    chart.x = pl.x, chart.y = pl.y, chart.quarterTurns = pl.q;
    chart.maskWidth = m.width[size_t(pl.q)];
    chart.maskHeight = (pl.q % 2) ? m.w : m.h;
    if (std::max(p.extent.x(), p.extent.y()) * bestDensity < 1) ++report.chartsBelowOneTexel;
    for (size_t i = 0; i < chart.faces.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d& uv = p.corners[3 * i + size_t(k)];
        double x = m.origin + uv.x() * bestDensity, y = m.origin + (p.extent.y() - uv.y()) * bestDensity;
        double w = m.w, h = m.h;
        for (int q = 0; q < pl.q; ++q) {
          const double nx = h - y, ny = x;
          x = nx, y = ny;
          std::swap(w, h);
        }
        atlas.texelUvs[3 * size_t(chart.faces[i]) + size_t(k)] = Eigen::Vector2f(float(pl.x + x), float(pl.y + y));
      }
  }
  // Degenerate triangles: all three corners at the atlas position of one of their vertices.
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
  return report;
}

} // namespace texfab::atlas
