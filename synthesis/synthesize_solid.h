// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Lazy solid texture synthesis: the colour of any voxel of an infinite volume, computing only the
// dependency chain of the voxels asked for.
//
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//   §5.1 (sparse multi-resolution synthesis: tiling of the candidate slab, jitter once, upsampling
//   by coordinate inheritance, 2 correction passes (8 sub-passes each in the paper; Jacobi by
//   default here, see below) with the two-step search,
//   colour = mean of the three exemplar colours), §5.2 (masks dilated per pass and level), §6.2
//   (a cache of coarse levels shared across requests).
// Notes: docs/synthesis-notes.md#lazy-solid-synthesis and #order-independence.
//
// Determinism (docs/design.md#the-determinism-contract): a voxel's triple is a pure function of
// (analysis, options, position).
// The mask of §5.2 is computed exactly per sub-pass (a voxel corrected in sub-pass t reads its
// 61-voxel 3-neighborhood as it was after sub-pass t-1; a voxel not of that sub-pass's class only
// carries its own value), so every voxel computed for a request has a complete dependency chain,
// whatever else was requested, in whatever order, split into whatever requests, on however many
// threads, with or without the cache.
//
// Deviations from the paper, on purpose:
//   * Jacobi passes by default (SolidSynthesisOptions::interleave = 1), not 8 sub-passes: the
//     dependency chain of §5.2 (dilated once per pass) is then exact and ~25x shorter, since
//     every sub-pass dilates; dependencyChainSize() reports both;
//   * the jitter warp is a sum of compactly supported polynomial bumps on two hashed grids (4 and
//     8 voxels at the start level) instead of ~200 Gaussians in a unit volume: the volume is
//     infinite, and integer arithmetic keeps backends identical;
//   * one correction pass at the finest level by default (SolidSynthesisOptions::finestPasses),
//     two above it as in the paper: the finest level's work drops ~3x (a planar cut: 6x) for a
//     small loss (docs/measurements.md);
//   * the search sees voxel colours through a per-level histogram-matching table learned from the
//     candidates (SolidSynthesisOptions::matchColors) instead of the mean of three; output colours
//     are still the mean of three;
//   * the search's targets are moved away from their neighborhood's mean, twice their difference
//     from it by default (SolidSynthesisOptions::contrastGain): slices keep more of the
//     exemplar's contrast and structure, and match its small windows less closely;
//   * the initialization reads the slab at a hashed offset per cell of 8 start-level voxels
//     (SolidSynthesisOptions::offsetCells) instead of one tiling, whose period survived every level;
//   * the volume has no size and nothing wraps: only exemplar coordinates wrap, and only those of a
//     toroidal exemplar (for one that does not tile, see solid_analysis.h: they never need to).

#include "core/context.h"
#include "core/image.h"
#include "synthesis/solid_analysis.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <span>
#include <tuple>
#include <vector>

