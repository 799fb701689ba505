// SPDX-License-Identifier: GPL-3.0-or-later
// texfab synth: 2-D texture synthesis from an exemplar (Lefebvre & Hoppe 2005/2006).
#include "apps/texfab/analysis.h"
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "apps/texfab/report_json.h"
#include "core/image_io.h"
#include "core/memory.h"
#include "core/text.h"
#include "synthesis/coord_map.h"
#include "synthesis/graph_file.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"
#include "synthesis/synthesize_graph.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

// A tile only a few times the exemplar's size can converge to the exemplar repeated: on so small
// a torus the correction passes reach the exact tiling. Above this shifted self-correlation at the
// exemplar's period (as `texfab stats` measures repetition) synth warns; below it a tile does not
// look repeated. Tiles larger than kRepetitionCheckedUpTo times the exemplar are not measured.
constexpr double kRepetitionLimit = 0.25;
constexpr int kRepetitionCheckedUpTo = 8;

struct SynthJob {
  std::string exemplar, graph, output, coords;
  double zoom = 1;
  std::vector<std::string> apply;
  synthesis::Window window{0, 0, 512, 512};
  bool windowGiven = false, tileable = false;
  WrapChoice wrap = WrapChoice::Auto;
  synthesis::SynthesisOptions options;
  synthesis::AnalysisOptions analysis;
  CommonFlags common;
};

// --apply MAP:OUT: a companion map of the exemplar (with --graph: the name of the graph's map),
// resolved through the same coordinates.
struct Companion {
  std::string input;
  fs::path output;  // staged
  Image map;
};

std::vector<Companion> reserveCompanions(const SynthJob& job, Run& run) {
  std::vector<Companion> companions;
  for (const std::string& spec : job.apply) {
    const size_t colon = spec.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == spec.size())
      throw UsageError("--apply: expected MAP:OUT, got '" + spec + "'");
    checkImageWritable(spec.substr(colon + 1));
    companions.push_back({spec.substr(0, colon), run.output(spec.substr(colon + 1)), {}});
  }
  return companions;
}

bool checksRepetition(const SynthJob& job, int exemplarWidth, int exemplarHeight) {
  const synthesis::Window& w = job.window;
  return job.tileable && w.width > exemplarWidth && w.height > exemplarHeight &&
         w.width <= kRepetitionCheckedUpTo * exemplarWidth && w.height <= kRepetitionCheckedUpTo * exemplarHeight;
}

// A tileable output's repetition, into the report ("repetition") and, above the limit, a warning.
void checkRepetition(const SynthJob& job, const Image& colors, const Image& exemplar, Run& run) {
  if (!checksRepetition(job, exemplar.width, exemplar.height)) return;
  const double correlation = synthesis::shiftedSelfCorrelation(colors, exemplar.width, exemplar.height);
  const bool repeats = correlation > kRepetitionLimit;
  if (run.reporting())
    run.report()["repetition"] = {{"shifted_correlation", correlation}, {"limit", kRepetitionLimit},
                                  {"repeats", repeats}};
  if (!repeats) return;
  char message[320];
  std::snprintf(message, sizeof message,
                "the %dx%d tile repeats its %dx%d exemplar (self-correlation %.2f at the exemplar's period, above "
                "%.2f): try another --seed, or a tile of at least %dx%d",
                colors.width, colors.height, exemplar.width, exemplar.height, correlation, kRepetitionLimit,
                4 * exemplar.width, 4 * exemplar.height);
  run.ctx().warn(message);
}

Image load(const SynthJob& job, std::vector<Companion>& companions, const Run& run) {
  Stage stage(run.ctx(), "load");
  Image exemplar = readImage(job.exemplar);
  try {
    synthesis::validateExemplarSize(exemplar);
  } catch (const Error& e) {
    throw Error(job.exemplar + ": " + e.what());
  }
  int channels = exemplar.channels;
  for (Companion& c : companions) {
    c.map = readImage(c.input);
    if (c.map.width != exemplar.width || c.map.height != exemplar.height)
      throw Error(c.input + ": companion map is " + std::to_string(c.map.width) + "x" + std::to_string(c.map.height) +
                  " but the exemplar is " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height));
    channels += c.map.channels;
  }
  if (checksRepetition(job, exemplar.width, exemplar.height)) ++channels;  // the luminance it measures
  run.checkMemory(synthesis::synthesize2dMemoryBytes(job.window, channels) +
                      synthesis::analysisMemoryBytes(exemplar.width, exemplar.height, job.analysis),
                  "a " + std::to_string(job.window.width) + "x" + std::to_string(job.window.height) + " output from a " +
                      std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) +
                      " exemplar (synthesize it in windows, --window)");
  stage.finish(job.exemplar + " " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height));
  return exemplar;
}

