// SPDX-License-Identifier: GPL-3.0-or-later
// Chart segmentation.
//  - D. Cohen-Steiner, P. Alliez, M. Desbrun, "Variational Shape Approximation", SIGGRAPH 2004:
//    the L2,1 normal metric and Lloyd iterations of competitive region growing.
//  - P. Sander, J. Snyder, S. Gortler, H. Hoppe, "Texture Mapping Progressive Meshes", SIGGRAPH
//    2001, and B. Lévy et al., "Least Squares Conformal Maps", SIGGRAPH 2002: charts should be
//    nearly developable (bounded normal cone) and compact, with short boundaries.
#include "atlas/segment_charts.h"

#include "atlas/chart_mesh.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <tuple>

namespace texfab::atlas {

void SegmentChartsOptions::validate() const {
  if (!(maxNormalDeviationDegrees > 0 && maxNormalDeviationDegrees <= 90))
    throw Error("maxNormalDeviationDegrees must be in (0, 90], got " + std::to_string(maxNormalDeviationDegrees));
  if (!(compactnessWeight >= 0)) throw Error("compactnessWeight must be >= 0");
  if (lloydIterations < 0) throw Error("lloydIterations must be >= 0");
}

namespace {

using Item = std::tuple<double, uint32_t, uint32_t>; // cost, face, chart
using MinQueue = std::priority_queue<Item, std::vector<Item>, std::greater<Item>>;

struct Proxy {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d seedPoint = Eigen::Vector3d::Zero();
  uint32_t seed = 0;
  double radius = 1;
};

/// Unit normals (zero for degenerate triangles) and centroids, in double precision.
struct TriangleFrames {
  std::vector<Eigen::Vector3d> normal, centroid;
  explicit TriangleFrames(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn)
      : normal(mesh.triangleCount(), Eigen::Vector3d::Zero()), centroid(mesh.triangleCount()) {
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
      centroid[t] = geometry::triangleCentroid(mesh, t);
      const Eigen::Vector3d a = mesh.corner(t, 0).cast<double>();
      const Eigen::Vector3d cr = (mesh.corner(t, 1).cast<double>() - a).cross(mesh.corner(t, 2).cast<double>() - a);
      if (!conn.degenerate[t]) normal[t] = cr / cr.norm();
    }
  }
};

/// Greedy growth of new charts from every unassigned face, in face order.
void growGreedy(const geometry::MeshConnectivity& conn, const TriangleFrames& tri, std::vector<int32_t>& faceChart,
                int32_t& chartCount, double cosMax, double compactness) {
  const size_t n = faceChart.size();
  for (size_t s = 0; s < n; ++s) {
    if (faceChart[s] != -2) continue;
    const int32_t c = chartCount++;
    Eigen::Vector3d sum = tri.normal[s] * conn.area[s];
    double area = conn.area[s];
    faceChart[s] = c;
    MinQueue pq;
    auto pushNeighbors = [&](uint32_t f) {
      const Eigen::Vector3d N = sum.normalized();
      const double radius = std::sqrt(std::max(area, 1e-30) / M_PI);
      for (int k = 0; k < 3; ++k)
        if (const int32_t g = conn.neighbor(f, k); g >= 0 && faceChart[size_t(g)] == -2) {
          const double cost = (1 - tri.normal[size_t(g)].dot(N)) +
                              compactness * (tri.centroid[size_t(g)] - tri.centroid[s]).norm() / radius * 0.1;
          pq.push({cost, uint32_t(g), uint32_t(c)});
        }
    };
    pushNeighbors(uint32_t(s));
    while (!pq.empty()) {
      const uint32_t f = std::get<1>(pq.top());
      pq.pop();
      if (faceChart[f] != -2) continue;
      const Eigen::Vector3d N = sum.normalized();
      if (tri.normal[f].dot(N) < cosMax || tri.normal[f].dot(tri.normal[s]) < cosMax) continue;
      faceChart[f] = c;
      sum += tri.normal[f] * conn.area[f];
      area += conn.area[f];
      pushNeighbors(f);
    }
  }
}

void renumber(std::vector<int32_t>& faceChart, int32_t& chartCount) {
  std::vector<int32_t> map(size_t(chartCount), -1);
  int32_t next = 0;
  for (int32_t& c : faceChart)
    if (c >= 0) {
      if (map[size_t(c)] < 0) map[size_t(c)] = next++;
      c = map[size_t(c)];
    }
  chartCount = next;
}

} // namespace

