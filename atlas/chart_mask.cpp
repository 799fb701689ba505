// SPDX-License-Identifier: GPL-3.0-or-later
#include "atlas/chart_mask.h"

#include "atlas/convex_hull.h"
#include "atlas/measure_stretch.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace texfab::atlas {

namespace {

double cross2(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

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

/// The w×h texels whose centers the chart covers (at least one: a chart too small to hold a
/// texel center still reserves the texel of its first corner, so every chart has a place).
std::vector<uint8_t> coverCenters(const OrientedChart& chart, double density, double rounding, const ChartMask& m) {
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
    // whose area rounds to zero in the stored (float) coordinates claims all of them there, so a
    // triangle that may collapse so reserves them all here.
    const int ix0 = std::max(0, int(std::floor(x0 - 0.5))), ix1 = std::min(m.w - 1, int(std::ceil(x1 - 0.5)));
    const int iy0 = std::max(0, int(std::floor(y0 - 0.5))), iy1 = std::min(m.h - 1, int(std::ceil(y1 - 0.5)));
    const bool sliver = std::abs(cross2(t[0], t[1], t[2])) < 1e-4 || collapsedUv(t, 0.5 * cross2(t[0], t[1], t[2]), rounding);
    for (int y = iy0; y <= iy1; ++y)
      for (int x = ix0; x <= ix1; ++x) {
        uint8_t& c = cover[size_t(y) * size_t(m.w) + size_t(x)];
        if (!c && (sliver || triangleCoversCenter(t, x, y, kCenterEps))) c = 1;
      }
  }
  if (std::find(cover.begin(), cover.end(), uint8_t(1)) == cover.end() && !chart.corners.empty()) {
    const Eigen::Vector2d& c = chart.corners[0];
    const int x = std::clamp(int(m.origin + c.x() * density), 0, m.w - 1);
    const int y = std::clamp(int(m.origin + (chart.extent.y() - c.y()) * density), 0, m.h - 1);
    cover[size_t(y) * size_t(m.w) + size_t(x)] = 1;
  }
  return cover;
}

/// Chebyshev dilation of a w×h 0/1 image by pad (separable max filter, sliding counts: O(w·h)).
std::vector<uint8_t> dilate(const std::vector<uint8_t>& in, int w, int h, int pad) {
  const size_t W = size_t(w);
  std::vector<uint8_t> tmp(in.size(), 0), out(in.size(), 0);
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = in.data() + size_t(y) * W;
    uint8_t* dst = tmp.data() + size_t(y) * W;
    int count = 0; // covered texels in [x - pad, x + pad]
    for (int x = 0; x < std::min(pad, w); ++x) count += row[x];
    for (int x = 0; x < w; ++x) {
      if (x + pad < w) count += row[x + pad];
      if (x - pad - 1 >= 0) count -= row[x - pad - 1];
      dst[x] = count > 0;
    }
  }
  for (int x = 0; x < w; ++x) {
    int count = 0;
    for (int y = 0; y < std::min(pad, h); ++y) count += tmp[size_t(y) * W + size_t(x)];
    for (int y = 0; y < h; ++y) {
      if (y + pad < h) count += tmp[size_t(y + pad) * W + size_t(x)];
      if (y - pad - 1 >= 0) count -= tmp[size_t(y - pad - 1) * W + size_t(x)];
      out[size_t(y) * W + size_t(x)] = count > 0;
    }
  }
  return out;
}

/// Fills the profiles and spans of every quarter turn from the runs of m.bits' rows and columns.
void measureTurns(ChartMask& m) {
  using Runs = ChartMask::Spans;
  const size_t W = size_t(m.w);
  std::vector<Runs> rowRuns(size_t(m.h)), colRuns(size_t(m.w));
  for (int y = 0; y < m.h; ++y) {
    const uint8_t* row = m.bits.data() + size_t(y) * W;
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
      const bool on = y < m.h && m.bits[size_t(y) * W + size_t(x)];
      int& st = colStart[size_t(x)];
      if (on && st < 0) st = y;
      if (!on && st >= 0) colRuns[size_t(x)].push_back({st, y}), st = -1;
    }
  for (int q = 0; q < 4; ++q) {
    const int rw = (q % 2) ? m.h : m.w, rh = m.heightAt(q);
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
}

} // namespace

OrientedChart orientChart(const Atlas& atlas, const Chart& chart) {
  OrientedChart p;
  std::vector<Eigen::Vector2d> pts;
  for (uint32_t f : chart.faces)
    for (int k = 0; k < 3; ++k) pts.push_back(atlas.chartUvs[3 * size_t(f) + size_t(k)]);
  const std::vector<Eigen::Vector2d> hull = convexHull(pts);
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
    p.corners[i] = {pts[i].dot(bestDir), pts[i].dot(n)};
    lo = lo.cwiseMin(p.corners[i]);
    hi = hi.cwiseMax(p.corners[i]);
  }
  for (auto& c : p.corners) c -= lo;
  p.extent = hi - lo;
  return p;
}

size_t ChartMask::texels() const { return size_t(std::count(bits.begin(), bits.end(), uint8_t(1))); }

ChartMask rasterizeChartMask(const OrientedChart& chart, double density, int pad, double rounding) {
  ChartMask m;
  m.origin = pad + 1;
  m.w = int(std::ceil(chart.extent.x() * density)) + 2 * m.origin;
  m.h = int(std::ceil(chart.extent.y() * density)) + 2 * m.origin;
  m.bits = dilate(coverCenters(chart, density, rounding, m), m.w, m.h, pad);
  measureTurns(m);
  return m;
}

} // namespace texfab::atlas
