// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Normal-map filtering in spherical harmonics, the linear form of Han et al. 2007 (Frequency Domain
// Normal Map Filtering; C. Han's thesis, §7.4, "Algorithm A", Eqs. 7.11-7.12): a texel's
// distribution of normals (NDF) as its real SH coefficients up to band l*. They are means over the
// texel's normals, so the MIP levels are plain box filters of level 0 and need no fit; a radially
// symmetric BRDF lobe convolves with them band by band (the Funk-Hecke theorem), and the cosine
// factor is taken at the texel's mean normal, as the thesis does. Accurate for low-frequency
// BRDFs: a Blinn-Phong exponent s needs l* ≈ sqrt(4s), which is where the vMF lobes of
// filter_normal_map.h take over (docs/normal-map-filtering.md measures where each fits).
//
// Deviations: the band factors of Blinn-Phong are integrated exactly (quadrature) instead of the
// approximation e^(-l²/2s); the convolved lobe is clamped at 0 (a truncated series rings).

#include "core/context.h"
#include "core/image.h"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace texfab::render {

struct NdfHarmonicsOptions {
  /// The highest band l*, [0, 16]: (order + 1)^2 coefficients per texel. 8 resolves normalized
  /// Blinn-Phong lobes of exponent up to about 16 (l* ≈ sqrt(4s); docs/normal-map-filtering.md).
  int order = 8;
};

/// One MIP level: (order + 1)^2 coefficients per texel (index l^2 + l + m), rows top first.
struct NdfHarmonicsLevel {
  int width = 0, height = 0, coefficientsPerTexel = 0;
  std::vector<float> coefficients;

  std::span<const float> texel(int x, int y) const;
};

struct NdfHarmonics {
  int order = 0;
  /// Level 0 has the map's size; each next level halves each side (rounding up) down to 1x1, and
  /// a texel of level l holds the mean over the normals of its 2^l x 2^l block of level 0
  /// (clipped at the map's edges), as filterNormalMap's levels cover them.
  std::vector<NdfHarmonicsLevel> levels;
};

/// The SH coefficients of every texel's NDF at every MIP level of a tangent-space normal map
/// (channels 0-2 hold (n + 1) / 2). Deterministic whatever the thread count. Throws texfab::Error
/// for a map with fewer than 3 channels or an order out of range.
NdfHarmonics ndfHarmonics(const Image& normalMap, const NdfHarmonicsOptions& options = {}, const Context& ctx = {});

/// The real spherical harmonics Y_lm(n) of a unit vector up to band `order`, index l^2 + l + m
/// (orthonormal on the sphere, without the Condon-Shortley phase).
void sphericalHarmonics(const Eigen::Vector3f& n, int order, std::span<float> out);

/// The Funk-Hecke factors λ_l = 2π ∫ g(t) P_l(t) dt, l = 0..order, of the normalized Blinn-Phong
/// lobe g(t) = ((s + 1) / 2π) max(t, 0)^s: a lobe g(h·n) averaged over an NDF with coefficients
/// γ_lm is Σ λ_l γ_lm Y_lm(h).
std::vector<double> blinnPhongBands(double exponent, int order);

/// Blinn-Phong over a texel's NDF from its SH coefficients: (Σ λ_l γ_lm Y_lm(h), at least 0) times
/// max(l·n̄, 0) at the texel's mean normal n̄ (from band 1). `light` and `half` are unit vectors in tangent space;
/// `bands` comes from blinnPhongBands for the exponent.
double shadeBlinnPhongHarmonics(std::span<const float> coefficients, int order, std::span<const double> bands,
                                const Eigen::Vector3f& light, const Eigen::Vector3f& half);

} // namespace texfab::render