// synth --graph: multiscale synthesis from an exemplar graph (Han et al. 2008), at --zoom.
void runGraphSynth(const SynthJob& job) {
  using namespace synthesis;
  Run run("synth", job.common);
  GraphSynthesisOptions options;
  options.seed = job.options.seed;
  options.jitter = job.options.jitter;
  options.passes = job.options.passes;
  options.interleave = job.options.interleave;
  if (job.tileable) {
    if (job.windowGiven) throw UsageError("--tileable and --window cannot be combined (the tile is the output size)");
    options.periodX = job.window.width;
    options.periodY = job.window.height;
  }
  try {
    options.zoomOctaves = graphZoomOctaves(job.zoom);
  } catch (const Error& e) {
    throw UsageError(std::string("--") + e.what());
  }
  checkImageWritable(job.output);
  const fs::path out = run.output(job.output);
  if (!job.coords.empty()) checkImageWritable(job.coords);
  const fs::path coordsOut = job.coords.empty() ? fs::path() : run.output(job.coords);
  std::vector<Companion> companions = reserveCompanions(job, run);  // MAP: a map name of the graph

  Stage load(run.ctx(), "load");
  const ExemplarGraph graph = readExemplarGraph(job.graph);
  const int rootOctaves = graph.rootOctaves();
  options.zoomOctaves -= rootOctaves;  // --zoom counts pixels of the root as given
  for (Companion& c : companions) {
    const GraphMap* map = graph.map(c.input);
    if (!map) throw UsageError("--apply " + c.input + ": " + job.graph + " gives no '" + c.input + "' map");
    c.map = graphMapAtlas(*map);
  }
  run.checkMemory(graphAnalysisMemoryBytes(int(graph.exemplars.size()), graph.side()) +
                      synthesizeGraphMemoryBytes(job.window),
                  "a " + std::to_string(job.window.width) + "x" + std::to_string(job.window.height) +
                      " output from a graph of " + std::to_string(graph.exemplars.size()) + " exemplars");
  load.finish(job.graph + ": " + std::to_string(graph.exemplars.size()) + " exemplars, " +
              std::to_string(graph.edges.size()) + " edges");
  bool cached = false;
  const GraphAnalysis analysis = analyzeGraph(graph, {}, run.analysisCache(), run.ctx(), &cached);
  options.validate(analysis);
  const int level = graphOutputLevel(analysis, options);
  if (const int first = graphFirstPeriodicLevel(analysis, options); first > 0)
    run.ctx().warn("a " + std::to_string(job.window.width) + "x" + std::to_string(job.window.height) + " tile at zoom " +
                   figure(job.zoom) + " wraps " + std::to_string(level + 1 - first) + " of " +
                   std::to_string(level + 1) + " levels (the coarser are cut at its edges); sizes that are "
                   "multiples of " + std::to_string(int64_t(options.interleave) << level) + " wrap them all");
  const int deepest = graph.deepestLevel();
  if (deepest >= 0 && level > deepest)
    run.ctx().warn("zoom " + figure(job.zoom) + " is finer than the graph's finest exemplar (zoom " +
                   figure(std::ldexp(1.0, deepest - analysis.finestLevel() + rootOctaves)) + "): its pixels are magnified");

  Stage synth(run.ctx(), "synthesis");
  const SynthesisResult result = synthesizeGraph(analysis, job.window, options, synth.inner());
  synth.finish(std::to_string(job.window.width) + "x" + std::to_string(job.window.height) + " at zoom " +
               figure(job.zoom));
  Stage write(run.ctx(), "write");
  writeImage(graphColors(result, analysis, run.ctx()), out);
  if (!coordsOut.empty()) writeCoordMap(result.coords, coordsOut);  // positions in the packed exemplars
  for (const Companion& c : companions) writeImage(applyCoords(result.coords, c.map, run.ctx()), c.output);
  write.finish(job.output);

  nlohmann::json& r = run.report();
  r["graph"] = {{"file", job.graph}, {"exemplars", graph.names}, {"edges", graph.edges.size()},
                {"colors", synthesis::graphColorsName(graph)}, {"side", graph.side()},
                {"root_magnification", graph.rootMagnification},
                {"deepest_level", deepest}, {"analysis_cached", cached}};
  r["window"] = {{"x", job.window.x}, {"y", job.window.y}, {"width", job.window.width}, {"height", job.window.height}};
  r["parameters"] = {{"seed", options.seed}, {"zoom", job.zoom}, {"passes", options.passes},
                     {"interleave", options.interleave}, {"tileable", job.tileable},
                     {"jitter", options.jitter.empty() ? defaultJitter(analysis.levels) : options.jitter}};
  r["levels"] = toJson(result.levels);
  run.finish();
}

