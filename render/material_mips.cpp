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
  Eigen::Vector3f slopes = Eigen::Vector3f::Zero();  // their tangent-plane moments: x², xy, y²
  float alpha2 = 0, metallic = 0, occlusion = 0, count = 0;

  void add(const Footprint& o) {
    normal += o.normal, slopes += o.slopes;
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
        f.slopes = {f.normal.x() * f.normal.x(), f.normal.x() * f.normal.y(), f.normal.y() * f.normal.y()};
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

// The spread of a footprint's normals in the tangent plane: the eigenvalues of the covariance of
// their x and y components, and the unit axis of the larger.
struct Spread {
  double major = 0, minor = 0;
  Eigen::Vector2d axis{1, 0};
};

Spread spreadOf(const Footprint& f) {
  const Eigen::Vector2d mean = f.normal.head<2>().cast<double>() / f.count;
  const double xx = double(f.slopes.x()) / f.count - mean.x() * mean.x();
  const double xy = double(f.slopes.y()) / f.count - mean.x() * mean.y();
  const double yy = double(f.slopes.z()) / f.count - mean.y() * mean.y();
  // Square roots only (no hypot): the same bits on every CPU.
  const double half = 0.5 * (xx + yy), gap = std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
  Spread s{half + gap, std::max(half - gap, 0.0), {}};
  s.axis = xy != 0 ? Eigen::Vector2d(xy, s.major - xx).normalized() : xx >= yy ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1);
  return s;
}

// The lobe fitted to a footprint's normals, as glTF can carry it: the roughness across the
// direction in which the normals spread most and, with anisotropy, the widening along it.
struct FittedLobe {
  float roughness = 1;
  Eigen::Vector2f direction{1, 0};  // tangent space, unit
  float strength = 0;               // KHR_materials_anisotropy's: α_t = mix(α, 1, strength²)
};

// The vMF lobe's 1/κ from the mean length |r| (isotropic) is split between the two principal axes
// of the normals' spread in proportion to its eigenvalues (a tight lobe's 1/κ is its variance per
// axis), and each axis widens α² as widenedAlpha2 does. An axis has two signs; the one toward
// `reference` is kept, since viewers filter directions linearly and opposite ones would cancel.
FittedLobe fitLobe(const Footprint& f, bool anisotropic, const Eigen::Vector2d& reference) {
  const double alpha2 = std::clamp(double(f.alpha2) / f.count, 0.0, 1.0);
  const double r = std::clamp(double(f.normal.norm()) / f.count, 0.0, 1.0);
  FittedLobe lobe;
  lobe.direction = reference.cast<float>();
  const Spread spread = anisotropic ? spreadOf(f) : Spread{};
  if (!(spread.major > 0) || alpha2 >= 1 || r <= 0) {
    lobe.roughness = widenedRoughness(alpha2, r);
    return lobe;
  }
  const double inverseSharpness = (1 - r * r) / (3 * r - r * r * r), half = 0.5 * (spread.major + spread.minor);
  const double alphaMinor = std::sqrt(widenedAlpha2(alpha2, inverseSharpness * spread.minor / half));
  const double alphaMajor = std::sqrt(widenedAlpha2(alpha2, inverseSharpness * spread.major / half));
  lobe.roughness = float(std::sqrt(alphaMinor));
  lobe.direction = (spread.axis.dot(reference) < 0 ? Eigen::Vector2d(-spread.axis) : spread.axis).cast<float>();
  lobe.strength = alphaMinor < 1 ? float(std::sqrt(std::max(alphaMajor - alphaMinor, 0.0) / (1 - alphaMinor))) : 0.0f;
  return lobe;
}

// The level's metallic-roughness texture (R, occlusion, and B, metallic, averaged; G widened) and,
// when `anisotropy` is not null, its anisotropy texture (directions signed toward `reference`;
// strength 0 unless `anisotropic`).
Image levelImage(const Level& level, bool anisotropic, const Eigen::Vector2d& reference, Image* anisotropy) {
  Image mr(level.width, level.height, 3);
  if (anisotropy) *anisotropy = Image(level.width, level.height, 3);
  for (int y = 0; y < level.height; ++y)
    for (int x = 0; x < level.width; ++x) {
      const Footprint& f = level.at(x, y);
      const FittedLobe lobe = fitLobe(f, anisotropic, reference);
      mr.at(x, y, 0) = f.occlusion / f.count;
      mr.at(x, y, 1) = lobe.roughness;
      mr.at(x, y, 2) = f.metallic / f.count;
      if (!anisotropy) continue;
      anisotropy->at(x, y, 0) = 0.5f * (lobe.direction.x() + 1);
      anisotropy->at(x, y, 1) = 0.5f * (lobe.direction.y() + 1);
      anisotropy->at(x, y, 2) = lobe.strength;
    }
  return mr;
}

