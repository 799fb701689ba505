// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/break/crack_measures.h"

#include "core/hash.h"
#include "geometry/embree_scene.h"
#include "geometry/mesh_connectivity.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace texfab::render {
namespace {

constexpr uint32_t kCutTag = 1;
using Vec3 = Eigen::Vector3d;

Vec3 cornerOf(const geometry::Mesh& m, size_t t, int k) { return m.corner(t, k).cast<double>(); }

// Barycentric coordinates of p (on the triangle's plane) in triangle t.
Vec3 barycentric(const geometry::Mesh& m, size_t t, const Vec3& p) {
  const Vec3 a = cornerOf(m, t, 0), e0 = cornerOf(m, t, 1) - a, e1 = cornerOf(m, t, 2) - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = d.dot(e0), d21 = d.dot(e1);
  const double det = d00 * d11 - d01 * d01;
  if (!(det > 0)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  const double v = (d11 * d20 - d01 * d21) / det, w = (d00 * d21 - d01 * d20) / det;
  return {1 - v - w, v, w};
}

// Bilinear base colour (texture times factor, RGB) at barycentric w of triangle t.
Eigen::Vector3f colorAt(const geometry::Mesh& m, size_t t, const Vec3& w) {
  const geometry::Material& material = m.materials[m.materialOf(t)];
  const Eigen::Vector3f factor = material.baseColorFactor.head<3>();
  const Image* image = material.baseColorTexture.image.get();
  if (!image || !m.hasUvs()) return factor;
  const Eigen::Vector2f uv = float(w[0]) * m.uvs[3 * t] + float(w[1]) * m.uvs[3 * t + 1] + float(w[2]) * m.uvs[3 * t + 2];
  const float x = uv.x() * float(image->width) - 0.5f, y = (1.0f - uv.y()) * float(image->height) - 0.5f;
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const float fx = x - float(x0), fy = y - float(y0);
  auto at = [&](int px, int py, int c) {
    return image->at(std::clamp(px, 0, image->width - 1), std::clamp(py, 0, image->height - 1), std::min(c, image->channels - 1));
  };
  Eigen::Vector3f color;
  for (int c = 0; c < 3; ++c)
    color[c] = factor[c] * ((1 - fy) * ((1 - fx) * at(x0, y0, c) + fx * at(x0 + 1, y0, c)) +
                             fy * ((1 - fx) * at(x0, y0 + 1, c) + fx * at(x0 + 1, y0 + 1, c)));
  return color;
}

double difference(const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return double((a - b).cwiseAbs().mean()); }

struct SurfaceSample {
  size_t piece, triangle;
  Vec3 point;
};

// Area-weighted points on the cut faces of all pieces (hashed, deterministic).
std::vector<SurfaceSample> cutFaceSamples(const BrokenModel& model, size_t n) {
  std::vector<std::pair<size_t, size_t>> faces;
  std::vector<double> cumulative;
  double total = 0;
  for (size_t p = 0; p < model.pieces.size(); ++p) {
    const geometry::Mesh& m = model.pieces[p].mesh;
    for (size_t t = 0; t < m.triangles.size(); ++t)
      if (m.tagOf(t) == kCutTag) {
        total += 0.5 * (cornerOf(m, t, 1) - cornerOf(m, t, 0)).cross(cornerOf(m, t, 2) - cornerOf(m, t, 0)).norm();
        faces.emplace_back(p, t);
        cumulative.push_back(total);
      }
  }
  std::vector<SurfaceSample> samples;
  if (faces.empty() || !(total > 0)) return samples;
  for (size_t i = 0; i < n; ++i) {
    const double pick = unitInterval(counterHash(7, uint32_t(i), 0)) * total;
    const size_t f = size_t(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    const auto [p, t] = faces[std::min(f, faces.size() - 1)];
    const double r1 = std::sqrt(unitInterval(counterHash(7, uint32_t(i), 1)));
    const double r2 = unitInterval(counterHash(7, uint32_t(i), 2));
    const geometry::Mesh& m = model.pieces[p].mesh;
    samples.push_back({p, t, (1 - r1) * cornerOf(m, t, 0) + r1 * (1 - r2) * cornerOf(m, t, 1) + r1 * r2 * cornerOf(m, t, 2)});
  }
  return samples;
}

double texelSize(const BrokenModel& model) {
  double size = model.interiorScale > 0 ? 1.0 / model.interiorScale : 0.0;
  if (model.interior) size = std::max(size, 1.0 / model.interior->atlas.atlas.texelsPerUnit);
  if (model.outer) size = std::max(size, 1.0 / model.outer->atlas.atlas.texelsPerUnit);
  return size;
}

} // namespace

CrackMatch measureCrackMatch(const BrokenModel& model, size_t n) {
  CrackMatch r;
  const std::vector<SurfaceSample> samples = cutFaceSamples(model, n);
  if (samples.empty()) return r;
  std::vector<std::unique_ptr<geometry::EmbreeScene>> scenes;
  geometry::BoundingBox box = geometry::boundingBox(model.pieces.front().mesh);
  for (const Piece& p : model.pieces) {
    scenes.push_back(std::make_unique<geometry::EmbreeScene>(p.mesh));
    const geometry::BoundingBox b = geometry::boundingBox(p.mesh);
    box.min = box.min.cwiseMin(b.min), box.max = box.max.cwiseMax(b.max);
  }
  const float tolerance = 1e-5f * box.diagonal();
  std::vector<Eigen::Vector3f> colors;
  for (const SurfaceSample& s : samples) {
    const geometry::Mesh& a = model.pieces[s.piece].mesh;
    const Eigen::Vector3f own = colorAt(a, s.triangle, barycentric(a, s.triangle, s.point));
    colors.push_back(own);
    for (size_t q = 0; q < scenes.size(); ++q) {
      if (q == s.piece) continue;
      const geometry::SurfacePoint hit = scenes[q]->closestPoint(s.point.cast<float>(), tolerance);
      const geometry::Mesh& b = model.pieces[q].mesh;
      if (!hit.found || b.tagOf(hit.triangle) != kCutTag) continue;
      r.difference += difference(own, colorAt(b, hit.triangle, barycentric(b, hit.triangle, s.point)));
      ++r.samples;
      break;
    }
  }
  for (size_t i = 0; i < colors.size(); ++i) r.unrelatedDifference += difference(colors[i], colors[(i + colors.size() / 2) % colors.size()]);
  r.unrelatedDifference /= double(colors.size());
  if (r.samples) r.difference /= double(r.samples);
  return r;
}

CrackSeams measureCrackSeams(const BrokenModel& model, double distance, size_t samples) {
  CrackSeams r;
  if (distance <= 0) distance = 1.5 * texelSize(model);
  if (!(distance > 0)) return r;
  struct Side {
    size_t piece, triangle;
    Vec3 inward;  // unit, in the triangle's plane, away from the edge
  };
  std::vector<std::tuple<Vec3, Side, Side>> points;  // edge point, outer side, cut side
  for (size_t p = 0; p < model.pieces.size(); ++p) {
    const geometry::Mesh& m = model.pieces[p].mesh;
    const geometry::MeshConnectivity connectivity = geometry::computeConnectivity(m);
    auto inward = [&](size_t t, const Vec3& a, const Vec3& b) {
      Vec3 c = Vec3::Zero();
      for (int k = 0; k < 3; ++k) c += cornerOf(m, t, k) / 3.0;
      const Vec3 e = (b - a).normalized(), d = (c - a) - (c - a).dot(e) * e;
      return d.normalized();
    };
    // Edges between an outer triangle t and a cut one.
    for (size_t t = 0; t < m.triangles.size(); ++t)
      for (int k = 0; k < 3 && m.tagOf(t) != kCutTag; ++k) {
        const int32_t other = connectivity.neighbor(t, k);
        if (other < 0 || m.tagOf(size_t(other)) != kCutTag) continue;
        const Vec3 a = m.positions[m.triangles[t][size_t(k)]].cast<double>();
        const Vec3 b = m.positions[m.triangles[t][size_t((k + 1) % 3)]].cast<double>();
        const int n = std::max(1, int((b - a).norm() / distance));
        for (int i = 0; i < n; ++i)
          points.emplace_back(a + (b - a) * ((i + 0.5) / n), Side{p, t, inward(t, a, b)},
                              Side{p, size_t(other), inward(size_t(other), a, b)});
      }
  }
  const size_t stride = std::max<size_t>(1, points.size() / std::max<size_t>(samples, 1));
  double within = 0;
  size_t withinCount = 0;
  auto color = [&](const Side& s, const Vec3& q, bool& ok) {
    const geometry::Mesh& m = model.pieces[s.piece].mesh;
    const Vec3 w = barycentric(m, s.triangle, q);
    ok = w.minCoeff() >= 0;
    return colorAt(m, s.triangle, w);
  };
  for (size_t i = 0; i < points.size(); i += stride) {
    const auto& [q, outer, cut] = points[i];
    bool ok1, ok2;
    const Eigen::Vector3f co = color(outer, q + distance * outer.inward, ok1), cc = color(cut, q + distance * cut.inward, ok2);
    if (!ok1 || !ok2) continue;
    r.acrossDifference += difference(co, cc);
    ++r.samples;
    for (const auto& [side, near] : {std::pair{outer, co}, std::pair{cut, cc}}) {
      bool ok;
      const Eigen::Vector3f far = color(side, q + 3 * distance * side.inward, ok);
      if (ok) within += difference(near, far), ++withinCount;
    }
  }
  if (!r.samples || !withinCount) return r;
  r.acrossDifference /= double(r.samples);
  r.withinDifference = within / double(withinCount);
  r.ratio = r.withinDifference > 0 ? r.acrossDifference / r.withinDifference : 0;
  return r;
}

} // namespace texfab::render
