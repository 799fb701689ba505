// SPDX-License-Identifier: GPL-3.0-or-later
#include "atlas/skyline_packer.h"

#include <algorithm>
#include <bit>
#include <limits>
#include <numeric>

namespace texfab::atlas {

namespace {

// The first texel at or after x of a bit row (one bit per texel, 64 a word) that is occupied
// (`occupied`) or free (!occupied); W if none before W.
int nextTexel(const uint64_t* row, int x, int W, bool occupied) {
  while (x < W) {
    const uint64_t word = row[size_t(x) >> 6];
    const uint64_t v = (occupied ? word : ~word) >> (x & 63); // wanted bits from x
    const int left = std::min(64 - (x & 63), W - x);
    const int skip = v ? std::countr_zero(v) : 64;
    if (skip < left) return x + skip;
    x += left;
  }
  return W;
}

/// Whether any texel of [x0, x1) of a bit row is occupied.
bool anyOccupied(const uint64_t* row, int x0, int x1) {
  const int w0 = x0 >> 6, w1 = (x1 - 1) >> 6;
  uint64_t any = 0;
  for (int w = w0; w <= w1; ++w) {
    uint64_t v = row[w];
    if (w == w1 && (x1 & 63) != 0) v &= (uint64_t(1) << (x1 & 63)) - 1;
    if (w == w0) v &= ~uint64_t(0) << (x0 & 63);
    any |= v;
  }
  return any != 0;
}

/// The bit-reversed rank of each of n rows (middle, quarters, eighths, ...).
std::vector<int> bitReversedRanks(size_t n) {
  int bits = 0;
  while ((size_t(1) << bits) < n) ++bits;
  std::vector<int> rank(n);
  for (size_t j = 0; j < n; ++j) {
    size_t r = 0;
    for (int b = 0; b < bits; ++b)
      if (j & (size_t(1) << b)) r |= size_t(1) << (bits - 1 - b);
    rank[j] = int(r);
  }
  return rank;
}

} // namespace

SkylinePacker::SkylinePacker(int width, const SkylinePackerOptions& options)
    : width_(width), options_(options), horizon_(size_t(width), 0), prefix_(size_t(width) + 1, 0.0),
      words_(size_t(width + 63) / 64), window_(size_t(width)) {}

std::optional<ChartPlacement> SkylinePacker::place(const ChartMask& m) {
  std::optional<ChartPlacement> p = dropOnHorizon(m);
  if (!p) return std::nullopt;
  if (std::optional<ChartPlacement> hole = findHole(m, p->y)) p = hole;
  occupy(m, *p);
  return p;
}

// Every column of a (connected, dilated) chart mask is occupied, so the waste under the chart at X
// is mw·Y + Σtop − Σh[X..X+mw): a window sum. Y(X) >= max(h over the window) − max(top) gives a
// lower bound on the score that prunes most positions before the exact O(mw) scan.
std::optional<ChartPlacement> SkylinePacker::dropOnHorizon(const ChartMask& m) {
  const int W = width_;
  double best = std::numeric_limits<double>::infinity();
  std::optional<ChartPlacement> bestAt;
  for (int q = 0; q < 4; ++q) {
    const int mw = m.width[size_t(q)];
    if (mw > W) continue;
    const auto& top = m.top[size_t(q)];
    int maxTop = 0;
    double sumTop = 0;
    for (int x = 0; x < mw; ++x) maxTop = std::max(maxTop, top[size_t(x)]), sumTop += top[size_t(x)];
    const int positions = W - mw + 1;
    // Sliding window maximum of the horizon (monotonic deque).
    std::vector<int>& dq = window_;
    size_t head = 0, tail = 0;
    for (int X = 0, R = 0; X < positions; ++X) {
      for (; R < X + mw; ++R) {
        while (tail > head && horizon_[size_t(dq[tail - 1])] <= horizon_[size_t(R)]) --tail;
        dq[tail++] = R;
      }
      while (dq[head] < X) ++head;
      const int windowMax = horizon_[size_t(dq[head])];
      const double windowSum = prefix_[size_t(X + mw)] - prefix_[size_t(X)];
      auto scoreOf = [&](int Y) {
        return double(mw) * Y + sumTop - windowSum +
               options_.heightWeight * double(W) * std::max(0, Y + m.maxBottom[size_t(q)] - used_);
      };
      const int ylb = std::max(0, windowMax - maxTop);
      if (scoreOf(ylb) > best) continue;
      int Y = 0;
      for (int x = 0; x < mw; ++x) Y = std::max(Y, horizon_[size_t(X + x)] - top[size_t(x)]);
      const double sc = scoreOf(Y);
      if (sc < best || (sc == best && Y < bestAt->y)) best = sc, bestAt = ChartPlacement{X, Y, q};
    }
  }
  return bestAt;
}

// The lowest-row position above `belowRow` where the chart fits in the free space left under
// earlier charts without growing the used height.
std::optional<ChartPlacement> SkylinePacker::findHole(const ChartMask& m, int belowRow) {
  std::optional<ChartPlacement> hole;
  work_ = 0;
  for (int q = 0; q < (options_.holeBudget > 0 ? 4 : 0); ++q) {
    const int rw = m.width[size_t(q)];
    if (rw > width_) continue;
    orderSpans(m.spans[size_t(q)]);
    const int yLimit = std::min({belowRow - 1, used_ - m.heightAt(q), hole ? hole->y - 1 : belowRow - 1});
    if (const auto yx = lowestFit(yLimit, width_ - rw)) hole = ChartPlacement{yx->second, yx->first, q};
  }
  return hole;
}

// Test order: the widest span, then the rows in bit-reversed order (each row's widest span
// first): far-apart rows meet different neighbours, so a position that does not fit is rejected
// after a few spans.
void SkylinePacker::orderSpans(const std::vector<ChartMask::Spans>& rows) {
  need_.assign(rows.size(), 0);
  for (size_t j = 0; j < rows.size(); ++j)
    for (const auto& [a, b] : rows[j]) need_[j] = std::max(need_[j], b - a);
  widestRow_ = int(std::max_element(need_.begin(), need_.end()) - need_.begin());
  minNeed_ = need_.empty() ? 0 : *std::min_element(need_.begin(), need_.end());
  spanOrder_.clear();
  for (size_t j = 0; j < rows.size(); ++j)
    for (const auto& [a, b] : rows[j]) spanOrder_.push_back({int(j), a, b});
  const std::vector<int> rank = bitReversedRanks(rows.size());
  rowOrder_.resize(rows.size());
  std::iota(rowOrder_.begin(), rowOrder_.end(), 0);
  std::sort(rowOrder_.begin(), rowOrder_.end(), [&](int u, int v) { return rank[size_t(u)] < rank[size_t(v)]; });
  std::stable_sort(spanOrder_.begin(), spanOrder_.end(), [&](const Span& u, const Span& v) {
    return rank[size_t(u.j)] != rank[size_t(v.j)] ? rank[size_t(u.j)] < rank[size_t(v.j)] : u.b - u.a > v.b - v.a;
  });
  const auto widestSpan = std::min_element(spanOrder_.begin(), spanOrder_.end(),
                                           [](const Span& u, const Span& v) { return u.b - u.a > v.b - v.a; });
  if (widestSpan != spanOrder_.end()) std::rotate(spanOrder_.begin(), widestSpan, widestSpan + 1);
}

// The lowest (row, column) in [0, yLimit] × [0, xMax] where the ordered spans fit, within the
// effort budget. Rows too full for the chart's span there rule a row out at once (widest mask row
// first); a strip row whose longest free run is shorter than every mask row blocks all the
// positions whose mask covers it: jump past it.
std::optional<std::pair<int, int>> SkylinePacker::lowestFit(int yLimit, int xMax) {
  const long long budget = options_.holeBudget * width_;
  for (int Y = 0; Y <= yLimit && work_ < budget; ++Y) {
    int blockedAt = -1;
    if (rowMaxRun_[size_t(Y + widestRow_)] < need_[size_t(widestRow_)]) blockedAt = Y + widestRow_;
    for (size_t i = 0; i < rowOrder_.size() && blockedAt < 0; ++i)
      if (rowMaxRun_[size_t(Y + rowOrder_[i])] < need_[size_t(rowOrder_[i])]) blockedAt = Y + rowOrder_[i];
    work_ += long(rowOrder_.size()) / 8 + 1;
    if (blockedAt >= 0) {
      if (rowMaxRun_[size_t(blockedAt)] < minNeed_) Y = blockedAt;
      continue;
    }
    const int X = fitRow(Y, xMax);
    if (X >= 0) return std::pair{Y, X};
  }
  return std::nullopt;
}

// The lowest X in [0, xMax] where the ordered spans fit at row Y, or -1. Exact: the allowed
// positions of each span are the free runs of its row long enough for it, shifted; the chart fits
// where all of them intersect.
int SkylinePacker::fitRow(int Y, int xMax) {
  cand_.assign(1, {0, xMax}); // positions X (closed intervals) where every span so far fits
  for (const Span& sp : spanOrder_) {
    const int len = sp.b - sp.a;
    const auto& runs = freeRuns_[size_t(Y + sp.j)][len >= kRunClass[2] ? 2 : len >= kRunClass[1] ? 1 : 0];
    // Fast path: the span's whole window over the candidates is free (a few word tests).
    const int x0 = cand_.front().first + sp.a, x1 = cand_.back().second + sp.b;
    if (x1 - x0 <= 256) {
      ++work_;
      if (!anyOccupied(occupied_.data() + size_t(Y + sp.j) * words_, x0, x1)) continue;
    }
    next_.clear();
    size_t c = 0;
    // Only the runs that can hold the span at a candidate position: e0 >= X + b for the first
    // candidate X, s0 <= X + a for the last (binary search, then a walk).
    const int firstEnd = cand_.front().first + sp.b, lastStart = cand_.back().second + sp.a;
    auto r = std::partition_point(runs.begin(), runs.end(),
                                  [&](const std::pair<int32_t, int32_t>& u) { return u.second < firstEnd; });
    work_ += long(cand_.size()) + 4;
    for (; r != runs.end() && r->first <= lastStart; ++r) {
      const auto [s0, e0] = *r;
      ++work_;
      if (e0 - s0 < len) continue;
      const int lo = s0 - sp.a, hi = e0 - sp.b; // allowed X for this run
      while (c < cand_.size() && cand_[c].second < lo) ++c;
      for (size_t d = c; d < cand_.size() && cand_[d].first <= hi; ++d) {
        const int l = std::max(lo, cand_[d].first), h = std::min(hi, cand_[d].second);
        if (l <= h) next_.push_back({l, h});
      }
    }
    cand_.swap(next_);
    if (cand_.empty()) return -1;
  }
  return cand_.front().first;
}

void SkylinePacker::occupy(const ChartMask& m, const ChartPlacement& p) {
  const auto& bottom = m.bottom[size_t(p.q)];
  for (int x = 0; x < m.width[size_t(p.q)]; ++x)
    if (bottom[size_t(x)] > 0) horizon_[size_t(p.x + x)] = std::max(horizon_[size_t(p.x + x)], p.y + bottom[size_t(x)]);
  const auto& rows = m.spans[size_t(p.q)];
  ensureRows(p.y + int(rows.size()));
  for (size_t j = 0; j < rows.size(); ++j) {
    uint64_t* row = occupied_.data() + (size_t(p.y) + j) * words_;
    for (const auto& [a, b] : rows[j])
      for (int x = p.x + a; x < p.x + b; ++x) row[size_t(x) >> 6] |= uint64_t(1) << (x & 63);
    refreshRuns(p.y + int(j));
  }
  used_ = std::max(used_, p.y + m.maxBottom[size_t(p.q)]);
  for (int x = 0; x < width_; ++x) prefix_[size_t(x + 1)] = prefix_[size_t(x)] + horizon_[size_t(x)];
}

void SkylinePacker::ensureRows(int rows) {
  if (int(rowMaxRun_.size()) < rows) {
    rowMaxRun_.resize(size_t(rows), width_);
    freeRuns_.resize(size_t(rows), {Runs{{0, width_}}, Runs{{0, width_}}, Runs{{0, width_}}});
    occupied_.resize(size_t(rows) * words_, 0);
  }
}

void SkylinePacker::refreshRuns(int y) {
  const uint64_t* row = occupied_.data() + size_t(y) * words_;
  auto& lists = freeRuns_[size_t(y)];
  for (Runs& l : lists) l.clear();
  int32_t longest = 0;
  int x = 0;
  while (x < width_) {
    x = nextTexel(row, x, width_, false);
    if (x >= width_) break;
    const int start = x;
    x = nextTexel(row, x, width_, true);
    for (size_t k = 0; k < kRunClass.size(); ++k)
      if (x - start >= kRunClass[k]) lists[k].push_back({start, x});
    longest = std::max(longest, x - start);
  }
  rowMaxRun_[size_t(y)] = longest;
}

} // namespace texfab::atlas
