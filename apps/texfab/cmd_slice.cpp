// SPDX-License-Identifier: GPL-3.0-or-later
// texfab slice: a closed model to one image per print layer for full-colour material jetting
// (PolyJet and similar), coloured from the model's texture or a solid texture, dithered to the
// printer's materials; texfab merge-slices: shards of one print (--layers, --shard) into one.
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "geometry/close_holes.h"
#include "geometry/mesh_io.h"
#include "geometry/print_grid.h"
#include "geometry/voxelize_layers.h"
#include "render/image/error.h"
#include "render/image/image_io.h"
#include "render/image/memory.h"
#include "render/slice_model.h"
#include "render/texture_mesh.h"
#include "render/voxel_colors.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <optional>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct SliceArgs {
  std::string model, output;
  double height = 50, scale = 0, layer = 0.027, shell = 1.0;
  std::string dpi = "600,300", layers, shard;
  std::string exemplar, mode = "solid", materials, core = "white", dither = "blue-noise", format = "png";
  double textureScale = 0, featureSize = 0;
  uint32_t seed = 1;
  int resolution = 2048;
  std::string preview, report, cacheDir;
  int threads = 0;
  bool force = false, noCache = false, quiet = false;
};

// Layers written, on stderr: on a terminal one line redrawn in place
// ("texfab slice: [######....] 412/1000 layers  85.3 layers/s  7 s left"), elsewhere a line per
// tenth. Silent when quiet. update() is thread-safe.
class LayerProgress {
public:
  LayerProgress(int64_t total, bool quiet) : total_(total), quiet_(quiet), terminal_(isatty(2) != 0) {}
  void update(double fraction) {
    std::lock_guard lock(mutex_);
    if (quiet_ || (!terminal_ && int(fraction * 10) <= tenths_)) return;
    tenths_ = int(fraction * 10);
    draw(fraction, false);
  }
  void finish() {
    std::lock_guard lock(mutex_);
    if (!quiet_) draw(1.0, true);
  }

private:
  void draw(double fraction, bool last) const {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    const int64_t done = int64_t(fraction * double(total_) + 0.5);
    const double rate = seconds > 0 ? double(done) / seconds : 0.0;
    std::string bar(size_t(fraction * 30), '#');
    bar.resize(30, '.');
    char left[32] = "";
    if (!last && rate > 0) std::snprintf(left, sizeof left, "  %.0f s left", double(total_ - done) / rate);
    std::fprintf(stderr, "%stexfab slice: [%s] %lld/%lld layers  %.1f layers/s%s%s", terminal_ ? "\r" : "", bar.c_str(),
                 (long long)done, (long long)total_, rate, left, terminal_ ? "\x1b[K" : "");
    if (last || !terminal_) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }
  int64_t total_;
  bool quiet_, terminal_;
  int tenths_ = -1;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  std::mutex mutex_;
};

// --layers A:B (B exclusive) or --shard I/K (the I-th of K near-equal ranges) into first, count.
std::pair<int, int> layerRange(const SliceArgs& a, int layers) {
  if (!a.layers.empty() && !a.shard.empty()) throw Error("give --layers or --shard, not both");
  if (!a.shard.empty()) {
    const size_t slash = a.shard.find('/');
    if (slash == std::string::npos) throw Error("--shard: expected I/K (e.g. 3/8), got '" + a.shard + "'");
    const std::vector<double> v = parseNumberList(a.shard.substr(0, slash) + "," + a.shard.substr(slash + 1), "--shard");
    const int64_t i = int64_t(v[0]), k = int64_t(v[1]);
    if (v[0] != double(i) || v[1] != double(k) || k < 1 || i < 0 || i >= k)
      throw Error("--shard: expected I/K with 0 <= I < K, got '" + a.shard + "'");
    const int first = int(i * layers / k), end = int((i + 1) * layers / k);
    if (first == end) throw Error("--shard " + a.shard + ": no layers (the print has " + std::to_string(layers) + ")");
    return {first, end - first};
  }
  if (a.layers.empty()) return {0, layers};
  const size_t colon = a.layers.find(':');
  if (colon == std::string::npos) throw Error("--layers: expected A:B (layers A to B-1), got '" + a.layers + "'");
  const std::vector<double> v = parseNumberList(a.layers.substr(0, colon) + "," + a.layers.substr(colon + 1), "--layers");
  if (v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]) || v[0] < 0 || v[1] <= v[0] || v[1] > layers)
    throw Error("--layers " + a.layers + ": expected 0 <= A < B <= " + std::to_string(layers) + " (the print's layers)");
  return {int(v[0]), int(v[1] - v[0])};
}

