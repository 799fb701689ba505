// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Small meshes and helpers shared by the geometry and render tests.

#include "core/error.h"
#include "geometry/mesh.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>

namespace texfab::test {

/// A w x h RGB(A) image whose pixels follow a simple formula (so texture round trips can compare).
inline std::shared_ptr<const Image> gradientImage(int w, int h, int channels = 3) {
  auto image = std::make_shared<Image>(w, h, channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c)
        image->at(x, y, c) = float((x * 37 + y * 11 + c * 80) % 256) / 255.0f;
  return image;
}

/// An axis-aligned closed box [lo, lo + size] (12 triangles, 8 shared vertices), normals outward.
inline geometry::Mesh box(Eigen::Vector3f lo, Eigen::Vector3f size) {
  geometry::Mesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.push_back(lo + Eigen::Vector3f(size.x() * float(i & 1), size.y() * float((i >> 1) & 1),
                                               size.z() * float((i >> 2) & 1)));
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

/// Appends b to a (b's vertices renumbered after a's).
inline void append(geometry::Mesh& a, const geometry::Mesh& b) {
  const uint32_t offset = uint32_t(a.positions.size());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

/// A closed unit cube (12 triangles, 8 shared vertices) with per-face UV squares (seams on every
/// edge), flat per-corner normals, two materials (one textured) and a face tag on the top face.
inline geometry::Mesh texturedCube() {
  geometry::Mesh m;
  m.positions = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  const int quads[6][4] = {{4, 5, 6, 7}, {1, 0, 3, 2}, {5, 1, 2, 6}, {0, 4, 7, 3}, {7, 6, 2, 3}, {0, 1, 5, 4}};
  const Eigen::Vector2f uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int f = 0; f < 6; ++f) {
    const int order[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (const auto& o : order) {
      m.triangles.push_back({uint32_t(quads[f][o[0]]), uint32_t(quads[f][o[1]]), uint32_t(quads[f][o[2]])});
      for (int k : o) m.uvs.push_back(uv[k] * 0.5f + Eigen::Vector2f(0.25f * float(f % 2), 0.25f));
      m.faceMaterials.push_back(f < 3 ? 0 : 1);
      m.faceTags.push_back(f == 4 ? 7 : 0);
    }
  }
  for (size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) m.normals.push_back(geometry::faceNormal(m, t));
  geometry::Material a;
  a.name = "textured";
  a.baseColorFactor = {1.0f, 0.9f, 0.8f, 1.0f};
  a.metallicFactor = 0.0f;
  a.roughnessFactor = 0.5f;
  a.baseColorTexture.image = gradientImage(16, 8);
  geometry::Material b;
  b.name = "plain";
  b.baseColorFactor = {0.2f, 0.4f, 0.6f, 1.0f};
  b.metallicFactor = 0.25f;
  b.roughnessFactor = 0.75f;
  m.materials = {a, b};
  return m;
}

/// The message of the texfab::Error that `fn` throws ("" if it throws none).
template <class Fn>
std::string errorOf(Fn&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

} // namespace texfab::test
