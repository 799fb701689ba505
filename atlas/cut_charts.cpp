// SPDX-License-Identifier: GPL-3.0-or-later
// Chart cutting for packing, after M. Limper, N. Vining, A. Sheffer, "Box Cutter: Atlas
// Refinement for Efficient Packing via Void Elimination", SIGGRAPH 2018: the packer places
// charts by their outline, so a chart that leaves large voids in its bounding rectangle (an
// arch, a comb) wastes atlas space that a cut through the void recovers. Here a cut is a straight
// line across the chart's minimal-area rectangle (H. Freeman, R. Shapira, CACM 1975), triangles
// going to the side of their centroid; the best of a few positions is kept when the padded
// rectangles of the pieces (gutters included) save enough area to pay for the new seam.
#include "atlas/cut_charts.h"

#include "atlas/chart_mesh.h"
#include "atlas/convex_hull.h"
#include "atlas/measure_stretch.h"
#include "core/error.h"
#include "core/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace texfab::atlas {

void CutChartsOptions::validate() const {
  if (!(minGain >= 0 && minGain < 1)) throw Error("minGain must be in [0, 1)");
  if (!(seamCost >= 0)) throw Error("seamCost must be >= 0");
  if (maxCutsPerChart < 0) throw Error("maxCutsPerChart must be >= 0");
  if (!(minChartArea >= 0)) throw Error("minChartArea must be >= 0");
}

namespace {

struct Rect {
  double area = std::numeric_limits<double>::infinity(); ///< padded: (w + 2g)(h + 2g)
  Eigen::Vector2d dir{1, 0};                              ///< long side direction
  double length = 0, width = 0;                           ///< unpadded sides (long, short)
};

/// Minimal-area padded rectangle of a point set sorted by lexLess (convex hull by Andrew's
/// monotone chain, then every hull edge direction).
Rect minimalRectangle(const std::vector<Eigen::Vector2d>& pts, double g) {
  Rect best;
  if (pts.empty()) return best;
  const std::vector<Eigen::Vector2d> hull = convexHullOfSorted(pts);
  forEachHullEdgeRectangle(hull, [&](const Eigen::Vector2d& d, const Eigen::Vector2d& n, double along, double across) {
    const double area = (along + 2 * g) * (across + 2 * g);
    if (area < best.area * (1 - 1e-12)) {
      best.area = area;
      best.dir = along >= across ? d : n;
      best.length = std::max(along, across);
      best.width = std::min(along, across);
    }
  });
  if (hull.size() < 2) best.area = 4 * g * g, best.length = best.width = 0;
  return best;
}

struct Cutter {
  const geometry::Mesh& mesh;
  const geometry::MeshConnectivity& conn;
  const Atlas& atlas;
  double g;        ///< half gutter plus half a texel, model units
  const CutChartsOptions& options;

  Rect rectOf(const std::vector<uint32_t>& faces) const {
    std::vector<Eigen::Vector2d> pts;
    pts.reserve(3 * faces.size());
    for (uint32_t f : faces)
      for (int k = 0; k < 3; ++k) pts.push_back(atlas.chartUvs[3 * size_t(f) + size_t(k)]);
    std::sort(pts.begin(), pts.end(), lexLess);
    return minimalRectangle(pts, g);
  }

  /// Sum of the padded rectangles of the parts, given each face's part (`partOf`, local) and the
  /// chart's corners presorted by lexLess (`sorted`: point, local face): O(n) per call.
  double partsArea(const std::vector<std::pair<Eigen::Vector2d, int32_t>>& sorted, const std::vector<int32_t>& partOf,
                   int partCount, std::vector<std::vector<Eigen::Vector2d>>& scratch) const {
    if (int(scratch.size()) < partCount) scratch.resize(size_t(partCount));
    for (int p = 0; p < partCount; ++p) scratch[size_t(p)].clear();
    for (const auto& [pt, f] : sorted) scratch[size_t(partOf[size_t(f)])].push_back(pt);
    double area = 0;
    for (int p = 0; p < partCount; ++p) area += minimalRectangle(scratch[size_t(p)], g).area;
    return area;
  }

  /// Labels the connected parts of each side (`partOf`, local faces); returns the part count.
  static int labelParts(const std::vector<std::array<int32_t, 3>>& nb, const std::vector<uint8_t>& sideOf,
                        std::vector<int32_t>& partOf, std::vector<int32_t>& stack) {
    std::fill(partOf.begin(), partOf.end(), -1);
    int count = 0;
    for (size_t s = 0; s < partOf.size(); ++s) {
      if (partOf[s] >= 0) continue;
      partOf[s] = count;
      stack.assign(1, int32_t(s));
      while (!stack.empty()) {
        const int32_t f = stack.back();
        stack.pop_back();
        for (int32_t n : nb[size_t(f)])
          if (n >= 0 && partOf[size_t(n)] < 0 && sideOf[size_t(n)] == sideOf[s]) partOf[size_t(n)] = count, stack.push_back(n);
      }
      ++count;
    }
    return count;
  }