render::SliceOptions sliceOptions(const SliceArgs& a) {
  render::SliceOptions o;
  if (a.dither == "blue-noise") o.dither = render::DitherMode::BlueNoise;
  else if (a.dither == "floyd-steinberg") o.dither = render::DitherMode::FloydSteinberg;
  else if (a.dither == "none") o.dither = render::DitherMode::None;
  else throw Error("--dither: expected blue-noise, floyd-steinberg or none, got '" + a.dither + "'");
  if (a.format == "png") o.format = render::SliceFormat::Indexed;
  else if (a.format == "voxelprint") o.format = render::SliceFormat::VoxelPrint;
  else throw Error("--format: expected png or voxelprint, got '" + a.format + "'");
  if (!a.materials.empty()) o.materials = render::readPrintMaterials(a.materials);
  o.coreMaterial = a.core;
  o.preview = !a.preview.empty();
  o.validate();
  return o;
}

geometry::PrintGrid gridFor(const SliceArgs& a, const geometry::Mesh& mesh) {
  geometry::PrintGridOptions o;
  const std::vector<double> dpi = parseNumberList(a.dpi, "--dpi");
  if (dpi.size() > 2) throw Error("--dpi: expected X or X,Y, got '" + a.dpi + "'");
  o.dpiX = dpi[0];
  o.dpiY = dpi.size() == 2 ? dpi[1] : dpi[0];
  o.heightMm = a.height;
  o.mmPerUnit = a.scale;
  if (!(a.scale >= 0)) throw Error("--scale must be a positive number of mm per model unit");
  o.layerMm = a.layer;
  return geometry::printGrid(geometry::boundingBox(mesh), o);
}

// The model coloured by surface synthesis (texfab texture's surface mode), for --mode surface.
geometry::Mesh surfaceTextured(const SliceArgs& a, const geometry::Mesh& mesh, const Image& exemplar, Progress& progress) {
  render::TextureMeshOptions o;
  o.atlas.pack.width = o.atlas.pack.height = a.resolution;
  o.atlas.pack.validate();
  o.surface.seed = a.seed;
  o.measure = false;
  o.textureScale = a.featureSize > 0 ? std::max(exemplar.width, exemplar.height) / a.featureSize : a.textureScale;
  progress.start("analysis");
  const Context threads{.threads = a.threads};
  const synthesis::ExemplarAnalysis analysis =
      a.noCache ? synthesis::analyzeExemplar(exemplar, {}, threads)
                : synthesis::analyzeExemplarCached(exemplar, {}, a.cacheDir.empty() ? synthesis::defaultCacheDir() : fs::path(a.cacheDir), threads);
  progress.finish();
  render::TextureExemplar ex;
  ex.color = &exemplar;
  ex.analysis = &analysis;
  Context ctx{.threads = a.threads};
  ctx.progress = [&](const ProgressEvent& e) {
    if (e.kind == ProgressEvent::Kind::End) progress.record(std::string(e.stage), e.seconds, std::string(e.detail));
  };
  return render::textureMesh(mesh, ex, o, ctx).mesh;
}

