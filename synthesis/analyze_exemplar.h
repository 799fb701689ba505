// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The analyses a job needs before it synthesizes, as the command line and the Python module make
// them: each an "analysis" stage of the context (and a "tiles" stage for the solid tiles method),
// read from the analysis cache when it holds them, else computed, stored and the cache pruned.

#include "core/context.h"
#include "core/image.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/solid_tiles.h"
#include "synthesis/synthesize_solid.h"

namespace texfab::synthesis {

/// The 2-D analysis of `exemplar`. `cached` (optional) tells whether it was read from the cache.
ExemplarAnalysis analyzeExemplar(const Image& exemplar, const AnalysisOptions& options,
                                 const AnalysisCacheSettings& cache, const Context& ctx, bool* cached = nullptr);

/// The solid analysis of the three axes' exemplars, with its tile set when `method` is Tiles.
/// `cached` (optional) tells whether the analysis was read from the cache.
SolidAnalysis analyzeSolid(const Image& ex, const Image& ey, const Image& ez, const SolidAnalysisOptions& options,
                           SolidMethod method, const SolidTileOptions& tiles, const AnalysisCacheSettings& cache,
                           const Context& ctx, bool* cached = nullptr);

} // namespace texfab::synthesis
