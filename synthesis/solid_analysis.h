// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Precomputation for lazy solid texture synthesis: 3-D candidates (coordinate triples) per
// exemplar pixel, and the PCA-projected, int8-quantized neighborhoods synthesis compares.
//
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis.
//   EGSR 2008: §3 (3-neighborhoods of three interleaved NxN neighborhoods, N = 5), §4.1 (crossbar
//   error CB; the S best strips of each other exemplar, all S^2 triples ranked by CB, 100 kept),
//   §4.2 (coherence filter down to <= 12 candidates), §4.3 (candidate slab), §6.1 (one image
//   used for all three axes shares one candidate set), §6.2 (PCA to 12..8 dimensions, 8-bit).
// Notes: docs/synthesis-notes.md#lazy-solid-synthesis and #stack-upsampling.
//
// Orientation (fixed, cyclic, so one candidate set serves all three axes, Fig. 3 / §6.1):
//   E_x lies in the (y, z) plane: exemplar u = volume y, v = volume z;
//   E_y lies in the (z, x) plane: u = z, v = x;
//   E_z lies in the (x, y) plane: u = x, v = y.
// Exemplar e's column strip (v varies) is its crossbar with exemplar (e+1)%3's row strip.
//
// Deviations from the paper, on purpose:
//   * a Gaussian *stack* (every level at the exemplar's size, taps 2^(L-l) apart) instead of a
//     pyramid, as in the 2-D synthesis of this module: stack upsampling adds h_l * (child bit);
//   * the S best strips are found by an exact brute-force search (blocked matrix products)
//     rather than ANN; ties go to the smaller pixel index;
//   * coherence (§4.2) reads "|C[p+d]_y - c_y| = 1" as a toroidal 4-neighbor step of the level's
//     tap spacing h_l in that exemplar; a filter iteration that would empty a pixel's set is not
//     applied to that pixel (the paper notes this "happens rarely");
//   * all neighborhood values are integers (colours are 8-bit, PCA bases 12-bit, distances int32)
//     so that every backend picks the same candidate (docs/design.md#the-determinism-contract);
//   * 2-D neighborhoods for the first search step are PCA-projected 5x5 neighborhoods (8 dims);
//     2-D candidate sets are the k-coherence sets of synthesis/exemplar_analysis;
//   * a voxel's colour in the neighborhoods the search compares (§5.1: the mean of its three
//     exemplar colours) can go through a per-level histogram-matching table (searchColors), in
//     the spirit of the histogram matching Kopf et al. 2007 (Solid Texture Synthesis from 2D
//     Exemplars, §3.3) run inside their optimization, learned here once from the candidates.
//
// Non-toroidal exemplars (SolidAnalysisOptions::wrap = Clamp; the paper assumes toroidal ones):
// the stack, strips and neighborhoods read mirrored borders instead of wrapped ones, and every
// coordinate a table holds (3-D triples, 2-D candidates) lies in the level's valid region, a margin
// of one tap spacing h_l inside the exemplar; a pixel of the margin takes the tables of its
// reflection into the region. Synthesis then never wraps: a voxel's coordinates stay in the region
// (they come from the tables), a step-1 shift by one tap stays in the exemplar, and upsampling
// adds h_l / 2 to a coordinate at least h_l from the border. Only the levels whose h_l is at most
// (side - 1) / 4 are synthesized (a 32x32 exemplar: 3 levels instead of 4).

#include "core/context.h"
#include "core/image.h"
#include "synthesis/exemplar_analysis.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

