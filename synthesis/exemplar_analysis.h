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
//   S. Lefebvre. Synthèse de textures par l'exemple pour les applications interactives. HDR
//     thesis, 2014, §3.3.2 and §3.3.2.2 (the scheme assumes a toroidal exemplar; without one,
//     synthesis itself must produce the seamless result): non-toroidal exemplars (ExemplarWrap).
//   C. Eisenacher et al. Example-based texture synthesis on Disney's Tangled. 2010, as summarised
//     in the thesis §3.3.2.3 (k-nearest sets of large exemplars built by randomized search).
// Notes: docs/synthesis-notes.md#appearance-space, #parallel-synthesis, #stack-upsampling.
//
// Non-toroidal exemplars (ExemplarWrap::Clamp): the stack is filtered, and neighborhoods are read,
// with mirrored borders instead of wrapped ones, and every level has a valid region: the pixels
// whose runtime neighborhood's 4 diagonal samples (h_l apart) lie inside the exemplar, the margin
// capped at a quarter of the side so that coarse levels keep half of the exemplar. (A margin of
// 3 h_l, the whole 5x5 footprint of those samples, lost more fidelity than the mirrored reads it
// avoids.) Synthesis keeps every coordinate, candidate and jittered coordinate of a level inside
// its valid region, so no synthesized neighborhood reads across the exemplar's border.
//
// Deviations from the papers, on purpose:
//   * appearance vectors and runtime neighborhoods are quantized to int8 with one scale per level,
//     so that every backend computes the same integer distances (the determinism contract);
//   * k-nearest neighbors are searched among the 8-D appearance vectors (a k-d tree, exact),
//     not among the 32-D runtime neighborhoods (the 8-D vector already encodes a 5x5 neighborhood);
//   * exemplars larger than kExactAnalysisPixels: the PCA is fitted on a regular sample of
//     kExactAnalysisPixels neighborhoods, and the k-nearest sets are searched exactly only on a
//     grid of sites, then spread to the other pixels (see analyzeExemplar).

#include "core/context.h"
#include "core/image.h"

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
/// Largest exemplar side (4096: 16.8 Mpixel).
inline constexpr int kMaxExemplarSide = 4096;
/// Exemplars up to this many pixels (256^2) are analysed exactly as the papers describe; larger
/// ones sample the PCA and spread the k-nearest search (see the header comment).
inline constexpr int64_t kExactAnalysisPixels = 256 * 256;

/// How synthesis treats the exemplar's borders.
enum class ExemplarWrap : uint8_t {
  Tile,   ///< toroidal: left/right and top/bottom borders match; coordinates wrap (LH05's assumption)
  Clamp,  ///< not toroidal: coordinates stay in each level's valid region, nothing wraps
};
const char* toString(ExemplarWrap wrap);

/// The discontinuity of an exemplar across its wrap compared with inside it, per axis: for block
/// sizes s = 1, 2, 4, 8 (while 16 s fits in the exemplar), the mean over rows of s x s blocks of
/// the colour difference between the blocks on either side of a column boundary (L1, values in
/// [0, 1]); the measure is the largest ratio, over s, of that mean at the wrap to the 90th
/// percentile of its values at the boundaries inside. About 1 for a toroidal exemplar (its wrap is
/// one boundary among many); a photograph's wrap joins unrelated content and stands out from the
/// boundaries inside, even where one strong edge (a crack) inside is as sharp as the wrap.
struct WrapDiscontinuity {
  double x = 0;  ///< across the left/right wrap
  double y = 0;  ///< across the top/bottom wrap
  double worst() const { return x > y ? x : y; }
};
WrapDiscontinuity wrapDiscontinuity(const Image& exemplar);

/// The discontinuity above which `auto` treats an exemplar as non-toroidal. Measured
/// (docs/exemplars.md#wrap-detection): GIMP's patterns whose tiles show no seam up to 1.67,
/// photograph crops whose wrap shows 1.90 and up.
inline constexpr double kWrapDiscontinuityThreshold = 1.8;
/// Exemplars with a side below this are too small to tell (a single motif whose one strong edge
/// may lie on the wrap, as GIMP's 26-pixel bluegrid): auto keeps them toroidal.
inline constexpr int kWrapDetectionMinSide = 32;

/// Clamp when the exemplar is at least kWrapDetectionMinSide per side and its wrapDiscontinuity
/// exceeds kWrapDiscontinuityThreshold; Tile otherwise.
ExemplarWrap detectExemplarWrap(const Image& exemplar);

