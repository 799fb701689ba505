// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/material_mips.h"

#include "core/error.h"
#include "core/parallel.h"
#include "render/filter_normal_map.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace texfab::render {
namespace {

// Sums over a texel's footprint in level 0.
struct Footprint {
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // unit normals as a viewer bends them (normalScale)
  float alpha2 = 0, metallic = 0, occlusion = 0, count = 0;

  void add(const Footprint& o) {
    normal += o.normal;
    alpha2 += o.alpha2, metallic += o.metallic, occlusion += o.occlusion, count += o.count;
  }
};

struct Level {
  int width = 0, height = 0;
  std::vector<Footprint> texels;
  const Footprint& at(int x, int y) const { return texels[size_t(y) * size_t(width) + size_t(x)]; }
};

// A metallic-roughness texture's channel c (1 and 2 channels are grey: every channel reads the first).
float channel(const Image& image, int x, int y, int c) { return image.at(x, y, image.channels >= 3 ? c : 0); }

Level baseLevel(const geometry::Material& m, const Context& ctx) {
  const Image& normals = *m.normalTexture.image;
  const Image* mr = m.metallicRoughnessTexture ? m.metallicRoughnessTexture.image.get() : nullptr;
  Level level{normals.width, normals.height, std::vector<Footprint>(size_t(normals.width) * size_t(normals.height))};
  parallelFor(0, level.height, ctx, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < level.width; ++x) {
        Footprint& f = level.texels[size_t(y) * size_t(level.width) + size_t(x)];
        const Eigen::Vector3f stored = decodeNormal(normals, x, y);
        const Eigen::Vector3f seen(m.normalScale * stored.x(), m.normalScale * stored.y(), stored.z());
        f.normal = seen.squaredNorm() > 0 ? Eigen::Vector3f(seen.normalized()) : Eigen::Vector3f::UnitZ();
        const float roughness = std::clamp(m.roughnessFactor * (mr ? channel(*mr, x, y, 1) : 1.0f), 0.0f, 1.0f);
        f.alpha2 = roughness * roughness * roughness * roughness;
        f.metallic = std::clamp(m.metallicFactor * (mr ? channel(*mr, x, y, 2) : 1.0f), 0.0f, 1.0f);
        f.occlusion = mr ? channel(*mr, x, y, 0) : 1.0f;
        f.count = 1;
      }
  });
  return level;
}

// The next level: each side halves, rounding down (at least 1), as KTX2 and OpenGL size their
// levels; a texel sums its 2x2 children, and the last row or column of an odd side joins the
// texels before it, so that every texel of level 0 is counted once.
Level nextLevel(const Level& fine, const Context& ctx) {
  Level coarse{std::max(1, fine.width / 2), std::max(1, fine.height / 2), {}};
  coarse.texels.resize(size_t(coarse.width) * size_t(coarse.height));
  auto span = [](int i, int coarseSide, int fineSide) {
    return std::pair{2 * i, i == coarseSide - 1 ? fineSide : std::min(2 * i + 2, fineSide)};
  };
  parallelFor(0, coarse.height, ctx, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < coarse.width; ++x) {
        Footprint& f = coarse.texels[size_t(y) * size_t(coarse.width) + size_t(x)];
        const auto [fy0, fy1] = span(y, coarse.height, fine.height);
        const auto [fx0, fx1] = span(x, coarse.width, fine.width);
        for (int fy = fy0; fy < fy1; ++fy)
          for (int fx = fx0; fx < fx1; ++fx) f.add(fine.at(fx, fy));
      }
  });
  return coarse;
}

// The level's metallic-roughness texture: R (occlusion) and B (metallic) averaged, G widened.
Image levelImage(const Level& level) {
  Image mr(level.width, level.height, 3);
  for (int y = 0; y < level.height; ++y)
    for (int x = 0; x < level.width; ++x) {
      const Footprint& f = level.at(x, y);
      mr.at(x, y, 0) = f.occlusion / f.count;
      mr.at(x, y, 1) = widenedRoughness(double(f.alpha2) / f.count, double(f.normal.norm()) / f.count);
      mr.at(x, y, 2) = f.metallic / f.count;
    }
  return mr;
}

} // namespace

float widenedRoughness(double alpha2, double meanLength) {
  alpha2 = std::clamp(alpha2, 0.0, 1.0);
  meanLength = std::clamp(meanLength, 0.0, 1.0);
  if (alpha2 >= 1 || meanLength <= 0) return 1.0f;
  const double r = meanLength;  // 1/κ = (1 - |r|²) / (3|r| - |r|³)
  return float(std::sqrt(std::sqrt(widenedAlpha2(alpha2, (1 - r * r) / (3 * r - r * r * r)))));
}

double widenedAlpha2(double alpha2, double inverseSharpness) {
  if (alpha2 >= 1 || std::isinf(inverseSharpness)) return 1;  // a uniform lobe (κ = 0) widens to roughness 1
  const double u = alpha2 / (2 - 2 * alpha2) + inverseSharpness;  // 1/s' = 1/s + 1/κ
  return 2 * u / (1 + 2 * u);
}

std::string filteredMipsUnavailable(const geometry::Material& m) {
  if (!m.normalTexture) return "the material has no normal map";
  const Image& normals = *m.normalTexture.image;
  if (normals.channels < 3) return "the normal map has fewer than 3 channels";
  if (normals.width % 4 != 0 || normals.height % 4 != 0)
    return "the normal map is " + std::to_string(normals.width) + "x" + std::to_string(normals.height) +
           ": KTX2 textures for glTF need sides that are multiples of 4";
  if (const geometry::Texture& mr = m.metallicRoughnessTexture) {
    if (mr.image->width != normals.width || mr.image->height != normals.height)
      return "the metallic-roughness texture and the normal map differ in size";
    if (mr.offset != m.normalTexture.offset || mr.scale != m.normalTexture.scale || mr.rotation != m.normalTexture.rotation)
      return "the metallic-roughness texture and the normal map are mapped with different transforms";
  }
  return "";
}

geometry::Material withFilteredMips(const geometry::Material& material, const Context& ctx) {
  if (const std::string why = filteredMipsUnavailable(material); !why.empty())
    throw Error("normal-map filtering for glTF: " + why);
  Stage stage(ctx, "roughness MIPs");
  auto chain = std::make_shared<std::vector<Image>>();
  for (Level level = baseLevel(material, ctx);; level = nextLevel(level, ctx)) {
    chain->push_back(levelImage(level));
    if (level.width == 1 && level.height == 1) break;
  }
  geometry::Material out = material;
  geometry::Texture& mr = out.metallicRoughnessTexture;
  if (!mr) {
    mr.offset = material.normalTexture.offset, mr.scale = material.normalTexture.scale;
    mr.rotation = material.normalTexture.rotation;
    mr.name = "metallic_roughness.png";
  }
  mr.image = std::make_shared<const Image>(chain->front());
  mr.encoded.reset();
  mr.mips = std::move(chain);
  out.metallicFactor = 1.0f, out.roughnessFactor = 1.0f;
  stage.finish();
  return out;
}

geometry::Mesh withFilteredMips(const geometry::Mesh& mesh, const Context& ctx, std::vector<std::string>* notes) {
  geometry::Mesh out = mesh;
  for (geometry::Material& m : out.materials) {
    if (!m.normalTexture) continue;
    if (const std::string why = filteredMipsUnavailable(m); why.empty())
      m = withFilteredMips(m, ctx);
    else if (notes)
      notes->push_back("material '" + m.name + "': the normal map's MIP levels are left to viewers (" + why + ")");
  }
  return out;
}

} // namespace texfab::render
