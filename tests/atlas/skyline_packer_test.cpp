// SPDX-License-Identifier: GPL-3.0-or-later
// The skyline packer alone, on masks rasterized from small synthetic charts: placed masks never
// overlap and stay inside the strip, the result is a pure function of the input, and hole filling
// packs L-shaped charts lower than the horizon rule alone.
#include "atlas/chart_mask.h"
#include "atlas/skyline_packer.h"

#include <gtest/gtest.h>

#include <random>

namespace texfab::atlas {
namespace {

/// An axis-aligned rectangle (two triangles) of w×h units, or an L (the rectangle minus its
/// top-right quarter) when `ell`.
OrientedChart shape(double w, double h, bool ell) {
  OrientedChart c;
  auto quad = [&](double x0, double y0, double x1, double y1) {
    for (const auto& p : {Eigen::Vector2d(x0, y0), Eigen::Vector2d(x1, y0), Eigen::Vector2d(x1, y1),
                          Eigen::Vector2d(x0, y0), Eigen::Vector2d(x1, y1), Eigen::Vector2d(x0, y1)})
      c.corners.push_back(p);
  };
  if (ell) {
    quad(0, 0, w, h / 2);
    quad(0, h / 2, w / 2, h);
  } else {
    quad(0, 0, w, h);
  }
  c.extent = {w, h};
  return c;
}

std::vector<ChartMask> masks(int count, bool ell, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> side(3, 30);
  std::vector<ChartMask> out;
  for (int i = 0; i < count; ++i) out.push_back(rasterizeChartMask(shape(side(rng), side(rng), ell), 1.0, 1, 0.0));
  return out;
}

struct Packed {
  std::vector<ChartPlacement> placements;
  int used = 0;
};

Packed pack(const std::vector<ChartMask>& ms, int width, long long holeBudget) {
  SkylinePackerOptions o;
  o.holeBudget = holeBudget;
  SkylinePacker packer(width, o);
  Packed p;
  for (const ChartMask& m : ms) {
    const std::optional<ChartPlacement> at = packer.place(m);
    EXPECT_TRUE(at.has_value());
    p.placements.push_back(at.value_or(ChartPlacement{}));
  }
  p.used = packer.usedHeight();
  return p;
}

/// Paints every mask's spans at its placement; fails on a texel painted twice or outside.
void expectDisjoint(const std::vector<ChartMask>& ms, const Packed& p, int width) {
  std::vector<uint8_t> owner(size_t(width) * size_t(p.used), 0);
  for (size_t i = 0; i < ms.size(); ++i) {
    const ChartPlacement& at = p.placements[i];
    const auto& rows = ms[i].spans[size_t(at.q)];
    for (size_t j = 0; j < rows.size(); ++j)
      for (const auto& [a, b] : rows[j])
        for (int x = at.x + a; x < at.x + b; ++x) {
          const int y = at.y + int(j);
          ASSERT_TRUE(x >= 0 && x < width && y >= 0 && y < p.used) << "mask " << i << " leaves the strip";
          uint8_t& o = owner[size_t(y) * size_t(width) + size_t(x)];
          ASSERT_EQ(o, 0) << "mask " << i << " overlaps another at (" << x << ", " << y << ")";
          o = 1;
        }
  }
}

TEST(SkylinePacker, MasksNeverOverlapAndStayInTheStrip) {
  for (bool ell : {false, true}) {
    const std::vector<ChartMask> ms = masks(120, ell, 7);
    const Packed p = pack(ms, 128, 256);
    expectDisjoint(ms, p, 128);
  }
}

TEST(SkylinePacker, SameInputSamePlacements) {
  const std::vector<ChartMask> ms = masks(80, true, 11);
  const Packed a = pack(ms, 96, 256), b = pack(ms, 96, 256);
  ASSERT_EQ(a.used, b.used);
  for (size_t i = 0; i < ms.size(); ++i) {
    EXPECT_EQ(a.placements[i].x, b.placements[i].x);
    EXPECT_EQ(a.placements[i].y, b.placements[i].y);
    EXPECT_EQ(a.placements[i].q, b.placements[i].q);
  }
}

TEST(SkylinePacker, HoleFillingPacksLShapesLower) {
  const std::vector<ChartMask> ms = masks(150, true, 3);
  const Packed horizon = pack(ms, 128, 0), holes = pack(ms, 128, 256);
  expectDisjoint(ms, holes, 128);
  EXPECT_LT(holes.used, horizon.used * 0.9) << "hole filling: " << holes.used << " rows, horizon only: " << horizon.used;
}

TEST(SkylinePacker, RefusesAMaskWiderThanTheStripInEveryTurn) {
  SkylinePacker packer(16);
  EXPECT_FALSE(packer.place(rasterizeChartMask(shape(40, 40, false), 1.0, 1, 0.0)).has_value());
  EXPECT_EQ(packer.usedHeight(), 0);
  EXPECT_TRUE(packer.place(rasterizeChartMask(shape(40, 5, false), 1.0, 1, 0.0)).has_value()); // turned
}

} // namespace
} // namespace texfab::atlas
