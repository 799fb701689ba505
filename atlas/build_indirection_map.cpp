// SPDX-License-Identifier: GPL-3.0-or-later
// Indirection maps: S. Lefebvre, H. Hoppe, "Appearance-Space Texture Synthesis", SIGGRAPH 2006,
// §5 ("precomputed by marching across chart boundaries").
#include "atlas/build_indirection_map.h"

#include "core/error.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <complex>

namespace texfab::atlas {

void IndirectionOptions::validate() const {
  if (radius < 1 || radius > 64) throw Error("indirection radius must be 1 to 64 texels, got " + std::to_string(radius));
}

IndirectionTarget walkAtlas(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const Atlas& atlas,
                            uint32_t triangle, Eigen::Vector2d p, Eigen::Vector2d d) {
  IndirectionTarget out;
  uint32_t t = triangle;
  int32_t from = -1;
  for (int guard = 0; guard < 256; ++guard) {
    const Eigen::Vector2d a = atlas.texelUvs[3 * size_t(t)].cast<double>();
    const Eigen::Vector2d e1 = atlas.texelUvs[3 * size_t(t) + 1].cast<double>() - a;
    const Eigen::Vector2d e2 = atlas.texelUvs[3 * size_t(t) + 2].cast<double>() - a;
    const double det = e1.x() * e2.y() - e1.y() * e2.x();
    auto bary = [&](const Eigen::Vector2d& q) {
      const Eigen::Vector2d r = q - a;
      const double b1 = (r.x() * e2.y() - r.y() * e2.x()) / det, b2 = (e1.x() * r.y() - e1.y() * r.x()) / det;
      return Eigen::Vector3d(1 - b1 - b2, b1, b2);
    };
    const Eigen::Vector3d l0 = bary(p), l1 = bary(p + d);
    const double eps = 1e-9;
    if (l1.minCoeff() >= -eps) {
      p += d;
      break;
    }
    // Leave through the edge whose barycentric hits zero first (ignoring the entry edge).
    double tExit = 2;
    int corner = -1;
    for (int i = 0; i < 3; ++i) {
      const double dl = l1(i) - l0(i);
      if (dl >= 0 || l1(i) >= -eps) continue;
      const int edge = (i + 1) % 3; // edge from corner i+1 to i+2 is opposite corner i
      if (conn.neighbor(t, edge) == from && from >= 0 && l0(i) <= eps) continue;
      const double s = std::max(0.0, -l0(i) / dl);
      if (s < tExit) tExit = s, corner = i;
    }
    if (corner < 0) { // numerically stuck: stay in this triangle
      p += d;
      break;
    }
    const int edge = (corner + 1) % 3;
    const Eigen::Vector2d exitPoint = p + tExit * d;
    const Eigen::Vector2d rest = (1 - tExit) * d;
    const int32_t g = conn.neighbor(t, edge);
    if (g < 0) { // open boundary (or a cut edge): stop on it
      p = exitPoint;
      out.hitBoundary = 1;
      break;
    }
    if (atlas.faceChart[size_t(g)] == atlas.faceChart[t]) {
      from = int32_t(t);
      t = uint32_t(g);
      p = exitPoint;
      d = rest;
      continue;
    }
    // Seam: map the exit point and the remaining step into g's chart by the similarity that takes
    // the shared edge in t's chart onto the same edge in g's chart.
    const uint32_t va = mesh.triangles[t][size_t(edge)], vb = mesh.triangles[t][size_t((edge + 1) % 3)];
    int ka = 0, kb = 0;
    for (int k = 0; k < 3; ++k) {
      if (mesh.triangles[size_t(g)][size_t(k)] == va) ka = k;
      if (mesh.triangles[size_t(g)][size_t(k)] == vb) kb = k;
    }
    const Eigen::Vector2d A = atlas.texelUvs[3 * size_t(t) + size_t(edge)].cast<double>();
    const Eigen::Vector2d B = atlas.texelUvs[3 * size_t(t) + size_t((edge + 1) % 3)].cast<double>();
    const Eigen::Vector2d A2 = atlas.texelUvs[3 * size_t(g) + size_t(ka)].cast<double>();
    const Eigen::Vector2d B2 = atlas.texelUvs[3 * size_t(g) + size_t(kb)].cast<double>();
    const Eigen::Vector2d ab = B - A, ab2 = B2 - A2;
    const double len2 = ab.squaredNorm();
    if (!(len2 > 0)) {
      p = exitPoint;
      break;
    }
    const double s = std::clamp((exitPoint - A).dot(ab) / len2, 0.0, 1.0);
    // Complex ratio ab2 / ab: rotation + scale.
    const std::complex<double> r = std::complex<double>(ab2.x(), ab2.y()) / std::complex<double>(ab.x(), ab.y());
    const std::complex<double> rd = r * std::complex<double>(rest.x(), rest.y());
    p = A2 + s * ab2;
    d = {rd.real(), rd.imag()};
    from = int32_t(t);
    t = uint32_t(g);
    out.crossedSeam = 1;
  }
  out.x = float(p.x());
  out.y = float(p.y());
  out.triangle = t;
  out.chart = atlas.faceChart[t];
  return out;
}

IndirectionMap buildIndirectionMap(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const Atlas& atlas,
                                   const AtlasFields& fields, const IndirectionOptions& options, const Context& ctx) {
  options.validate();
  const int W = fields.samples.width, H = fields.samples.height;
  IndirectionMap map;
  map.entry = TexelField<int32_t>(W, H, -1);
  // Chebyshev distance to the nearest non-chart texel (two-pass chamfer, exact for unit weights),
  // capped at radius + 1.
  const int cap = options.radius + 1;
  std::vector<int> dist(size_t(W) * size_t(H), cap);
  for (size_t i = 0; i < dist.size(); ++i)
    if (fields.samples.values[i].chart < 0) dist[i] = 0;
  auto at = [&](int x, int y) -> int { return (x < 0 || y < 0 || x >= W || y >= H) ? 0 : dist[size_t(y) * size_t(W) + size_t(x)]; };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      int& d = dist[size_t(y) * size_t(W) + size_t(x)];
      if (d == 0) continue;
      d = std::min({d, at(x - 1, y) + 1, at(x - 1, y - 1) + 1, at(x, y - 1) + 1, at(x + 1, y - 1) + 1});
    }
  for (int y = H - 1; y >= 0; --y)
    for (int x = W - 1; x >= 0; --x) {
      int& d = dist[size_t(y) * size_t(W) + size_t(x)];
      if (d == 0) continue;
      d = std::min({d, at(x + 1, y) + 1, at(x + 1, y + 1) + 1, at(x, y + 1) + 1, at(x - 1, y + 1) + 1});
    }
  std::vector<size_t> texels;
  for (size_t i = 0; i < dist.size(); ++i)
    if (dist[i] > 0 && dist[i] <= options.radius) {
      map.entry.values[i] = int32_t(texels.size());
      texels.push_back(i);
    }
  map.targets.resize(texels.size());
  parallelFor(0, int(texels.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) {
      const size_t idx = texels[size_t(i)];
      const int x = int(idx % size_t(W)), y = int(idx / size_t(W));
      const SurfaceSample& s = fields.samples.values[idx];
      for (int k = 0; k < 8; ++k)
        map.targets[size_t(i)][size_t(k)] =
            walkAtlas(mesh, conn, atlas, s.triangle, {x + 0.5, y + 0.5}, {double(kStepX[k]), double(kStepY[k])});
    }
  }, 256);
  for (const auto& t8 : map.targets)
    for (const IndirectionTarget& t : t8) map.seamCrossings += t.crossedSeam, map.boundaryStops += t.hitBoundary;
  return map;
}

} // namespace texfab::atlas
