// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/break/own_texels.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace texfab::render {

namespace {

// A rectangle of texels, inclusive.
struct TexelBox {
  int x0, y0, x1, y1;
  int width() const { return x1 - x0 + 1; }
  int height() const { return y1 - y0 + 1; }
};

std::vector<geometry::Texture*> texturesOf(geometry::Material& m) {
  std::vector<geometry::Texture*> out;
  for (geometry::Texture* t : m.textures())
    if (*t) out.push_back(t);
  return out;
}

// The triangles of material `m`, or nothing when its UVs leave [0, 1].
std::vector<size_t> trianglesWithin(const geometry::Mesh& mesh, uint32_t m) {
  std::vector<size_t> out;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    if (mesh.materialOf(t) != m) continue;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2f& uv = mesh.uvs[3 * t + size_t(k)];
      if (!(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1)) return {};
    }
    out.push_back(t);
  }
  return out;
}

// Texel (x right, y down) of a UV (v up) on a w x h image.
Eigen::Vector2f texelOf(const Eigen::Vector2f& uv, int w, int h) { return {uv.x() * float(w), (1 - uv.y()) * float(h)}; }

} // namespace

geometry::Mesh keepOwnTexels(const geometry::Mesh& input, int margin) {
  geometry::Mesh mesh = input;
  if (!mesh.hasUvs()) return mesh;
  for (uint32_t m = 0; m < mesh.materials.size(); ++m) {
    const std::vector<geometry::Texture*> textures = texturesOf(mesh.materials[m]);
    if (textures.empty()) continue;
    const int w = textures[0]->image->width, h = textures[0]->image->height;
    if (!std::all_of(textures.begin(), textures.end(), [&](const geometry::Texture* t) {
          return t->image->width == w && t->image->height == h && !t->hasTransform();
        }))
      continue;
    const std::vector<size_t> triangles = trianglesWithin(mesh, m);
    if (triangles.empty()) continue;

    // The texels each triangle may show, grown by the margin; their union is kept.
    std::vector<uint8_t> keep(size_t(w) * size_t(h), 0);
    TexelBox crop{w, h, -1, -1};
    for (size_t t : triangles) {
      Eigen::Vector2f lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2f p = texelOf(mesh.uvs[3 * t + size_t(k)], w, h);
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      const TexelBox box{std::max(0, int(std::floor(lo.x())) - margin), std::max(0, int(std::floor(lo.y())) - margin),
                         std::min(w - 1, int(std::floor(hi.x())) + margin),
                         std::min(h - 1, int(std::floor(hi.y())) + margin)};
      for (int y = box.y0; y <= box.y1; ++y) std::fill_n(&keep[size_t(y) * size_t(w) + size_t(box.x0)], box.width(), 1);
      crop = {std::min(crop.x0, box.x0), std::min(crop.y0, box.y0), std::max(crop.x1, box.x1), std::max(crop.y1, box.y1)};
    }

    for (geometry::Texture* texture : textures) {
      const Image& full = *texture->image;
      auto cropped = std::make_shared<Image>(crop.width(), crop.height(), full.channels, full.format);
      for (int y = 0; y < crop.height(); ++y)
        for (int x = 0; x < crop.width(); ++x)
          if (keep[size_t(y + crop.y0) * size_t(w) + size_t(x + crop.x0)])
            std::copy_n(full.pixel(x + crop.x0, y + crop.y0), full.channels, cropped->pixel(x, y));
      texture->image = std::move(cropped);
      texture->encoded.reset();
      texture->mips.reset();
      texture->encodedMips.reset();
    }
    for (size_t t : triangles)
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector2f& uv = mesh.uvs[3 * t + size_t(k)];
        const Eigen::Vector2f p = texelOf(uv, w, h);
        uv = {(p.x() - float(crop.x0)) / float(crop.width()), 1 - (p.y() - float(crop.y0)) / float(crop.height())};
      }
  }
  return mesh;
}

} // namespace texfab::render
