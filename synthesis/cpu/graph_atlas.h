// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// GraphAnalysis's packed atlas as the graph kernels see it (exemplar_graph.h): tiles of m x m
// pixels, level k of node i at (k m, i m). A coordinate is packCoord(u, v) in 1/2^subpixelBits
// pixels (0 for the 2-D kernels, kSubpixelBits for the surface ones); moves wrap in the tile.

#include "synthesis/coord_map.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/exemplar_graph.h"

#include <bit>
#include <climits>
#include <cstddef>
#include <cstdint>

namespace texfab::synthesis::cpu {

struct GraphAtlas {
  int bits = 0;     ///< subpixel bits of a coordinate
  int shift = 0;    ///< log2 of a tile's side in coordinate units
  int finest = 0, levels = 0, width = 0, k = 0;
  const int8_t* appearance = nullptr;
  const int8_t* neighborhood = nullptr;
  const uint32_t* candidates = nullptr;
  const uint8_t* selfAdmissible = nullptr;
  const uint32_t* moves = nullptr;

  explicit GraphAtlas(const GraphAnalysis& a, int subpixelBits = 0)
      : bits(subpixelBits), shift(std::countr_zero(unsigned(a.side)) + subpixelBits), finest(a.finestLevel()),
        levels(a.levels), width(a.atlasWidth()), k(a.k), appearance(a.appearance.data()),
        neighborhood(a.neighborhood.data()), candidates(a.candidates.data()), selfAdmissible(a.selfAdmissible.data()),
        moves(a.moves.data()) {}

  uint32_t mask() const { return (1u << shift) - 1; }
  int level(uint32_t c) const { return int(coordU(c) >> shift); }
  int node(uint32_t c) const { return int(coordV(c) >> shift); }
  int tile(uint32_t c) const { return node(c) * levels + level(c); }
  /// Whether a texel pointing at `current` may take candidate `c` (GraphAnalysis::moves).
  bool mayTake(uint32_t current, uint32_t c) const { return (moves[texel(current)] >> node(c)) & 1u; }
  /// h_k of c's level, in pixels of its exemplar.
  int spacing(uint32_t c) const { return 1 << (finest - level(c)); }
  /// The atlas pixel nearest c, wrapped in its tile, as an index into the per-texel tables.
  size_t texel(uint32_t c) const { return size_t(pixelOf(coordV(c))) * size_t(width) + pixelOf(coordU(c)); }
  /// c moved by (dx, dy) coordinate units, wrapped in its tile.
  uint32_t move(uint32_t c, int64_t dx, int64_t dy) const {
    const uint32_t u = coordU(c), v = coordV(c);
    return packCoord((u & ~mask()) | ((u + uint32_t(dx)) & mask()), (v & ~mask()) | ((v + uint32_t(dy)) & mask()));
  }
  /// The coordinate of atlas pixel `pixel` (a candidate), in coordinate units.
  uint32_t fromPixel(uint32_t pixel) const { return packCoord(coordU(pixel) << bits, coordV(pixel) << bits); }

 private:
  uint32_t pixelOf(uint32_t x) const {
    const uint32_t half = bits ? 1u << (bits - 1) : 0u, pixelMask = mask() >> bits;
    return ((x & ~mask()) >> bits) | ((((x & mask()) + half) >> bits) & pixelMask);
  }
};

/// A graph texel's correction choice, by the rules of cpu::correctKernel: `current` competes
/// where it may stay (or at the output level); a candidate in a node `current` may move to
/// replaces the best when nearer the target neighbourhood, on a tie when it is the smaller
/// coordinate and the best is not `current`.
class GraphChoice {
 public:
  GraphChoice(const GraphAtlas& a, const int8_t* target, uint32_t current, bool outputLevel)
      : a_(a), target_(target), current_(current), best_(current),
        distance_(outputLevel || a.selfAdmissible[a.texel(current)] ? distanceTo(current) : INT32_MAX) {}

  void offer(uint32_t c) {
    if (c == best_ || !a_.mayTake(current_, c)) return;
    const int32_t d = distanceTo(c);
    if (d < distance_ || (d == distance_ && best_ != current_ && c < best_)) distance_ = d, best_ = c;
  }
  uint32_t best() const { return best_; }

 private:
  int32_t distanceTo(uint32_t c) const {
    return neighborhoodDistance(target_, a_.neighborhood + a_.texel(c) * kNeighborhoodDims);
  }
  const GraphAtlas& a_;
  const int8_t* target_;
  uint32_t current_, best_;
  int32_t distance_;
};

} // namespace texfab::synthesis::cpu
