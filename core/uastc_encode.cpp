// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/uastc_encode.h"

#include "core/error.h"
#include "core/parallel.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <string>

namespace texfab::uastc {
namespace {

// ---- Bits (UASTC spec, "Block Encoding": fields are packed from bit 0 of byte 0 upward) ----

class BitWriter {
public:
  void put(uint32_t value, int bits) {
    assert(pos_ + bits <= 128 && (bits == 32 || value < (1u << bits)));
    for (int i = 0; i < bits; ++i, ++pos_)
      if ((value >> i) & 1u) block_[size_t(pos_ >> 3)] |= uint8_t(1u << (pos_ & 7));
  }
  const Block& block() const { return block_; }

private:
  Block block_{};
  int pos_ = 0;
};

class BitReader {
public:
  explicit BitReader(const Block& block) : block_(block) {}
  uint32_t get(int bits) {
    uint32_t value = 0;
    for (int i = 0; i < bits; ++i, ++pos_) value |= uint32_t((block_[size_t(pos_ >> 3)] >> (pos_ & 7)) & 1u) << i;
    return value;
  }

private:
  const Block& block_;
  int pos_ = 0;
};

// ---- Modes (UASTC spec, "Mode Table") ----

// The mode prefix codes, bit 0 first, and their lengths; index 19 is reserved.
constexpr std::array<std::pair<uint8_t, uint8_t>, 20> kModeCodes = {{{0x01, 4}, {0x35, 6}, {0x1D, 5}, {0x03, 5}, {0x13, 5},
                                                                     {0x0B, 5}, {0x1B, 5}, {0x07, 5}, {0x17, 5}, {0x0F, 5},
                                                                     {0x02, 3}, {0x00, 2}, {0x06, 3}, {0x1F, 5}, {0x0D, 5},
                                                                     {0x05, 7}, {0x15, 6}, {0x25, 6}, {0x09, 4}, {0x45, 7}}};
constexpr int kSolidMode = 8;

// ASTC BISE ranges used here (DFS 23.11): 11 = 0..31 (5 bits), 18 = 0..159 (5 bits + a quint),
// 19 = 0..191 (6 bits + a trit), 20 = 0..255 (8 bits).
struct Mode {
  int index;
  int weightBits;     ///< weight levels = 1 << weightBits
  int endpointRange;  ///< BISE range of the six endpoint values
  int planes;         ///< 2: the channel `ccs` has its own weights
};
constexpr std::array<Mode, 4> kModes = {{{0, 4, 19, 1}, {5, 3, 20, 1}, {18, 5, 11, 1}, {6, 2, 18, 2}}};

int endpointLevels(int range) { return range == 18 ? 160 : range == 19 ? 192 : range == 20 ? 256 : 32; }

// Unquantized value (0..255) of a BISE endpoint value; trit and quint values are stored as
// bits | digit << bits (UASTC keeps the digit and the bits of a value together).
int unquantEndpoint(int range, int v) {
  if (range == 20) return v;
  if (range == 11) return (v << 3) | (v >> 2);  // bit replication
  // A = bit a replicated, B from the bits, C, D = the trit or quint (DFS 23.11, table of colour
  // unquantization parameters): 0..191 B = "fedcb000f", C = 5; 0..159 B = "edcb0000e", C = 6.
  const bool trit = range == 19;
  const int bits = trit ? v & 63 : v & 31, digit = trit ? v >> 6 : v >> 5;
  const auto bit = [bits](int k) { return (bits >> k) & 1; };
  const int a = (bits & 1) ? 0x1FF : 0;
  const int b = trit ? (bit(5) << 8) | (bit(4) << 7) | (bit(3) << 6) | (bit(2) << 5) | (bit(1) << 4) | bit(5)
                     : (bit(4) << 8) | (bit(3) << 7) | (bit(2) << 6) | (bit(1) << 5) | bit(4);
  const int t = (digit * (trit ? 5 : 6) + b) ^ a;
  return (a & 0x80) | (t >> 2);
}

// Weight 0..64 of a quantized weight (DFS 23.12: bit replication to 6 bits, +1 above 32).
int unquantWeight(int weightBits, int v) {
  const int w = weightBits == 2 ? (v << 4) | (v << 2) | v
                : weightBits == 3 ? (v << 3) | v
                : weightBits == 4 ? (v << 2) | (v >> 2)
                                  : (v << 1) | (v >> 4);
  return w > 32 ? w + 1 : w;
}

// ASTC LDR interpolation as UASTC decodes it (UNORM8 endpoints widened to 16 bits).
int interpolate(int lo, int hi, int w) {
  return ((((lo << 8) | lo) * (64 - w) + ((hi << 8) | hi) * w + 32) >> 6) >> 8;
}

// Per range: unquantized values, the values in order of their unquantized value (rank), and
// the nearest value to each 8-bit target.
struct Quantizer {
  int levels = 0;
  std::array<uint8_t, 256> unquant{}, byRank{}, rank{}, nearest{};
};

Quantizer makeQuantizer(int range) {
  Quantizer q;
  q.levels = endpointLevels(range);
  for (int v = 0; v < q.levels; ++v) {
    q.unquant[size_t(v)] = uint8_t(unquantEndpoint(range, v));
    q.byRank[size_t(v)] = uint8_t(v);
  }
  std::stable_sort(q.byRank.begin(), q.byRank.begin() + q.levels,
                   [&](uint8_t x, uint8_t y) { return q.unquant[x] < q.unquant[y]; });
  for (int r = 0; r < q.levels; ++r) q.rank[q.byRank[size_t(r)]] = uint8_t(r);
  for (int x = 0, r = 0; x < 256; ++x) {
    while (r + 1 < q.levels && std::abs(q.unquant[q.byRank[size_t(r + 1)]] - x) < std::abs(q.unquant[q.byRank[size_t(r)]] - x)) ++r;
    q.nearest[size_t(x)] = q.byRank[size_t(r)];
  }
  return q;
}

const Quantizer& quantizer(int range) {
  static const Quantizer q11 = makeQuantizer(11), q18 = makeQuantizer(18), q19 = makeQuantizer(19), q20 = makeQuantizer(20);
  return range == 11 ? q11 : range == 18 ? q18 : range == 19 ? q19 : q20;
}

// ---- Fitting ----

using Rgb = std::array<std::array<int, 3>, 16>;

int64_t divRound(int64_t n, int64_t d) { return n >= 0 ? (n + d / 2) / d : -((-n + d / 2) / d); }

struct Fit {
  int ccs = -1;             ///< dual plane: the channel on plane 1
  std::array<int, 6> ep{};  ///< BISE values r0 r1 g0 g1 b0 b1 (ASTC CEM 8 order)
  std::array<std::array<uint8_t, 16>, 2> w{};  ///< per plane, per texel
  int64_t err = std::numeric_limits<int64_t>::max();
};

size_t planeOf(const Fit& f, size_t channel) { return int(channel) == f.ccs ? 1 : 0; }

// Picks each texel's nearest weight level (per plane) for the fit's endpoints; sets w and err.
void chooseWeights(const Mode& m, const Rgb& px, Fit& f) {
  const Quantizer& q = quantizer(m.endpointRange);
  const int levels = 1 << m.weightBits;
  std::array<std::array<int, 3>, 32> palette{};
  for (int l = 0; l < levels; ++l)
    for (int c = 0; c < 3; ++c)
      palette[size_t(l)][size_t(c)] = interpolate(q.unquant[size_t(f.ep[size_t(2 * c)])], q.unquant[size_t(f.ep[size_t(2 * c + 1)])],
                                                  unquantWeight(m.weightBits, l));
  f.err = 0;
  for (size_t plane = 0; plane < size_t(m.planes); ++plane)
    for (size_t i = 0; i < 16; ++i) {
      int best = std::numeric_limits<int>::max(), bestLevel = 0;
      for (int l = 0; l < levels; ++l) {
        int e = 0;
        for (size_t c = 0; c < 3; ++c) {
          const int d = palette[size_t(l)][c] - px[i][c];
          e += planeOf(f, c) == plane ? d * d : 0;
        }
        if (e < best) best = e, bestLevel = l;
      }
      f.w[plane][i] = uint8_t(bestLevel);
      f.err += best;
    }
}

Fit quantizeFit(const Mode& m, const Rgb& px, const std::array<int, 6>& endpoints8, int ccs) {
  Fit f;
  f.ccs = ccs;
  const Quantizer& q = quantizer(m.endpointRange);
  for (size_t k = 0; k < 6; ++k) f.ep[k] = q.nearest[size_t(std::clamp(endpoints8[k], 0, 255))];
  chooseWeights(m, px, f);
  return f;
}

// Least-squares endpoints (8-bit, r0 r1 g0 g1 b0 b1) for the fit's weights; a plane whose
// texels share one weight keeps its quantized endpoints.
void leastSquares(const Mode& m, const Rgb& px, const Fit& f, std::array<int, 6>& endpoints8) {
  const Quantizer& q = quantizer(m.endpointRange);
  for (size_t c = 0; c < 3; ++c) {
    const size_t plane = planeOf(f, c);
    int64_t a = 0, b = 0, d = 0, r0 = 0, r1 = 0;
    for (size_t i = 0; i < 16; ++i) {
      const int64_t w = unquantWeight(m.weightBits, f.w[plane][i]), u = 64 - w;
      a += u * u, b += u * w, d += w * w;
      r0 += u * px[i][c] * 64, r1 += w * px[i][c] * 64;
    }
    const int64_t det = a * d - b * b;
    for (size_t e = 0; e < 2; ++e) endpoints8[2 * c + e] = q.unquant[size_t(f.ep[2 * c + e])];
    if (det <= 0) continue;
    endpoints8[2 * c] = int(std::clamp<int64_t>(divRound(d * r0 - b * r1, det), 0, 255));
    endpoints8[2 * c + 1] = int(std::clamp<int64_t>(divRound(a * r1 - b * r0, det), 0, 255));
  }
}

// Endpoints at the extremes of the texels' projections on their principal axis (integer power
// iteration on the covariance matrix); with a plane-1 channel `ccs`, the axis of the other two
// and that channel's own extremes.
std::array<int, 6> principalEndpoints(Rgb px, int ccs) {
  if (ccs >= 0) {
    int lo = 255, hi = 0;
    for (auto& p : px) lo = std::min(lo, p[size_t(ccs)]), hi = std::max(hi, p[size_t(ccs)]), p[size_t(ccs)] = 0;
    std::array<int, 6> endpoints8 = principalEndpoints(px, -1);
    endpoints8[size_t(2 * ccs)] = lo, endpoints8[size_t(2 * ccs + 1)] = hi;
    return endpoints8;
  }
  std::array<int64_t, 3> sum{};
  for (const auto& p : px)
    for (size_t c = 0; c < 3; ++c) sum[c] += p[c];
  std::array<std::array<int64_t, 3>, 3> cov{};  // 256 x covariance
  for (size_t j = 0; j < 3; ++j)
    for (size_t k = 0; k < 3; ++k) {
      int64_t s = 0;
      for (const auto& p : px) s += int64_t(p[j]) * p[k];
      cov[j][k] = 16 * s - sum[j] * sum[k];
    }
  size_t start = 0;
  for (size_t c = 1; c < 3; ++c)
    if (cov[c][c] > cov[start][start]) start = c;
  std::array<int64_t, 3> axis = {cov[0][start], cov[1][start], cov[2][start]};
  for (int iteration = 0; iteration < 8; ++iteration) {
    const int64_t m = std::max({std::abs(axis[0]), std::abs(axis[1]), std::abs(axis[2])});
    if (m == 0) break;
    for (auto& v : axis) v = v * 65536 / m;  // |v| <= 2^16
    std::array<int64_t, 3> next{};
    for (size_t j = 0; j < 3; ++j)
      for (size_t k = 0; k < 3; ++k) next[j] += cov[j][k] * axis[k];
    if (iteration < 7) axis = next;
  }
  const int64_t norm2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
  std::array<int, 6> endpoints8{};
  if (norm2 == 0) {
    for (size_t c = 0; c < 3; ++c) endpoints8[2 * c] = endpoints8[2 * c + 1] = int(divRound(sum[c], 16));
    return endpoints8;
  }
  int64_t tMin = std::numeric_limits<int64_t>::max(), tMax = std::numeric_limits<int64_t>::min();
  for (const auto& p : px) {
    int64_t t = 0;
    for (size_t c = 0; c < 3; ++c) t += (16 * int64_t(p[c]) - sum[c]) * axis[c];
    tMin = std::min(tMin, t), tMax = std::max(tMax, t);
  }
  for (size_t c = 0; c < 3; ++c) {
    endpoints8[2 * c] = int(std::clamp<int64_t>(divRound(sum[c] * norm2 + axis[c] * tMin, 16 * norm2), 0, 255));
    endpoints8[2 * c + 1] = int(std::clamp<int64_t>(divRound(sum[c] * norm2 + axis[c] * tMax, 16 * norm2), 0, 255));
  }
  return endpoints8;
}

// Principal-axis start, two rounds of least squares, then ±1 steps on each endpoint value.
Fit fitMode(const Mode& m, const Rgb& px, int ccs) {
  Fit best = quantizeFit(m, px, principalEndpoints(px, ccs), ccs);
  for (int round = 0; round < 2 && best.err > 0; ++round) {
    std::array<int, 6> endpoints8{};
    leastSquares(m, px, best, endpoints8);
    Fit f = quantizeFit(m, px, endpoints8, ccs);
    if (f.err >= best.err) break;
    best = f;
  }
  const Quantizer& q = quantizer(m.endpointRange);
  for (int pass = 0; pass < 2 && best.err > 0; ++pass) {
    bool improved = false;
    for (size_t k = 0; k < 6; ++k)
      for (int step : {-1, 1}) {
        const int r = q.rank[size_t(best.ep[k])] + step;
        if (r < 0 || r >= q.levels) continue;
        Fit f = best;
        f.ep[k] = q.byRank[size_t(r)];
        chooseWeights(m, px, f);
        if (f.err < best.err) best = f, improved = true;
      }
    if (!improved) break;
  }
  return best;
}

// ---- ETC1 hints (UASTC spec, "Hint bits"; ETC1 per the Khronos Data Format Specification,
// section 21.1) ----

constexpr std::array<std::array<int, 2>, 8> kEtc1Modifiers = {{{2, 8}, {5, 17}, {9, 29}, {13, 42}, {18, 60}, {24, 80}, {33, 106}, {47, 183}}};
constexpr int kNeutralBias = 13;  // ETC1 bias whose per-channel deltas are all 0

struct Etc1Hints {
  int flip = 0, diff = 1, inten0 = 0, inten1 = 0;
};

bool inSubblock(int flip, int subblock, int i) { return ((flip ? i / 4 : i % 4) >= 2) == (subblock == 1); }

// Squared error of a subblock drawn from `base` with one intensity table (best modifier per texel).
int64_t etc1SubblockError(const Texels& t, int flip, int subblock, const std::array<int, 3>& base, int table) {
  int64_t err = 0;
  for (int i = 0; i < 16; ++i) {
    if (!inSubblock(flip, subblock, i)) continue;
    int best = std::numeric_limits<int>::max();
    for (int s = 0; s < 4; ++s) {
      const int mod = (s & 1 ? kEtc1Modifiers[size_t(table)][1] : kEtc1Modifiers[size_t(table)][0]) * (s & 2 ? -1 : 1);
      int e = 0;
      for (size_t c = 0; c < 3; ++c) {
        const int d = std::clamp(base[c] + mod, 0, 255) - t[size_t(4 * i) + c];
        e += d * d;
      }
      best = std::min(best, e);
    }
    err += best;
  }
  return err;
}

// The transcoder builds ETC1 from the decoded block: subblock averages at 5 bits (diff) or 4
// bits, the bias, then selectors; the hints choose flip, diff and the two intensity tables.
Etc1Hints etc1Hints(const Texels& t) {
  Etc1Hints best;
  int64_t bestErr = std::numeric_limits<int64_t>::max();
  for (int diff = 1; diff >= 0; --diff)
    for (int flip = 0; flip < 2; ++flip) {
      const int limit = diff ? 31 : 15;
      std::array<std::array<int, 3>, 2> color{};
      for (int sb = 0; sb < 2; ++sb)
        for (size_t c = 0; c < 3; ++c) {
          int sum = 0;
          for (int i = 0; i < 16; ++i)
            if (inSubblock(flip, sb, i)) sum += t[size_t(4 * i) + c];
          int v = (sum * limit + 1020) / (8 * 255);
          v = v == 0 ? 1 : v == limit ? limit - 1 : v;  // the neutral bias moves the extremes inward
          color[size_t(sb)][c] = v;
        }
      if (diff)
        for (size_t c = 0; c < 3; ++c) color[1][c] = color[0][c] + std::clamp(color[1][c] - color[0][c], -4, 3);
      Etc1Hints h{flip, diff, 0, 0};
      int64_t err = 0;
      for (int sb = 0; sb < 2; ++sb) {
        std::array<int, 3> base{};
        for (size_t c = 0; c < 3; ++c) {
          const int v = color[size_t(sb)][c];
          base[c] = diff ? (v << 3) | (v >> 2) : (v << 4) | v;
        }
        int64_t sbBest = std::numeric_limits<int64_t>::max();
        for (int table = 0; table < 8; ++table)
          if (const int64_t e = etc1SubblockError(t, flip, sb, base, table); e < sbBest) {
            sbBest = e;
            (sb ? h.inten1 : h.inten0) = table;
          }
        err += sbBest;
      }
      if (err < bestErr) bestErr = err, best = h;
    }
  return best;
}

struct Etc1Solid {
  int inten = 0, selector = 0;
  std::array<int, 3> color5{};
};

// Solid blocks: ETC1 colour (5 bits, diff mode), intensity table and the one selector for all
// texels (selector 0..3 = modifier -b, -a, +a, +b).
Etc1Solid etc1Solid(const std::array<int, 3>& rgb) {
  Etc1Solid best;
  int bestErr = std::numeric_limits<int>::max();
  for (int table = 0; table < 8; ++table)
    for (int sel = 0; sel < 4; ++sel) {
      const int mod = kEtc1Modifiers[size_t(table)][sel == 0 || sel == 3 ? 1 : 0] * (sel < 2 ? -1 : 1);
      Etc1Solid s{table, sel, {}};
      int err = 0;
      for (size_t c = 0; c < 3; ++c) {
        int cBest = std::numeric_limits<int>::max();
        for (int v = 0; v < 32; ++v) {
          const int d = std::abs(std::clamp(((v << 3) | (v >> 2)) + mod, 0, 255) - rgb[c]);
          if (d < cBest) cBest = d, s.color5[c] = v;
        }
        err += cBest * cBest;
      }
      if (err < bestErr) bestErr = err, best = s;
    }
  return best;
}

// ---- Packing ----

void putModeCode(BitWriter& out, int mode) { out.put(kModeCodes[size_t(mode)].first, kModeCodes[size_t(mode)].second); }

Block packSolid(const std::array<int, 3>& rgb) {
  BitWriter out;
  putModeCode(out, kSolidMode);
  for (size_t c = 0; c < 3; ++c) out.put(uint32_t(rgb[c]), 8);
  out.put(255, 8);
  const Etc1Solid e = etc1Solid(rgb);
  out.put(1, 1);  // ETC1 diff
  out.put(uint32_t(e.inten), 3);
  out.put(uint32_t(e.selector), 2);
  for (size_t c = 0; c < 3; ++c) out.put(uint32_t(e.color5[c]), 5);
  return out.block();
}

Block packFit(const Mode& m, Fit f, const Etc1Hints& h) {
  const int levels = 1 << m.weightBits;
  for (size_t plane = 0; plane < size_t(m.planes); ++plane)
    if (f.w[plane][0] >= levels / 2) {  // each plane's first weight is stored without its top bit
      for (size_t c = 0; c < 3; ++c)
        if (planeOf(f, c) == plane) std::swap(f.ep[2 * c], f.ep[2 * c + 1]);
      for (auto& w : f.w[plane]) w = uint8_t(levels - 1 - w);
    }
  BitWriter out;
  putModeCode(out, m.index);
  out.put(0, 1), out.put(0, 1);  // BC1 hints 0 and 1: off
  out.put(uint32_t(h.flip), 1), out.put(uint32_t(h.diff), 1);
  out.put(uint32_t(h.inten0), 3), out.put(uint32_t(h.inten1), 3);
  out.put(kNeutralBias, 5);
  if (m.planes == 2) out.put(uint32_t(f.ccs), 2);
  if (m.endpointRange == 19) {
    // Trits first: five per 8-bit group (base 3, first value least significant), the sixth
    // alone in 2 bits; then the low 6 bits of each value.
    uint32_t group = 0;
    for (int k = 4; k >= 0; --k) group = group * 3 + uint32_t(f.ep[size_t(k)] >> 6);
    out.put(group, 8);
    out.put(uint32_t(f.ep[5] >> 6), 2);
    for (int v : f.ep) out.put(uint32_t(v & 63), 6);
  } else if (m.endpointRange == 18) {
    // Quints first: three per 7-bit group (base 5, first value least significant); then the
    // low 5 bits of each value.
    for (size_t g = 0; g < 6; g += 3)
      out.put(uint32_t((f.ep[g + 2] >> 5) * 25 + (f.ep[g + 1] >> 5) * 5 + (f.ep[g] >> 5)), 7);
    for (int v : f.ep) out.put(uint32_t(v & 31), 5);
  } else {
    const int bits = m.endpointRange == 20 ? 8 : 5;
    for (int v : f.ep) out.put(uint32_t(v), bits);
  }
  // Weights texel by texel (plane 0 then plane 1 for dual plane); each plane's first weight
  // (the anchor) has one bit less.
  for (size_t i = 0; i < 16; ++i)
    for (size_t plane = 0; plane < size_t(m.planes); ++plane) out.put(f.w[plane][i], i == 0 ? m.weightBits - 1 : m.weightBits);
  return out.block();
}

uint8_t toUnorm8(float v) { return uint8_t(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); }

} // namespace

int blockMode(const Block& block) {
  for (int mode = 0; mode < 19; ++mode) {
    const auto [code, bits] = kModeCodes[size_t(mode)];
    if ((block[0] & ((1u << bits) - 1u)) == code) return mode;
  }
  return -1;
}

bool decodeBlock(const Block& block, Texels& texels) {
  const int mode = blockMode(block);
  BitReader in(block);
  in.get(mode < 0 ? 0 : kModeCodes[size_t(mode)].second);
  if (mode == kSolidMode) {
    std::array<uint8_t, 4> rgba{};
    for (auto& v : rgba) v = uint8_t(in.get(8));
    for (size_t i = 0; i < 16; ++i) std::copy(rgba.begin(), rgba.end(), texels.begin() + std::ptrdiff_t(4 * i));
    return true;
  }
  const auto m = std::find_if(kModes.begin(), kModes.end(), [&](const Mode& x) { return x.index == mode; });
  if (m == kModes.end()) return false;
  in.get(15);  // hints
  const int ccs = m->planes == 2 ? int(in.get(2)) : -1;
  std::array<int, 6> ep{};
  if (m->endpointRange == 18) {
    for (size_t g = 0; g < 6; g += 3) {
      uint32_t group = in.get(7);
      for (size_t k = g; k < g + 3; ++k, group /= 5) ep[k] = int((group % 5) << 5);
    }
    for (auto& v : ep) v |= int(in.get(5));
  } else if (m->endpointRange == 19) {
    uint32_t group = in.get(8);
    const uint32_t last = in.get(2);
    for (size_t k = 0; k < 6; ++k) {
      const uint32_t trit = k < 5 ? group % 3 : last;
      group /= 3;
      ep[k] = int(trit << 6);
    }
    for (auto& v : ep) v |= int(in.get(6));
  } else {
    for (auto& v : ep) v = int(in.get(m->endpointRange == 20 ? 8 : 5));
  }
  for (size_t i = 0; i < 16; ++i) {
    std::array<int, 2> w{};
    for (int plane = 0; plane < m->planes; ++plane)
      w[size_t(plane)] = unquantWeight(m->weightBits, int(in.get(i == 0 ? m->weightBits - 1 : m->weightBits)));
    for (size_t c = 0; c < 3; ++c)
      texels[4 * i + c] = uint8_t(interpolate(unquantEndpoint(m->endpointRange, ep[2 * c]), unquantEndpoint(m->endpointRange, ep[2 * c + 1]),
                                              w[int(c) == ccs ? 1 : 0]));
    texels[4 * i + 3] = 255;
  }
  return true;
}

Block encodeBlock(const Texels& texels) {
  Rgb px{};
  std::array<int, 3> sum{};
  bool solid = true;
  for (size_t i = 0; i < 16; ++i)
    for (size_t c = 0; c < 3; ++c) {
      px[i][c] = texels[4 * i + c];
      sum[c] += px[i][c];
      solid = solid && px[i][c] == px[0][c];
    }
  if (solid) return packSolid(px[0]);

  std::array<int, 3> mean{};
  int64_t solidErr = 0;
  for (size_t c = 0; c < 3; ++c) {
    mean[c] = (sum[c] + 8) / 16;
    for (const auto& p : px) solidErr += (p[c] - mean[c]) * (p[c] - mean[c]);
  }
  const Mode* bestMode = nullptr;
  Fit best;
  best.err = solidErr;
  for (const Mode& m : kModes)
    for (int ccs = m.planes == 2 ? 0 : -1; ccs < (m.planes == 2 ? 3 : 0); ++ccs)
      if (Fit f = fitMode(m, px, ccs); f.err < best.err) best = f, bestMode = &m;
  if (!bestMode) return packSolid(mean);

  Block block = packFit(*bestMode, best, {});
  Texels decoded{};
  decodeBlock(block, decoded);
  return packFit(*bestMode, best, etc1Hints(decoded));
}

std::vector<uint8_t> encodeImage(const Image& image) {
  if (image.empty() || image.width <= 0 || image.height <= 0) throw Error("UASTC: empty image");
  if (image.channels != 1 && image.channels != 3 && image.channels != 4)
    throw Error("UASTC: " + std::to_string(image.channels) + "-channel image (1, 3 or 4 channels expected)");
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const float v = image.pixels[i];
    if (!std::isfinite(v)) throw Error("UASTC: non-finite value at pixel " + std::to_string(i / size_t(image.channels)));
    if (image.channels == 4 && i % 4 == 3 && toUnorm8(v) != 255)
      throw Error("UASTC: alpha below 1 at pixel " + std::to_string(i / 4) + " (only opaque RGB is encoded)");
  }
  const int bw = (image.width + 3) / 4, bh = (image.height + 3) / 4;
  std::vector<uint8_t> out(size_t(bw) * size_t(bh) * 16);
  parallelFor(0, bh, 0, [&](int by0, int by1) {
    for (int by = by0; by < by1; ++by)
      for (int bx = 0; bx < bw; ++bx) {
        Texels t{};
        for (int y = 0; y < 4; ++y)
          for (int x = 0; x < 4; ++x) {
            const float* p = image.pixel(std::min(4 * bx + x, image.width - 1), std::min(4 * by + y, image.height - 1));
            uint8_t* q = t.data() + 4 * (4 * y + x);
            for (int c = 0; c < 3; ++c) q[c] = toUnorm8(p[image.channels == 1 ? 0 : c]);
            q[3] = 255;
          }
        const Block b = encodeBlock(t);
        std::copy(b.begin(), b.end(), out.begin() + std::ptrdiff_t((size_t(by) * size_t(bw) + size_t(bx)) * 16));
      }
  });
  return out;
}

