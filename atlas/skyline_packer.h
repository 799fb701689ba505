// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A raster packer for chart masks into a strip of fixed width (height unbounded), one mask at a
// time, each in the quarter turn and place chosen by two rules:
//  - B. Lévy, S. Petitjean, N. Ray, J. Maillot, "Least Squares Conformal Maps for Automatic
//    Texture Atlas Generation", SIGGRAPH 2002, §5: the "Tetris" horizon packer (each chart is
//    dropped where its lower profile wastes the least area under the current horizon), with a
//    penalty for growing the used height.
//  - Hole filling as in bottom-left-fill raster packers (xatlas's brute-force placement, and
//    E. Hopper, B. Turton, "An empirical investigation of meta-heuristic and heuristic algorithms
//    for a 2D packing problem", EJOR 2001): before dropping a chart on the horizon, look for the
//    lowest free spot in the space left under earlier charts. Each strip row keeps its free runs;
//    at a row, the positions where a mask span fits are the long-enough runs of its row, shifted,
//    and the chart fits where those of all its spans intersect (exact, spans taken from far-apart
//    mask rows first so most rows are ruled out after a few; bounded effort, counted in span
//    tests, never timed: the result is deterministic).
// Masks never overlap: the strip keeps one occupancy bit per texel.

#include "atlas/chart_mask.h"

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace texfab::atlas {

struct SkylinePackerOptions {
  /// Weight of growing the used height against the area wasted under a chart (measured on CGAL
  /// meshes: 0.3 packs best; 0 fills one column first, 1 wastes more under overhangs).
  double heightWeight = 0.3;
  /// Hole-search effort per chart, in span tests per strip column; 0 turns hole filling off.
  long long holeBudget = 256;
};

/// Where a mask went: its top-left texel and its quarter turns (ChartMask's convention).
struct ChartPlacement {
  int x = 0, y = 0, q = 0;
};

class SkylinePacker {
 public:
  explicit SkylinePacker(int width, const SkylinePackerOptions& options = {});

  /// Places `mask` and marks its texels occupied; nullopt (and nothing changes) when the mask is
  /// wider than the strip in every quarter turn.
  std::optional<ChartPlacement> place(const ChartMask& mask);

  /// Rows used by the masks placed so far.
  int usedHeight() const { return used_; }

 private:
  using Runs = std::vector<std::pair<int32_t, int32_t>>;
  struct Span {
    int j, a, b; ///< mask row j, texels [a, b)
  };

  std::optional<ChartPlacement> dropOnHorizon(const ChartMask& m);
  std::optional<ChartPlacement> findHole(const ChartMask& m, int belowRow);
  void orderSpans(const std::vector<ChartMask::Spans>& rows);
  std::optional<std::pair<int, int>> lowestFit(int yLimit, int xMax);
  int fitRow(int y, int xMax);
  void occupy(const ChartMask& m, const ChartPlacement& p);
  void ensureRows(int rows);
  void refreshRuns(int y);

  int width_;
  SkylinePackerOptions options_;
  int used_ = 0;
  std::vector<int> horizon_;
  std::vector<double> prefix_; ///< prefix sums of the horizon
  size_t words_;               ///< 64-texel words per strip row
  std::vector<uint64_t> occupied_;
  // Free runs [start, end) of each row in three lists by length (all, >= 16, >= 64 texels): a
  // span only looks at the runs that can hold it; and each row's longest free run.
  static constexpr std::array<int, 3> kRunClass{0, 16, 64};
  std::vector<std::array<Runs, 3>> freeRuns_;
  std::vector<int32_t> rowMaxRun_;
  // Scratch of the current chart: hole-search effort, its spans in test order, candidates.
  long long work_ = 0;
  std::vector<Span> spanOrder_;
  std::vector<int> need_, rowOrder_; ///< longest span per mask row; rows in test order
  int widestRow_ = 0, minNeed_ = 0;
  Runs cand_, next_;
  std::vector<int> window_;
};

} // namespace texfab::atlas
