// SPDX-License-Identifier: GPL-3.0-or-later
// The glTF route of normal-map filtering (render/material_mips.h): a roughness MIP chain whose
// widening is the BRDF convolved with each texel's fitted vMF lobe.
#include "render/filter_normal_map.h"
#include "render/material_mips.h"
#include "tests/render/test_normal_maps.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

using namespace texfab;
using namespace texfab::render;

namespace {

geometry::Material glossy(const Image& normalMap) {
  geometry::Material m;
  m.metallicFactor = 0.5f;
  m.roughnessFactor = 0.3f;
  m.normalTexture.image = std::make_shared<const Image>(normalMap);
  return m;
}

double meanChannel(const Image& image, int c) {
  double sum = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) sum += image.at(x, y, c);
  return sum / (double(image.width) * image.height);
}

} // namespace

// The widened roughness's Blinn-Phong exponent 2/α'² - 2 is the convolved exponent κs / (κ + s)
// [Han et al. 2007, Eq. 7.20] of the lobe's κ (Banerjee et al.'s approximation) and the
// roughness's s.
TEST(MaterialMips, WideningIsTheBrdfConvolvedWithTheLobe) {
  for (double roughness : {0.1, 0.3, 0.6})
    for (double r : {0.999, 0.99, 0.9, 0.6, 0.2}) {
      const double alpha2 = std::pow(roughness, 4);
      const double s = 2 / alpha2 - 2, kappa = (3 * r - r * r * r) / (1 - r * r);
      const double widened = std::pow(double(widenedRoughness(alpha2, r)), 4);
      EXPECT_NEAR((2 / widened - 2) / convolvedExponent(kappa, s), 1.0, 1e-4) << roughness << " " << r;
    }
  EXPECT_NEAR(widenedRoughness(std::pow(0.3, 4), 1.0), 0.3f, 1e-6f);  // one normal: no widening
  EXPECT_EQ(widenedRoughness(0.01, 0.0), 1.0f);                          // normals all round: rough
  EXPECT_EQ(widenedRoughness(1.0, 0.9), 1.0f);
  // In α, from 1/κ, as the previews' microfacet BRDF widens each lobe: a uniform lobe gives α'² = 1.
  EXPECT_NEAR(widenedAlpha2(std::pow(0.3, 4), 0.0), std::pow(0.3, 4), 1e-12);
  EXPECT_EQ(widenedAlpha2(0.01, std::numeric_limits<double>::infinity()), 1.0);
}

// A flat normal map keeps its roughness at every level; levels halve rounding down to 1x1.
TEST(MaterialMips, FlatNormalsKeepTheirRoughness) {
  Image flat(24, 12, 3);
  for (size_t i = 0; i < flat.pixels.size(); i += 3) flat.pixels[i] = 0.5f, flat.pixels[i + 1] = 0.5f, flat.pixels[i + 2] = 1.0f;
  const geometry::Material given = glossy(flat), m = withFilteredMips(given);
  ASSERT_TRUE(m.metallicRoughnessTexture.mips);
  const std::vector<Image>& chain = *m.metallicRoughnessTexture.mips;
  const std::vector<std::pair<int, int>> sizes = {{24, 12}, {12, 6}, {6, 3}, {3, 1}, {1, 1}};
  ASSERT_EQ(chain.size(), sizes.size());
  for (size_t l = 0; l < chain.size(); ++l) {
    EXPECT_EQ(std::pair(chain[l].width, chain[l].height), sizes[l]);
    for (int y = 0; y < chain[l].height; ++y)
      for (int x = 0; x < chain[l].width; ++x) {
        EXPECT_NEAR(chain[l].at(x, y, 1), 0.3f, 1e-6f);
        EXPECT_NEAR(chain[l].at(x, y, 2), 0.5f, 1e-6f);
      }
  }
  EXPECT_EQ(m.metallicFactor, 1.0f);
  EXPECT_EQ(m.roughnessFactor, 1.0f);
  EXPECT_EQ(m.metallicRoughnessTexture.image->pixels, chain[0].pixels);  // the fallback is level 0
  EXPECT_EQ(m.normalTexture.image, given.normalTexture.image);  // the normal map as it was, its MIPs the viewer's
  EXPECT_FALSE(m.normalTexture.mips);
}

