// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Solid texture tiles: a precomputed set of solid tiles whose faces match by construction (Wang
// cubes), optimized so that their slices look like the exemplars; a voxel is then read from the
// tile that a hash of its cell selects, in constant time, in any order, for any subset.
//
// Based on:
//   J. Kopf, C.-W. Fu, D. Cohen-Or, O. Deussen, D. Lischinski, T.-T. Wong. Solid Texture Synthesis
//     from 2D Exemplars. SIGGRAPH 2007, §3 (global optimization: each voxel's three orthogonal
//     slice neighborhoods matched in the exemplars, colours voted with IRLS weights), §3.3
//     (histogram matching against the exemplar's statistics);
//   J. Chen, B. Wang. High Quality Solid Texture Synthesis using Position and Index Histogram
//     Matching. The Visual Computer 26, 2010, §4 (the position histogram: exemplar positions used
//     more than their share are penalized in the search, which keeps every part of the exemplar);
//   A. C. Sibley, G. Taubin et al. Wang Cubes for Video Synthesis and Geometry Placement (2004);
//     M. F. Cohen, J. Shade, S. Hiller, O. Deussen. Wang Tiles for Image and Texture Generation.
//     SIGGRAPH 2003 (tiles selected by hashed edge colours; here faces, V = 2 or 3 colours per
//     face: the complete set of V^6 cubes).
// Notes: docs/synthesis-notes.md#solid-tiles.
//
// Layout. A tile is n^3 voxels; its face, edge and corner voxels (a local coordinate 0) belong to
// shared storage: the x-face of a cell (local x = 0) is one of V face variants of its axis, chosen
// by a hash of the face's lattice position, and the tile whose 6 face variants are those of its
// cell's 6 faces fills the interior; edges and corners are shared variants too (2 each, hashed by
// position). Every arrangement is therefore seamless by construction, and a voxel is a handful of
// hashes and one read. Boxes and lists of voxels (synthesizeSolidBox, synthesizeSolid) are read
// on the Vulkan device when the context asks for one (vulkan/solid_kernels.h: the same bytes).
//
// Optimization. The tile set is optimized where it is seen: on periodic arrangements of M^3 cells
// in which every tile appears, drawn anew at each iteration so that tiles meet many neighbours.
// Coarse to fine over the solid analysis' levels (its Gaussian stack, k-coherence candidates and
// PCA-projected 5x5 neighborhoods, solid_analysis.h), tiles n / 2^k voxels at level k above the
// finest, from the coarsest level whose tiles are 8 voxels wide; each level starts from its parent's
// coordinates, and at the finest a tile's last voxel along an axis from the next cell's face, so
// that a face continues into both of its sides (a seam otherwise). The result is a coordinate triple
// per voxel, so colours and companion maps are the mean of the three exemplars' values
// (solidColors), as for lazy synthesis.
//
// Deviations, on purpose:
//   * 5x5 neighborhoods at every level, compared through the analysis' 8-dimensional projections,
//     searched PatchMatch-like (k-coherence candidates of the 3x3 neighbours, then random
//     positions at halving radii around the best; Barnes et al. 2009) instead of Kopf's ANN over
//     full 8x8 neighborhoods;
//   * the position histogram enters the search as an additive penalty scaled by the spread of the
//     level's descriptors;
//   * the result is a triple per voxel, the centres of its three neighborhoods' best matches, not
//     Kopf's voted colour: the voted colours guide the search only, after a histogram transfer
//     (§3.3 as a transfer, not as reweighting); the triples keep the exemplar's sharpness and its
//     companion maps;
//   * a storage element seen at several places of an arrangement (a face, shared by 32 tiles on
//     each side) takes the values of its best-matching occurrence, not their mean, which would
//     flatten faces into visible bands;
//   * the search and vote are Jacobi steps (all voxels from the previous iteration's values), so
//     the result is the same on any number of threads; all arithmetic is integer or IEEE float
//     in a fixed order (docs/design.md#the-determinism-contract).

#include "core/context.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <climits>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

namespace texfab::synthesis {

struct SolidTileOptions {
  /// Finest-level voxels per tile side (the lattice period): 8, 16, 32 or 64. The largest
  /// structure a tile set keeps is about a tile; the work grows with the cube of the side (32: about
  /// half a minute on 2 cores). 32 even for exemplars of 50 pixels: 16 would be 10x faster, with
  /// a worse fidelity and a stronger lattice (docs/measurements.md#solid-tiles).
  int tileSide = 32;
  /// Variants per face, V: 2 (64 tiles) or 3 (729 tiles: a face variant shared by a third of the
  /// cells instead of half, for 11x the storage and, with arrangements of 9^3 cells, 11x the
  /// work at the same tile side). Three lower the lattice on some exemplars, not all, and cost
  /// contrast on others (docs/measurements.md#solid-tiles).
  int faceVariants = 2;
  /// Copies of every tile in the periodic arrangements the optimization runs on, whose side is
  /// copies * V^2 cells: 1 (each tile once per iteration) or 2 (more neighbours met, 8x the work).
  int arrangementCopies = 1;
  /// Search-and-vote iterations per level above the finest, and at the finest. [1, 16]
  int iterations = 4;
  int finestIterations = 3;
  /// Weight of the position histogram (Chen & Wang 2010): a candidate whose exemplar position is
  /// used k times its share costs (k - 1) * this * the spread of the level's descriptors (their
  /// mean squared norm) more; 0 = Kopf's search. [0, 16]
  float histogramWeight = 1.0f;

