// SPDX-License-Identifier: GPL-3.0-or-later
// texfab slice: a closed model to one image per print layer for full-colour material jetting
// (PolyJet and similar), coloured from the model's texture or a solid texture, dithered to the
// printer's materials; texfab merge-slices: shards of one print (--layers, --shard) into one.
#include "apps/texfab/analysis.h"
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "geometry/close_holes.h"
#include "geometry/mesh_io.h"
#include "geometry/orient_mesh.h"
#include "geometry/print_grid.h"
#include "geometry/voxelize_layers.h"
#include "render/image/image_io.h"
#include "render/image/memory.h"
#include "render/image/text.h"
#include "render/slice_model.h"
#include "render/slice_writer.h"
#include "render/texture_mesh.h"
#include "render/voxel_colors.h"
#include "synthesis/refine_solid.h"
#include "synthesis/synthesize_solid.h"

#include <algorithm>
#include <memory>
#include <optional>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

enum class ColorMode { Solid, Surface };

struct SliceJob {
  std::string model, output, exemplar, materials, preview, layers, shard;
  std::string core = "white";
  geometry::PrintGridOptions grid;
  geometry::VoxelizeOptions voxelize;
  render::SliceOptions slice;
  ColorMode mode = ColorMode::Solid;
  double textureScale = 0, featureSize = 0;
  uint32_t seed = 1;
  SolidMethodChoice solid;
  float contrastGain = synthesis::SolidSynthesisOptions{}.contrastGain;
  int refinePasses = synthesis::SolidSynthesisOptions{}.refinePasses;
  int resolution = 2048;
  bool force = false;
  WrapChoice wrap = WrapChoice::Auto;
  UpAxis up = UpAxis::Auto;
  CommonFlags common;
};

// The model axis that points up in the print: as the previews stand the model (upVector).
geometry::UpAxis printUpAxis(UpAxis axis, const fs::path& model) {
  const Eigen::Vector3f v = upVector(axis, model);
  const int a = v.x() != 0 ? 0 : v.y() != 0 ? 1 : 2;
  const bool negative = v[a] < 0;
  static const geometry::UpAxis positive[3] = {geometry::UpAxis::X, geometry::UpAxis::Y, geometry::UpAxis::Z};
  static const geometry::UpAxis negatives[3] = {geometry::UpAxis::NegX, geometry::UpAxis::NegY, geometry::UpAxis::NegZ};
  return negative ? negatives[a] : positive[a];
}

// --layers A:B (B exclusive) or --shard I/K (the I-th of K near-equal ranges) into first, count.
std::pair<int, int> layerRange(const SliceJob& job, int layers) {
  if (!job.layers.empty() && !job.shard.empty()) throw UsageError("give --layers or --shard, not both");
  const auto pair = [](const std::string& flag, const std::string& text, char separator) {
    const size_t at = text.find(separator);
    if (at == std::string::npos)
      throw UsageError(flag + ": expected two numbers separated by '" + separator + "', got '" + text + "'");
    return std::pair{int64_t(parseNumber(flag, text.substr(0, at), {0, 1e9}, true)),
                     int64_t(parseNumber(flag, text.substr(at + 1), {0, 1e9}, true))};
  };
  if (!job.shard.empty()) {
    const auto [i, k] = pair("--shard", job.shard, '/');
    if (k < 1 || i >= k) throw UsageError("--shard: expected I/K with 0 <= I < K, got '" + job.shard + "'");
    const int first = int(i * layers / k), end = int((i + 1) * layers / k);
    if (first == end) throw Error("--shard " + job.shard + ": no layers (the print has " + std::to_string(layers) + ")");
    return {first, end - first};
  }
  if (job.layers.empty()) return {0, layers};
  const auto [a, b] = pair("--layers", job.layers, ':');
  if (b <= a) throw UsageError("--layers: expected A:B with A < B, got '" + job.layers + "'");
  if (b > layers)
    throw Error("--layers " + job.layers + ": expected 0 <= A < B <= " + std::to_string(layers) + " (the print's layers)");
  return {int(a), int(b - a)};
}

