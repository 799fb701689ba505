// SPDX-License-Identifier: GPL-3.0-or-later
// texfab stats: the quality measures of DESIGN.md for an image synthesized from an exemplar.
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "render/image/error.h"
#include "render/image/image_io.h"
#include "synthesis/quality_measures.h"

#include <cmath>
#include <cstdio>
#include <memory>

namespace texfab::cli {

namespace {

struct StatsArgs {
  std::string image;
  std::string exemplar;
  std::string coords;
  std::string report;
  int samples = synthesis::FidelityOptions{}.samples;
  int threads = 0;
};

void runStats(const StatsArgs& args) {
  using namespace synthesis;
  const Image image = readImage(args.image);
  const Image exemplar = readImage(args.exemplar);
  std::optional<CoordMap> coords;
  if (!args.coords.empty()) {
    coords = readCoordMap(args.coords, exemplar.width, exemplar.height);
    if (coords->width != image.width || coords->height != image.height)
      throw Error(args.coords + ": coordinate map is " + std::to_string(coords->width) + "x" +
                  std::to_string(coords->height) + " but the image is " + std::to_string(image.width) + "x" +
                  std::to_string(image.height));
  }
  FidelityOptions fidelity;
  fidelity.samples = args.samples;
  const QualityReport q = measureQuality(image, exemplar, coords ? &*coords : nullptr, fidelity, Context{.threads = args.threads});

  std::printf("fidelity             %.4f   (7x7 RMS distance to the nearest exemplar neighborhood; lower is better)\n",
              q.fidelity);
  std::printf("histogram distance   %.4f   (largest per-channel earth mover's distance)\n", q.histogramDistance);
  if (std::isnan(q.shiftedCorrelation))
    std::printf("shifted correlation  n/a      (image not larger than the exemplar)\n");
  else
    std::printf("shifted correlation  %.4f   (1 = repeats with the exemplar's period)\n", q.shiftedCorrelation);
  if (q.coherence) std::printf("coherence            %.4f   (1 = verbatim tiling, 0 = noise)\n", *q.coherence);
  if (q.coverage) std::printf("coverage             %.4f   (fraction of the exemplar used)\n", *q.coverage);

  if (!args.report.empty()) {
    nlohmann::json report = {{"image", args.image},
                             {"exemplar", args.exemplar},
                             {"fidelity", q.fidelity},
                             {"histogram_distance", q.histogramDistance},
                             {"shifted_correlation", q.shiftedCorrelation}};
    if (q.coherence) report["coherence"] = *q.coherence;
    if (q.coverage) report["coverage"] = *q.coverage;
    writeReport(report, args.report);
  }
}

} // namespace

Command addStatsCommand(CLI::App& root) {
  auto args = std::make_shared<StatsArgs>();
  CLI::App* app = root.add_subcommand("stats", "Measure a synthesized image against its exemplar: neighborhood "
                                               "fidelity, histogram distance, coherence, coverage, repetition");
  app->add_option("image", args->image, "Synthesized image")->required();
  app->add_option("--exemplar", args->exemplar, "The exemplar it was synthesized from")->required();
  app->add_option("--coords", args->coords, "Its coordinate map (from 'texfab synth --coords'): adds coherence and coverage");
  app->add_option("--report", args->report, "Also write the measures to this JSON file");
  app->add_option("--samples", args->samples, "Neighborhoods measured for fidelity (0 = all; exact search each)")
      ->capture_default_str();
  app->add_option("--threads", args->threads, "Worker threads (0 = all cores)")->capture_default_str();
  return {app, [args] { runStats(*args); }};
}

} // namespace texfab::cli
