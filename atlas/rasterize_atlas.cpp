// SPDX-License-Identifier: GPL-3.0-or-later
// Atlas rasterization (texel-center sampling) and gutter filling by nearest-texel propagation:
//  - P.-E. Danielsson, "Euclidean distance mapping", CGIP 1980 (two-pass vector propagation).
#include "atlas/rasterize_atlas.h"

#include "core/parallel.h"

#include <algorithm>
#include <cmath>

namespace texfab::atlas {

void atlasBarycentrics(const Atlas& atlas, uint32_t t, const Eigen::Vector2d& p, double& b1, double& b2) {
  const Eigen::Vector2d a = atlas.texelUvs[3 * size_t(t)].cast<double>();
  const Eigen::Vector2d e1 = atlas.texelUvs[3 * size_t(t) + 1].cast<double>() - a;
  const Eigen::Vector2d e2 = atlas.texelUvs[3 * size_t(t) + 2].cast<double>() - a;
  const double det = e1.x() * e2.y() - e1.y() * e2.x();
  const Eigen::Vector2d d = p - a;
  if (det == 0) {
    b1 = b2 = 0;
    return;
  }
  b1 = (d.x() * e2.y() - d.y() * e2.x()) / det;
  b2 = (e1.x() * d.y() - e1.y() * d.x()) / det;
}

namespace {

// Position and smooth normal at barycentrics of a triangle; vertex normals (area-weighted) when
// the mesh has none.
class SurfaceEvaluator {
public:
  explicit SurfaceEvaluator(const geometry::Mesh& mesh) : mesh_(mesh) {
    if (mesh.hasNormals()) return;
    vertexNormal_.assign(mesh.vertexCount(), Eigen::Vector3f::Zero());
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
      const Eigen::Vector3f n = (mesh.corner(t, 1) - mesh.corner(t, 0)).cross(mesh.corner(t, 2) - mesh.corner(t, 0));
      for (int k = 0; k < 3; ++k) vertexNormal_[mesh.triangles[t][size_t(k)]] += n;
    }
    for (auto& n : vertexNormal_)
      if (n.squaredNorm() > 0) n.normalize();
  }

  void operator()(uint32_t t, float b1, float b2, Float3& pos, Float3& nrm) const {
    const float b0 = 1 - b1 - b2;
    const Eigen::Vector3f p = b0 * mesh_.corner(t, 0) + b1 * mesh_.corner(t, 1) + b2 * mesh_.corner(t, 2);
    Eigen::Vector3f n = b0 * cornerNormal(t, 0) + b1 * cornerNormal(t, 1) + b2 * cornerNormal(t, 2);
    if (n.squaredNorm() > 0) n.normalize();
    pos = {p.x(), p.y(), p.z()};
    nrm = {n.x(), n.y(), n.z()};
  }

private:
  Eigen::Vector3f cornerNormal(size_t t, int k) const {
    return mesh_.hasNormals() ? mesh_.normals[3 * t + size_t(k)] : vertexNormal_[mesh_.triangles[t][size_t(k)]];
  }
  const geometry::Mesh& mesh_;
  std::vector<Eigen::Vector3f> vertexNormal_;
};

struct TexelTriangle {
  uint32_t t;
  int32_t chart;
  int x0, x1, y0, y1;  // texel bounds, inclusive
};

// The charts' triangles in chart order, with the texels their bounding boxes cover.
std::vector<TexelTriangle> texelTriangles(const Atlas& atlas) {
  std::vector<TexelTriangle> triangles;
  for (size_t c = 0; c < atlas.charts.size(); ++c)
    for (uint32_t t : atlas.charts[c].faces) {
      Eigen::Vector2d p[3];
      for (int k = 0; k < 3; ++k) p[k] = atlas.texelUvs[3 * size_t(t) + size_t(k)].cast<double>();
      triangles.push_back({t, int32_t(c), std::max(0, int(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}) - 0.5))),
                           std::min(atlas.width - 1, int(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}) - 0.5))),
                           std::max(0, int(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}) - 0.5))),
                           std::min(atlas.height - 1, int(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}) - 0.5)))});
    }
  return triangles;
}

