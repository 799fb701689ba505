// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/analyze_exemplar.h"

#include <memory>
#include <string>

namespace texfab::synthesis {

ExemplarAnalysis analyzeExemplar(const Image& exemplar, const AnalysisOptions& options,
                                 const AnalysisCacheSettings& cache, const Context& ctx, bool* cached) {
  Stage stage(ctx, "analysis");
  bool fromCache = false;
  ExemplarAnalysis a = cache.dir ? analyzeExemplarCached(exemplar, options, *cache.dir, stage.inner(), &fromCache)
                                 : analyzeExemplar(exemplar, options, stage.inner());
  pruneCache(cache);
  stage.finish(fromCache ? "(cached)" : std::to_string(a.levels.size()) + " levels");
  if (cached) *cached = fromCache;
  return a;
}

SolidAnalysis analyzeSolid(const Image& ex, const Image& ey, const Image& ez, const SolidAnalysisOptions& options,
                           SolidMethod method, const SolidTileOptions& tiles, const AnalysisCacheSettings& cache,
                           const Context& ctx, bool* cached) {
  Stage stage(ctx, "analysis");
  bool fromCache = false;
  SolidAnalysis a = cache.dir ? analyzeSolidCached(ex, ey, ez, options, *cache.dir, stage.inner(), &fromCache)
                              : analyzeSolid(ex, ey, ez, options, stage.inner());
  pruneCache(cache);
  stage.finish(fromCache ? "(cached)"
                         : std::to_string(a.levels.size()) + " levels" + (a.shared ? ", candidates shared" : ""));
  if (cached) *cached = fromCache;
  if (method == SolidMethod::Tiles) {
    Stage build(ctx, "tiles");
    bool tilesCached = false;
    a.tiles = std::make_shared<const SolidTileSet>(
        cache.dir ? buildSolidTilesCached(a, tiles, *cache.dir, build.inner(), &tilesCached)
                  : buildSolidTiles(a, tiles, build.inner()));
    pruneCache(cache);
    build.finish(tilesCached ? "(cached)" : std::to_string(a.tiles->layout.side) + "^3 voxels per tile");
  }
  return a;
}

} // namespace texfab::synthesis
