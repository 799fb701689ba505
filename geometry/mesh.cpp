// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/mesh.h"

#include "core/error.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstring>
#include <map>
#include <unordered_map>
#include <tuple>

namespace texfab::geometry {

Eigen::Vector2f Texture::apply(const Eigen::Vector2f& uv) const {
  if (!hasTransform()) return uv;
  // KHR_texture_transform: T * R * S with R = [[c, s], [-s, c]], defined on glTF's v-down
  // coordinates; ours are v-up.
  const Eigen::Vector2f s = scale.cwiseProduct(Eigen::Vector2f(uv.x(), 1.0f - uv.y()));
  const float c = std::cos(rotation), n = std::sin(rotation);
  const Eigen::Vector2f t = offset + Eigen::Vector2f(c * s.x() + n * s.y(), -n * s.x() + c * s.y());
  return Eigen::Vector2f(t.x(), 1.0f - t.y());
}

BoundingBox boundingBox(const Mesh& mesh) {
  BoundingBox box;
  bool first = true;
  for (const auto& tri : mesh.triangles)
    for (uint32_t v : tri) {
      if (v >= mesh.positions.size()) continue;
      const Eigen::Vector3f& p = mesh.positions[v];
      if (first) {
        box.min = box.max = p;
        first = false;
      } else {
        box.min = box.min.cwiseMin(p);
        box.max = box.max.cwiseMax(p);
      }
    }
  return box;
}

double surfaceArea(const Mesh& mesh) {
  double area = 0;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const Eigen::Vector3d a = mesh.corner(t, 0).cast<double>(), b = mesh.corner(t, 1).cast<double>(),
                          c = mesh.corner(t, 2).cast<double>();
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

void validateMesh(const Mesh& mesh, const std::string& name) {
  const size_t t = mesh.triangles.size();
  if (t == 0) throw Error(name + ": the model has no triangles");
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite())
      throw Error(name + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
  for (size_t i = 0; i < t; ++i)
    for (uint32_t v : mesh.triangles[i])
      if (v >= mesh.positions.size())
        throw Error(name + ": triangle " + std::to_string(i) + " uses vertex " + std::to_string(v) + " but there are " +
                    std::to_string(mesh.positions.size()) + " vertices");
  auto checkSize = [&](size_t n, const char* what) {
    if (n != 0 && n != 3 * t)
      throw Error(name + ": " + what + " count " + std::to_string(n) + " does not match 3 x " + std::to_string(t) +
                  " triangle corners");
  };
  checkSize(mesh.uvs.size(), "UV");
  checkSize(mesh.normals.size(), "normal");
  checkSize(mesh.tangents.size(), "tangent");
  for (const auto& uv : mesh.uvs)
    if (!uv.allFinite()) throw Error(name + ": a texture coordinate is NaN or infinite");
  for (const auto& n : mesh.normals)
    if (!n.allFinite()) throw Error(name + ": a normal is NaN or infinite");
  for (const auto& g : mesh.tangents)
    if (!g.allFinite()) throw Error(name + ": a tangent is NaN or infinite");
  if (!mesh.faceMaterials.empty() && mesh.faceMaterials.size() != t)
    throw Error(name + ": per-face material count does not match the triangle count");
  if (!mesh.faceTags.empty() && mesh.faceTags.size() != t)
    throw Error(name + ": per-face tag count does not match the triangle count");
  const size_t materials = std::max<size_t>(1, mesh.materials.size());
  for (uint32_t m : mesh.faceMaterials)
    if (m >= materials) throw Error(name + ": a triangle uses material " + std::to_string(m) + " which does not exist");
}

Eigen::Vector3f faceNormal(const Mesh& mesh, size_t t) {
  const Eigen::Vector3f n = (mesh.corner(t, 1) - mesh.corner(t, 0)).cross(mesh.corner(t, 2) - mesh.corner(t, 0));
  const float len = n.norm();
  return len > 0 ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
}

void computeSmoothNormals(Mesh& mesh, float creaseDegrees) {
  const size_t n = mesh.triangles.size();
  std::vector<Eigen::Vector3f> area(n), unit(n);
  for (size_t t = 0; t < n; ++t) {
    area[t] = (mesh.corner(t, 1) - mesh.corner(t, 0)).cross(mesh.corner(t, 2) - mesh.corner(t, 0));
    unit[t] = faceNormal(mesh, t);
  }
  // Triangles around each vertex (CSR layout).
  std::vector<uint32_t> start(mesh.positions.size() + 1, 0), around(3 * n);
  for (const auto& tri : mesh.triangles)
    for (uint32_t v : tri) ++start[v + 1];
  for (size_t v = 0; v < mesh.positions.size(); ++v) start[v + 1] += start[v];
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (size_t t = 0; t < n; ++t)
    for (uint32_t v : mesh.triangles[t]) around[fill[v]++] = uint32_t(t);
  const float cosCrease = std::cos(std::min(creaseDegrees, 180.0f) * 3.14159265f / 180.0f);
  mesh.normals.resize(3 * n);
  for (size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.triangles[t][size_t(k)];
      Eigen::Vector3f sum = Eigen::Vector3f::Zero();
      for (uint32_t i = start[v]; i < start[v + 1]; ++i)
        if (creaseDegrees >= 180.0f || unit[around[i]].dot(unit[t]) >= cosCrease) sum += area[around[i]];
      if (sum.squaredNorm() == 0) sum = unit[t];
      if (sum.squaredNorm() == 0) sum = Eigen::Vector3f(0, 0, 1);
      mesh.normals[3 * t + size_t(k)] = sum.normalized();
    }
}

void computeTangents(Mesh& mesh) {
  if (!mesh.hasUvs()) return;
  if (!mesh.hasNormals()) computeSmoothNormals(mesh);
  const size_t n = mesh.triangles.size();
  // Corners that share vertex, UV and normal share a tangent frame (welded like a GPU vertex).
  using Key = std::tuple<uint32_t, float, float, float, float, float>;
  std::map<Key, uint32_t> groups;
  std::vector<uint32_t> groupOf(3 * n);
  for (size_t c = 0; c < 3 * n; ++c) {
    const Eigen::Vector2f& uv = mesh.uvs[c];
    const Eigen::Vector3f& nn = mesh.normals[c];
    const Key key{mesh.triangles[c / 3][c % 3], uv.x(), uv.y(), nn.x(), nn.y(), nn.z()};
    groupOf[c] = groups.emplace(key, uint32_t(groups.size())).first->second;
  }
  std::vector<Eigen::Vector3f> tan(groups.size(), Eigen::Vector3f::Zero());
  std::vector<Eigen::Vector3f> bit(groups.size(), Eigen::Vector3f::Zero());
  for (size_t t = 0; t < n; ++t) {
    const Eigen::Vector3f e1 = mesh.corner(t, 1) - mesh.corner(t, 0), e2 = mesh.corner(t, 2) - mesh.corner(t, 0);
    const Eigen::Vector2f d1 = mesh.uvs[3 * t + 1] - mesh.uvs[3 * t], d2 = mesh.uvs[3 * t + 2] - mesh.uvs[3 * t];
    const float det = d1.x() * d2.y() - d2.x() * d1.y();
    if (std::abs(det) < 1e-20f) continue;
    const Eigen::Vector3f T = (e1 * d2.y() - e2 * d1.y()) / det;
    const Eigen::Vector3f B = (e2 * d1.x() - e1 * d2.x()) / det;
    // Weight by the triangle's area so slivers do not dominate.
    const float w = 0.5f * e1.cross(e2).norm() / std::max(T.norm() * B.norm(), 1e-30f);
    for (int k = 0; k < 3; ++k) {
      tan[groupOf[3 * t + size_t(k)]] += w * T;
      bit[groupOf[3 * t + size_t(k)]] += w * B;
    }
  }
  mesh.tangents.resize(3 * n);
  for (size_t c = 0; c < 3 * n; ++c) {
    const Eigen::Vector3f& nn = mesh.normals[c];
    Eigen::Vector3f t = tan[groupOf[c]];
    t -= nn * nn.dot(t);
    if (t.squaredNorm() < 1e-20f) {
      // No usable UV gradient: any unit vector orthogonal to the normal.
      t = std::abs(nn.x()) < 0.9f ? Eigen::Vector3f::UnitX().cross(nn) : Eigen::Vector3f::UnitY().cross(nn);
    }
    t.normalize();
    const float w = nn.cross(t).dot(bit[groupOf[c]]) < 0 ? -1.0f : 1.0f;
    mesh.tangents[c] = Eigen::Vector4f(t.x(), t.y(), t.z(), w);
  }
}

void flipTriangle(Mesh& mesh, size_t t) {
  std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
  if (mesh.hasUvs()) std::swap(mesh.uvs[3 * t + 1], mesh.uvs[3 * t + 2]);
  if (mesh.hasTangents()) std::swap(mesh.tangents[3 * t + 1], mesh.tangents[3 * t + 2]);
  if (mesh.hasNormals()) {
    std::swap(mesh.normals[3 * t + 1], mesh.normals[3 * t + 2]);
    const Eigen::Vector3f n = faceNormal(mesh, t);
    for (size_t k = 0; k < 3; ++k)
      if (mesh.normals[3 * t + k].dot(n) < 0) mesh.normals[3 * t + k] *= -1.0f;
  }
}

void weldPositions(Mesh& mesh) {
  struct KeyHash {
    size_t operator()(const std::array<uint32_t, 3>& k) const {
      return (size_t(k[0]) * 73856093u) ^ (size_t(k[1]) * 19349663u) ^ (size_t(k[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<uint32_t, 3>, uint32_t, KeyHash> index;
  index.reserve(mesh.positions.size());
  std::vector<uint32_t> remap(mesh.positions.size());
  std::vector<Eigen::Vector3f> kept;
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const Eigen::Vector3f& p = mesh.positions[i];
    // Bit patterns as the key; +0.0f folds -0 into 0 so that both weld.
    std::array<uint32_t, 3> key;
    for (int k = 0; k < 3; ++k) {
      const float c = p[k] + 0.0f;
      std::memcpy(&key[size_t(k)], &c, 4);
    }
    const auto [it, inserted] = index.emplace(key, uint32_t(kept.size()));
    if (inserted) kept.push_back(p);
    remap[i] = it->second;
  }
  for (auto& tri : mesh.triangles)
    for (uint32_t& v : tri)
      if (v < remap.size()) v = remap[v];
  mesh.positions = std::move(kept);
}

void removeUnusedVertices(Mesh& mesh) {
  std::vector<uint32_t> remap(mesh.positions.size(), UINT32_MAX);
  std::vector<Eigen::Vector3f> kept;
  for (auto& tri : mesh.triangles)
    for (uint32_t& v : tri) {
      if (remap[v] == UINT32_MAX) {
        remap[v] = uint32_t(kept.size());
        kept.push_back(mesh.positions[v]);
      }
      v = remap[v];
    }
  mesh.positions = std::move(kept);
}

} // namespace texfab::geometry