// Bumps make a material rougher the further it is seen (one isotropic lobe per texel): level 0
// keeps the roughness, each level is at least as rough on average as the one below, and a bumpy
// map's coarse levels much rougher. Both routes' chains are the same bytes on any thread count; of
// the three materials only the brushed metal's grooves get an anisotropy chain.
TEST(MaterialMips, BumpsWidenRoughnessWithDistance) {
  for (const test::TestMap& t : test::testMaps(64)) {
    const geometry::Material m = withFilteredMips(glossy(t.map), {.anisotropy = false}, Context{.threads = 2});
    const std::vector<Image>& chain = *m.metallicRoughnessTexture.mips;
    ASSERT_EQ(chain.size(), 7u);
    EXPECT_FALSE(m.anisotropy);
    EXPECT_NEAR(meanChannel(chain[0], 1), 0.3, 1e-6) << t.name;
    for (size_t l = 1; l < chain.size(); ++l) EXPECT_GE(meanChannel(chain[l], 1), meanChannel(chain[l - 1], 1) - 1e-6) << t.name;
    EXPECT_GT(meanChannel(chain.back(), 1), 0.4) << t.name;
    EXPECT_NEAR(meanChannel(chain.back(), 2), 0.5, 1e-6) << t.name;
    for (bool anisotropy : {false, true}) {
      const geometry::Material two = withFilteredMips(glossy(t.map), {anisotropy}, Context{.threads = 2});
      const geometry::Material one = withFilteredMips(glossy(t.map), {anisotropy}, Context{.threads = 1});
      ASSERT_EQ(bool(two.anisotropy), bool(one.anisotropy)) << t.name;
      EXPECT_EQ(bool(two.anisotropy), anisotropy && t.name == "brushed metal") << t.name;  // docs/normal-map-filtering.md
      for (size_t l = 0; l < chain.size(); ++l) {
        EXPECT_EQ((*two.metallicRoughnessTexture.mips)[l].pixels, (*one.metallicRoughnessTexture.mips)[l].pixels);
        if (two.anisotropy) {
          EXPECT_EQ((*two.anisotropy.texture.mips)[l].pixels, (*one.anisotropy.texture.mips)[l].pixels);
        }
      }
    }
  }
}