void runSynth(SynthJob& job) {
  using namespace synthesis;
  if (job.exemplar.empty() == job.graph.empty())
    throw UsageError(job.graph.empty() ? "give an exemplar image (or --graph)" : "give an exemplar image or --graph, not both");
  if (!job.graph.empty()) return runGraphSynth(job);
  if (job.zoom != 1) throw UsageError("--zoom needs --graph");
  Run run("synth", job.common);
  // Everything checkable is checked, and every output reserved, before any work.
  if (job.tileable) {
    if (job.windowGiven) throw UsageError("--tileable and --window cannot be combined (the tile is the output size)");
    job.options.periodX = job.window.width;
    job.options.periodY = job.window.height;
  }
  job.options.validate();
  checkImageWritable(job.output);
  const fs::path out = run.output(job.output);
  if (!job.coords.empty()) checkImageWritable(job.coords);
  const fs::path coordsOut = job.coords.empty() ? fs::path() : run.output(job.coords);
  std::vector<Companion> companions = reserveCompanions(job, run);

  const Image exemplar = load(job, companions, run);
  job.analysis.wrap = chooseWrap(job.wrap, exemplar, run);
  bool cached = false;
  const ExemplarAnalysis analysis = analyzeExemplar(run, exemplar, job.analysis, cached);
  const int levels = int(analysis.levels.size());
  if (const int first = firstSynthesisLevel(levels, job.options); first > 0)
    run.ctx().warn("a " + std::to_string(job.window.width) + "x" + std::to_string(job.window.height) +
                   " tile allows " + std::to_string(levels - first) + " of " + std::to_string(levels) +
                   " levels; sizes that are multiples of " + std::to_string(job.options.interleave << (levels - 1)) +
                   " keep the whole multiresolution synthesis");

  Stage synth(run.ctx(), "synthesis");
  const SynthesisResult result = synthesize2d(analysis, job.window, job.options, synth.inner());
  synth.finish(std::to_string(job.window.width) + "x" + std::to_string(job.window.height));
  Stage resolve(run.ctx(), "resolve");
  const Image colors = applyCoords(result.coords, exemplar, run.ctx());
  std::vector<Image> applied;
  for (const Companion& c : companions) applied.push_back(applyCoords(result.coords, c.map, run.ctx()));
  resolve.finish();
  checkRepetition(job, colors, exemplar, run);
  if (run.reporting()) {
    Stage measures(run.ctx(), "measures");
    run.report()["measures"] = toJson(measureQuality(colors, exemplar, &result.coords, {}, run.ctx()));
    measures.finish();
  }

  Stage write(run.ctx(), "write");
  writeImage(colors, out);
  if (!coordsOut.empty()) writeCoordMap(result.coords, coordsOut);
  for (size_t i = 0; i < companions.size(); ++i) writeImage(applied[i], companions[i].output);
  write.finish(job.output);

  nlohmann::json& r = run.report();
  r["exemplar"] = imageJson(job.exemplar, exemplar);
  r["exemplar"]["levels"] = levels;
  r["exemplar"]["analysis_cached"] = cached;
  r["window"] = {{"x", job.window.x}, {"y", job.window.y}, {"width", job.window.width}, {"height", job.window.height}};
  r["parameters"] = {{"seed", job.options.seed}, {"passes", job.options.passes},
                     {"interleave", job.options.interleave}, {"k", job.analysis.k},
                     {"feature_weight", job.analysis.featureWeight}, {"tileable", job.tileable},
                     {"exemplar_wrap", toString(job.analysis.wrap)},
                     {"jitter", job.options.jitter.empty() ? defaultJitter(levels) : job.options.jitter}};
  r["levels"] = toJson(result.levels);
  run.finish();
}

} // namespace