namespace texfab::synthesis {

/// A finest-level voxel position. |x|, |y|, |z| <= kMaxSolidPosition.
struct Voxel {
  int64_t x = 0, y = 0, z = 0;
  int64_t& operator[](int axis) { return axis == 0 ? x : axis == 1 ? y : z; }
  int64_t operator[](int axis) const { return axis == 0 ? x : axis == 1 ? y : z; }
  bool operator==(const Voxel&) const = default;
};
inline constexpr int64_t kMaxSolidPosition = int64_t(1) << 30;

/// An axis-aligned box of finest-level voxels.
struct VoxelBox {
  int64_t x = 0, y = 0, z = 0;
  int nx = 0, ny = 0, nz = 0;
  int64_t count() const { return int64_t(nx) * ny * nz; }
};

/// How voxels are made: lazy synthesis (Dong et al. 2008, this file), or read from the analysis'
/// precomputed tile set (solid_tiles.h: constant time per voxel; SolidAnalysis::tiles).
enum class SolidMethod : uint8_t { Lazy, Tiles };
const char* toString(SolidMethod method);

struct SolidSynthesisOptions {
  uint32_t seed = 1;     ///< the only source of variation
  /// Lazy (default) or Tiles. With Tiles, the analysis must carry its tile set, the seed picks the
  /// arrangement of tiles, and every option below is the tile set's business, not read.
  SolidMethod method = SolidMethod::Lazy;
  /// Strength of the random warp applied once after initialization, in voxels of the start level
  /// (amplitudes 1.5 and 1 voxel on 4- and 8-voxel grids at 1); 0 = no warp. [0, 4]
  float jitter = 1.0f;
  /// Side, in start-level voxels, of the cells of the initialization that each read the candidate
  /// slab at their own hashed offset (cells of the warped volume, so their borders are not planes);
  /// 0 = one tiling of the slab (the paper), which repeats with the exemplar's period through every
  /// level. Default 8: shifted-self correlation at that period <= 0.21 on ten GIMP patterns (up to
  /// 0.51 with one tiling) for the same fidelity. [0, 1024]
  /// Figures: docs/measurements.md#offset-cells-at-initialization.
  int offsetCells = 8;
  int passes = 2;        ///< correction passes per level above the finest; 0..4
  /// Correction passes at the finest level; 0..4. One (default) instead of the paper's two: ~6x
  /// less work on a planar cut for 2-8% worse slice fidelity; 2 = the paper's schedule.
  /// Figures: docs/measurements.md#correction-passes-at-the-finest-level.
  int finestPasses = 1;
  /// 2: each pass is 8 sub-passes over the 2x2x2 parity classes (§5.1, the paper's choice);
  /// 1 (default): each pass corrects every voxel at once (Jacobi): a dependency chain ~25x shorter
  /// and 3-6x faster lazy synthesis, slice fidelity within 4%. The paper's dilation (§5.2, once
  /// per pass) is exact for Jacobi passes only.
  /// Figures: docs/measurements.md#jacobi-passes-against-sub-passes.
  int interleave = 1;
  /// true (default): the neighborhoods the search compares show each voxel's colour through its
  /// level's histogram-matching table (SolidLevel::searchColors) instead of the mean of its three
  /// exemplar colours (§5.1). The mean regresses to the middle wherever the three disagree; the
  /// search then prefers flat exemplar regions, and every pass flattens slices further. Output
  /// colours (solidColors) stay the mean of three. false: the paper's rule.
  bool matchColors = true;
  /// Gain of the search's targets: each voxel of a 3-neighborhood is shown to the search at its
  /// neighborhood's mean colour plus `contrastGain` times its difference from it; 1: the paper's
  /// targets. At 2 (default) the search prefers candidates with the exemplar's dark and bright
  /// features over flat ones: slices keep more contrast (ten GIMP patterns: 0.63 -> 0.88 of the
  /// exemplar's), histograms twice as close to the exemplar's and more of its structure
  /// (completeness), for worse 7x7 neighbourhood fidelity (1.56 -> 1.89 times the 2-D synthesis',
  /// a measure that flat slices win). [1, 4]
  /// Figures: docs/measurements.md#contrast-gain-of-the-search-targets, #a-default-gain-of-2.
  float contrastGain = 2.0f;
  /// Passes of slice refinement after the finest level (Kopf et al. 2007's search and vote,
  /// refine_solid.h); 0 (default): none, the paper's triples. Each pass makes a voxel read its
  /// neighbours within 4 voxels, so a request synthesizes a region 8 voxels thicker per pass, and
  /// one pass makes a 128^3 volume about 3.5x slower. Ten GIMP patterns, contrast / 7x7 fidelity
  /// over the 2-D synthesis': the paper's search 0.63 / 1.56; the default contrast gain 0.88 / 1.89;
  /// one pass after it 0.80 / 1.58. [0, 4]
  /// Figures: docs/measurements.md#slice-refinement.
  int refinePasses = 0;

  /// contrastGain in sixteenths, as the kernels apply it.
  int contrastGain16() const { return int(std::lrint(double(contrastGain) * 16.0)); }

  int subpasses() const { return interleave == 2 ? 8 : 1; }
  int passesAt(bool finest) const { return finest ? finestPasses : passes; }

  void validate() const;
};

/// Exemplar coordinates of one voxel in E_x, E_y, E_z (packed, coord_map.h).
using Triple = std::array<uint32_t, 3>;

struct SolidLevelStats {
  int stackLevel = 0;
  int64_t voxels = 0;        ///< voxels synthesized at this level (the dependency chain)
  int64_t corrections = 0;   ///< voxel corrections (a voxel is corrected once per pass)
  double seconds = 0.0;
};

struct SolidSynthesisResult {
  std::vector<Triple> triples;           ///< one per requested voxel, in request order
  int64_t distinctVoxels = 0;            ///< distinct voxels among those requested (Tiles: all requested)
  std::vector<SolidLevelStats> levels;   ///< coarsest first (Tiles: none, nothing is synthesized)
  int64_t voxelsSynthesized() const;     ///< sum over levels
};

/// Adds the level statistics of `r` to `total` (per level, same schedule; an empty total takes them).
void addLevelStats(std::vector<SolidLevelStats>& total, const SolidSynthesisResult& r);

/// Final values of coarse levels, kept across requests in 4^3 bricks (a brick may hold only the
/// voxels a request computed: `valid`; later requests add to it), least recently used evicted
/// beyond `maxBytes`. Owned by the caller; one cache serves one (analysis, options) pair
/// at a time (it clears itself when they change). Not thread-safe: one request at a time.
class SolidLevelCache {
public:
  /// What a request computes of a coarse level's brick it finds missing or incomplete: only the
  /// voxels it needs (Needed), or the whole brick (WholeBricks), so that the next requests nearby
  /// find it complete: for a cut dragged through a model, about a third less work per position
  /// and a third more for the first (docs/measurements.md#the-interactive-re-cut). Values are the
  /// same either way.
  enum class Fill : uint8_t { Needed, WholeBricks };