  /// Throws texfab::Error naming the field when a value is out of range.
  void validate() const;
};

/// The storage of one tile set at one level (finest for a finished set).
struct SolidTileLayout {
  int side = 0;      ///< n, voxels per tile side: a power of two
  int shift = 0;     ///< log2(n)
  int variants = 2;  ///< V, variants per face (edges and corners have 2)
  size_t faces = 0, interiors = 0, elements = 0;  ///< first face element, first interior element, total

  explicit SolidTileLayout(int n = 0, int faceVariants = 2);

  /// The variants of a cell's faces, edges and corner: bits 0-9 the tile, sum over the faces i
  /// (2a: the start of axis a, 2a + 1: its end) of variant_i V^i; bit 10 + a the edge along axis a
  /// at the cell's origin, bit 13 its corner. `variant(kind, x, y, z)` is the variant of the face
  /// (kind 0..2: axis; 0..V-1), edge (3..5: axis; 0..1) or corner (6; 0..1) of lattice cell (x, y, z).
  template <class Variant> uint32_t cellCode(int64_t x, int64_t y, int64_t z, const Variant& variant) const;
  /// The storage element of local position (x, y, z) in [0, n)^3 of a cell with that code.
  size_t element(int x, int y, int z, uint32_t code) const;
  /// The storage element of voxel (x, y, z).
  template <class Variant> size_t element(int64_t x, int64_t y, int64_t z, const Variant& variant) const {
    return element(int(x & (side - 1)), int(y & (side - 1)), int(z & (side - 1)),
                   cellCode(x >> shift, y >> shift, z >> shift, variant));
  }
};

struct SolidTileSet {
  int width = 0, height = 0;   ///< exemplar size (coordinates lie inside)
  SolidTileLayout layout;
  std::vector<Triple> elements;  ///< layout.elements triples
  uint64_t key = 0;              ///< solidTilesKey of the analysis and options
  double seconds = 0;            ///< time of the optimization (not of reading it from a cache)
};

/// The optimization. Pure: depends only on the analysis and options, never on the context.
/// Reports "level k/n" stages with their iterations through ctx.
SolidTileSet buildSolidTiles(const SolidAnalysis& analysis, const SolidTileOptions& options, const Context& ctx = {});

/// Rough CPU seconds of buildSolidTiles (one core of the 2-core machine it was measured on).
double solidTilesCpuSeconds(const SolidTileOptions& options);

uint64_t solidTilesKey(const SolidAnalysis& analysis, const SolidTileOptions& options);

/// Through the on-disk cache `cacheDir/<key>.tiles` (analysis_cache.h).
SolidTileSet buildSolidTilesCached(const SolidAnalysis& analysis, const SolidTileOptions& options,
                                   const std::filesystem::path& cacheDir, const Context& ctx = {},
                                   bool* fromCache = nullptr);
void writeSolidTiles(const SolidTileSet& tiles, const std::filesystem::path& path);
std::optional<SolidTileSet> readSolidTiles(const std::filesystem::path& path, uint64_t expectedKey);

/// The analysis' tile set; throws texfab::Error when it has none (SolidMethod::Tiles needs it).
const SolidTileSet& requireTiles(const SolidAnalysis& analysis);

/// Reads voxels one at a time from the tile arrangement of `seed` (one tile set serves every seed),
/// remembering the last cell's variants: neighbouring voxels mostly share a cell. One per thread.
class SolidTileReader {
public:
  SolidTileReader(const SolidTileSet& tiles, uint32_t seed) : tiles_(tiles), seed_(seed) {}
  /// The triple of voxel (x, y, z), |coordinates| <= kMaxSolidPosition.
  Triple operator()(int64_t x, int64_t y, int64_t z);

private:
  const SolidTileSet& tiles_;
  uint32_t seed_;
  int64_t cell_[3] = {INT64_MIN, 0, 0};
  uint32_t bits_ = 0;
};

/// The triples of `voxels` (|coordinates| <= kMaxSolidPosition), in order (SolidTileReader).
void evaluateSolidTiles(const SolidTileSet& tiles, uint32_t seed, std::span<const Voxel> voxels, std::span<Triple> out,
                        const Context& ctx = {});
/// Every voxel of `box`, x fastest, then y, then z.
void evaluateSolidTilesBox(const SolidTileSet& tiles, uint32_t seed, const VoxelBox& box, std::span<Triple> out,
                           const Context& ctx = {});

// ---- implementation of the template ----

template <class Variant>
uint32_t SolidTileLayout::cellCode(int64_t x, int64_t y, int64_t z, const Variant& variant) const {
  const uint32_t v = uint32_t(variants);
  uint32_t tile = 0, weight = 1;
  const int64_t next[3][3] = {{x + 1, y, z}, {x, y + 1, z}, {x, y, z + 1}};
  for (int a = 0; a < 3; ++a) {
    tile += weight * uint32_t(variant(a, x, y, z));
    weight *= v;
    tile += weight * uint32_t(variant(a, next[a][0], next[a][1], next[a][2]));
    weight *= v;
  }
  uint32_t code = tile;
  for (int a = 0; a < 3; ++a) code |= uint32_t(variant(3 + a, x, y, z)) << (10 + a);
  return code | uint32_t(variant(6, x, y, z)) << 13;
}

} // namespace texfab::synthesis