Command addSynthCommand(CLI::App& root) {
  auto job = std::make_shared<SynthJob>();
  synthesis::SynthesisOptions& o = job->options;
  Flags f(root.add_subcommand("synth", "Synthesize a texture of any size from a small exemplar image "
                                       "(parallel appearance-space synthesis, Lefebvre & Hoppe 2005/2006)"));
  f.input("exemplar", job->exemplar, "Exemplar image (PNG, JPEG, TGA, TIFF, EXR, GIMP .pat)")->required(false);
  f.text("--graph", job->graph,
         "Synthesize from an exemplar graph instead (JSON: exemplars at several scales and the edges between "
         "them; docs/exemplar-graphs.md): structure from the largest scale to the finest");
  f.option("--zoom", job->zoom,
           "With --graph: output texels are 1/ZOOM of a root exemplar pixel (a power of two; 16 shows the "
           "exemplar an edge of scale 16 leads to at its own resolution)",
           {1.0 / 4096, 1e18});
  f.text("-o,--output", job->output, "Output image (.png, .exr, .tif, ...)")->required();
  f.size("--size", job->window.width, job->window.height, "Output size", {1, kMaxImageSide});
  f.numbers("--window", 4, "X,Y,W,H",
            "Synthesize the window X,Y,W,H of the infinite texture plane instead of --size; overlapping windows "
            "agree texel for texel (X, Y may be negative; W, H 1 to " + std::to_string(kMaxImageSide) + ")",
            {-1e15, 1e15}, true, [job](const std::vector<double>& v) {
              if (v[2] < 1 || v[3] < 1 || v[2] > kMaxImageSide || v[3] > kMaxImageSide)
                throw CLI::ValidationError("--window", "W and H must be 1 to " + std::to_string(kMaxImageSide));
              job->window = {int64_t(v[0]), int64_t(v[1]), int(v[2]), int(v[3])};
              job->windowGiven = true;
            });
  f.option("--seed", o.seed, "Random seed: the only source of variation");
  f.option("--jitter", o.jitter,
           "Jitter strength, one value for every level or one per level coarsest first (default 1,1,1,0.5,0...: "
           "randomize the large-scale layout only; 0 gives an exact tiling)",
           {0, 1});
  f.option("--passes", o.passes, "Correction passes per level", {0, 8});
  f.option("--interleave", o.interleave, "Sub-pass interleave: 1, 2 (4 sub-passes) or 3 (9)", {1, 3});
  f.option("--k", job->analysis.k, "k-coherence candidates per exemplar pixel", {1, 8});
  f.option("--feature-weight", job->analysis.featureWeight,
           "Weight of the feature-distance channel in appearance space (0 = off)", {0, 100});
  f.flag("--tileable", job->tileable,
         "Make the output wrap at its size (a tile). A tile of 2-3 times the exemplar's size may repeat the "
         "exemplar (synth warns when its self-correlation at the exemplar's period exceeds 0.25; try another "
         "--seed); at 4 times or more it stayed below on the patterns measured. With --graph, a tile wraps every "
         "scale when its size is a multiple of the interleave times 2^level (synth says so otherwise)");
  wrapFlag(f, job->wrap);
  f.text("--coords", job->coords, "Also write the coordinate map (16-bit .png/.tif or .exr)");
  f.app()->add_option("--apply", job->apply,
                      "MAP:OUT: apply the same coordinates to a companion map of the exemplar (normal, roughness, "
                      "height; same size as the exemplar) and write OUT (repeatable); with --graph, MAP names a map "
                      "the graph's exemplars give (normal, roughness or height)");
  f.common(job->common, Common::Threads | Common::Memory | Common::Report | Common::Cache | Common::Backend | Common::Quiet);
  return {f.app(), [job] { runSynth(*job); }};
}

} // namespace texfab::cli
