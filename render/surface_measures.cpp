// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/surface_measures.h"

#include "core/error.h"
#include "synthesis/quality_measures.h"

#include <algorithm>
#include <cmath>

namespace texfab::render {
using namespace atlas;

namespace {

int colorChannels(const Image& image) { return image.channels >= 3 ? 3 : 1; }

// Toroidal difference b - a of two exemplar coordinates (pixels), in [-size/2, size/2).
double wrapped(double a, double b, double size) {
  const double d = b - a;
  return d - size * std::floor(d / size + 0.5);
}

} // namespace

SeamMeasure measureSeams(const synthesis::SurfaceLevel& finest, const Image& image) {
  const int c = colorChannels(image);
  SeamMeasure m;
  double seamSum = 0, interiorSum = 0;
  for (size_t s = 0; s < finest.size(); ++s)
    for (int d = 0; d < 8; d += 2) {  // the 4 axis steps
      const int32_t n = finest.neighbors[s][size_t(d)];
      if (n < 0) continue;
      const float* a = image.pixel(finest.x[s], finest.y[s]);
      const float* b = image.pixel(finest.x[size_t(n)], finest.y[size_t(n)]);
      double diff = 0;
      for (int ch = 0; ch < c; ++ch) diff += std::fabs(double(a[ch]) - double(b[ch]));
      diff /= c;
      if (finest.chart[size_t(n)] != finest.chart[s]) seamSum += diff, ++m.seamPairs;
      else interiorSum += diff, ++m.interiorPairs;
    }
  m.seamDifference = m.seamPairs ? seamSum / double(m.seamPairs) : 0;
  m.interiorDifference = m.interiorPairs ? interiorSum / double(m.interiorPairs) : 0;
  m.ratio = m.interiorDifference > 0 ? m.seamDifference / m.interiorDifference : (m.seamDifference > 0 ? INFINITY : 1);
  return m;
}

ScaleMeasure measureScale(const synthesis::SurfaceLevel& finest, const std::vector<uint32_t>& coords,
                          const AtlasFields& fields, int exemplarWidth, int exemplarHeight,
                          double requestedPixelsPerUnit, double tolerance) {
  if (coords.size() != finest.size()) throw Error("scale measure: one coordinate per site expected");
  const int w = fields.samples.width, h = fields.samples.height;
  TexelField<int32_t> site(w, h, -1);
  for (size_t s = 0; s < finest.size(); ++s) site.at(finest.x[s], finest.y[s]) = int32_t(s);

  // Per texel and axis (0 = x, 1 = y): the pair (texel, texel + axis step) when both are sites of
  // the same chart and coherent; its squared coordinate step and squared surface step.
  struct Pair {
    float dc2 = -1, dp2 = 0;
  };
  std::vector<Pair> pairs(size_t(w) * size_t(h) * 2);
  for (size_t s = 0; s < finest.size(); ++s)
    for (int axis = 0; axis < 2; ++axis) {
      const int x = finest.x[s], y = finest.y[s], nx = x + (axis == 0), ny = y + (axis == 1);
      if (!site.contains(nx, ny)) continue;
      const int32_t n = site.at(nx, ny);
      if (n < 0 || finest.chart[size_t(n)] != finest.chart[s]) continue;
      const Float3 &p = fields.position.at(x, y), &q = fields.position.at(nx, ny);
      const double dp2 = double(q.x - p.x) * (q.x - p.x) + double(q.y - p.y) * (q.y - p.y) + double(q.z - p.z) * (q.z - p.z);
      const uint32_t a = coords[s], b = coords[size_t(n)];
      const double du = wrapped(synthesis::surfaceU(a), synthesis::surfaceU(b), exemplarWidth);
      const double dv = wrapped(synthesis::surfaceV(a), synthesis::surfaceV(b), exemplarHeight);
      const double limit = 2.0 * requestedPixelsPerUnit * std::sqrt(dp2) + 1.5;
      if (du * du + dv * dv > limit * limit) continue;  // a jump between patches
      pairs[site.index(x, y) * 2 + size_t(axis)] = {float(du * du + dv * dv), float(dp2)};
    }

  ScaleMeasure m;
  m.tolerance = tolerance;
  std::vector<float> scales, window;
  size_t within = 0;
  for (size_t s = 0; s < finest.size(); ++s) {
    window.clear();
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const int x = finest.x[s] + dx, y = finest.y[s] + dy;
        if (!site.contains(x, y)) continue;
        const int32_t t = site.at(x, y);
        if (t < 0 || finest.chart[size_t(t)] != finest.chart[s]) continue;
        for (int axis = 0; axis < 2; ++axis) {
          const Pair& p = pairs[site.index(x, y) * 2 + size_t(axis)];
          if (p.dc2 >= 0 && p.dp2 > 0) window.push_back(std::sqrt(p.dc2 / p.dp2));
        }
      }
    if (window.size() < 8) continue;
    std::nth_element(window.begin(), window.begin() + std::ptrdiff_t(window.size() / 2), window.end());
    const double scale = window[window.size() / 2];
    scales.push_back(float(scale));
    if (std::fabs(scale / requestedPixelsPerUnit - 1.0) <= tolerance) ++within;
  }
  if (!finest.size()) return m;
  m.fractionMeasured = double(scales.size()) / double(finest.size());
  m.fractionWithin = double(within) / double(finest.size());
  if (!scales.empty()) {
    std::nth_element(scales.begin(), scales.begin() + std::ptrdiff_t(scales.size() / 2), scales.end());
    m.medianPixelsPerUnit = scales[scales.size() / 2];
  }
  return m;
}

