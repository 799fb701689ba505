// SPDX-License-Identifier: GPL-3.0-or-later
// texfab slice: a closed model to one image per print layer for full-colour material jetting
// (PolyJet and similar), coloured from the model's texture or a solid texture, dithered to the
// printer's materials; texfab merge-slices: shards of one print (--layers, --shard) into one.
#include "apps/texfab/analysis.h"
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "apps/texfab/report_json.h"
#include "core/downsample.h"
#include "core/image_io.h"
#include "core/memory.h"
#include "core/text.h"
#include "geometry/io/mesh_io.h"
#include "print/print_grid.h"
#include "print/print_job.h"
#include "print/slice_writer.h"
#include "synthesis/synthesize_solid.h"

#include <algorithm>
#include <memory>
#include <optional>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct SliceJob {
  std::string model, output, exemplar, materials, iccProfile, preview, layers, shard;
  std::string core = "white";
  print::PrintJobOptions print;
  print::PrintColors mode = print::PrintColors::Solid;  ///< with --exemplar: Solid or Surface
  SolidMethodChoice solid;
  bool force = false;
  WrapChoice wrap = WrapChoice::Auto;
  UpChoice up;
  CommonFlags common;
};

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

// The exemplar and the analysis its colour mode needs.
struct Exemplar {
  std::optional<Image> image;
  std::optional<synthesis::SolidAnalysis> solid;
  std::optional<synthesis::ExemplarAnalysis> surface;
};

print::PrintExemplar analyze(const SliceJob& job, const print::PrintJob& print, Run& run, Exemplar& e) {
  if (!e.image) return {};
  const print::PrintExemplar view{&*e.image, nullptr, nullptr, fs::path(job.exemplar).filename().string()};
  bool cached = false;
  if (job.print.colors == print::PrintColors::Solid) {
    synthesis::validateSolidExemplars(*e.image, *e.image, *e.image);
    const WrapChoice wrap = wrapAsGiven(job.wrap, *e.image, run);
    const int factor = print.analysisDownsampling(*e.image);
    if (factor > 1) {
      e.image = downsample(*e.image, factor);
      run.note("the print puts at least " + std::to_string(factor) + " exemplar pixels in every voxel: the solid " +
               "texture is synthesized from a copy " + std::to_string(factor) + " times smaller (" +
               std::to_string(e.image->width) + "x" + std::to_string(e.image->height) + ")");
    }
    e.solid = analyzeSolid(run, *e.image, *e.image, *e.image, {}, wrap, cached, job.solid);
    return {view.color, &*e.solid, nullptr, view.name, factor};
  }
  synthesis::AnalysisOptions options;
  options.wrap = chooseWrap(job.wrap, *e.image, run);
  e.surface = analyzeExemplar(run, *e.image, options, cached);
  return {view.color, nullptr, &*e.surface, view.name};
}