SegmentChartsReport segmentCharts(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, Atlas& atlas,
                                  const SegmentChartsOptions& options) {
  options.validate();
  const size_t n = mesh.triangleCount();
  const double cosMax = std::cos(options.maxNormalDeviationDegrees * M_PI / 180.0);
  const TriangleFrames tri(mesh, conn);
  std::vector<int32_t> faceChart(n, -2); // -2 = unassigned, -1 = degenerate
  for (size_t t = 0; t < n; ++t)
    if (conn.degenerate[t]) faceChart[t] = -1;
  int32_t chartCount = 0;
  growGreedy(conn, tri, faceChart, chartCount, cosMax, options.compactnessWeight);

  for (int it = 0; it < options.lloydIterations; ++it) {
    // Proxies: area-weighted mean normal, centroid; the seed is the face that best fits both.
    std::vector<Proxy> proxies(static_cast<size_t>(chartCount));
    std::vector<Eigen::Vector3d> centroid(size_t(chartCount), Eigen::Vector3d::Zero());
    std::vector<double> area(size_t(chartCount), 0.0);
    for (size_t t = 0; t < n; ++t) {
      const int32_t c = faceChart[t];
      if (c < 0) continue;
      proxies[size_t(c)].normal += tri.normal[t] * conn.area[t];
      centroid[size_t(c)] += tri.centroid[t] * conn.area[t];
      area[size_t(c)] += conn.area[t];
    }
    std::vector<double> bestCost(size_t(chartCount), std::numeric_limits<double>::infinity());
    for (size_t c = 0; c < size_t(chartCount); ++c) {
      if (proxies[c].normal.squaredNorm() > 0) proxies[c].normal.normalize();
      centroid[c] /= std::max(area[c], 1e-300);
      proxies[c].radius = std::sqrt(std::max(area[c], 1e-30) / M_PI);
    }
    for (size_t t = 0; t < n; ++t) {
      const int32_t c = faceChart[t];
      if (c < 0) continue;
      const Proxy& p = proxies[size_t(c)];
      const double cost = (1 - tri.normal[t].dot(p.normal)) + (tri.centroid[t] - centroid[size_t(c)]).norm() / p.radius;
      if (cost < bestCost[size_t(c)]) {
        bestCost[size_t(c)] = cost;
        proxies[size_t(c)].seed = uint32_t(t);
      }
    }
    // Competitive growth from all seeds at once.
    for (size_t t = 0; t < n; ++t)
      if (faceChart[t] >= 0) faceChart[t] = -2;
    MinQueue pq;
    for (size_t c = 0; c < size_t(chartCount); ++c) {
      if (area[c] <= 0) continue;
      proxies[c].seedPoint = tri.centroid[proxies[c].seed];
      pq.push({0.0, proxies[c].seed, uint32_t(c)});
    }
    while (!pq.empty()) {
      const auto [cost, f, c] = pq.top();
      pq.pop();
      if (faceChart[f] != -2) continue;
      faceChart[f] = int32_t(c);
      const Proxy& p = proxies[c];
      for (int k = 0; k < 3; ++k) {
        const int32_t g = conn.neighbor(f, k);
        if (g < 0 || faceChart[size_t(g)] != -2) continue;
        const double d = tri.normal[size_t(g)].dot(p.normal);
        if (d < cosMax) continue;
        const double gc = (1 - d) +
                          options.compactnessWeight * (tri.centroid[size_t(g)] - p.seedPoint).norm() / p.radius;
        pq.push({gc, uint32_t(g), c});
      }
    }
    growGreedy(conn, tri, faceChart, chartCount, cosMax, options.compactnessWeight);
    renumber(faceChart, chartCount);
  }

  // Boundary smoothing: a triangle with two of its three neighbours in another chart (a tooth of a
  // ragged border) moves there when its normal fits that chart's cone. Shorter seams, charts that
  // pack tighter. Sequential in triangle order (deterministic).
  for (int pass = 0; pass < options.smoothingPasses; ++pass) {
    std::vector<Eigen::Vector3d> proxy(size_t(chartCount), Eigen::Vector3d::Zero());
    for (size_t t = 0; t < n; ++t)
      if (faceChart[t] >= 0) proxy[size_t(faceChart[t])] += tri.normal[t] * conn.area[t];
    for (auto& p : proxy)
      if (p.squaredNorm() > 0) p.normalize();
    size_t changed = 0;
    for (size_t t = 0; t < n; ++t) {
      const int32_t c = faceChart[t];
      if (c < 0) continue;
      int32_t other[3];
      int count = 0;
      for (int k = 0; k < 3; ++k) {
        const int32_t g = conn.neighbor(t, k);
        other[k] = g >= 0 ? faceChart[size_t(g)] : -1;
      }
      for (int k = 0; k < 3; ++k) {
        const int32_t o = other[k];
        if (o < 0 || o == c) continue;
        count = (other[0] == o) + (other[1] == o) + (other[2] == o);
        if (count >= 2 && tri.normal[t].dot(proxy[size_t(o)]) >= cosMax) {
          faceChart[t] = o;
          ++changed;
          break;
        }
      }
    }
    if (changed == 0) break;
  }
  renumber(faceChart, chartCount);

  atlas.faceChart = faceChart;
  atlas.charts.assign(size_t(chartCount), Chart{});
  for (size_t t = 0; t < n; ++t)
    if (faceChart[t] >= 0) atlas.charts[size_t(faceChart[t])].faces.push_back(uint32_t(t));
  SegmentChartsReport report;
  report.splitsForDisks = makeChartsDisks(mesh, conn, atlas);
  report.charts = atlas.charts.size();
  report.degenerateTriangles = conn.degenerateTriangles;
  report.nonManifoldEdges = conn.nonManifoldEdges;
  report.inconsistentEdges = conn.inconsistentEdges;
  return report;
}