SurfaceFidelity measureSurfaceFidelity(const synthesis::SurfaceLevel& finest, const Image& image,
                                       const Image& exemplar, const AtlasFields& fields,
                                       const synthesis::FidelityOptions& options, const Context& ctx) {
  const int r = options.radius, samples = options.samples;
  const int c = colorChannels(exemplar);
  if (colorChannels(image) != c) throw Error("surface fidelity: image and exemplar differ in colour channels");
  SurfaceFidelity out;
  if (finest.size() == 0 || samples <= 0) return out;
  const size_t stride = std::max<size_t>(1, finest.size() / size_t(samples));
  std::vector<float> patches, patch;
  for (size_t s = stride / 2; s < finest.size() && out.samples < size_t(samples); s += stride) {
    const auto& j = finest.jacobian[s];
    const double det = double(j[0]) * j[3] - double(j[1]) * j[2];
    if (det == 0) continue;
    // J⁻¹: exemplar pixels -> atlas texels.
    const double i00 = j[3] / det, i01 = -j[1] / det, i10 = -j[2] / det, i11 = j[0] / det;
    const double cx = finest.x[s] + 0.5, cy = finest.y[s] + 0.5;
    patch.clear();
    bool inside = true;
    for (int v = -r; v <= r && inside; ++v)
      for (int u = -r; u <= r && inside; ++u) {
        const double px = cx + i00 * u + i01 * v - 0.5, py = cy + i10 * u + i11 * v - 0.5;
        const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
        const double fx = px - x0, fy = py - y0;
        for (int k = 0; k < 4 && inside; ++k) {
          const int x = x0 + (k & 1), y = y0 + (k >> 1);
          inside = fields.samples.contains(x, y) && fields.samples.at(x, y).chart == finest.chart[s];
        }
        if (!inside) break;
        for (int ch = 0; ch < c; ++ch) {
          const double top = (1 - fx) * image.at(x0, y0, ch) + fx * image.at(x0 + 1, y0, ch);
          const double bottom = (1 - fx) * image.at(x0, y0 + 1, ch) + fx * image.at(x0 + 1, y0 + 1, ch);
          patch.push_back(float((1 - fy) * top + fy * bottom));
        }
      }
    if (!inside) continue;
    patches.insert(patches.end(), patch.begin(), patch.end());
    ++out.samples;
  }
  if (out.samples) out.fidelity = synthesis::patchFidelity(patches, exemplar, options, ctx);
  return out;
}

} // namespace texfab::render
