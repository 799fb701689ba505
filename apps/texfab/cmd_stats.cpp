// SPDX-License-Identifier: GPL-3.0-or-later
// texfab stats: the quality measures (docs/design.md#quality-measures) of an image synthesized
// from an exemplar.
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "apps/texfab/report_json.h"
#include "render/image/error.h"
#include "render/image/image_io.h"
#include "synthesis/quality_measures.h"

#include <cmath>
#include <cstdio>
#include <memory>

namespace texfab::cli {

namespace {

struct StatsJob {
  std::string image, exemplar, coords;
  synthesis::FidelityOptions fidelity;
  CommonFlags common;
};

void runStats(const StatsJob& args) {
  using namespace synthesis;
  Run run("stats", args.common);
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
  const QualityReport q = measureQuality(image, exemplar, coords ? &*coords : nullptr, args.fidelity, run.ctx());

  std::printf("fidelity             %.4f   (7x7 RMS distance to the nearest exemplar neighborhood; lower is better)\n",
              q.fidelity);
  std::printf("histogram distance   %.4f   (largest per-channel earth mover's distance)\n", q.histogramDistance);
  std::printf("contrast ratio       %.4f   (luminance standard deviation, image / exemplar; 1 = kept)\n", q.contrast);
  if (std::isnan(q.shiftedCorrelation))
    std::printf("shifted correlation  n/a      (image not larger than the exemplar)\n");
  else
    std::printf("shifted correlation  %.4f   (1 = repeats with the exemplar's period)\n", q.shiftedCorrelation);
  if (q.coherence) std::printf("coherence            %.4f   (1 = verbatim tiling, 0 = noise)\n", *q.coherence);
  if (q.coverage) std::printf("coverage             %.4f   (fraction of the exemplar used)\n", *q.coverage);

  run.report() = toJson(q);
  run.report()["image"] = args.image;
  run.report()["exemplar"] = args.exemplar;
  run.finish();
}

} // namespace

Command addStatsCommand(CLI::App& root) {
  auto job = std::make_shared<StatsJob>();
  Flags f(root.add_subcommand("stats", "Measure a synthesized image against its exemplar: neighborhood "
                                       "fidelity, histogram distance, coherence, coverage, repetition"));
  f.input("image", job->image, "Synthesized image");
  f.text("--exemplar", job->exemplar, "The exemplar it was synthesized from")->required();
  f.text("--coords", job->coords, "Its coordinate map (from 'texfab synth --coords'): adds coherence and coverage");
  f.option("--samples", job->fidelity.samples, "Neighborhoods measured for fidelity (0 = all; exact search each)",
           {0, 1e9});
  f.common(job->common, Common::Threads | Common::Report | Common::Quiet);
  return {f.app(), [job] { runStats(*job); }};
}

} // namespace texfab::cli
