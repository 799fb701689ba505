// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The exemplar analyses the synthesis commands share, as one "analysis" stage of a Run: through the
// on-disk cache unless --no-cache, which is then kept within --cache-size; --exemplar-wrap and
// --contrast-gain.

#include "apps/texfab/cli.h"
#include "synthesis/analyze_exemplar.h"

namespace texfab::cli {

/// --exemplar-wrap: the library's modes, or auto (measured on the exemplar).
enum class WrapChoice { Auto, Tile, Clamp };

/// Adds --exemplar-wrap to a command.
CLI::Option* wrapFlag(Flags& f, WrapChoice& choice);

/// How a command's solid texture is made: --solid-method and --tile-size.
struct SolidMethodChoice {
  synthesis::SolidMethod method = synthesis::SolidMethod::Lazy;
  synthesis::SolidTileOptions tiles;  ///< with Tiles
};

/// Adds --solid-method, --tile-size, --contrast-gain and --refine (synthesis::SolidSynthesisOptions::
/// contrastGain and refinePasses) to a command with solid texture; `what` says where they apply.
void solidFidelityFlags(Flags& f, SolidMethodChoice& method, float& gain, int& refinePasses, const std::string& what);

/// The wrap mode the choice asks for; auto measures the exemplar and notes what it chose.
synthesis::ExemplarWrap chooseWrap(WrapChoice choice, const Image& exemplar, const Run& run);
/// chooseWrap on the exemplar as given, as a fixed choice for analysing a smaller copy of it (which
/// hides part of its seam).
WrapChoice wrapAsGiven(WrapChoice choice, const Image& exemplar, const Run& run);

synthesis::ExemplarAnalysis analyzeExemplar(Run& run, const Image& exemplar, const synthesis::AnalysisOptions& options,
                                            bool& cached);

/// `options.wrap` is the choice's; auto: clamp when any of the exemplars does not tile. Warns when
/// the exemplars' colours differ (a voxel shows the mean of its three colours, so every slice
/// blends them).
/// With the tiles method, the analysis carries its tile set (a "tiles" stage, cached like the analysis).
synthesis::SolidAnalysis analyzeSolid(Run& run, const Image& ex, const Image& ey, const Image& ez,
                                      synthesis::SolidAnalysisOptions options, WrapChoice wrap, bool& cached,
                                      const SolidMethodChoice& method = {});

} // namespace texfab::cli