// The sign of every direction: the principal axis of the whole map's normals, so that the
// directions a viewer filters together agree, whichever way the material's grain runs (the
// diagonal when they spread evenly).
Eigen::Vector2d referenceAxis(const Level& base) {
  Footprint all;
  for (const Footprint& f : base.texels) all.add(f);
  const Spread spread = spreadOf(all);
  return spread.major > spread.minor ? spread.axis : Eigen::Vector2d(std::sqrt(0.5), std::sqrt(0.5));
}

// How much the normals under a level's texels spread one way: Σ(λ₁ - λ₂) / Σ(λ₁ + λ₂) over its
// texels' principal spreads (0 where nothing spreads).
double anisotropyOf(const Level& level) {
  double one = 0, all = 0;
  for (const Footprint& f : level.texels) {
    const Spread s = spreadOf(f);
    one += s.major - s.minor, all += s.major + s.minor;
  }
  return all > 0 ? one / all : 0.0;
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

geometry::Material withFilteredMips(const geometry::Material& material, const FilteredMipsOptions& options,
                                    const Context& ctx) {
  if (const std::string why = filteredMipsUnavailable(material); !why.empty())
    throw Error("normal-map filtering for glTF: " + why);
  Stage stage(ctx, "roughness MIPs");
  auto chain = std::make_shared<std::vector<Image>>();
  auto anisotropy = std::make_shared<std::vector<Image>>();
  // A material with anisotropy of its own keeps it; level 0 (one normal per texel) has none.
  const bool fitAnisotropy = options.anisotropy && !material.anisotropy;
  bool anyAnisotropic = false;
  Level level = baseLevel(material, ctx);
  const Eigen::Vector2d reference = referenceAxis(level);
  for (bool first = true;; level = nextLevel(level, ctx), first = false) {
    // An isotropic level's anisotropy texture is constant: made below, only if another level needs one.
    const bool anisotropic = fitAnisotropy && !first && anisotropyOf(level) >= options.minAnisotropy;
    anyAnisotropic |= anisotropic;
    Image directions(level.width, level.height, 0);
    chain->push_back(levelImage(level, anisotropic, reference, anisotropic ? &directions : nullptr));
    anisotropy->push_back(std::move(directions));
    if (level.width == 1 && level.height == 1) break;
  }
  for (Image& directions : *anisotropy)
    if (anyAnisotropic && directions.channels == 0) {
      directions = Image(directions.width, directions.height, 3);
      for (int y = 0; y < directions.height; ++y)
        for (int x = 0; x < directions.width; ++x)
          directions.at(x, y, 0) = 0.5f * (float(reference.x()) + 1), directions.at(x, y, 1) = 0.5f * (float(reference.y()) + 1);
    }
  geometry::Material out = material;
  const geometry::Texture& normals = material.normalTexture;
  const auto mappedAsNormals = [&](geometry::Texture& t, const char* name) {
    t.offset = normals.offset, t.scale = normals.scale, t.rotation = normals.rotation;
    t.name = name;
  };
  geometry::Texture& mr = out.metallicRoughnessTexture;
  if (!mr) mappedAsNormals(mr, "metallic_roughness.png");
  mr.image = std::make_shared<const Image>(chain->front());
  mr.encoded.reset();
  mr.mips = std::move(chain);
  out.metallicFactor = 1.0f, out.roughnessFactor = 1.0f;
  if (anyAnisotropic) {
    out.anisotropy = {};
    mappedAsNormals(out.anisotropy.texture, "anisotropy.png");
    out.anisotropy.strength = 1.0f;
    out.anisotropy.texture.image = std::make_shared<const Image>(anisotropy->front());
    out.anisotropy.texture.mips = std::move(anisotropy);
  }
  stage.finish();
  return out;
}

geometry::Mesh withFilteredMips(const geometry::Mesh& mesh, const FilteredMipsOptions& options, const Context& ctx,
                                std::vector<std::string>* notes) {
  geometry::Mesh out = mesh;
  for (geometry::Material& m : out.materials) {
    if (!m.normalTexture) continue;
    if (const std::string why = filteredMipsUnavailable(m); why.empty())
      m = withFilteredMips(m, options, ctx);
    else if (notes)
      notes->push_back("material '" + m.name + "': the normal map's MIP levels are left to viewers (" + why + ")");
  }
  return out;
}

} // namespace texfab::render
