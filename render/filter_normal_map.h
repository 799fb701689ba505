// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Normal-map filtering by fitting the distribution of normals (the NDF) under each texel of each
// MIP level with a mixture of von Mises-Fisher lobes, and shading a texel by convolving each lobe
// with the BRDF. A MIP-mapped normal map averages its normals: seen from a distance bumps turn
// flat and shiny; the fitted lobes keep the spread of normals, so the material stays as rough as
// its bumps make it.
//
// Based on: C. Han, B. Sun, R. Ramamoorthi, E. Grinspun. Frequency Domain Normal Map Filtering.
// SIGGRAPH 2007 (C. Han's thesis, 2011, §7.6: spherical EM per texel, lobes initialized from the
// children's, Blinn-Phong convolved as s' = κs / (κ + s)); A. Banerjee, I. Dhillon, J. Ghosh, S.
// Sra. Clustering on the Unit Hypersphere using von Mises-Fisher Distributions. JMLR 6, 2005 (the
// approximation of κ). M. Toksvig. Mipmapping Normal Maps. JGT 10(3), 2005 (the baseline).
//
// Deviations: the E-step weighs each lobe by its mixing weight (standard movMF EM; the thesis'
// printed algorithm omits it); a fixed number of EM iterations (no convergence test), so that the
// work per texel is fixed; the exponential is texfab's own (pinned arithmetic, not libm's).

#include "core/context.h"
#include "core/image.h"
#include "synthesis/analysis_cache.h"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace texfab::render {

/// One lobe of a texel's NDF.
struct VmfLobe {
  float weight = 0;  ///< α: the share of the texel's normals in this lobe (the lobes sum to 1)
  /// r: the mean of those normals, in tangent space. Its direction is the lobe's axis μ; its length
  /// (< 1 when the normals spread) gives the lobe's sharpness κ.
  Eigen::Vector3f mean = Eigen::Vector3f::UnitZ();

  Eigen::Vector3f axis() const;
  /// κ ≈ (3|r| - |r|³) / (1 - |r|²) [Banerjee et al. 2005], at most kMaxVmfSharpness.
  float sharpness() const;
};

/// The sharpness of a single normal's lobe: a width of about 0.01 radian.
inline constexpr float kMaxVmfSharpness = 1.0e4f;

/// The NDF of one MIP level: lobesPerTexel lobes per texel, rows top first; lobes beyond a
/// texel's fit weigh 0.
struct NdfLevel {
  int width = 0, height = 0, lobesPerTexel = 0;
  std::vector<VmfLobe> lobes;

  std::span<const VmfLobe> texel(int x, int y) const;
};

struct NdfMipChain {
  /// Level 0 has the map's size and one lobe per texel, its normal; each next level halves each
  /// side (rounding up) down to 1x1, as MipPyramid does, with FilterNormalMapOptions::lobes lobes.
  std::vector<NdfLevel> levels;

  std::span<const VmfLobe> texel(int level, int x, int y) const { return levels[size_t(level)].texel(x, y); }
};

struct FilterNormalMapOptions {
  /// Lobes per texel, [1, 8]. Han et al. find 3-4 enough in renderings; on texfab's tests (stone,
  /// brushed metal, fabric) 8 lobes have 1.5-14x less error than 4 (docs/normal-map-filtering.md).
  int lobes = 8;
  /// EM iterations per texel and level, [1, 100]. Han et al.: seldom more than 10 are needed; 5
  /// and 10 agree within 15 % in error on the tests.
  int iterations = 5;
};

/// Fits the NDF of every texel of every MIP level of a tangent-space normal map (channels 0-2 hold
/// (n + 1) / 2, as written by texfab and read by glTF viewers). A texel of level l covers the
/// normals of its 2^l x 2^l block of level 0 (clipped at the map's edges). Deterministic: a pure
/// function of the map and the options, whatever the thread count. Reports progress per level.
/// Throws texfab::Error for a map with fewer than 3 channels or options out of range.
NdfMipChain filterNormalMap(const Image& normalMap, const FilterNormalMapOptions& options = {},
                            const Context& ctx = {});

/// filterNormalMap through the analysis cache (`<key>.ndf` in cache.dir, keyed by the map's pixels
/// and the options): read when present and valid, else fitted and stored, the cache then pruned.
/// `cached` (optional) tells which.
NdfMipChain filterNormalMap(const Image& normalMap, const FilterNormalMapOptions& options,
                            const synthesis::AnalysisCacheSettings& cache, const Context& ctx, bool* cached = nullptr);

/// The tangent-space normal of texel (x, y) of a normal map (decoded and normalized; +z when the
/// texel encodes a zero vector).
Eigen::Vector3f decodeNormal(const Image& normalMap, int x, int y);

/// Normalized Blinn-Phong, ((s + 1) / 2π) (h·n)^s max(l·n, 0), of one normal: the BRDF the
/// filtered shadings below approximate over a texel's normals.
double blinnPhong(const Eigen::Vector3f& normal, const Eigen::Vector3f& light, const Eigen::Vector3f& half,
                  double exponent);

/// Blinn-Phong over a texel's NDF: Σ α_j ((s'_j + 1) / 2π) (h·μ_j)^s'_j max(l·μ_j, 0) with
/// s'_j = κ_j s / (κ_j + s) [Han et al. 2007, Eq. 7.20]. `light` and `half` are unit vectors in
/// tangent space.
double shadeBlinnPhong(std::span<const VmfLobe> lobes, const Eigen::Vector3f& light, const Eigen::Vector3f& half,
                       double exponent);

/// The exponent of a Blinn-Phong lobe of exponent s convolved with a vMF lobe of sharpness κ:
/// s' = κs / (κ + s) [Han et al. 2007, Eq. 7.20] (0 for a uniform lobe, κ = 0).
template <class T>
T convolvedExponent(T sharpness, T exponent) {
  return sharpness * exponent / (sharpness + exponent);
}

/// The mean of direction `dir` reflected about the normals m of a vMF lobe (unit `axis`,
/// sharpness κ, mean resultant length A = |E m|): dir - 2 E[m m^T] dir, where E[m m^T] =
/// (A/κ) I + (1 - 3A/κ) axis axis^T (Mardia & Jupp 2000, §9.3.2; a uniform lobe as κ -> 0). What a
/// linear environment shows through the lobe (Han et al. 2007, §7.6.3).
Eigen::Vector3f meanReflection(const Eigen::Vector3f& dir, const Eigen::Vector3f& axis, float sharpness, float length);

/// Toksvig's filtering from a texel's mean normal `mean` (|mean| ≤ 1): the exponent
/// s' = |m| s / (|m| + s (1 - |m|)) at the normalized mean.
double shadeToksvig(const Eigen::Vector3f& mean, const Eigen::Vector3f& light, const Eigen::Vector3f& half,
                    double exponent);

} // namespace texfab::render
