// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/analysis.h"

#include "synthesis/quality_measures.h"
#include "synthesis/solid_tile_measures.h"
#include "synthesis/synthesize_solid.h"

#include <algorithm>
#include <array>
#include <cstdio>

namespace texfab::cli {

namespace {
// The histogram distance between two exemplars above which their colours are said to differ:
// another crop of one photograph stays far below it (0.005 and 0.011 for 64^2 crops of GIMP's
// marble1 and walnut), wood5 against wood1 is 0.33.
constexpr double kSolidColorMismatch = 0.1;
// The seam ratio above which the tiles' faces are said to show: issue 33's target. Of eighteen
// exemplars measured only the smooth procedural clouds exceed it (docs/measurements.md).
constexpr double kTileSeamWarning = 1.1;

// The tile set's lattice measures: a note, the report's "solid_tiles", and a warning when its faces show.
void reportTileLattice(Run& run, const synthesis::SolidAnalysis& a, const Image& ex, const Image& ey, const Image& ez) {
  const synthesis::SolidTileSet& tiles = synthesis::requireTiles(a);
  const synthesis::SolidTileLattice m = synthesis::measureSolidTileLattice(tiles, ex, ey, ez, run.ctx());
  const int side = tiles.layout.side;
  char text[320];
  std::snprintf(text, sizeof text,
                "solid tiles: seam ratio %.2f and peak step %.2f (about 1 where faces do not show), "
                "self-correlation %.2f at the %d-voxel period (0 = no lattice)",
                m.seamRatio, m.peakStep, m.correlation, side);
  run.note(text);
  run.report()["solid_tiles"] = {{"tile_side", side},
                                 {"seam_ratio", m.seamRatio},
                                 {"peak_step", m.peakStep},
                                 {"lattice_correlation", m.correlation},
                                 {"precomputation_seconds", tiles.seconds}};
  if (m.seamRatio > kTileSeamWarning) {
    std::snprintf(text, sizeof text,
                  "the solid tiles' faces show on this exemplar (seam ratio %.2f, above %.1f): its features are about "
                  "as large and smooth as a tile; --solid-method lazy has no tiles",
                  m.seamRatio, kTileSeamWarning);
    run.ctx().warn(text);
  }
}
} // namespace

CLI::Option* wrapFlag(Flags& f, WrapChoice& choice) {
  char threshold[16];
  std::snprintf(threshold, sizeof threshold, "%.1f", synthesis::kWrapDiscontinuityThreshold);
  return f.choice("--exemplar-wrap", choice,
           Names<WrapChoice>{{"auto", WrapChoice::Auto}, {"tile", WrapChoice::Tile}, {"clamp", WrapChoice::Clamp}},
           std::string("How the exemplar's borders are treated: tile (it is toroidal: coordinates wrap), clamp (a "
                       "photograph that does not tile: synthesis never reads across its border), or auto: clamp when "
                       "the color jump across its wrap is more than ") +
               threshold + " times the jumps between columns (rows) inside (their 90th percentile)");
}

void solidFidelityFlags(Flags& f, SolidMethodChoice& method, float& gain, int& refinePasses, const std::string& what) {
  f.choice("--solid-method", method.method,
           Names<synthesis::SolidMethod>{{"lazy", synthesis::SolidMethod::Lazy},
                                         {"tiles", synthesis::SolidMethod::Tiles}},
           "How the solid texture" + what +
               " is made: lazy (Dong et al. 2008: each voxel synthesized with its dependency chain) or tiles (64 "
               "matching solid tiles optimized once per exemplar, about half a minute on 2 cores, and cached; then "
               "each voxel is one read, hundreds of times faster; slices more faithful to the exemplar, but its "
               "structure repeats faintly with the tile period, and its largest features are about a tile, 32 "
               "voxels; a smooth exemplar with large soft features such as clouds shows the tiles' grid; "
               "--contrast-gain and --refine do not apply). docs/measurements.md#solid-tiles compares them");
  f.option("--tile-size", method.tiles.tileSide,
           "With --solid-method tiles: voxels per tile side (8, 16, 32 or 64), the period of the tiles' lattice and "
           "about the largest feature they keep; the precomputation grows with its cube (16: a few seconds, 64: "
           "minutes)",
           {8, 64})
      ->check(CLI::IsMember({8, 16, 32, 64}));
  f.option("--contrast-gain", gain,
           "Contrast of the solid texture" + what +
               ": 1 = the paper's search, whose slices keep about 0.63 of the exemplar's contrast; higher values keep "
               "more of its dark and bright features, cracks and veins (2: about 0.88), at the cost of less faithful "
               "small-scale structure (which --refine restores)",
           {1, 4});
  f.option("--refine", refinePasses,
           "Passes of slice refinement of the solid texture" + what +
               " (Kopf et al. 2007's search and vote after the synthesis; 0 = off): at the default contrast gain, one "
               "pass keeps about 0.80 of the exemplar's contrast with small-scale structure as faithful as the "
               "paper's search (--contrast-gain 1). Slow: each pass synthesizes a region 8 voxels thicker than the "
               "one requested; one pass takes about 3.5 times the default's time for a volume or a surface, 12 for a "
               "planar cut",
           {0, 4});
}

synthesis::ExemplarWrap chooseWrap(WrapChoice choice, const Image& exemplar, const Run& run) {
  using synthesis::ExemplarWrap;
  if (choice != WrapChoice::Auto) return choice == WrapChoice::Tile ? ExemplarWrap::Tile : ExemplarWrap::Clamp;
  const synthesis::WrapDiscontinuity d = synthesis::wrapDiscontinuity(exemplar);
  const ExemplarWrap wrap = synthesis::detectExemplarWrap(exemplar);
  char note[240];
  std::snprintf(note, sizeof note,
                "exemplar wrap: %s (auto: the color jump across its wrap is %.2fx (x), %.2fx (y) the jumps "
                "inside; above %.1fx it does not tile%s)",
                synthesis::toString(wrap), d.x, d.y, synthesis::kWrapDiscontinuityThreshold,
                std::min(exemplar.width, exemplar.height) < synthesis::kWrapDetectionMinSide ? "; too small to tell" : "");
  run.note(note);
  return wrap;
}

WrapChoice wrapAsGiven(WrapChoice choice, const Image& exemplar, const Run& run) {
  return chooseWrap(choice, exemplar, run) == synthesis::ExemplarWrap::Clamp ? WrapChoice::Clamp : WrapChoice::Tile;
}

synthesis::ExemplarAnalysis analyzeExemplar(Run& run, const Image& exemplar, const synthesis::AnalysisOptions& options,
                                            bool& cached) {
  return synthesis::analyzeExemplar(exemplar, options, run.analysisCache(), run.ctx(), &cached);
}

synthesis::SolidAnalysis analyzeSolid(Run& run, const Image& ex, const Image& ey, const Image& ez,
                                      synthesis::SolidAnalysisOptions options, WrapChoice wrap, bool& cached,
                                      const SolidMethodChoice& method) {
  const std::array<const Image*, 3> axes = {&ex, &ey, &ez};
  options.wrap = synthesis::ExemplarWrap::Tile;
  for (auto e = axes.begin(); e != axes.end(); ++e) {
    const bool seen = std::any_of(axes.begin(), e, [&](const Image* other) {
      return other->width == (*e)->width && other->pixels == (*e)->pixels;
    });
    if (!seen && chooseWrap(wrap, **e, run) == synthesis::ExemplarWrap::Clamp)
      options.wrap = synthesis::ExemplarWrap::Clamp;  // one image for several axes is measured once
  }
  // The most different pair of distinct exemplars, as synthesis reads their colours.
  const int channels = synthesis::solidColorChannels(ex, ey, ez);
  double worst = 0;
  std::array<char, 2> pair{};
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      if (axes[size_t(a)] != axes[size_t(b)]) {
        const double d = synthesis::histogramDistance(synthesis::solidColorView(*axes[size_t(a)], channels),
                                                      synthesis::solidColorView(*axes[size_t(b)], channels));
        if (d > worst) worst = d, pair = {"xyz"[a], "xyz"[b]};
      }
  if (worst > kSolidColorMismatch) {
    char warning[320];
    std::snprintf(warning, sizeof warning,
                  "the %c and %c exemplars differ in colour (histogram distance %.2f): a voxel shows the mean of "
                  "its three exemplar colours, so every slice blends them; use exemplars of one material",
                  pair[0], pair[1], worst);
    run.ctx().warn(warning);
  }
  synthesis::SolidAnalysis a = synthesis::analyzeSolid(ex, ey, ez, options, method.method, method.tiles,
                                                       run.analysisCache(), run.ctx(), &cached);
  if (method.method == synthesis::SolidMethod::Tiles) reportTileLattice(run, a, ex, ey, ez);
  return a;
}

} // namespace texfab::cli