namespace texfab::synthesis {

/// Side of each of the three interleaved 2-D neighborhoods (paper: N = 5).
inline constexpr int kSolidNeighborhoodSide = 5;
/// Voxels of a 3-neighborhood: three 5x5 planes through the centre.
inline constexpr int kSolidCrossVoxels = 61;
/// Dimensions of a projected 2-D neighborhood (first search step).
inline constexpr int kSolid2dDims = 8;
/// Most dimensions of a projected 3-neighborhood (coarse levels; the finest keeps 8).
inline constexpr int kSolidMaxDims = 12;
/// Largest exemplar side the precomputation accepts: its exact strip search grows with the
/// square of the pixel count (2 cores: 8 s at 128^2, 65 s at 256^2, about 15 min at 512^2).
inline constexpr int kMaxSolidExemplarSide = 512;
/// Most 3-D candidates per exemplar pixel after the coherence filter.
inline constexpr int kSolidMaxCandidates = 12;
/// Sums of three 8-bit colour values: 0..765.
inline constexpr int kSolidColorSums = 766;
/// 3-D candidates per pixel whose colours set the search colour transfer (SolidLevel::searchColors).
inline constexpr int kSolidTransferCandidates = 4;

struct SolidAnalysisOptions {
  int strips = 65;              ///< S: best crossbar strips taken from each other exemplar; 4..256
  int kept = 100;               ///< triples kept per pixel by crossbar error; kSolidMaxCandidates..S^2
  int coherenceIterations = 3;  ///< coherence filter iterations at most (stops at <= 12 per pixel); 0..8
  int levels = 4;               ///< synthesized levels: the finest and those above it (paper: l_start = L-3); 1..8
  int candidates2d = 4;         ///< k-coherence 2-D candidates per pixel (coarse levels; finest uses 2); 1..8
  ExemplarWrap wrap = ExemplarWrap::Tile;  ///< toroidal exemplars or not (detectExemplarWrap() decides for users)

  /// Throws texfab::Error naming the field when a value is out of range.
  void validate() const;
};

/// Integer PCA projection: q = clamp(floor((sum_i basis[d][i] * (x_i - mean_i) + divisor/2) / divisor), +-127),
/// divisor a power of two (a shift).
struct SolidProjection {
  int inputs = 0;
  int dims = 0;
  std::vector<int32_t> mean;    ///< inputs
  std::vector<int16_t> basis;   ///< dims * inputs, 12-bit fixed point
  int32_t divisor = 1;