  explicit SolidLevelCache(size_t maxBytes = size_t(256) << 20, Fill fill = Fill::Needed)
      : maxBytes_(maxBytes), fill_(fill) {}
  size_t bytes() const { return bytes_; }
  size_t maxBytes() const { return maxBytes_; }
  Fill fill() const { return fill_; }
  int64_t hits() const { return hits_; }
  int64_t misses() const { return misses_; }
  void clear();

  // Used by the synthesizer.
  using Key = std::tuple<int, int64_t, int64_t, int64_t>;  // level index, brick x, y, z
  struct Brick {
    std::vector<uint32_t> values;  // 4^3 * 3
    uint64_t valid = ~uint64_t(0);  // bit (z * 4 + y) * 4 + x: that voxel's values are set
  };
  void bind(uint64_t owner);
  std::shared_ptr<const Brick> find(const Key& key);
  void insert(const Key& key, std::shared_ptr<const Brick> brick);

private:
  size_t maxBytes_;
  Fill fill_;
  size_t bytes_ = 0;
  uint64_t owner_ = 0;
  int64_t hits_ = 0, misses_ = 0;
  std::list<Key> order_;  // most recent first
  std::map<Key, std::pair<std::shared_ptr<const Brick>, std::list<Key>::iterator>> bricks_;
};

/// Triples of the given finest-level voxels (any set: shell, plane, box, scattered; duplicates
/// allowed). `cache` may be null (nothing kept between requests).
/// Reports its stages through ctx: "masks" (the dependency chains, fine to coarse), then one per
/// level, "level k/n" coarsest first, with the voxels synthesized and corrected. With
/// options.refinePasses, refineSolid (refine_solid.h) runs this over a larger region first.
SolidSynthesisResult synthesizeSolid(const SolidAnalysis& analysis, std::span<const Voxel> voxels,
                                     const SolidSynthesisOptions& options, SolidLevelCache* cache = nullptr,
                                     const Context& ctx = {});

/// Peak memory of synthesizeSolid for `voxels` requested voxels (a plane, points), in bytes: the
/// request, its triples and colours, and the finest level's masks; with refinement passes, one
/// slab's region (refineSolidMemoryBytes).
double synthesizeSolidMemoryBytes(int64_t voxels, int refinePasses = 0);

/// Triples of every voxel of `box`, x fastest, then y, then z.
SolidSynthesisResult synthesizeSolidBox(const SolidAnalysis& analysis, const VoxelBox& box,
                                        const SolidSynthesisOptions& options, SolidLevelCache* cache = nullptr,
                                        const Context& ctx = {});

/// Colour of each triple: the mean of E_x, E_y and E_z at its three coordinates (first three
/// channels, or grey). `channels` is 3, or 1 when all three exemplars are grey. Values are
/// appended to `out`, `channels` per triple.
int solidColorChannels(const Image& ex, const Image& ey, const Image& ez);
/// `image` with `channels` (1 or 3) colour channels as solidColors reads it: a grey image's value
/// in each channel, an RGB image's first three (a copy when it has them already).
Image solidColorView(const Image& image, int channels);
void solidColors(std::span<const Triple> triples, const Image& ex, const Image& ey, const Image& ez,
                 std::vector<float>& out);
/// The colour of one triple (solidColors): solidColorChannels(ex, ey, ez) values at out.
void solidColor(const Triple& triple, const Image& ex, const Image& ey, const Image& ez, float* out);

/// The dependency chain of one voxel: voxels synthesized per level (exact, as computed), and the
/// paper's count (§5.2: the mask dilated by the 3-neighborhood once per pass, not per sub-pass).
struct DependencyChain {
  std::vector<int64_t> exactPerLevel;  ///< coarsest first
  int64_t exact = 0;
  int64_t perPassDilation = 0;
};
DependencyChain dependencyChainSize(const SolidAnalysis& analysis, const SolidSynthesisOptions& options);

} // namespace texfab::synthesis
