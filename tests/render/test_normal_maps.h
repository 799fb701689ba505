// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Normal maps for the tests of normal-map filtering and of its shading in previews: three materials
// as tiling height fields turned into tangent-space normal maps; a glossy metal sphere that wears
// one, and the views and the error measure of its renders; the glTF route's materials as a viewer
// of the written file sees them.
#include "core/hash.h"
#include "core/image.h"
#include "core/uastc_encode.h"
#include "geometry/mesh.h"
#include "render/material_mips.h"
#include "render/preview_renderer.h"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace texfab::test {

// Tiling value noise: bilinear between hashed lattice values `period` texels apart.
inline double valueNoise(uint32_t seed, double x, double y, int periodX, int periodY, int size) {
  const auto lattice = [&](int i, int j) {
    const int nx = size / periodX, ny = size / periodY;
    return unitInterval(counterHash(seed, uint32_t((i % nx + nx) % nx), uint32_t((j % ny + ny) % ny)));
  };
  const double u = x / periodX, v = y / periodY;
  const int i = int(std::floor(u)), j = int(std::floor(v));
  const double s = u - i, t = v - j;
  return (1 - t) * ((1 - s) * lattice(i, j) + s * lattice(i + 1, j)) + t * ((1 - s) * lattice(i, j + 1) + s * lattice(i + 1, j + 1));
}

// A normal map of a tiling height field: n ∝ (-gain dh/dx, -gain dh/dy, 1), encoded as (n + 1) / 2.
inline Image normalMap(int size, double gain, const std::function<double(int, int)>& height) {
  Image map(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double dx = (height((x + 1) % size, y) - height((x + size - 1) % size, y)) / 2;
      const double dy = (height(x, (y + 1) % size) - height(x, (y + size - 1) % size)) / 2;
      const Eigen::Vector3d n = Eigen::Vector3d(-gain * dx, -gain * dy, 1).normalized();
      for (int c = 0; c < 3; ++c) map.at(x, y, c) = float((n[c] + 1) / 2);
    }
  return map;
}

struct TestMap {
  std::string name;
  Image map;
};

// The three materials, as height fields: bumpy stone (noise at two scales), brushed metal
// (grooves along x: noise that changes every row, slowly along it) and fabric (a plain weave).
inline std::vector<TestMap> testMaps(int size) {
  std::vector<TestMap> maps;
  maps.push_back({"stone", normalMap(size, 2.0, [&](int x, int y) {
                    return 6 * valueNoise(1, x, y, 16, 16, size) + 2 * valueNoise(2, x, y, 4, 4, size);
                  })});
  maps.push_back({"brushed metal", normalMap(size, 1.5, [&](int x, int y) {
                    return 1.5 * valueNoise(3, x, y, 32, 1, size);
                  })});
  maps.push_back({"fabric", normalMap(size, 1.0, [&](int x, int y) {
                    const bool warp = ((x / 8) + (y / 8)) % 2 == 0;
                    const double s = std::sin(3.14159265358979323846 * ((warp ? x : y) % 8) / 8.0);
                    return 3 * s * s;
                  })});
  return maps;
}

// A latitude-longitude sphere of radius 1 (y up) of glossy metal (roughness 0.3) whose normal map
// is tiled `tilesAround` times around it and tilesAround / 2 times from pole to pole.
inline geometry::Mesh normalMappedSphere(const Image& normalMap, int tilesAround, int segments = 256) {
  geometry::Mesh m;
  const int rings = segments / 2;
  const double pi = 3.14159265358979323846;
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i <= segments; ++i) {
      const double theta = pi * j / rings, phi = 2 * pi * i / segments;
      m.positions.emplace_back(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)), float(std::sin(theta) * std::sin(phi)));
    }
  const auto index = [&](int i, int j) { return uint32_t(j * (segments + 1) + i); };
  const auto uv = [&](int i, int j) {
    return Eigen::Vector2f(float(tilesAround * i) / float(segments), 0.5f * float(tilesAround) * (1 - float(j) / float(rings)));
  };
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < segments; ++i) {
      const std::array<std::array<int, 2>, 6> corners = {{{i, j}, {i, j + 1}, {i + 1, j + 1}, {i, j}, {i + 1, j + 1}, {i + 1, j}}};
      for (int t = 0; t < 2; ++t) {
        std::array<uint32_t, 3> triangle;
        for (int k = 0; k < 3; ++k) {
          const auto& c = corners[size_t(3 * t + k)];
          triangle[size_t(k)] = index(c[0], c[1]);
          m.uvs.push_back(uv(c[0], c[1]));
        }
        m.triangles.push_back(triangle);
      }
    }
  geometry::computeSmoothNormals(m);
  geometry::Material metal;
  metal.baseColorFactor = Eigen::Vector4f(0.95f, 0.9f, 0.8f, 1.0f);
  metal.metallicFactor = 1.0f;
  metal.roughnessFactor = 0.3f;
  metal.normalTexture.image = std::make_shared<Image>(normalMap);
  m.materials = {metal};
  return m;
}

