// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// GraphAnalysis's packed atlas as the graph kernels see it (exemplar_graph.h): tiles of m x m
// pixels, level k of node i at (k m, i m). A coordinate is packCoord(u, v) in 1/2^subpixelBits
// pixels (0 for the 2-D kernels, kSubpixelBits for the surface ones); moves wrap in the tile.

#include "synthesis/coord_map.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/exemplar_graph.h"

#include <algorithm>
#include <array>
#include <bit>
#include <climits>
#include <cstddef>
#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace texfab::synthesis::cpu {

/// A texel's cumulative transfer R (thesis §5.3): the RGB offset its colour is shown with, in
/// 1/kTransferOne.
using Transfer = std::array<int16_t, 3>;

/// R as the RGB offset a texel's colour is shown with, in colour values.
inline std::array<float, 3> colorOffset(const Transfer& r) {
  return {float(r[0]) / kTransferOne, float(r[1]) / kTransferOne, float(r[2]) / kTransferOne};
}

/// R composed with a candidate's offset b (three values), saturating.
inline Transfer compose(const Transfer& r, const int16_t* b) {
  Transfer out;
  for (int c = 0; c < 3; ++c) out[size_t(c)] = int16_t(std::clamp(int32_t(r[size_t(c)]) + b[c], -32767, 32767));
  return out;
}

/// The largest appearance shift kept: 8x an appearance vector's range, and small enough that a
/// distance between shifted neighbourhoods (32 terms of at most (127 + 3 * 1024)^2) fits an int32.
inline constexpr int kMaxAppearanceShift = 1024;

/// A texel's transfer with the shift A R it gives appearance vectors (GraphAtlas::appearanceShift),
/// computed when R changes rather than at every comparison.
struct TexelTransfer {
  Transfer r{};
  std::array<int16_t, kAppearanceDims> shift{};
};

/// A level of graph synthesis: a coordinate per texel and, with inconsistency correction, its
/// transfer (null without).
struct GraphLevelState {
  uint32_t* coords;
  TexelTransfer* transfers;
};

/// R interpolated from four texels' transfers with weights 9, 3, 3, 1 / 16 (the nearest first):
/// thesis §5.3's bilinear upsampling of a child from its four nearest parents. Integer, rounding
/// half up.
inline Transfer upsampledTransfer(const Transfer& nearest, const Transfer& alongX, const Transfer& alongY,
                                  const Transfer& diagonal) {
  Transfer r;
  for (size_t c = 0; c < 3; ++c)
    r[c] = int16_t((9 * nearest[c] + 3 * (alongX[c] + alongY[c]) + diagonal[c] + 8) >> 4);
  return r;
}

struct GraphAtlas {
  int bits = 0;     ///< subpixel bits of a coordinate
  int shift = 0;    ///< log2 of a tile's side in coordinate units
  int finest = 0, levels = 0, width = 0, k = 0;
  const int8_t* appearance = nullptr;
  const int8_t* neighborhood = nullptr;
  const uint32_t* candidates = nullptr;
  const uint8_t* selfAdmissible = nullptr;
  const uint32_t* moves = nullptr;
  const int16_t* transfers = nullptr;  ///< k * 3 per texel; null without inconsistency correction
  const int32_t* transferAppearance = nullptr;

  explicit GraphAtlas(const GraphAnalysis& a, int subpixelBits = 0)
      : bits(subpixelBits), shift(std::countr_zero(unsigned(a.side)) + subpixelBits), finest(a.finestLevel()),
        levels(a.levels), width(a.atlasWidth()), k(a.k), appearance(a.appearance.data()),
        neighborhood(a.neighborhood.data()), candidates(a.candidates.data()), selfAdmissible(a.selfAdmissible.data()),
        moves(a.moves.data()), transfers(a.transfers.empty() ? nullptr : a.transfers.data()),
        transferAppearance(a.transferAppearance.data()) {}

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
  /// The offsets b of the candidates of texel c (k * 3 values).
  const int16_t* transfersOf(uint32_t c) const { return transfers + texel(c) * size_t(k) * 3; }
  /// A r: how offset r moves an appearance vector, in whole appearance units (rounded half up,
  /// clamped to +-kMaxAppearanceShift).
  void appearanceShift(const Transfer& r, int16_t* out) const {
    constexpr int64_t half = int64_t(1) << (kTransferAppearanceBits - 1);
    for (int d = 0; d < kAppearanceDims; ++d) {
      const int64_t exact = int64_t(transferAppearance[d * 3]) * r[0] + int64_t(transferAppearance[d * 3 + 1]) * r[1] +
                            int64_t(transferAppearance[d * 3 + 2]) * r[2];
      out[d] = int16_t(std::clamp<int64_t>((exact + half) >> kTransferAppearanceBits, -kMaxAppearanceShift,
                                           kMaxAppearanceShift));
    }
  }
  TexelTransfer texelTransfer(const Transfer& r) const {
    TexelTransfer t{r, {}};
    appearanceShift(r, t.shift.data());
    return t;
  }

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

/// GraphChoice with thesis §5.3's inconsistency correction: every option is a coordinate with the
/// transfer R it would be shown with, and neighbourhoods compare as seen, each appearance vector
/// moved by A R (GraphAtlas::appearanceShift). A candidate from neighbour q's list is shown with
/// R_q composed with its offset b (the thesis composes b onto R_p, whose frame b was not fitted
/// in where R_q != R_p): frame(R_q) before offering q's candidates. The target is compared in
/// that frame, target - A R_q, and a candidate's neighbourhood moved by A b. `current` competes
/// with R_p where it may stay; ties as GraphChoice's.
class GraphTransferChoice {
 public:
  /// `target`: the diagonal neighbours' appearance as seen (kNeighborhoodDims values, rounded).
  GraphTransferChoice(const GraphAtlas& a, const int16_t* target, uint32_t current, const TexelTransfer& r,
                      bool outputLevel)
      : a_(a), target_(target), current_(current), best_(current), transfer_(r.r) {
    frame(r);
    static constexpr int16_t none[3] = {};
    distance_ = outputLevel || a.selfAdmissible[a.texel(current)] ? distanceTo(current, none) : INT32_MAX;
  }