  void project(const int32_t* values, int8_t* out) const;
};

/// One synthesized level: everything the correction kernel reads.
struct SolidLevel {
  int stackLevel = 0;  ///< index into the Gaussian stack (L = finest)
  int spacing = 1;     ///< h_l = 2^(L - stackLevel): exemplar pixels between neighboring voxels
  ValidRegion valid;   ///< every coordinate the tables hold: the whole exemplar, or (Clamp) h_l inside it
  int dims = 0;        ///< dimensions of the projected 3-neighborhoods at this level
  int k2d = 0;         ///< 2-D candidates used per pixel at this level
  int k3d = 0;         ///< 3-D candidates used per pixel at this level
  std::array<std::vector<uint8_t>, 3> colors;        ///< per exemplar: w*h*3, the stack level in 8 bits
  std::array<std::vector<uint32_t>, 3> candidates2d; ///< per exemplar: w*h*candidates2d packed coords
  std::array<std::vector<int8_t>, 3> descriptors2d;  ///< per exemplar: w*h*kSolid2dDims
  /// Derived (not cached): per exemplar, w*h*(2-D candidates)*kSolid2dDims, the descriptor of each
  /// 2-D candidate of a pixel, side by side, so the search reads one cache line per pixel.
  std::array<std::vector<int8_t>, 3> candidateDescriptors2d;
  /// Derived (not cached): per channel, the colour a voxel shows to the search, indexed by the sum
  /// of its three 8-bit exemplar colours, at the scale of the projection inputs (6x, 0..1530).
  /// Histogram matching: the distribution of that sum over the first kSolidTransferCandidates
  /// 3-D candidates of every pixel is mapped onto the exemplars' own colour distribution (each
  /// sum to the exemplar quantile at the middle of its share), so that targets built from voxels
  /// keep the exemplar's contrast instead of regressing to the mean of three.
  std::array<std::array<int16_t, kSolidColorSums>, 3> searchColors{};
  /// Per exemplar: w*h*kSolidMaxCandidates triples (x, y, z exemplar coordinates, packed), best
  /// crossbar error first; the e-th coordinate is the pixel itself. Short sets repeat their first.
  std::array<std::vector<uint32_t>, 3> triples;
  std::array<std::vector<int8_t>, 3> descriptors3d;  ///< per exemplar: w*h*kSolidMaxCandidates*dims
  SolidProjection projection2d;  ///< 25 voxels * 3 channels -> kSolid2dDims
  SolidProjection projection3d;  ///< 61 voxels * 3 channels -> dims
};

/// Figures of the precomputation, for reports and tests (never read by synthesis).
struct SolidAnalysisStats {
  double meanCandidatesBeforeFilter = 0;  ///< per pixel, finest level (the kept triples)
  double meanCandidatesAfterFilter = 0;   ///< per pixel, finest level, before truncation to 12
  double meanBestCrossbarError = 0;       ///< finest level, 8-bit colour units squared
  double seconds = 0;
};

struct SolidTileSet;

struct SolidAnalysis {
  int width = 0;    ///< all three exemplars share this size
  int height = 0;
  bool shared = false;  ///< one image for the three axes: one candidate computation (§6.1)
  ExemplarWrap wrap = ExemplarWrap::Tile;
  int finestStackLevel = 0;  ///< L
  std::vector<SolidLevel> levels;  ///< synthesized levels, coarsest (l_start) first
  SolidAnalysisStats stats;
  uint64_t key = 0;
  /// The tile set optimized from this analysis (solid_tiles.h), for SolidMethod::Tiles; computed
  /// and cached on its own (buildSolidTilesCached), null until then.
  std::shared_ptr<const SolidTileSet> tiles;

  int startStackLevel() const { return finestStackLevel - int(levels.size()) + 1; }
};

/// The 61 offsets of a 3-neighborhood, in the order of projection inputs: the (x, y) plane row by
/// row, then the (z, x) plane without its x axis, then the (y, z) plane without its y and z axes.
const std::array<std::array<int, 3>, kSolidCrossVoxels>& solidCrossOffsets();

/// Throws texfab::Error unless the three exemplars can be analysed together (same size, at least
/// 8x8, at most kMaxSolidExemplarSide per side). Names the exemplars as given in `names` (x, y, z).
void validateSolidExemplars(const Image& ex, const Image& ey, const Image& ez,
                            const std::array<std::string, 3>& names = {"x exemplar", "y exemplar", "z exemplar"});

/// The precomputation. Pure: depends only on the pixels and options, never on the context.
/// Passing the same image three times shares the candidate computation.
SolidAnalysis analyzeSolid(const Image& ex, const Image& ey, const Image& ez, const SolidAnalysisOptions& options,
                           const Context& ctx = {});

/// Rough CPU seconds of the precomputation (on one core of the 2-core machine it was measured on).
double solidAnalysisCpuSeconds(int width, int height);

uint64_t solidAnalysisKey(const Image& ex, const Image& ey, const Image& ez, const SolidAnalysisOptions& options);

/// Through the on-disk cache `cacheDir/<key>.solid` (see analyzeExemplarCached).
SolidAnalysis analyzeSolidCached(const Image& ex, const Image& ey, const Image& ez,
                                 const SolidAnalysisOptions& options, const std::filesystem::path& cacheDir,
                                 const Context& ctx = {}, bool* fromCache = nullptr);

void writeSolidAnalysis(const SolidAnalysis& analysis, const std::filesystem::path& path);
std::optional<SolidAnalysis> readSolidAnalysis(const std::filesystem::path& path, uint64_t expectedKey);

} // namespace texfab::synthesis