size_t makeChartsDisks(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, Atlas& atlas) {
  std::vector<std::vector<uint32_t>> work;
  for (Chart& c : atlas.charts)
    for (auto& part : detail::connectedParts(conn, c.faces)) work.push_back(std::move(part));
  std::vector<Chart> done;
  size_t splits = 0;
  while (!work.empty()) {
    std::vector<uint32_t> faces = std::move(work.back());
    work.pop_back();
    const detail::ChartMesh cm = detail::buildChartMesh(mesh, conn, faces);
    if (cm.isDisk()) {
      Chart chart;
      chart.faces = std::move(faces);
      chart.disk = true;
      chart.boundaryLength = cm.boundaryLength;
      for (uint32_t f : chart.faces) chart.area += conn.area[f];
      done.push_back(std::move(chart));
      continue;
    }
    std::vector<uint32_t> a, b;
    detail::splitFaces(mesh, conn, faces, a, b);
    ++splits;
    for (auto* half : {&a, &b})
      for (auto& part : detail::connectedParts(conn, *half)) work.push_back(std::move(part));
  }
  std::sort(done.begin(), done.end(), [](const Chart& x, const Chart& y) { return x.faces.front() < y.faces.front(); });
  atlas.charts = std::move(done);
  atlas.faceChart.assign(mesh.triangleCount(), -1);
  for (size_t c = 0; c < atlas.charts.size(); ++c)
    for (uint32_t f : atlas.charts[c].faces) atlas.faceChart[f] = int32_t(c);
  return splits;
}

} // namespace texfab::atlas