std::vector<uint8_t> decodeImage(std::span<const uint8_t> blocks, int width, int height) {
  const int bw = (width + 3) / 4, bh = (height + 3) / 4;
  if (width <= 0 || height <= 0 || blocks.size() != size_t(bw) * size_t(bh) * 16)
    throw Error("UASTC: " + std::to_string(blocks.size()) + " bytes of blocks for a " + std::to_string(width) + "x" +
                std::to_string(height) + " image");
  std::vector<uint8_t> rgba(size_t(width) * size_t(height) * 4);
  for (int by = 0; by < bh; ++by)
    for (int bx = 0; bx < bw; ++bx) {
      Block block;
      std::copy_n(blocks.begin() + std::ptrdiff_t((size_t(by) * size_t(bw) + size_t(bx)) * 16), 16, block.begin());
      Texels t{};
      if (!decodeBlock(block, t)) throw Error("UASTC: block " + std::to_string(bx) + "," + std::to_string(by) + " holds mode " +
                                              std::to_string(blockMode(block)) + ", which is not decoded here");
      for (int y = 0; y < 4 && 4 * by + y < height; ++y)
        for (int x = 0; x < 4 && 4 * bx + x < width; ++x)
          std::copy_n(&t[size_t(4 * (4 * y + x))], 4, &rgba[(size_t(4 * by + y) * size_t(width) + size_t(4 * bx + x)) * 4]);
    }
  return rgba;
}

} // namespace texfab::uastc