void runSlice(SliceJob& job) {
  Run run("slice", job.common);
  print::PrintJobOptions& o = job.print;
  // Everything checkable is checked before any work.
  if (o.textureScale != 0 && o.featureSize != 0) throw UsageError("give --texture-scale or --feature-size, not both");
  if (!job.materials.empty()) o.slice.materials = print::readPrintMaterials(job.materials);
  o.slice.coreMaterial = job.core;
  o.slice.iccProfile = job.iccProfile;
  o.slice.preview = !job.preview.empty();
  o.colors = job.exemplar.empty() ? print::PrintColors::Model : job.mode;
  o.solid.method = job.solid.method;
  o.grid.up = upAxisFor(job.up, job.model);  // as the previews stand the model
  o.validate();
  if (!job.preview.empty()) checkImageWritable(job.preview);
  const fs::path preview = job.preview.empty() ? fs::path() : run.output(job.preview);
  print::SliceWriter writer(job.output, job.force);  // refuses a non-empty output before any work
  run.outputs().atCommit([&writer] { writer.publish(); });

  Stage load(run.ctx(), "load");
  const print::PrintJob print(geometry::readMesh(job.model, run.ctx()), o, run.ctx());
  Exemplar exemplar;
  if (!job.exemplar.empty()) exemplar.image = readImage(job.exemplar);
  const print::PrintGrid& grid = print.grid();
  const auto [first, count] = layerRange(job, grid.layers);
  run.checkMemory(print.memoryBytes(run.ctx()),
                  "one layer of " + std::to_string(grid.width) + " x " + std::to_string(grid.height) +
                      " voxels with its batch (lower --dpi or the size)");
  const Eigen::Vector3d size = grid.sizeMm();
  load.finish(job.model + ": " + counted(int64_t(print.mesh().triangleCount()), "triangle") + "; print " +
              figure(size.x()) + " x " + figure(size.y()) + " x " + figure(size.z()) + " mm (wide x deep x tall), " +
              std::to_string(grid.width) + " x " + std::to_string(grid.height) + " x " + std::to_string(grid.layers) +
              " voxels");

  const print::PrintJobResult result = print.slice(analyze(job, print, run, exemplar), first, count, writer,
                                                    fs::path(job.model).filename().string(), run.ctx());
  const print::SliceReport& r = result.slice.report;
  run.note(counted(int64_t(r.layers), "layer") + " in " + job.output + " (" + figure(r.layers / std::max(1e-9, r.seconds)) +
           " layers/s), " + std::to_string(r.shellVoxels) + " shell voxels of " + std::to_string(r.insideVoxels));
  if (result.slice.preview) writeImage(*result.slice.preview, preview);
  const print::PrintColorError& ce = r.colorError;
  if (ce.blocks > 0)
    run.note("colour as printed: ΔE2000 " + figure(ce.mean) + " mean, " + figure(ce.p95) + " at the 95th percentile over " +
             counted(int64_t(ce.blocks), "block") + " of 16³ voxels");

  nlohmann::json& report = run.report();
  if (run.reporting())  // the print block as the manifest has it
    report["print"] = nlohmann::json::parse(print::readSliceManifest(writer.staging())["print"].dump());
  report["model"] = modelJson(job.model, print.mesh());
  report["model"]["preparation"] = toJson(print.preparation());
  report["layers"] = {{"first", first}, {"count", count}, {"total", grid.layers}};
  report["voxels"] = {{"inside", r.insideVoxels}, {"shell", r.shellVoxels}, {"per_layer", grid.voxelsPerLayer()}};
  if (o.colors == print::PrintColors::Solid)
    report["solid"] = {{"voxels_requested", result.voxelsRequested}, {"voxels_synthesized", result.voxelsSynthesized}};
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
  print::PrintJobOptions& o = job->print;
  print::PrintGridOptions& g = o.grid;
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
              job->print.grid.dpiX = v[0];
              job->print.grid.dpiY = v.back();
            });
  f.option("--layer", g.layerMm, "Layer thickness in mm", positive(10));
  f.text("--layers", job->layers, "Only layers A to B-1 (A:B), byte for byte as in a full run");
  f.text("--shard", job->shard, "Only the I-th of K equal layer ranges (I/K, 0-based; for job arrays)");
  f.option("--shell", o.voxelize.shellMm,
           "Colour voxels within this distance of the surface, in mm; deeper ones get the core material", positive(1000));
  f.text("--core", job->core, "Material of the core (default: white)");
  f.text("--materials", job->materials,
         "Printer materials (JSON: name, color #RRGGBB, opacity); default: Vero cyan, magenta, yellow, black, white, clear");
  f.text("--icc-profile", job->iccProfile,
         "The printer's ICC output profile: mixes aim at the colour it says the printer reproduces for each "
         "requested colour (perceptual intent); materials must lie inside its gamut");
  f.choice("--mix", o.slice.mixSpace,
           Names<print::MixSpace>{{"cielab", print::MixSpace::Perceptual}, {"linear-rgb", print::MixSpace::LinearRgb}},
           "How a colour's mix of materials is chosen: cielab (the smallest perceptual error, default) or linear-rgb "
           "(the smallest error in linear RGB)");
  f.choice("--dither", o.slice.dither,
           Names<print::DitherMode>{{"blue-noise", print::DitherMode::BlueNoise},
                                     {"floyd-steinberg", print::DitherMode::FloydSteinberg},
                                     {"none", print::DitherMode::None}},
           "blue-noise (3-D, position-based), floyd-steinberg (within each layer) or none (the continuous colour)");
  f.choice("--format", o.slice.format,
           Names<print::SliceFormat>{{"png", print::SliceFormat::Indexed}, {"voxelprint", print::SliceFormat::VoxelPrint}},
           "png (indexed, material colours) or voxelprint (RGBA, empty voxels transparent, as GrabCAD Voxel Print reads)");
  f.text("-e,--exemplar", job->exemplar, "Colour from this exemplar's texture instead of the model's own");
  f.choice("--mode", job->mode,
           Names<print::PrintColors>{{"solid", print::PrintColors::Solid}, {"surface", print::PrintColors::Surface}},
           "With --exemplar: solid (the solid texture of texfab texture --mode solid) or surface (synthesize over the "
           "surface first)");
  f.option("--texture-scale", o.textureScale,
           "Exemplar pixels per model unit (0 = auto, as texfab texture's: the print shows the textured model's "
           "pattern)", {0, 1e9});
  f.option("--feature-size", o.featureSize, "Model units one exemplar spans (instead of --texture-scale)", {0, 1e9});
  f.option("--seed", o.seed, "Random seed of the synthesis");
  wrapFlag(f, job->wrap);
  solidFidelityFlags(f, job->solid, o.solid.contrastGain, o.solid.refinePasses, " (--mode solid)");
  f.option("--resolution", o.resolution, "Atlas size for --mode surface", {64, 16384});
  f.text("--preview", job->preview,
         "Also write a picture of the print to this PNG: front and side, four layers as dithered and, below them, "
         "as the eye sees the mixed print");
  f.flag("--force", job->force, "Replace an existing, non-empty output folder");
  f.common(job->common, Common::Threads | Common::Memory | Common::Report | Common::Cache | Common::Backend | Common::Quiet);
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
            print::mergeSliceFolders(shards, job->output, job->force);
          }};
}

} // namespace texfab::cli