// The texels whose centres lie in a chart triangle; the first triangle in chart order to cover a
// centre owns it. Bands of rows run in parallel, each over every triangle in that order: the
// same result on any number of threads.
void rasterizeCharts(const geometry::Mesh& mesh, const Atlas& atlas, AtlasFields& fields, const Context& ctx) {
  const SurfaceEvaluator evaluate(mesh);
  const std::vector<TexelTriangle> triangles = texelTriangles(atlas);
  constexpr int kBand = 32;
  const int H = atlas.height, bands = (H + kBand - 1) / kBand;
  std::vector<size_t> chartTexels(size_t(bands), 0), overlapping(size_t(bands), 0);
  parallelFor(0, bands, ctx, [&](int b0, int b1) {
    for (int band = b0; band < b1; ++band) {
      const int rowBegin = band * kBand, rowEnd = std::min(H, rowBegin + kBand);
      for (const TexelTriangle& tri : triangles) {
        if (tri.y1 < rowBegin || tri.y0 >= rowEnd) continue;
        for (int y = std::max(tri.y0, rowBegin); y <= std::min(tri.y1, rowEnd - 1); ++y)
          for (int x = tri.x0; x <= tri.x1; ++x) {
            double b1, b2;
            atlasBarycentrics(atlas, tri.t, {x + 0.5, y + 0.5}, b1, b2);
            const double b0 = 1 - b1 - b2;
            const double eps = -1e-9;
            if (b0 < eps || b1 < eps || b2 < eps) continue;
            SurfaceSample& s = fields.samples.at(x, y);
            if (s.chart >= 0) {
              if (s.chart != tri.chart) ++overlapping[size_t(band)];
              continue;
            }
            s = {tri.chart, tri.t, float(b1), float(b2)};
            evaluate(tri.t, float(b1), float(b2), fields.position.at(x, y), fields.normal.at(x, y));
            ++chartTexels[size_t(band)];
          }
      }
    }
  }, 1);
  for (int band = 0; band < bands; ++band) {
    fields.chartTexels += chartTexels[size_t(band)];
    fields.overlappingTexels += overlapping[size_t(band)];
  }
}

// Every texel outside the charts takes the fields of the nearest chart texel (Danielsson's
// two-pass propagation of source coordinates), keeping chart = -1.
void fillGutters(AtlasFields& fields) {
  const int W = fields.samples.width, H = fields.samples.height;
  std::vector<int32_t> srcX(size_t(W) * size_t(H), -1), srcY(size_t(W) * size_t(H), -1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (fields.samples.at(x, y).chart >= 0) srcX[fields.samples.index(x, y)] = x, srcY[fields.samples.index(x, y)] = y;
  auto relax = [&](int x, int y, int nx, int ny) {
    if (nx < 0 || ny < 0 || nx >= W || ny >= H) return;
    const size_t i = size_t(y) * size_t(W) + size_t(x), j = size_t(ny) * size_t(W) + size_t(nx);
    if (srcX[j] < 0) return;
    const long long d = (long long)(srcX[j] - x) * (srcX[j] - x) + (long long)(srcY[j] - y) * (srcY[j] - y);
    if (srcX[i] >= 0) {
      const long long e = (long long)(srcX[i] - x) * (srcX[i] - x) + (long long)(srcY[i] - y) * (srcY[i] - y);
      if (e <= d) return;
    }
    srcX[i] = srcX[j], srcY[i] = srcY[j];
  };
  // A chart texel is its own source (distance 0): no neighbour can improve it.
  auto inGutter = [&](int x, int y) { return fields.samples.at(x, y).chart < 0; };
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x)
      if (inGutter(x, y)) relax(x, y, x - 1, y), relax(x, y, x - 1, y - 1), relax(x, y, x, y - 1), relax(x, y, x + 1, y - 1);
    for (int x = W - 1; x >= 0; --x)
      if (inGutter(x, y)) relax(x, y, x + 1, y);
  }
  for (int y = H - 1; y >= 0; --y) {
    for (int x = W - 1; x >= 0; --x)
      if (inGutter(x, y)) relax(x, y, x + 1, y), relax(x, y, x + 1, y + 1), relax(x, y, x, y + 1), relax(x, y, x - 1, y + 1);
    for (int x = 0; x < W; ++x)
      if (inGutter(x, y)) relax(x, y, x - 1, y);
  }
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = fields.samples.index(x, y);
      if (fields.samples.values[i].chart >= 0 || srcX[i] < 0) continue;
      const size_t j = fields.samples.index(srcX[i], srcY[i]);
      fields.samples.values[i] = fields.samples.values[j];
      fields.samples.values[i].chart = -1;
      fields.position.values[i] = fields.position.values[j];
      fields.normal.values[i] = fields.normal.values[j];
    }
}

} // namespace

AtlasFields rasterizeAtlas(const geometry::Mesh& mesh, const Atlas& atlas, const Context& ctx) {
  AtlasFields fields;
  // Three fields of 12-16 B per texel (160 MiB at 2048^2): their first touch, spread over threads.
  parallelFor(0, 3, ctx, [&](int b, int e) {
    for (int f = b; f < e; ++f) {
      if (f == 0) fields.samples = TexelField<SurfaceSample>(atlas.width, atlas.height);
      if (f == 1) fields.position = TexelField<Float3>(atlas.width, atlas.height);
      if (f == 2) fields.normal = TexelField<Float3>(atlas.width, atlas.height);
    }
  });
  rasterizeCharts(mesh, atlas, fields, ctx);
  fillGutters(fields);
  return fields;
}

} // namespace texfab::atlas