  /// The frame of the candidates offered next: the transfer of the neighbour whose list they are in.
  void frame(const TexelTransfer& r) {
    frame_ = r.r;
    for (int i = 0; i < kNeighborhoodSamples; ++i)
      for (int d = 0; d < kAppearanceDims; ++d)
        seen_[i * kAppearanceDims + d] = int16_t(target_[i * kAppearanceDims + d] - r.shift[size_t(d)]);
  }
  /// Candidate c with offset b (three values) in the current frame.
  void offer(uint32_t c, const int16_t* b) {
    if (!a_.mayTake(current_, c)) return;
    const int32_t d = distanceTo(c, b);
    if (d < distance_ || (d == distance_ && best_ != current_ && c < best_))
      distance_ = d, best_ = c, transfer_ = compose(frame_, b);
  }
  uint32_t best() const { return best_; }
  const Transfer& transfer() const { return transfer_; }

 private:
  // Exact in 16-bit lanes: |seen_| <= 127 + 2 * kMaxAppearanceShift, and the candidate's shift and
  // vector add at most kMaxAppearanceShift + 128, so each difference fits an int16 and the sum of
  // 32 squares an int32 (kMaxAppearanceShift's bound); SSE2's multiply-add where there is one.
  int32_t distanceTo(uint32_t c, const int16_t* b) const {
    alignas(16) int16_t shift[kAppearanceDims] = {};  // the candidate moved by A b: the target moved back
    if (b[0] | b[1] | b[2]) a_.appearanceShift({b[0], b[1], b[2]}, shift);
    const int8_t* n = a_.neighborhood + a_.texel(c) * kNeighborhoodDims;
    static_assert(kAppearanceDims == 8 && kNeighborhoodSamples == 4);
#if defined(__SSE2__)
    const __m128i s = _mm_load_si128(reinterpret_cast<const __m128i*>(shift));
    const __m128i n0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(n));
    const __m128i n1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(n + 16));
    const __m128i widened[4] = {  // int8 to int16: each byte doubled, then shifted down with its sign
        _mm_srai_epi16(_mm_unpacklo_epi8(n0, n0), 8), _mm_srai_epi16(_mm_unpackhi_epi8(n0, n0), 8),
        _mm_srai_epi16(_mm_unpacklo_epi8(n1, n1), 8), _mm_srai_epi16(_mm_unpackhi_epi8(n1, n1), 8)};
    __m128i sum = _mm_setzero_si128();
    for (int i = 0; i < kNeighborhoodSamples; ++i) {
      const __m128i t = _mm_load_si128(reinterpret_cast<const __m128i*>(seen_ + i * kAppearanceDims));
      const __m128i e = _mm_sub_epi16(_mm_sub_epi16(t, s), widened[i]);
      sum = _mm_add_epi32(sum, _mm_madd_epi16(e, e));
    }
    sum = _mm_add_epi32(sum, _mm_shuffle_epi32(sum, _MM_SHUFFLE(1, 0, 3, 2)));
    sum = _mm_add_epi32(sum, _mm_shuffle_epi32(sum, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtsi128_si32(sum);
#else
    int32_t sum = 0;
    for (int j = 0; j < kNeighborhoodDims; ++j) {
      const int32_t e = int32_t(seen_[j]) - shift[j % kAppearanceDims] - n[j];
      sum += e * e;
    }
    return sum;
#endif
  }
  const GraphAtlas& a_;
  const int16_t* target_;
  uint32_t current_, best_;
  Transfer transfer_, frame_{};
  alignas(16) int16_t seen_[kNeighborhoodDims];
  int32_t distance_;
};

} // namespace texfab::synthesis::cpu