// The model coloured by surface synthesis (texfab texture's surface mode), for --mode surface.
geometry::Mesh surfaceTextured(const SliceJob& job, Run& run, const geometry::Mesh& mesh, const Image& exemplar) {
  render::TextureMeshOptions o;
  o.atlas.pack.width = o.atlas.pack.height = job.resolution;
  o.surface.seed = job.seed;
  o.measure = false;
  o.textureScale = job.featureSize > 0 ? std::max(exemplar.width, exemplar.height) / job.featureSize : job.textureScale;
  bool cached = false;
  synthesis::AnalysisOptions options;
  options.wrap = chooseWrap(job.wrap, exemplar, run);
  const synthesis::ExemplarAnalysis analysis = analyzeExemplar(run, exemplar, options, cached);
  render::TextureExemplar ex;
  ex.color = &exemplar;
  ex.analysis = &analysis;
  Stage stage(run.ctx(), "surface texture");
  return render::textureMesh(mesh, ex, o, stage.inner()).mesh;
}

// Where voxel colours come from: the solid texture, the surface (synthesized or the model's own).
std::unique_ptr<render::VoxelColorSource> colorSource(const SliceJob& job, Run& run, geometry::Mesh& mesh,
                                                      const std::optional<Image>& exemplar,
                                                      const geometry::PrintGrid& grid,
                                                      std::optional<synthesis::SolidAnalysis>& solid,
                                                      nlohmann::ordered_json& source) {
  const std::string name = fs::path(job.exemplar).filename().string();
  if (exemplar && job.mode == ColorMode::Solid) {
    synthesis::validateSolidExemplars(*exemplar, *exemplar, *exemplar);
    bool cached = false;
    solid = analyzeSolid(run, *exemplar, *exemplar, *exemplar, {}, job.wrap, cached, job.solid);
    synthesis::SolidSynthesisOptions so;
    so.seed = job.seed;
    so.method = job.solid.method;
    so.contrastGain = job.contrastGain;
    so.refinePasses = job.refinePasses;
    // Default: one exemplar spans a quarter of the print's height (model units along the up axis).
    const geometry::BoundingBox box = geometry::boundingBox(mesh);
    const double height = std::abs((grid.rotation * (box.max - box.min).cast<double>()).z());
    const double span = job.featureSize > 0 ? job.featureSize : height / 4;
    const double scale = job.textureScale > 0 ? job.textureScale : std::max(exemplar->width, exemplar->height) / span;
    source["colors"] = {{"mode", "solid"}, {"method", synthesis::toString(job.solid.method)}, {"exemplar", name}, {"seed", job.seed},
                         {"contrast_gain", job.contrastGain}, {"refine_passes", job.refinePasses},
                         {"texture_scale", scale}};
    return std::make_unique<render::SolidVoxelColors>(*solid, *exemplar, *exemplar, *exemplar, so, scale, grid);
  }
  if (exemplar) mesh = surfaceTextured(job, run, mesh, *exemplar);
  source["colors"] = exemplar ? nlohmann::ordered_json{{"mode", "surface"}, {"exemplar", name}, {"seed", job.seed}}
                              : nlohmann::ordered_json{{"mode", "model"}};
  return std::make_unique<render::SurfaceVoxelColors>(mesh, grid, job.voxelize.shellMm);
}