// The diameter in pixels at which a normalMappedSphere shows `texelsPerPixel` texels of its
// normal map per pixel at its centre: tilesAround map widths span its circumference 2π.
inline int sphereDiameter(int mapSize, int tilesAround, int texelsPerPixel) {
  return int(std::lround(tilesAround * mapSize / (3.14159265358979323846 * texelsPerPixel)));
}

// A view that frames the sphere at `diameter` pixels: key light only, no shadows, no AO (nothing
// but the shading of the normals), transparent background.
inline render::RenderOptions sphereView(int diameter, int samplesPerPixel, render::NormalMapFiltering filtering) {
  render::RenderOptions o;
  o.width = o.height = int(std::lround(1.1 * diameter)) + 2;
  o.margin = float(o.width) / float(diameter);
  o.aoSamples = 0;
  o.shadows = false;
  o.transparentBackground = true;
  o.samplesPerPixel = samplesPerPixel;
  o.normalMapFiltering = filtering;
  return o;
}

// The RMS difference of the colour channels over the pixels both images cover whole (a
// silhouette's coverage is not what normal-map filtering changes).
inline double coveredRms(const Image& image, const Image& truth) {
  double sum = 0;
  size_t n = 0;
  for (int y = 0; y < truth.height; ++y)
    for (int x = 0; x < truth.width; ++x) {
      if (truth.at(x, y, 3) < 1 || image.at(x, y, 3) < 1) continue;
      for (int c = 0; c < 3; ++c, ++n) sum += std::pow(double(image.at(x, y, c)) - truth.at(x, y, c), 2);
    }
  return std::sqrt(sum / double(std::max<size_t>(n, 1)));
}

// An image through UASTC: encoded, then decoded as a transcoder decodes it (3 channels).
inline Image throughUastc(const Image& image) {
  const std::vector<uint8_t> rgba = uastc::decodeImage(uastc::encodeImage(image), image.width, image.height);
  Image out(image.width, image.height, 3);
  for (size_t p = 0; p < size_t(image.width) * size_t(image.height); ++p)
    for (size_t c = 0; c < 3; ++c) out.pixels[3 * p + c] = float(rgba[4 * p + c]) / 255.0f;
  return out;
}

// The mesh as a viewer of texfab's glTF sees it with KHR_texture_basisu (and, where `options` ask
// for it, KHR_materials_anisotropy): each material with the MIP chains of render/material_mips.h,
// their levels through UASTC when `uastc`.
inline geometry::Mesh withGltfRoute(geometry::Mesh mesh, bool uastc, const render::FilteredMipsOptions& options = {}) {
  const auto throughUastcAll = [](geometry::Texture& t) {
    auto levels = std::make_shared<std::vector<Image>>();
    for (const Image& level : *t.mips) levels->push_back(throughUastc(level));
    t.mips = std::move(levels);
  };
  for (geometry::Material& m : mesh.materials) {
    m = render::withFilteredMips(m, options);
    if (!uastc) continue;
    throughUastcAll(m.metallicRoughnessTexture);
    if (m.anisotropy) throughUastcAll(m.anisotropy.texture);
  }
  return mesh;
}

// Supersampling that resolves every texel (each sample's footprint at most one texel), at least
// 256 samples per pixel.
inline int truthSamples(int texelsPerPixel) { return std::clamp(texelsPerPixel * texelsPerPixel, 256, 4096); }

} // namespace texfab::test
