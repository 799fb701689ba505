// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Exemplar analysis for parallel synthesis: what synthesize2d() needs to know about an exemplar,
// computed once and cached.
//
// Based on:
//   S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005 (Gaussian
//     stack of a toroidal exemplar, §3; k-coherence candidate sets spread apart, §3.3).
//   S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006 (§3: appearance
//     vectors = 5x5 neighborhoods plus a feature-distance channel, PCA to 8 dimensions; §4: runtime
//     neighborhoods of 4 diagonal appearance vectors).
//   X. Tong et al. Synthesis of bidirectional texture functions on arbitrary surfaces.
//     SIGGRAPH 2002 (k-coherence search).
// Notes: ../shared/notes/lefebvre-hdr-notes.md §2.3, §4 and errata §20.
//
// Deviations from the papers, on purpose:
//   * appearance vectors and runtime neighborhoods are quantized to int8 with one scale per level,
//     so that every backend computes the same integer distances (the determinism contract);
//   * k-nearest neighbors are searched among the 8-D appearance vectors (a k-d tree, exact),
//     not among the 32-D runtime neighborhoods (the 8-D vector already encodes a 5x5 neighborhood).

#include "render/image/context.h"
#include "render/image/image.h"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace texfab::synthesis {

/// Dimension of a per-pixel appearance vector after PCA.
inline constexpr int kAppearanceDims = 8;
/// Runtime neighborhood: the appearance vectors at the 4 diagonal neighbors.
inline constexpr int kNeighborhoodSamples = 4;
inline constexpr int kNeighborhoodDims = kAppearanceDims * kNeighborhoodSamples;
/// The order of the runtime neighborhood's samples: u + spacing * (kDiagonalX[i], kDiagonalY[i]).
inline constexpr int kDiagonalX[kNeighborhoodSamples] = {-1, 1, -1, 1};
inline constexpr int kDiagonalY[kNeighborhoodSamples] = {-1, -1, 1, 1};
/// Smallest exemplar side: the 5x5 appearance neighborhood needs at least this many pixels.
inline constexpr int kMinExemplarSide = 5;

struct AnalysisOptions {
  int k = 2;                   ///< candidates per exemplar pixel, the pixel itself first; 2..8
  /// Weight of the feature-distance channel relative to colour; 0 = off. Off by default: on GIMP's
  /// brick and parquet it lowered 7x7 neighborhood fidelity (0.048 vs 0.055, 0.045 vs 0.047).
  float featureWeight = 0.0f;
  int searchNeighbors = 12;    ///< nearest neighbors examined to pick k spread-apart candidates
  float minSpread = 0.05f;     ///< candidates lie at least max(2, minSpread * exemplar side) apart

  /// Throws texfab::Error naming the field when a value is out of range.
  void validate() const;
};

/// One level of the Gaussian stack, as synthesis sees it.
struct AnalysisLevel {
  int spacing = 1;  ///< h_l = 2^(L-l): exemplar pixels between neighboring synthesized pixels
  std::vector<int8_t> appearance;    ///< width*height*kAppearanceDims, quantized PCA coefficients
  std::vector<int8_t> neighborhood;  ///< width*height*kNeighborhoodDims: appearance at u + spacing*(±1,±1)
  std::vector<uint32_t> candidates;  ///< width*height*k exemplar indices (y*width+x); [0] is the pixel
};

/// Everything synthesis reads about an exemplar. Levels go from 0 (coarsest, spacing 2^L)
/// to L (the exemplar itself, spacing 1), with L = ceil(log2(max(width, height))).
struct ExemplarAnalysis {
  int width = 0;
  int height = 0;
  int k = 0;
  std::vector<AnalysisLevel> levels;
  uint64_t key = 0;  ///< content + options hash identifying this analysis (the cache key)

  int finestLevel() const { return static_cast<int>(levels.size()) - 1; }
};

/// Number of stack levels for an exemplar: ceil(log2(max(width, height))) + 1.
int stackLevelCount(int width, int height);

/// The Gaussian stack of `exemplar` (first three colour channels, or grey), toroidal, from the
/// coarsest level (index 0) to the exemplar itself. Each level keeps the exemplar's size; level l
/// is filtered to the bandwidth of a 2^(L-l) downsampling (à trous binomial filter).
std::vector<Image> gaussianStack(const Image& exemplar);

/// Distance of each pixel to the nearest strong edge (top decile of gradient magnitude), toroidal,
/// in pixels: the feature-distance channel of appearance-space synthesis (LH06 §3.2).
Image featureDistance(const Image& exemplar);

/// Throws texfab::Error unless the exemplar's size is usable (kMinExemplarSide to 4096 per side).
void validateExemplarSize(const Image& exemplar);

/// Analyses `exemplar` (at least kMinExemplarSide pixels per side). Pure: the result depends only
/// on the pixels and the options, never on the context.
ExemplarAnalysis analyzeExemplar(const Image& exemplar, const AnalysisOptions& options, const Context& ctx = {});

/// The cache key of (exemplar pixels, options).
uint64_t analysisKey(const Image& exemplar, const AnalysisOptions& options);

/// Analysis through an on-disk cache in `cacheDir`: loads `<key>.analysis` when present and valid,
/// otherwise analyses and stores it (a cache that cannot be written is skipped, not an error).
/// `fromCache` tells which happened.
ExemplarAnalysis analyzeExemplarCached(const Image& exemplar, const AnalysisOptions& options,
                                       const std::filesystem::path& cacheDir, const Context& ctx = {},
                                       bool* fromCache = nullptr);

/// The default cache folder: $TEXFAB_CACHE_DIR, else $XDG_CACHE_HOME/texfab, else ~/.cache/texfab.
std::filesystem::path defaultCacheDir();

/// Writes / reads one analysis file. readAnalysis returns nothing for a missing, foreign or
/// damaged file (a damaged cache is recomputed, never trusted).
void writeAnalysis(const ExemplarAnalysis& analysis, const std::filesystem::path& path);
std::optional<ExemplarAnalysis> readAnalysis(const std::filesystem::path& path, uint64_t expectedKey);

} // namespace texfab::synthesis