  /// Local index of mesh triangle f in the ascending `faces`, or -1.
  static int32_t local(const std::vector<uint32_t>& faces, int32_t f) {
    if (f < 0) return -1;
    const auto it = std::lower_bound(faces.begin(), faces.end(), uint32_t(f));
    return it != faces.end() && *it == uint32_t(f) ? int32_t(it - faces.begin()) : -1;
  }

  /// Connected parts of the faces whose side is `side`; `nb` holds the local neighbours.
  static std::vector<std::vector<uint32_t>> parts(const std::vector<uint32_t>& faces,
                                                  const std::vector<std::array<int32_t, 3>>& nb,
                                                  const std::vector<uint8_t>& sideOf, uint8_t side) {
    std::vector<std::vector<uint32_t>> out;
    std::vector<uint8_t> seen(faces.size(), 0);
    std::vector<int32_t> stack;
    for (size_t s = 0; s < faces.size(); ++s) {
      if (sideOf[s] != side || seen[s]) continue;
      std::vector<uint32_t> part;
      seen[s] = 1;
      stack.push_back(int32_t(s));
      while (!stack.empty()) {
        const int32_t f = stack.back();
        stack.pop_back();
        part.push_back(faces[size_t(f)]);
        for (int32_t n : nb[size_t(f)])
          if (n >= 0 && sideOf[size_t(n)] == side && !seen[size_t(n)]) seen[size_t(n)] = 1, stack.push_back(n);
      }
      std::sort(part.begin(), part.end());
      out.push_back(std::move(part));
    }
    return out;
  }

  /// Recursively cuts `faces` (a disk chart); appends the final pieces to `out`.
  void cut(std::vector<uint32_t> faces, int cutsLeft, std::vector<std::vector<uint32_t>>& out, size_t& cuts) {
    if (cutsLeft <= 0 || faces.size() < 4) {
      out.push_back(std::move(faces));
      return;
    }
    const Rect whole = rectOf(faces);
    std::vector<std::pair<Eigen::Vector2d, int32_t>> sorted;
    sorted.reserve(3 * faces.size());
    for (size_t i = 0; i < faces.size(); ++i)
      for (int k = 0; k < 3; ++k) sorted.push_back({atlas.chartUvs[3 * size_t(faces[i]) + size_t(k)], int32_t(i)});
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return lexLess(a.first, b.first); });
    std::vector<int32_t> partOf(faces.size(), -1), stack;
    std::vector<std::vector<Eigen::Vector2d>> scratch;
    std::vector<std::array<int32_t, 3>> nb(faces.size());
    for (size_t i = 0; i < faces.size(); ++i)
      for (int k = 0; k < 3; ++k) nb[i][size_t(k)] = local(faces, conn.neighbor(faces[i], k));
    std::vector<uint8_t> sideOf(faces.size(), 0);
    const Eigen::Vector2d d = whole.dir, n(-d.y(), d.x());
    // Centroid coordinates along both rectangle axes.
    std::vector<Eigen::Vector2d> c(faces.size());
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (size_t i = 0; i < faces.size(); ++i) {
      Eigen::Vector2d m = Eigen::Vector2d::Zero();
      for (int k = 0; k < 3; ++k) m += atlas.chartUvs[3 * size_t(faces[i]) + size_t(k)];
      m /= 3;
      c[i] = {m.dot(d), m.dot(n)};
      u0 = std::min(u0, c[i].x()), u1 = std::max(u1, c[i].x());
      v0 = std::min(v0, c[i].y()), v1 = std::max(v1, c[i].y());
    }
    struct Candidate {
      double score;
      int axis;
      double at;
    };
    std::vector<Candidate> candidates;
    constexpr int kPositions = 16;
    for (int axis = 0; axis < 2; ++axis) {
      const double lo = axis == 0 ? u0 : v0, hi = axis == 0 ? u1 : v1;
      if (!(hi > lo)) continue;
      for (int k = 1; k < kPositions; ++k) {
        const double at = lo + (hi - lo) * k / kPositions;
        for (size_t i = 0; i < faces.size(); ++i) sideOf[i] = (axis == 0 ? c[i].x() : c[i].y()) < at ? 0 : 1;
        // New seam: UV length of the edges between the two sides.
        double seam = 0;
        for (size_t i = 0; i < faces.size(); ++i)
          if (sideOf[i] == 0)
            for (int k2 = 0; k2 < 3; ++k2) {
              const int32_t o = nb[i][size_t(k2)];
              if (o >= 0 && sideOf[size_t(o)] == 1)
                seam += (atlas.chartUvs[3 * size_t(faces[i]) + size_t(k2)] -
                         atlas.chartUvs[3 * size_t(faces[i]) + size_t((k2 + 1) % 3)])
                            .norm();
            }
        const int partCount = labelParts(nb, sideOf, partOf, stack);
        if (partCount < 2) continue;
        const double area = partsArea(sorted, partOf, partCount, scratch);
        const double score = area + options.seamCost * 2 * g * seam;
        candidates.push_back({score, axis, at});
      }
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
    // The best cut whose pieces are all disks (a few tries).
    for (size_t t = 0; t < std::min<size_t>(candidates.size(), 4); ++t) {
      const Candidate& best = candidates[t];
      if (!(best.score < whole.area * (1 - options.minGain))) break;
      for (size_t i = 0; i < faces.size(); ++i) sideOf[i] = (best.axis == 0 ? c[i].x() : c[i].y()) < best.at ? 0 : 1;
      std::vector<std::vector<uint32_t>> pieces;
      for (uint8_t side = 0; side < 2; ++side)
        for (auto& part : parts(faces, nb, sideOf, side)) pieces.push_back(std::move(part));
      bool disks = pieces.size() >= 2;
      for (const auto& p : pieces) disks = disks && detail::buildChartMesh(mesh, conn, p).isDisk();
      if (!disks) continue;
      ++cuts;
      // Every piece may be cut again, one level fewer (a straight cut of a concave chart may
      // leave more than two pieces: they count as levels too).
      for (auto& p : pieces) cut(std::move(p), cutsLeft - int(pieces.size()) + 1, out, cuts);
      return;
    }
    out.push_back(std::move(faces));
  }
};