void runSlice(const SliceArgs& a) {
  Progress progress("texfab slice", a.quiet);
  render::SliceOptions options = sliceOptions(a);
  if (a.mode != "solid" && a.mode != "surface") throw Error("--mode: expected solid or surface, got '" + a.mode + "'");
  if (a.textureScale != 0 && a.featureSize != 0) throw Error("give --texture-scale or --feature-size, not both");
  if (!(a.textureScale >= 0 && std::isfinite(a.textureScale)) || !(a.featureSize >= 0 && std::isfinite(a.featureSize)))
    throw Error("--texture-scale and --feature-size must be positive");
  if (!a.preview.empty()) checkImageWritable(a.preview);
  geometry::VoxelizeOptions voxelize;
  voxelize.shellMm = a.shell;
  voxelize.validate();
  render::SliceWriter writer(a.output, a.force);  // refuses a non-empty output before any work

  progress.start("load");
  geometry::Mesh mesh = geometry::readMesh(a.model);
  if (const geometry::CloseHolesReport holes = geometry::closeHoles(mesh); holes.holes > 0)
    progress.note("closed " + std::to_string(holes.holes) + " holes (" + std::to_string(holes.boundaryEdges) +
                  " boundary edges) with fans of triangles");
  std::optional<Image> exemplar;
  if (!a.exemplar.empty()) exemplar = readImage(a.exemplar);
  const geometry::PrintGrid grid = gridFor(a, mesh);
  const auto [first, count] = layerRange(a, grid.layers);
  options.firstLayer = first;
  options.layerCount = count;
  const uint64_t needed = render::sliceMemoryBytes(grid, options, a.threads > 0 ? a.threads : 16);
  if (needed > uint64_t(0.8 * double(physicalMemoryBytes())))
    throw Error("one layer of " + std::to_string(grid.width) + " x " + std::to_string(grid.height) +
                " voxels needs up to " + std::to_string(needed >> 30) + " GiB with its batch, more than this machine has: "
                "lower --dpi or the size");
  progress.finish(a.model + ": " + std::to_string(mesh.triangleCount()) + " triangles; print " +
                  std::to_string(grid.width) + " x " + std::to_string(grid.height) + " x " + std::to_string(grid.layers) +
                  " voxels");

  nlohmann::ordered_json source;
  source["model"] = fs::path(a.model).filename().string();
  std::unique_ptr<render::VoxelColorSource> colors;
  std::optional<synthesis::SolidAnalysis> solid;
  if (exemplar && a.mode == "solid") {
    synthesis::validateSolidExemplars(*exemplar, *exemplar, *exemplar);
    progress.start("analysis");
    const Context threads{.threads = a.threads};
    solid = a.noCache ? synthesis::analyzeSolid(*exemplar, *exemplar, *exemplar, {}, threads)
                      : synthesis::analyzeSolidCached(*exemplar, *exemplar, *exemplar, {},
                                                      a.cacheDir.empty() ? synthesis::defaultCacheDir() : fs::path(a.cacheDir), threads);
    progress.finish();
    synthesis::SolidSynthesisOptions so;
    so.seed = a.seed;
    // Default: one exemplar spans a quarter of the model's height.
    const geometry::BoundingBox box = geometry::boundingBox(mesh);
    const double span = a.featureSize > 0 ? a.featureSize : (box.max.z() - box.min.z()) / 4;
    const double scale = a.textureScale > 0 ? a.textureScale : std::max(exemplar->width, exemplar->height) / span;
    colors = std::make_unique<render::SolidVoxelColors>(*solid, *exemplar, *exemplar, *exemplar, so, scale, grid);
    source["colors"] = {{"mode", "solid"}, {"exemplar", fs::path(a.exemplar).filename().string()}, {"seed", a.seed},
                        {"texture_scale", scale}};
  } else {
    if (exemplar) mesh = surfaceTextured(a, mesh, *exemplar, progress);
    colors = std::make_unique<render::SurfaceVoxelColors>(mesh, grid, a.shell);
    source["colors"] = exemplar ? nlohmann::ordered_json{{"mode", "surface"}, {"exemplar", fs::path(a.exemplar).filename().string()},
                                                         {"seed", a.seed}}
                                : nlohmann::ordered_json{{"mode", "model"}};
  }

  progress.start("voxelizer");
  const geometry::LayerVoxelizer voxelizer(mesh, grid, voxelize);
  for (const std::string& repair : voxelizer.report().repairs) progress.note(repair);
  progress.finish();

  LayerProgress bar(count, a.quiet);
  Context ctx{.threads = a.threads};
  ctx.progress = [&](const ProgressEvent& e) {
    if (e.kind == ProgressEvent::Kind::Advance && e.depth == 0 && e.stage == "slice") bar.update(e.fraction);
  };
  const render::SliceResult result = render::sliceModel(voxelizer, *colors, options, writer, source, ctx);
  bar.finish();
  const render::SliceReport& r = result.report;
  progress.record("slice", r.seconds, std::to_string(r.layers) + " layers in " + a.output + ", " +
                                          std::to_string(r.shellVoxels) + " shell voxels of " + std::to_string(r.insideVoxels));
  if (result.preview) {
    writeImage(*result.preview, a.preview);
    progress.note("preview: " + a.preview);
  }
  if (!a.report.empty()) {
    nlohmann::json report;
    report["command"] = "slice";
    report["print"] = nlohmann::json::parse(render::slicePrintInfo(grid, options, a.shell, source).dump());
    report["layers"] = {{"first", first}, {"count", count}, {"total", grid.layers}};
    report["voxels"] = {{"inside", r.insideVoxels}, {"shell", r.shellVoxels}, {"per_layer", grid.voxelsPerLayer()}};
    if (auto* s = dynamic_cast<const render::SolidVoxelColors*>(colors.get()))
      report["solid"] = {{"voxels_requested", s->voxelsRequested()}, {"voxels_synthesized", s->voxelsSynthesized()}};
    report["bytes"] = r.bytes;
    report["seconds"] = {{"total", r.seconds}, {"voxelize_cpu", r.voxelizeSeconds}, {"prepare_colors", r.prepareSeconds},
                         {"colors_cpu", r.colorSeconds}, {"dither_cpu", r.ditherSeconds}, {"encode_cpu", r.encodeSeconds},
                         {"write_cpu", r.writeSeconds}};
    report["layers_per_second"] = r.layers / std::max(1e-9, r.seconds);
    report["timings"] = progress.timings();
    report["peak_memory_mib"] = peakMemoryMiB();
    writeReport(report, a.report);
  }
}