void runSlice(SliceJob& job) {
  Run run("slice", job.common);
  // Everything checkable is checked before any work.
  if (job.textureScale != 0 && job.featureSize != 0) throw UsageError("give --texture-scale or --feature-size, not both");
  if (!job.materials.empty()) job.slice.materials = render::readPrintMaterials(job.materials);
  job.slice.coreMaterial = job.core;
  job.slice.preview = !job.preview.empty();
  job.slice.validate();
  job.voxelize.validate();
  if (!job.preview.empty()) checkImageWritable(job.preview);
  const fs::path preview = job.preview.empty() ? fs::path() : run.output(job.preview);
  render::SliceWriter writer(job.output, job.force);  // refuses a non-empty output before any work

  Stage load(run.ctx(), "load");
  geometry::Mesh mesh = geometry::readMesh(job.model, run.ctx());
  // Wound one way, outward, as texture and fracture do (a flipped triangle is no hole).
  if (const std::string repair = geometry::describeRepair(geometry::orientMesh(mesh)); !repair.empty())
    run.ctx().warn(repair);
  if (const geometry::CloseHolesReport holes = geometry::closeHoles(mesh); holes.holes > 0)
    run.ctx().warn("closed " + counted(int64_t(holes.holes), "hole") + " (" +
                   counted(int64_t(holes.boundaryEdges), "boundary edge") + ") with fans of triangles");
  std::optional<Image> exemplar;
  if (!job.exemplar.empty()) exemplar = readImage(job.exemplar);
  job.grid.up = printUpAxis(job.up, job.model);
  const geometry::PrintGrid grid = geometry::printGrid(geometry::boundingBox(mesh), job.grid);
  const auto [first, count] = layerRange(job, grid.layers);
  job.slice.firstLayer = first;
  job.slice.layerCount = count;
  // A batch's solid voxels are at most its print voxels; refinement's slab is the part that grows.
  const int64_t batchVoxels = int64_t(grid.width) * grid.height * job.slice.batchLayers;
  const double refinement = exemplar && job.mode == ColorMode::Solid
                                ? synthesis::refineSolidMemoryBytes(batchVoxels, job.refinePasses)
                                : 0.0;
  checkMemory(double(render::sliceMemoryBytes(grid, job.slice, job.common.threads > 0 ? job.common.threads : 16)) +
                  refinement,
              "one layer of " + std::to_string(grid.width) + " x " + std::to_string(grid.height) +
                  " voxels with its batch (lower --dpi or the size)");
  const Eigen::Vector3d size = grid.sizeMm();
  load.finish(job.model + ": " + counted(int64_t(mesh.triangleCount()), "triangle") + "; print " + figure(size.x()) +
              " x " + figure(size.y()) + " x " + figure(size.z()) + " mm (wide x deep x tall), " +
              std::to_string(grid.width) + " x " + std::to_string(grid.height) + " x " + std::to_string(grid.layers) +
              " voxels");

  nlohmann::ordered_json source;
  source["model"] = fs::path(job.model).filename().string();
  std::optional<synthesis::SolidAnalysis> solid;
  const std::unique_ptr<render::VoxelColorSource> colors = colorSource(job, run, mesh, exemplar, grid, solid, source);

  Stage prepare(run.ctx(), "voxelizer");
  const geometry::LayerVoxelizer voxelizer(mesh, grid, job.voxelize);
  for (const std::string& repair : voxelizer.report().repairs) run.ctx().warn(repair);
  prepare.finish();

  const render::SliceResult result = render::sliceModel(voxelizer, *colors, job.slice, writer, source, run.ctx());
  const render::SliceReport& r = result.report;
  run.note(counted(int64_t(r.layers), "layer") + " in " + job.output + " (" + figure(r.layers / std::max(1e-9, r.seconds)) +
           " layers/s), " + std::to_string(r.shellVoxels) + " shell voxels of " + std::to_string(r.insideVoxels));
  if (result.preview) writeImage(*result.preview, preview);
  const render::PrintColorError& ce = r.colorError;
  if (ce.blocks > 0)
    run.note("colour as printed: ΔE2000 " + figure(ce.mean) + " mean, " + figure(ce.p95) + " at the 95th percentile over " +
             counted(int64_t(ce.blocks), "block") + " of 16³ voxels");

  nlohmann::json& report = run.report();
  report["print"] = nlohmann::json::parse(render::slicePrintInfo(grid, job.slice, job.voxelize.shellMm, source).dump());
  report["layers"] = {{"first", first}, {"count", count}, {"total", grid.layers}};
  report["voxels"] = {{"inside", r.insideVoxels}, {"shell", r.shellVoxels}, {"per_layer", grid.voxelsPerLayer()}};
  if (auto* s = dynamic_cast<const render::SolidVoxelColors*>(colors.get()))
    report["solid"] = {{"voxels_requested", s->voxelsRequested()}, {"voxels_synthesized", s->voxelsSynthesized()}};
  report["color_error"] = {{"blocks", ce.blocks}, {"delta_e2000_mean", ce.mean}, {"delta_e2000_p95", ce.p95},
                           {"delta_e2000_max", ce.max}};
  report["bytes"] = r.bytes;
  report["seconds"] = {{"total", r.seconds}, {"voxelize_cpu", r.voxelizeSeconds}, {"prepare_colors", r.prepareSeconds},
                       {"colors_cpu", r.colorSeconds}, {"dither_cpu", r.ditherSeconds}, {"encode_cpu", r.encodeSeconds},
                       {"write_cpu", r.writeSeconds}};
  report["layers_per_second"] = r.layers / std::max(1e-9, r.seconds);
  run.finish();
}

} // namespace

