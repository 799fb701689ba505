// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A roughness MIP chain that carries a normal map's spread of normals, for the files texfab
// writes: the glTF route of normal-map filtering (render/filter_normal_map.h fits the full NDF for
// texfab's own renders). glTF's metallic-roughness material has no NDF, and a viewer averages a
// normal map's MIP levels: from afar the bumps flatten and the material turns shiny. Here each
// texel of each level keeps the one von Mises-Fisher lobe fitted to the normals it covers (their
// mean r; κ ≈ (3|r| - |r|³) / (1 - |r|²), Banerjee et al. 2005) and its roughness widens so that
// the viewer's specular lobe is the BRDF convolved with that lobe: with the Blinn-Phong exponent
// s = 2/α² - 2 of α = roughness², s' = κs / (κ + s) [Han et al. 2007, Eq. 7.20], so
// α'² = 2u / (1 + 2u) with u = 1/s + 1/κ. This is Toksvig's idea (2005) with the fitted lobe's κ;
// α² is averaged over the footprint.
//
// Where the normals spread one way (grooves), the lobe is anisotropic (KHR_materials_anisotropy):
// 1/κ is shared between the principal axes of the normals' tangent-plane covariance in proportion
// to its eigenvalues, and each axis widens α² as above; the roughness chain carries the narrower
// axis, an anisotropy chain the direction and the wider one. Deviation: Han et al. fit vMF lobes,
// which are round; this anisotropic lobe is the one glTF can carry.
//
// The normal map keeps no chain of its own: a viewer's box-filtered levels of it point along the
// same mean normals r (a viewer normalizes what it samples), and the map stays lossless.

#include "core/context.h"
#include "geometry/mesh.h"

#include <string>
#include <vector>

namespace texfab::render {

/// Why `material` cannot get filtered MIP chains, or "" when it can: it needs a normal map of at
/// least 3 channels whose sides are multiples of 4 (KHR_texture_basisu's rule for the base level),
/// and a metallic-roughness texture, if any, of the same size and texture transform.
std::string filteredMipsUnavailable(const geometry::Material& material);

struct FilteredMipsOptions {
  /// Fit each footprint's lobe with its principal direction (KHR_materials_anisotropy) where the
  /// normals spread one way: the roughness chain then widens across the direction in which they
  /// spread most, and an anisotropy texture with a chain of its own (mapped as the normal map;
  /// level 0 isotropic) widens it along that direction. Viewers without the extension see the
  /// narrower widening. False: one isotropic lobe per texel (Toksvig's case) everywhere.
  bool anisotropy = true;
  /// A level's lobes are anisotropic only where its normals spread one way, Σ(λ₁ - λ₂) / Σ(λ₁ + λ₂)
  /// over its texels' principal spreads at least this (brushed metal's grooves 0.99 at every level;
  /// bumps 0.2-0.7, threads 0.6-0.9 at small footprints, where one anisotropic lobe gains nothing
  /// measurable: docs/normal-map-filtering.md); a material with no such level gets no anisotropy
  /// texture, its chain that of `anisotropy` false.
  double minAnisotropy = 0.9;
};

/// `material` with a metallic-roughness texture whose MIP chain of its own (geometry::Texture::mips)
/// widens roughness with the spread of the normals under each texel. The metallic and roughness
/// factors are baked into that texture (a new one when the material had none, mapped as the normal
/// map) and set to 1; its R channel (occlusion, when a viewer reads it there) and metallic are
/// averaged. Level 0 is the texture as it was. Deterministic (sums in a fixed order, square roots
/// only), whatever the thread count. Throws texfab::Error with the reason of
/// filteredMipsUnavailable.
geometry::Material withFilteredMips(const geometry::Material& material, const FilteredMipsOptions& options = {},
                                    const Context& ctx = {});

/// `mesh` as texfab writes it to glTF: every normal-mapped material withFilteredMips, where
/// filteredMipsUnavailable allows; for each material that cannot have them, a line in `notes`
/// (optional) says why.
geometry::Mesh withFilteredMips(const geometry::Mesh& mesh, const FilteredMipsOptions& options = {},
                                const Context& ctx = {}, std::vector<std::string>* notes = nullptr);

/// α'²: a specular lobe of α² (GGX's, or Blinn-Phong's of exponent s = 2/α² - 2) convolved with a
/// vMF lobe of sharpness κ, given as 1/κ (0: a single normal): 2u / (1 + 2u) with u = 1/s + 1/κ
/// (s' = κs / (κ + s), Han et al. 2007, Eq. 7.20). 1 for α² >= 1 or a uniform lobe (1/κ infinite).
double widenedAlpha2(double alpha2, double inverseSharpness);

/// The roughness whose specular lobe is the one of `roughness` convolved with a vMF lobe whose mean
/// vector has length `meanLength` (1: a single normal, no widening; 0: roughness 1). `alpha2` is
/// the α² = roughness⁴ to widen (a footprint's mean).
float widenedRoughness(double alpha2, double meanLength);

} // namespace texfab::render
