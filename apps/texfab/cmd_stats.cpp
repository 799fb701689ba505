// SPDX-License-Identifier: GPL-3.0-or-later
// texfab stats: the quality measures (docs/design.md#quality-measures) of an image synthesized
// from an exemplar.
#include "apps/texfab/analysis.h"
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "apps/texfab/report_json.h"
#include "core/error.h"
#include "core/image_io.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

namespace texfab::cli {

namespace {

struct StatsJob {
  std::string image, exemplar, coords;
  synthesis::FidelityOptions fidelity;
  bool baseline = false;
  int latticePeriod = 0;
  CommonFlags common;
};

void runStats(const StatsJob& args) {
  using namespace synthesis;
  Run run("stats", args.common);
  if (args.latticePeriod > 0 && args.latticePeriod < 3) throw UsageError("--lattice-period: 3 or more, or 0 (off)");
  const Image image = readImage(args.image);
  const Image exemplar = readImage(args.exemplar);
  if (std::min(image.width, image.height) <= 2 * args.latticePeriod)
    throw Error("--lattice-period " + std::to_string(args.latticePeriod) + ": the image must be more than twice as "
                "wide and tall, it is " + std::to_string(image.width) + "x" + std::to_string(image.height));
  std::optional<CoordMap> coords;
  if (!args.coords.empty()) {
    coords = readCoordMap(args.coords, exemplar.width, exemplar.height);
    if (coords->width != image.width || coords->height != image.height)
      throw Error(args.coords + ": coordinate map is " + std::to_string(coords->width) + "x" +
                  std::to_string(coords->height) + " but the image is " + std::to_string(image.width) + "x" +
                  std::to_string(image.height));
  }
  double bytes = measureQualityMemoryBytes(image, exemplar, args.fidelity);
  if (args.baseline)
    bytes = std::max(bytes, analysisMemoryBytes(exemplar.width, exemplar.height, {}) +
                                synthesize2dMemoryBytes({0, 0, image.width, image.height}, exemplar.channels) +
                                measureQualityMemoryBytes(image, exemplar, args.fidelity));
  run.checkMemory(bytes, "measuring a " + std::to_string(image.width) + "x" + std::to_string(image.height) + " image");
  Stage measure(run.ctx(), "measures");
  const QualityReport q = measureQuality(image, exemplar, coords ? &*coords : nullptr, args.fidelity, measure.inner());
  measure.finish();
  std::optional<QualityReport> baseline;
  if (args.baseline) {
    bool cached = false;
    const ExemplarAnalysis analysis = analyzeExemplar(run, exemplar, {}, cached);
    Stage stage(run.ctx(), "2-D baseline");
    baseline = measureSynthesisBaseline(analysis, exemplar, image.width, image.height, args.fidelity, stage.inner());
    stage.finish(std::to_string(image.width) + "x" + std::to_string(image.height));
  }

  std::printf("fidelity             %.4f   (7x7 RMS distance to the nearest exemplar neighborhood; lower is better)\n",
              q.fidelity);
  std::printf("completeness         %.4f   (the reverse: exemplar neighborhoods to the image's nearest; lower is better)\n",
              q.completeness);
  std::printf("histogram distance   %.4f   (largest per-channel earth mover's distance)\n", q.histogramDistance);
  std::printf("contrast ratio       %.4f   (luminance standard deviation, image / exemplar; 1 = kept)\n", q.contrast);
  if (std::isnan(q.shiftedCorrelation))
    std::printf("shifted correlation  n/a      (image not larger than the exemplar)\n");
  else
    std::printf("shifted correlation  %.4f   (1 = repeats with the exemplar's period)\n", q.shiftedCorrelation);
  if (q.coherence) std::printf("coherence            %.4f   (1 = verbatim tiling, 0 = noise)\n", *q.coherence);
  if (q.coverage) std::printf("coverage             %.4f   (fraction of the exemplar used)\n", *q.coverage);
  if (baseline) {
    std::printf("fidelity ratio       %.4f   (fidelity / a 2-D synthesis' of the same size, %.4f; 1 = as faithful)\n",
                q.fidelity / baseline->fidelity, baseline->fidelity);
    std::printf("completeness ratio   %.4f   (completeness / the same 2-D synthesis', %.4f; 1 = shows as much of it)\n",
                q.completeness / baseline->completeness, baseline->completeness);
    std::printf("2-D histogram dist.  %.4f   (the same 2-D synthesis')\n", baseline->histogramDistance);
    std::printf("2-D contrast ratio   %.4f   (the same 2-D synthesis')\n", baseline->contrast);
  }

  std::optional<LatticeSteps> steps;
  double correlation = 0;
  if (args.latticePeriod > 0) {
    steps = latticeSteps(image, args.latticePeriod, 0, 0);
    correlation = latticeCorrelation(image, args.latticePeriod);
    std::printf("lattice seam ratio   %.4f   (mean step into and out of the planes every %d pixels over inside; 1 = "
                "they do not show)\n",
                steps->seamRatio(), args.latticePeriod);
    std::printf("lattice peak step    %.4f   (largest mean step at an offset over the median offset's)\n",
                steps->peak());
    std::printf("lattice correlation  %.4f   (shifted self-correlation at the period and its multiples; 0 = none)\n",
                correlation);
  }

  run.report() = baseline ? toJson(q, *baseline) : toJson(q);
  if (steps)
    run.report()["lattice"] = {{"period", args.latticePeriod},
                               {"seam_ratio", steps->seamRatio()},
                               {"peak_step", steps->peak()},
                               {"correlation", correlation}};
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
  f.flag("--baseline-2d", job->baseline,
         "Also measure a 2-D synthesis of the image's size from the exemplar (seed 1, default options) and give "
         "the image's fidelity relative to it: for slices of a solid texture, 1 = as faithful as 2-D synthesis");
  f.option("--lattice-period", job->latticePeriod,
           "Also measure a lattice of planes this many pixels apart, starting at pixel 0 (a slice of solid tiles: "
           "the tile size, at voxel size 1 and a plane through voxel 0): the step across its planes and the image's "
           "self-correlation at the period (0 = off)",
           {0, 65536});
  f.common(job->common, Common::Threads | Common::Memory | Common::Report | Common::Cache | Common::Quiet);
  return {f.app(), [job] { runStats(*job); }};
}

} // namespace texfab::cli