Command addSliceCommand(CLI::App& root) {
  auto job = std::make_shared<SliceJob>();
  geometry::PrintGridOptions& g = job->grid;
  g.dpiX = 600;
  g.dpiY = 300;
  g.heightMm = 50;
  g.layerMm = 0.027;
  job->voxelize.shellMm = 1.0;
  Flags f(root.add_subcommand("slice", "Slice a closed model into one image per print layer for full-colour 3D "
                                       "printing: every voxel one material, coloured from the model's texture or a "
                                       "solid texture and dithered"));
  f.input("model", job->model, "Closed model (.obj .ply .off .stl .gltf .glb .3mf)");
  f.text("-o,--output", job->output, "Output folder: slice_00000.png ... and slices.json")->required();
  f.up(job->up)->description("The model's up axis, along which layers stack (auto: z for STL, else y, as the "
                              "previews stand the model); the model rests on the bed with its lowest point in layer 0");
  f.option("--height", g.heightMm, "Print height in mm (the model's extent along --up)", positive(10000));
  f.unit(g.mmPerUnit)->excludes("--height")->default_str("from --height");
  f.numbers("--dpi", 0, "X[,Y]", "Printer resolution in dots per inch (default 600,300)", positive(100000), false,
            [job](const std::vector<double>& v) {
              if (v.size() > 2) throw CLI::ValidationError("--dpi", "expected X or X,Y");
              job->grid.dpiX = v[0];
              job->grid.dpiY = v.back();
            });
  f.option("--layer", g.layerMm, "Layer thickness in mm", positive(10));
  f.text("--layers", job->layers, "Only layers A to B-1 (A:B), byte for byte as in a full run");
  f.text("--shard", job->shard, "Only the I-th of K equal layer ranges (I/K, 0-based; for job arrays)");
  f.option("--shell", job->voxelize.shellMm,
           "Colour voxels within this distance of the surface, in mm; deeper ones get the core material", positive(1000));
  f.text("--core", job->core, "Material of the core (default: white)");
  f.text("--materials", job->materials,
         "Printer materials (JSON: name, color #RRGGBB, opacity); default: Vero cyan, magenta, yellow, black, white, clear");
  f.choice("--dither", job->slice.dither,
           Names<render::DitherMode>{{"blue-noise", render::DitherMode::BlueNoise},
                                     {"floyd-steinberg", render::DitherMode::FloydSteinberg},
                                     {"none", render::DitherMode::None}},
           "blue-noise (3-D, position-based), floyd-steinberg (within each layer) or none (the continuous colour)");
  f.choice("--format", job->slice.format,
           Names<render::SliceFormat>{{"png", render::SliceFormat::Indexed}, {"voxelprint", render::SliceFormat::VoxelPrint}},
           "png (indexed, material colours) or voxelprint (RGBA, empty voxels transparent, as GrabCAD Voxel Print reads)");
  f.text("-e,--exemplar", job->exemplar, "Colour from this exemplar's texture instead of the model's own");
  f.choice("--mode", job->mode, Names<ColorMode>{{"solid", ColorMode::Solid}, {"surface", ColorMode::Surface}},
           "With --exemplar: solid (the solid texture of texfab texture --mode solid) or surface (synthesize over the "
           "surface first)");
  f.option("--texture-scale", job->textureScale,
           "Exemplar pixels per model unit, as texfab texture's (0 = auto: an exemplar spans a quarter of the model's "
           "height)", {0, 1e9});
  f.option("--feature-size", job->featureSize, "Model units one exemplar spans (instead of --texture-scale)", {0, 1e9});
  f.option("--seed", job->seed, "Random seed of the synthesis");
  wrapFlag(f, job->wrap);
  solidFidelityFlags(f, job->solid, job->contrastGain, job->refinePasses, " (--mode solid)");
  f.option("--resolution", job->resolution, "Atlas size for --mode surface", {64, 16384});
  f.text("--preview", job->preview, "Also write a picture of the print (front, side, four layers) to this PNG");
  f.flag("--force", job->force, "Replace an existing, non-empty output folder");
  f.common(job->common, Common::Threads | Common::Report | Common::Cache | Common::Backend | Common::Quiet);
  return {f.app(), [job] { runSlice(*job); }};
}

Command addMergeSlicesCommand(CLI::App& root) {
  struct MergeJob {
    std::vector<std::string> shards;
    std::string output;
    bool force = false;
  };
  auto job = std::make_shared<MergeJob>();
  Flags f(root.add_subcommand("merge-slices", "Join the shards of one print (texfab slice --layers or --shard) into "
                                              "the folder a full run writes"));
  f.app()->add_option("shards", job->shards, "Shard folders, in any order")->required();
  f.text("-o,--output", job->output, "Output folder")->required();
  f.flag("--force", job->force, "Replace an existing, non-empty output folder");
  return {f.app(), [job] {
            const std::vector<fs::path> shards(job->shards.begin(), job->shards.end());
            render::mergeSliceFolders(shards, job->output, job->force);
          }};
}

} // namespace texfab::cli