struct AnalysisOptions {
  int k = 2;                   ///< candidates per exemplar pixel, the pixel itself first; 2..8
  /// Weight of the feature-distance channel relative to colour; 0 = off. Off by default: it made
  /// fidelity worse on GIMP's brick and parquet (docs/measurements.md#feature-distance-channel).
  float featureWeight = 0.0f;
  int searchNeighbors = 12;    ///< nearest neighbors examined to pick k spread-apart candidates
  float minSpread = 0.05f;     ///< candidates lie at least max(2, minSpread * exemplar side) apart
  ExemplarWrap wrap = ExemplarWrap::Tile;  ///< toroidal or not (detectExemplarWrap() decides for users)

  /// Throws texfab::Error naming the field when a value is out of range.
  void validate() const;
};

/// The exemplar index of a position that may lie outside [0, side): wrapped (Tile) or mirrored,
/// ... 1 0 | 0 1 ... side-1 | side-1 side-2 ... (Clamp).
int foldIndex(int a, int side, ExemplarWrap wrap);

/// The exemplar pixels synthesis may use at one level: [x0, x1] x [y0, y1], inclusive.
struct ValidRegion {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool contains(int64_t x, int64_t y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
};

/// The valid region of a level of spacing h: the whole exemplar when it tiles; otherwise a margin
/// of min(h, (side - 1) / 4) pixels on every side.
ValidRegion validRegion(int width, int height, int spacing, ExemplarWrap wrap);

/// One level of the Gaussian stack, as synthesis sees it.
struct AnalysisLevel {
  int spacing = 1;  ///< h_l = 2^(L-l): exemplar pixels between neighboring synthesized pixels
  ValidRegion valid;  ///< coordinates synthesis may use at this level
  std::vector<int8_t> appearance;    ///< width*height*kAppearanceDims, quantized PCA coefficients
  std::vector<int8_t> neighborhood;  ///< width*height*kNeighborhoodDims: appearance at u + spacing*(±1,±1)
  std::vector<uint32_t> candidates;  ///< width*height*k packed coordinates (coord_map.h); [0] is the pixel
};

/// Everything synthesis reads about an exemplar. Levels go from 0 (coarsest, spacing 2^L)
/// to L (the exemplar itself, spacing 1), with L = ceil(log2(max(width, height))).
struct ExemplarAnalysis {
  int width = 0;
  int height = 0;
  int k = 0;
  ExemplarWrap wrap = ExemplarWrap::Tile;
  std::vector<AnalysisLevel> levels;
  uint64_t key = 0;  ///< content + options hash identifying this analysis (the cache key)

  int finestLevel() const { return static_cast<int>(levels.size()) - 1; }
};

/// Number of stack levels for an exemplar: ceil(log2(max(width, height))) + 1.
int stackLevelCount(int width, int height);

/// The Gaussian stack of `exemplar` (first three colour channels, or grey), from the coarsest
/// level (index 0) to the exemplar itself. Each level keeps the exemplar's size; level l is
/// filtered to the bandwidth of a 2^(L-l) downsampling (à trous binomial filter), toroidal (Tile)
/// or with mirrored borders (Clamp).
std::vector<Image> gaussianStack(const Image& exemplar, ExemplarWrap wrap = ExemplarWrap::Tile);

/// Distance of each pixel to the nearest strong edge (top decile of gradient magnitude), toroidal
/// or not, in pixels: the feature-distance channel of appearance-space synthesis (LH06 §3.2).
Image featureDistance(const Image& exemplar, ExemplarWrap wrap = ExemplarWrap::Tile);

/// Throws texfab::Error unless the exemplar's size is usable (kMinExemplarSide to
/// kMaxExemplarSide per side).
void validateExemplarSize(const Image& exemplar);

/// Peak memory of analyzeExemplar on a width x height exemplar, in bytes, the caller's float copy
/// of the exemplar included (meant as an upper bound), so callers can refuse an exemplar before
/// the work.
double analysisMemoryBytes(int width, int height, const AnalysisOptions& options);
/// Rough CPU seconds of analyzeExemplar (on one core of the 2-core machine it was measured on).
double analysisCpuSeconds(int width, int height);

/// Analyses `exemplar` (at least kMinExemplarSide pixels per side). Pure: the result depends only
/// on the pixels and the options, never on the context. Reports the stages "stack", then
/// "level l/L" per level through ctx.
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
