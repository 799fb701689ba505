// SPDX-License-Identifier: GPL-3.0-or-later
// texfab synth: 2-D texture synthesis from an exemplar (Lefebvre & Hoppe 2005/2006).
#include "apps/texfab/backend_flags.h"
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "render/image/error.h"
#include "render/image/memory.h"
#include "render/image/image_io.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"

#include <memory>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct SynthArgs {
  std::string exemplar;
  std::string output;
  std::string size = "512x512";
  std::string window;
  uint32_t seed = 1;
  std::string jitter;
  int passes = 2;
  int interleave = 2;
  int k = 2;
  float featureWeight = synthesis::AnalysisOptions{}.featureWeight;
  bool tileable = false;
  std::string coords;
  std::vector<std::string> apply;
  int threads = 0;
  BackendFlags backend;
  std::string report;
  std::string cacheDir;
  bool noCache = false;
  bool quiet = false;
};

struct Companion {
  fs::path output;
  Image map;
};

void runSynth(const SynthArgs& args) {
  using namespace synthesis;
  Progress progress("texfab synth", args.quiet);
  Context ctx{.threads = args.threads};
  if (const std::string line = applyBackend(args.backend, ctx); !line.empty()) progress.note("backend: " + line);

  // Everything that can be checked before the work is checked first: a bad argument never costs
  // a synthesis, and a failure never leaves some outputs written and others not.
  Window window;
  if (!args.window.empty()) {
    const std::vector<double> v = parseNumberList(args.window, "--window");
    if (v.size() != 4) throw Error("--window: expected X,Y,W,H, got '" + args.window + "'");
    for (double d : v)
      if (d != std::floor(d)) throw Error("--window: values must be integers, got '" + args.window + "'");
    if (v[2] < 1 || v[3] < 1 || v[2] > kMaxImageSide || v[3] > kMaxImageSide)
      throw Error("--window: size is out of range (1 to " + std::to_string(kMaxImageSide) + " per side)");
    window = {int64_t(v[0]), int64_t(v[1]), int(v[2]), int(v[3])};
  } else {
    const auto [w, h] = parseSize(args.size, "--size");
    window = {0, 0, w, h};
  }
  SynthesisOptions options;
  options.seed = args.seed;
  options.passes = args.passes;
  options.interleave = args.interleave;
  if (!args.jitter.empty())
    for (double j : parseNumberList(args.jitter, "--jitter")) options.jitter.push_back(float(j));
  if (args.tileable) {
    if (!args.window.empty()) throw Error("--tileable and --window cannot be combined (the tile is the output size)");
    options.periodX = window.width;
    options.periodY = window.height;
  }
  options.validate();
  AnalysisOptions analysisOptions;
  analysisOptions.k = args.k;
  analysisOptions.featureWeight = args.featureWeight;
  analysisOptions.validate();

  checkImageWritable(args.output);
  if (!args.coords.empty()) checkImageWritable(args.coords);

  progress.start("load");
  const Image exemplar = readImage(args.exemplar);
  try {
    validateExemplarSize(exemplar);
  } catch (const Error& e) {
    throw Error(args.exemplar + ": " + e.what());
  }
  std::vector<Companion> companions;
  for (const std::string& spec : args.apply) {
    const size_t colon = spec.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == spec.size())
      throw Error("--apply: expected MAP:OUT, got '" + spec + "'");
    Companion companion{spec.substr(colon + 1), readImage(spec.substr(0, colon))};
    if (companion.map.width != exemplar.width || companion.map.height != exemplar.height)
      throw Error(spec.substr(0, colon) + ": companion map is " + std::to_string(companion.map.width) + "x" +
                  std::to_string(companion.map.height) + " but the exemplar is " + std::to_string(exemplar.width) +
                  "x" + std::to_string(exemplar.height));
    checkImageWritable(companion.output);
    companions.push_back(std::move(companion));
  }
  progress.finish(args.exemplar + " " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height));

  // Coordinates (two buffers while synthesizing) plus the colour and companion images, as floats.
  int channels = exemplar.channels;
  for (const Companion& c : companions) channels += c.map.channels;
  const double needed = double(window.width) * window.height * (12.0 + 4.0 * channels);
  if (needed > 0.8 * double(physicalMemoryBytes()))
    throw Error("a " + std::to_string(window.width) + "x" + std::to_string(window.height) + " output needs about " +
                std::to_string(int(needed / double(1 << 30)) + 1) + " GiB, more than this machine's memory; " +
                "synthesize it in windows (--window) instead");

  progress.start("analysis");
  bool cached = false;
  const ExemplarAnalysis analysis =
      args.noCache ? analyzeExemplar(exemplar, analysisOptions, ctx)
                   : analyzeExemplarCached(exemplar, analysisOptions,
                                           args.cacheDir.empty() ? defaultCacheDir() : fs::path(args.cacheDir),
                                           ctx, &cached);
  progress.finish(cached ? "(cached)" : std::to_string(analysis.levels.size()) + " levels");

  if (const int first = firstSynthesisLevel(int(analysis.levels.size()), options); first > 0) {
    const int full = options.interleave << (analysis.levels.size() - 1);
    progress.note("tileable: a " + std::to_string(window.width) + "x" + std::to_string(window.height) +
                  " tile allows " + std::to_string(analysis.levels.size() - size_t(first)) + " of " +
                  std::to_string(analysis.levels.size()) + " levels; sizes that are multiples of " +
                  std::to_string(full) + " keep the whole multiresolution synthesis");
  }

  progress.start("synthesis");
  const SynthesisResult result = synthesize2d(analysis, window, options, ctx);
  progress.finish(std::to_string(window.width) + "x" + std::to_string(window.height));

  progress.start("resolve");
  const Image colours = applyCoords(result.coords, exemplar, ctx);
  std::vector<Image> applied;
  for (const Companion& c : companions) applied.push_back(applyCoords(result.coords, c.map, ctx));
  progress.finish();

  nlohmann::json report;
  if (!args.report.empty()) {
    progress.start("measures");
    const QualityReport q = measureQuality(colours, exemplar, &result.coords, {}, ctx);
    report["measures"] = {{"fidelity", q.fidelity},
                          {"histogram_distance", q.histogramDistance},
                          {"shifted_correlation", q.shiftedCorrelation},
                          {"coherence", *q.coherence},
                          {"coverage", *q.coverage}};
    progress.finish();
  }

  progress.start("write");
  writeImage(colours, args.output);
  if (!args.coords.empty()) writeCoordMap(result.coords, args.coords);
  for (size_t i = 0; i < companions.size(); ++i) writeImage(applied[i], companions[i].output);
  progress.finish(args.output);

  if (!args.report.empty()) {
    report["command"] = "synth";
    report["exemplar"] = {{"path", args.exemplar}, {"width", exemplar.width}, {"height", exemplar.height},
                          {"channels", exemplar.channels}, {"levels", analysis.levels.size()},
                          {"analysis_cached", cached}};
    report["window"] = {{"x", window.x}, {"y", window.y}, {"width", window.width}, {"height", window.height}};
    report["parameters"] = {{"seed", options.seed},    {"passes", options.passes},
                            {"interleave", options.interleave}, {"k", analysisOptions.k},
                            {"feature_weight", analysisOptions.featureWeight},
                            {"tileable", args.tileable},
                            {"jitter", options.jitter.empty() ? defaultJitter(int(analysis.levels.size())) : options.jitter}};
    nlohmann::json levels = nlohmann::json::array();
    for (const LevelStats& l : result.levels)
      levels.push_back({{"level", l.level}, {"texels", l.texels}, {"seconds", l.seconds}});
    report["levels"] = levels;
    report["timings"] = progress.timings();
    report["peak_memory_mib"] = peakMemoryMiB();
    writeReport(report, args.report);
  }
}

} // namespace

