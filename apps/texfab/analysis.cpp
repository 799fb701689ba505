// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/analysis.h"

namespace texfab::cli {

synthesis::ExemplarAnalysis analyzeExemplar(Run& run, const Image& exemplar, const synthesis::AnalysisOptions& options,
                                            bool& cached) {
  Stage stage(run.ctx(), "analysis");
  const auto dir = run.cacheDir();
  cached = false;
  synthesis::ExemplarAnalysis a = dir ? synthesis::analyzeExemplarCached(exemplar, options, *dir, stage.inner(), &cached)
                                      : synthesis::analyzeExemplar(exemplar, options, stage.inner());
  run.pruneCache();
  stage.finish(cached ? "(cached)" : std::to_string(a.levels.size()) + " levels");
  return a;
}

synthesis::SolidAnalysis analyzeSolid(Run& run, const Image& ex, const Image& ey, const Image& ez,
                                      const synthesis::SolidAnalysisOptions& options, bool& cached) {
  Stage stage(run.ctx(), "analysis");
  const auto dir = run.cacheDir();
  cached = false;
  synthesis::SolidAnalysis a = dir ? synthesis::analyzeSolidCached(ex, ey, ez, options, *dir, stage.inner(), &cached)
                                   : synthesis::analyzeSolid(ex, ey, ez, options, stage.inner());
  run.pruneCache();
  stage.finish(cached ? "(cached)"
                      : std::to_string(a.levels.size()) + " levels" + (a.shared ? ", candidates shared" : ""));
  return a;
}

} // namespace texfab::cli
