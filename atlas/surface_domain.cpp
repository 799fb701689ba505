// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6.
#include "atlas/surface_domain.h"

#include "atlas/build_indirection_map.h"
#include "core/error.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>

namespace texfab::atlas {

namespace {

using synthesis::SurfaceLevel;

// Sites of one level grouped by texel: the sites of texel i are [first[i], first[i + 1]).
struct TexelIndex {
  int width = 0, height = 0;
  std::vector<int32_t> first;

  int32_t find(const SurfaceLevel& level, int x, int y, int32_t chart) const {
    if (x < 0 || y < 0 || x >= width || y >= height) return -1;
    const size_t i = size_t(y) * size_t(width) + size_t(x);
    for (int32_t s = first[i]; s < first[i + 1]; ++s)
      if (level.chart[size_t(s)] == chart) return s;
    return -1;
  }
};

TexelIndex indexTexels(const SurfaceLevel& level) {
  TexelIndex index{level.width, level.height, std::vector<int32_t>(size_t(level.width) * level.height + 1, 0)};
  for (size_t s = 0; s < level.size(); ++s) ++index.first[size_t(level.y[s]) * level.width + size_t(level.x[s]) + 1];
  for (size_t i = 1; i < index.first.size(); ++i) index.first[i] += index.first[i - 1];
  return index;
}

// The site of `level` (cells of `cell` atlas texels) where atlas point (px, py) of `chart` lies:
// the one of that chart in the point's cell, else the nearest one of that chart in the 3x3 cells
// around it (a landing point just outside the chart's rasterized texels), else -1.
int32_t siteAt(const SurfaceLevel& level, const TexelIndex& index, int cell, double px, double py, int32_t chart) {
  const int cx = int(std::floor(px / cell)), cy = int(std::floor(py / cell));
  if (const int32_t s = index.find(level, cx, cy, chart); s >= 0) return s;
  int32_t best = -1;
  double bestDistance = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int32_t s = index.find(level, cx + dx, cy + dy, chart);
      if (s < 0) continue;
      const double ex = (cx + dx + 0.5) * cell - px, ey = (cy + dy + 0.5) * cell - py;
      const double d = ex * ex + ey * ey;
      if (best < 0 || d < bestDistance) best = s, bestDistance = d;
    }
  return best;
}

// Neighbors of every site of `level` (cells of `cell` atlas texels); repX/repY give each site's
// representative chart texel of level 0, where border walks start.
void linkNeighbors(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity, const Atlas& atlas,
                   const AtlasFields& fields, SurfaceLevel& level, const std::vector<int32_t>& repX,
                   const std::vector<int32_t>& repY, int cell, const Context& ctx) {
  const TexelIndex index = indexTexels(level);
  level.neighbors.assign(level.size(), {});
  parallelFor(0, int(level.size()), ctx, [&](int begin, int end) {
    for (int s = begin; s < end; ++s) {
      const size_t i = size_t(s);
      for (int d = 0; d < 8; ++d) {
        const int dx = synthesis::kSurfaceStepX[d], dy = synthesis::kSurfaceStepY[d];
        int32_t n = index.find(level, level.x[i] + dx, level.y[i] + dy, level.chart[i]);
        if (n < 0) {
          const SurfaceSample& sample = fields.samples.at(repX[i], repY[i]);
          const IndirectionTarget t =
              walkAtlas(mesh, connectivity, atlas, sample.triangle, {repX[i] + 0.5, repY[i] + 0.5},
                        {double(dx) * cell, double(dy) * cell});
          if (!t.hitBoundary) n = siteAt(level, index, cell, t.x, t.y, t.chart);
          if (n == s) n = -1;
        }
        level.neighbors[i][size_t(d)] = n;
      }
    }
  }, 1024);
}

// The finest level: one site per chart texel, row-major.
SurfaceLevel finestLevel(const Atlas& atlas, const AtlasFields& fields, const TexelField<TexelJacobian>& jacobians) {
  SurfaceLevel level;
  level.width = atlas.width;
  level.height = atlas.height;
  level.x.reserve(fields.chartTexels);
  level.y.reserve(fields.chartTexels);
  level.chart.reserve(fields.chartTexels);
  level.jacobian.reserve(fields.chartTexels);
  for (int y = 0; y < atlas.height; ++y)
    for (int x = 0; x < atlas.width; ++x) {
      const int32_t chart = fields.samples.at(x, y).chart;
      if (chart < 0) continue;
      level.x.push_back(x);
      level.y.push_back(y);
      level.chart.push_back(chart);
      if (jacobians.values.empty()) {
        level.jacobian.push_back({1.0f, 0.0f, 0.0f, 1.0f});
      } else {
        const float* j = jacobians.at(x, y).j;
        level.jacobian.push_back({-j[2], -j[3], -j[0], -j[1]}); // exemplar +u = -b, +v = -t (see header)
      }
    }
  level.parent.assign(level.size(), -1);
  // A degenerate Jacobian (a singular point of the tangent field, a degenerate triangle) becomes
  // an isotropic one of the median scale, so every site can predict its neighborhood.
  const double found = synthesis::medianPixelsPerTexel(level);
  const float median = found > 0 ? float(found) : 1.0f;
  for (auto& j : level.jacobian) {
    const float det = j[0] * j[3] - j[1] * j[2];
    const bool finite = std::isfinite(j[0]) && std::isfinite(j[1]) && std::isfinite(j[2]) && std::isfinite(j[3]);
    if (!finite || !(std::fabs(det) > 1e-6f * median * median)) j = {median, 0.0f, 0.0f, median};
  }
  return level;
}

// Level a+1 from level a: one site per (coarse texel, chart), children's Jacobians averaged and
// doubled; each site's representative is its children's representative closest to its centre.
SurfaceLevel coarserLevel(SurfaceLevel& fine, const std::vector<int32_t>& fineRepX,
                          const std::vector<int32_t>& fineRepY, int cell, std::vector<int32_t>& repX,
                          std::vector<int32_t>& repY) {
  SurfaceLevel coarse;
  coarse.width = (fine.width + 1) / 2;
  coarse.height = (fine.height + 1) / 2;
  const TexelIndex index = indexTexels(fine);
  repX.clear();
  repY.clear();
  std::vector<int32_t> children;
  std::vector<int32_t> charts;
  for (int y = 0; y < coarse.height; ++y)
    for (int x = 0; x < coarse.width; ++x) {
      children.clear();
      for (int cy = 2 * y; cy < std::min(2 * y + 2, fine.height); ++cy)
        for (int cx = 2 * x; cx < std::min(2 * x + 2, fine.width); ++cx) {
          const size_t i = size_t(cy) * size_t(fine.width) + size_t(cx);
          for (int32_t s = index.first[i]; s < index.first[i + 1]; ++s) children.push_back(s);
        }
      charts.clear();
      for (int32_t c : children) charts.push_back(fine.chart[size_t(c)]);
      std::sort(charts.begin(), charts.end());
      charts.erase(std::unique(charts.begin(), charts.end()), charts.end());
      const double centreX = (x + 0.5) * cell, centreY = (y + 0.5) * cell;
      for (int32_t chart : charts) {
        const auto site = int32_t(coarse.size());
        std::array<float, 4> sum{0, 0, 0, 0};
        int count = 0;
        int32_t rep = -1;
        double repDistance = 0;
        for (int32_t c : children) {
          if (fine.chart[size_t(c)] != chart) continue;
          fine.parent[size_t(c)] = site;
          for (int k = 0; k < 4; ++k) sum[size_t(k)] += fine.jacobian[size_t(c)][size_t(k)];
          ++count;
          const double ex = fineRepX[size_t(c)] + 0.5 - centreX, ey = fineRepY[size_t(c)] + 0.5 - centreY;
          const double d = ex * ex + ey * ey;
          if (rep < 0 || d < repDistance) rep = c, repDistance = d;
        }
        const float f = 2.0f / float(count);
        coarse.x.push_back(x);
        coarse.y.push_back(y);
        coarse.chart.push_back(chart);
        coarse.jacobian.push_back({sum[0] * f, sum[1] * f, sum[2] * f, sum[3] * f});
        coarse.parent.push_back(-1);
        repX.push_back(fineRepX[size_t(rep)]);
        repY.push_back(fineRepY[size_t(rep)]);
      }
    }
  return coarse;
}

} // namespace