Command addSynthCommand(CLI::App& root) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* app = root.add_subcommand("synth", "Synthesize a texture of any size from a small exemplar image "
                                               "(parallel appearance-space synthesis, Lefebvre & Hoppe 2005/2006)");
  app->add_option("exemplar", args->exemplar, "Exemplar image (PNG, JPEG, TGA, TIFF, EXR, GIMP .pat)")->required();
  app->add_option("-o,--output", args->output, "Output image (.png, .exr, .tif, ...)")->required();
  app->add_option("--size", args->size, "Output size WxH (or N for NxN)")->capture_default_str();
  app->add_option("--window", args->window,
                  "Synthesize the window X,Y,W,H of the infinite texture plane instead of --size; "
                  "overlapping windows agree texel for texel (X, Y may be negative)");
  app->add_option("--seed", args->seed, "Random seed: the only source of variation")->capture_default_str();
  app->add_option("--jitter", args->jitter,
                  "Jitter strength in [0,1]: one value for every level, or one per level coarsest first "
                  "(default 1,1,1,0.5,0...: randomize the large-scale layout only; 0 gives an exact tiling)");
  app->add_option("--passes", args->passes, "Correction passes per level")->capture_default_str();
  app->add_option("--interleave", args->interleave, "Sub-pass interleave: 1, 2 (4 sub-passes) or 3 (9)")
      ->capture_default_str();
  app->add_option("--k", args->k, "k-coherence candidates per exemplar pixel (1-8)")->capture_default_str();
  app->add_option("--feature-weight", args->featureWeight,
                  "Weight of the feature-distance channel in appearance space (0 = off)")
      ->capture_default_str();
  app->add_flag("--tileable", args->tileable, "Make the output wrap at its size (a tile)");
  app->add_option("--coords", args->coords, "Also write the coordinate map (16-bit .png/.tif or .exr)");
  app->add_option("--apply", args->apply,
                  "MAP:OUT: apply the same coordinates to a companion map of the exemplar (normal, "
                  "roughness, height; same size as the exemplar) and write OUT (repeatable)");
  app->add_option("--threads", args->threads, "Worker threads (0 = all cores)")->capture_default_str();
  addBackendFlags(*app, args->backend);
  app->add_option("--report", args->report, "Write timings and quality measures to this JSON file");
  app->add_option("--cache-dir", args->cacheDir, "Exemplar analysis cache folder (default: ~/.cache/texfab)");
  app->add_flag("--no-cache", args->noCache, "Neither read nor write the analysis cache");
  app->add_flag("-q,--quiet", args->quiet, "No progress output");
  return {app, [args] { runSynth(*args); }};
}

} // namespace texfab::cli