// Grooves whose normals tilt one way widen the lobe along that way only (KHR_materials_anisotropy):
// the roughness chain keeps the material's roughness (nothing spreads across), the anisotropy chain
// points along the tilt, every texel with the same sign, with a strength that grows with distance;
// level 0 is isotropic. Seen through the extension, α_t is the one isotropic lobe's widening of that spread.
TEST(MaterialMips, GroovesWidenTheLobeAlongTheirTilt) {
  for (const double angle : {0.0, std::numbers::pi / 2, std::numbers::pi / 4, 3 * std::numbers::pi / 4}) {
    const Eigen::Vector2d along(std::cos(angle), std::sin(angle));
    Image grooves(32, 32, 3);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        const double tilt = 0.4 * std::sin(2 * std::numbers::pi * (along.x() * x + along.y() * y) / 8);
        const Eigen::Vector3d n(std::sin(tilt) * along.x(), std::sin(tilt) * along.y(), std::cos(tilt));
        for (int c = 0; c < 3; ++c) grooves.at(x, y, c) = float(0.5 * n[c] + 0.5);
      }
    const geometry::Material m = withFilteredMips(glossy(grooves));
    ASSERT_TRUE(m.anisotropy);
    EXPECT_EQ(m.anisotropy.strength, 1.0f);
    const std::vector<Image>& roughness = *m.metallicRoughnessTexture.mips;
    const std::vector<Image>& anisotropy = *m.anisotropy.texture.mips;
    ASSERT_EQ(anisotropy.size(), roughness.size());
    EXPECT_NEAR(meanChannel(anisotropy[0], 2), 0.0, 1e-6);
    const Image& top = anisotropy.back();
    const Eigen::Vector2d sign(2 * top.at(0, 0, 0) - 1, 2 * top.at(0, 0, 1) - 1);
    const Eigen::Vector2d expected = sign.dot(along) < 0 ? Eigen::Vector2d(-along) : along;
    for (size_t l = 2; l < anisotropy.size(); ++l) {
      const Image& a = anisotropy[l];
      EXPECT_NEAR(meanChannel(roughness[l], 1), 0.3, 0.02) << angle << " level " << l;
      EXPECT_NEAR(2 * meanChannel(a, 0) - 1, expected.x(), 0.02) << angle << " level " << l;
      EXPECT_NEAR(2 * meanChannel(a, 1) - 1, expected.y(), 0.02) << angle << " level " << l;
      EXPECT_GT(meanChannel(a, 2), l < 3 ? 0.3 : 0.5) << angle << " level " << l;  // from a whole period on
      EXPECT_GE(meanChannel(a, 2), meanChannel(anisotropy[l - 1], 2) - 1e-6) << angle << " level " << l;
    }
    // Along the tilt, the widening of every normal's spread: more than the isotropic lobe's, which
    // shares it with the direction across.
    const geometry::Material isotropic = withFilteredMips(glossy(grooves), {.anisotropy = false});
    const float alpha = 0.09f, strength = anisotropy.back().at(0, 0, 2);
    const float alphaT = alpha + (1 - alpha) * strength * strength;
    const float alphaIsotropic = std::pow(isotropic.metallicRoughnessTexture.mips->back().at(0, 0, 1), 2.0f);
    EXPECT_GT(alphaT, alphaIsotropic) << angle;
  }
}

// A metallic-roughness texture's channels are kept: R (occlusion) and B (metallic) averaged, G
// times the factor widened.
TEST(MaterialMips, KeepsTheMaterialsOwnTexture) {
  const Image map = test::testMaps(32)[0].map;
  Image mr(32, 32, 3);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) mr.at(x, y, 0) = 0.25f, mr.at(x, y, 1) = x < 16 ? 1.0f : 0.5f, mr.at(x, y, 2) = 1.0f;
  geometry::Material m = glossy(map);
  m.metallicRoughnessTexture.image = std::make_shared<const Image>(mr);
  const geometry::Material out = withFilteredMips(m);
  const Image& base = *out.metallicRoughnessTexture.image;
  EXPECT_NEAR(base.at(3, 5, 1), 0.3f, 1e-6f);
  EXPECT_NEAR(base.at(20, 5, 1), 0.15f, 1e-6f);
  EXPECT_NEAR(base.at(20, 5, 0), 0.25f, 1e-6f);
  EXPECT_NEAR(base.at(20, 5, 2), 0.5f, 1e-6f);
  const Image& top = out.metallicRoughnessTexture.mips->back();
  EXPECT_NEAR(top.at(0, 0, 0), 0.25f, 1e-6f);
  EXPECT_NEAR(top.at(0, 0, 2), 0.5f, 1e-6f);
  EXPECT_GT(top.at(0, 0, 1), 0.15f);
}

TEST(MaterialMips, SaysWhyAMaterialCannotHaveThem) {
  EXPECT_EQ(filteredMipsUnavailable(geometry::Material{}), "the material has no normal map");
  EXPECT_NE(filteredMipsUnavailable(glossy(Image(30, 32, 3))).find("multiples of 4"), std::string::npos);
  geometry::Material m = glossy(Image(32, 32, 3));
  EXPECT_EQ(filteredMipsUnavailable(m), "");
  m.metallicRoughnessTexture.image = std::make_shared<const Image>(16, 16, 3);
  EXPECT_NE(filteredMipsUnavailable(m).find("differ in size"), std::string::npos);
  EXPECT_THROW(withFilteredMips(m), Error);
}