synthesis::SurfaceDomain buildSurfaceDomain(const geometry::Mesh& mesh, const geometry::MeshConnectivity& connectivity,
                                            const Atlas& atlas, const AtlasFields& fields,
                                            const TexelField<TexelJacobian>& jacobians,
                                            const SurfaceDomainOptions& options, const Context& ctx) {
  if (options.maxLevels < 1) throw Error("surface domain: maxLevels must be >= 1");
  if (fields.samples.width != atlas.width)
    throw Error("surface domain: the texel fields must have the atlas's size");
  if (!jacobians.values.empty() ? jacobians.width != atlas.width || jacobians.height != atlas.height
                                : options.maxLevels != 1)
    throw Error("surface domain: the Jacobians must have the atlas's size (or be empty, for one level)");
  synthesis::SurfaceDomain domain;
  domain.levels.push_back(finestLevel(atlas, fields, jacobians));
  if (!options.neighbors) {
    if (options.maxLevels != 1) throw Error("surface domain: coarse levels need the neighbors");
    return domain;
  }
  std::vector<int32_t> repX = domain.levels[0].x, repY = domain.levels[0].y;
  linkNeighbors(mesh, connectivity, atlas, fields, domain.levels[0], repX, repY, 1, ctx);
  for (int a = 1; a < options.maxLevels; ++a) {
    const SurfaceLevel& last = domain.levels.back();
    if (last.width <= 1 && last.height <= 1) break;
    std::vector<int32_t> coarseX, coarseY;
    SurfaceLevel coarse = coarserLevel(domain.levels.back(), repX, repY, 1 << a, coarseX, coarseY);
    linkNeighbors(mesh, connectivity, atlas, fields, coarse, coarseX, coarseY, 1 << a, ctx);
    domain.levels.push_back(std::move(coarse));
    repX = std::move(coarseX);
    repY = std::move(coarseY);
  }
  return domain;
}

} // namespace texfab::atlas