struct MergeArgs {
  std::vector<std::string> shards;
  std::string output;
  bool force = false;
};

} // namespace

Command addSliceCommand(CLI::App& root) {
  auto a = std::make_shared<SliceArgs>();
  CLI::App* app = root.add_subcommand(
      "slice", "Slice a closed model into one image per print layer for full-colour 3D printing: every voxel one "
               "material, coloured from the model's texture or a solid texture and dithered");
  app->add_option("model", a->model, "Closed model (.obj .ply .off .stl .gltf .glb .3mf)")->required();
  app->add_option("-o,--output", a->output, "Output folder: slice_00000.png ... and slices.json")->required();
  app->add_option("--height", a->height, "Print height in mm (the model's z extent)")->capture_default_str();
  app->add_option("--scale", a->scale, "Millimetres per model unit (instead of --height)");
  app->add_option("--dpi", a->dpi, "Printer resolution X[,Y] in dots per inch")->capture_default_str();
  app->add_option("--layer", a->layer, "Layer thickness in mm")->capture_default_str();
  app->add_option("--layers", a->layers, "Only layers A to B-1 (A:B), byte for byte as in a full run");
  app->add_option("--shard", a->shard, "Only the I-th of K equal layer ranges (I/K, 0-based; for job arrays)");
  app->add_option("--shell", a->shell, "Colour voxels within this distance of the surface, in mm; deeper ones get "
                                       "the core material")->capture_default_str();
  app->add_option("--core", a->core, "Material of the core")->capture_default_str();
  app->add_option("--materials", a->materials, "Printer materials (JSON: name, color #RRGGBB, opacity); "
                                               "default: Vero cyan, magenta, yellow, black, white, clear");
  app->add_option("--dither", a->dither, "blue-noise (3-D, position-based), floyd-steinberg (within each layer) "
                                         "or none (write the continuous colour)")->capture_default_str();
  app->add_option("--format", a->format, "png (indexed, material colours) or voxelprint (RGBA, empty voxels "
                                         "transparent, as GrabCAD Voxel Print reads)")->capture_default_str();
  app->add_option("-e,--exemplar", a->exemplar, "Colour from this exemplar's texture instead of the model's own");
  app->add_option("--mode", a->mode, "With --exemplar: solid (the solid texture of texfab texture --mode solid) "
                                     "or surface (synthesize over the surface first)")->capture_default_str();
  app->add_option("--texture-scale", a->textureScale, "Exemplar pixels per model unit, as texfab texture's --scale "
                                                      "(default: an exemplar spans a quarter of the model's height)");
  app->add_option("--feature-size", a->featureSize, "Model units one exemplar spans (instead of --texture-scale)");
  app->add_option("--seed", a->seed, "Random seed of the synthesis")->capture_default_str();
  app->add_option("--resolution", a->resolution, "Atlas size for --mode surface")->capture_default_str();
  app->add_option("--preview", a->preview, "Also write a picture of the print (front, side, four layers) to this PNG");
  app->add_option("--report", a->report, "Write figures and timings as JSON");
  app->add_option("--threads", a->threads, "Worker threads (0 = all cores); the output does not depend on it")
      ->capture_default_str();
  app->add_flag("--force", a->force, "Replace an existing, non-empty output folder");
  app->add_option("--cache-dir", a->cacheDir, "Exemplar analysis cache folder (default: ~/.cache/texfab)");
  app->add_flag("--no-cache", a->noCache, "Neither read nor write the analysis cache");
  app->add_flag("-q,--quiet", a->quiet, "No progress output");
  return {app, [a] { runSlice(*a); }};
}

Command addMergeSlicesCommand(CLI::App& root) {
  auto a = std::make_shared<MergeArgs>();
  CLI::App* app = root.add_subcommand("merge-slices", "Join the shards of one print (texfab slice --layers or "
                                                      "--shard) into the folder a full run writes");
  app->add_option("shards", a->shards, "Shard folders, in any order")->required();
  app->add_option("-o,--output", a->output, "Output folder")->required();
  app->add_flag("--force", a->force, "Replace an existing, non-empty output folder");
  return {app, [a] {
            std::vector<fs::path> shards(a->shards.begin(), a->shards.end());
            render::mergeSliceFolders(shards, a->output, a->force);
          }};
}

} // namespace texfab::cli