double seamLength(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const std::vector<int32_t>& faceChart) {
  double length = 0;
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int32_t o = conn.neighbor(t, k);
      if (o > int32_t(t) && faceChart[size_t(o)] != faceChart[t])
        length += double((mesh.corner(t, k) - mesh.corner(t, (k + 1) % 3)).norm());
    }
  return length;
}

} // namespace

CutChartsReport cutChartsForPacking(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, Atlas& atlas, int width,
                                    int height, int gutter, const CutChartsOptions& options, const Context& ctx) {
  options.validate();
  CutChartsReport report;
  if (!options.enabled || atlas.charts.empty()) return report;
  double total = 0;
  for (const Chart& c : atlas.charts) total += c.area;
  if (!(total > 0)) return report;
  // Packing density estimate (texels per unit) for a ~75 % full atlas; the cut decisions only
  // weigh the gutter band against the voids.
  const double density = std::sqrt(0.75 * double(width) * double(height) / total);
  const double g = (0.5 * gutter + 0.5) / density;
  std::vector<std::vector<std::vector<uint32_t>>> pieces(atlas.charts.size());
  std::vector<size_t> cutCount(atlas.charts.size(), 0);
  const int chunks = int(atlas.charts.size());
  parallelFor(0, chunks, ctx, [&](int b, int e) {
    Cutter cutter{mesh, conn, atlas, g, options};
    for (int i = b; i < e; ++i) {
      const Chart& chart = atlas.charts[size_t(i)];
      if (chart.area < options.minChartArea * total) {
        pieces[size_t(i)].push_back(chart.faces);
        continue;
      }
      cutter.cut(chart.faces, options.maxCutsPerChart, pieces[size_t(i)], cutCount[size_t(i)]);
    }
  });
  for (size_t n : cutCount) report.cuts += n;
  if (report.cuts == 0) return report;
  std::vector<Chart> charts;
  for (size_t i = 0; i < atlas.charts.size(); ++i) {
    if (pieces[i].size() == 1) {
      charts.push_back(std::move(atlas.charts[i]));
      continue;
    }
    for (auto& p : pieces[i]) {
      Chart chart;
      chart.faces = std::move(p);
      chart.disk = true;
      for (uint32_t f : chart.faces) chart.area += conn.area[f];
      chart.boundaryLength = detail::buildChartMesh(mesh, conn, chart.faces).boundaryLength;
      const StretchStats s = measureStretch(mesh, chart.faces, [&](size_t corner) { return atlas.chartUvs[corner]; });
      chart.l2Stretch = s.l2;
      chart.maxStretch = s.max;
      charts.push_back(std::move(chart));
    }
  }
  std::sort(charts.begin(), charts.end(), [](const Chart& x, const Chart& y) { return x.faces.front() < y.faces.front(); });
  const double before = seamLength(mesh, conn, atlas.faceChart);
  atlas.faceChart.assign(mesh.triangleCount(), -1);
  for (size_t c = 0; c < charts.size(); ++c)
    for (uint32_t f : charts[c].faces) atlas.faceChart[f] = int32_t(c);
  atlas.charts = std::move(charts);
  report.seamLengthAdded = seamLength(mesh, conn, atlas.faceChart) - before;
  return report;
}

} // namespace texfab::atlas
