// SPDX-License-Identifier: GPL-3.0-or-later
// texfab texture: synthesize a texture over a mesh (anisometric synthesis in the atlas,
// Lefebvre & Hoppe 2006, or lazy solid synthesis, Dong et al. 2008) and write the textured model.
#include "apps/texfab/backend_flags.h"
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "render/texture_mesh.h"
#include "geometry/mesh_io.h"
#include "render/image/error.h"
#include "render/image/memory.h"
#include "render/image/image_io.h"
#include "render/preview_renderer.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"

#include <cmath>
#include <memory>
#include <optional>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct TextureArgs {
  std::string model;
  std::string exemplar;
  std::string output;
  std::string mode = "surface";
  double scale = 0;
  double featureSize = 0;
  std::string direction = "0,1,0";
  std::string field = "direction";
  std::string resolution = "2048";
  int gutter = 4;
  uint32_t seed = 1;
  std::string maps;
  bool draco = false;
  std::string preview;
  std::string previewSize = "800";
  std::string report;
  int threads = 0;
  BackendFlags backend;
  std::string cacheDir;
  bool noCache = false;
  bool quiet = false;
};

struct CompanionMaps {
  std::optional<Image> normal, roughness, height;
};

// "normal=N.png,roughness=R.png,height=H.png" (any subset, any order).
CompanionMaps readCompanionMaps(const std::string& spec) {
  CompanionMaps maps;
  if (spec.empty()) return maps;
  size_t begin = 0;
  while (begin <= spec.size()) {
    const size_t end = std::min(spec.find(',', begin), spec.size());
    const std::string item = spec.substr(begin, end - begin);
    const size_t eq = item.find('=');
    if (eq == std::string::npos || eq + 1 == item.size())
      throw Error("--maps: expected KIND=FILE items (normal, roughness, height), got '" + item + "'");
    const std::string kind = item.substr(0, eq), path = item.substr(eq + 1);
    std::optional<Image>* slot = kind == "normal" ? &maps.normal : kind == "roughness" ? &maps.roughness
                               : kind == "height" ? &maps.height : nullptr;
    if (!slot) throw Error("--maps: unknown map '" + kind + "' (expected normal, roughness or height)");
    if (*slot) throw Error("--maps: '" + kind + "' given twice");
    *slot = readImage(path);
    if (kind == "normal" && (*slot)->channels < 3) throw Error("--maps: normal map " + path + " needs 3 channels");
    begin = end + 1;
  }
  return maps;
}

fs::path siblingPath(const fs::path& output, const std::string& suffix, const std::string& extension) {
  return output.parent_path() / (output.stem().string() + suffix + extension);
}

void runTexture(const TextureArgs& args) {
  Progress progress("texfab texture", args.quiet);
  Context ctx{.threads = args.threads};
  applyBackend(args.backend, ctx);  // the progress lines below name it
  // Everything checkable is checked before any work.
  geometry::meshFormatOf(args.output);
  render::TextureMeshOptions options;
  if (args.mode == "surface") options.mode = render::TextureMode::Surface;
  else if (args.mode == "solid") options.mode = render::TextureMode::Solid;
  else throw Error("--mode: expected surface or solid, got '" + args.mode + "'");
  if (args.scale != 0 && args.featureSize != 0) throw Error("give --scale or --feature-size, not both");
  if (!(args.scale >= 0 && std::isfinite(args.scale)))
    throw Error("--scale: must be a positive number of exemplar pixels per model unit");
  if (!(args.featureSize >= 0 && std::isfinite(args.featureSize)))
    throw Error("--feature-size: must be a positive length in model units");
  const auto [width, height] = parseSize(args.resolution, "--resolution");
  options.atlas.pack.width = width;
  options.atlas.pack.height = height;
  options.atlas.pack.gutter = args.gutter;
  if (args.gutter < 2)
    throw Error("--gutter: at least 2 texels are needed (texture filtering reads across chart borders), got " +
                std::to_string(args.gutter));
  try {
    options.atlas.pack.validate();
  } catch (const Error& e) {
    throw Error(std::string("--resolution/--gutter: ") + e.what());
  }
  // Peak memory per atlas texel, measured at 2048² on an 89K-triangle mesh (texture_bench): 218 bytes
  // in surface mode, 440 in solid mode (lazy synthesis of ~1 voxel per texel).
  const double bytesPerTexel = options.mode == render::TextureMode::Solid ? 440.0 : 220.0;
  const double needed = double(width) * height * bytesPerTexel;
  if (needed > 0.8 * double(physicalMemoryBytes()))
    throw Error("a " + std::to_string(width) + "x" + std::to_string(height) + " atlas needs about " +
                std::to_string(int(needed / double(1 << 30)) + 1) + " GiB in " + args.mode +
                " mode, more than this machine's memory");
  const std::vector<double> dir = parseNumberList(args.direction, "--direction");
  if (dir.size() != 3) throw Error("--direction: expected X,Y,Z, got '" + args.direction + "'");
  options.field.direction = Eigen::Vector3f(float(dir[0]), float(dir[1]), float(dir[2]));
  if (!(options.field.direction.norm() > 0) || !options.field.direction.allFinite())
    throw Error("--direction: must be a finite non-zero vector, got '" + args.direction + "'");
  if (args.field == "direction") options.field.kind = geometry::TangentFieldKind::Direction;
  else if (args.field == "curvature") options.field.kind = geometry::TangentFieldKind::Curvature;
  else throw Error("--field: expected direction or curvature, got '" + args.field + "'");
  options.surface.seed = args.seed;
  options.solid.seed = args.seed;
  options.measure = !args.report.empty();  // the measures (seconds on a 2048² atlas) go to the report
  render::RenderOptions previewOptions;
  if (!args.preview.empty()) {
    checkImageWritable(args.preview);
    std::tie(previewOptions.width, previewOptions.height) = parseSize(args.previewSize, "--preview-size");
  }

  progress.start("load");
  const Image exemplar = readImage(args.exemplar);
  synthesis::validateExemplarSize(exemplar);
  const CompanionMaps maps = readCompanionMaps(args.maps);
  render::TextureExemplar ex;
  ex.color = &exemplar;
  ex.normal = maps.normal ? &*maps.normal : nullptr;
  ex.roughness = maps.roughness ? &*maps.roughness : nullptr;
  ex.height = maps.height ? &*maps.height : nullptr;
  render::checkCompanionMaps(ex, options.mode);  // before the (possibly long) analysis
  const geometry::Mesh mesh = geometry::readMesh(args.model);
  if (mesh.triangleCount() == 0) throw Error(args.model + ": the model has no triangles");
  progress.finish(args.model + ": " + std::to_string(mesh.triangleCount()) + " triangles; " + args.exemplar + " " +
                  std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height));

  progress.start("analysis");
  const fs::path cacheDir = args.cacheDir.empty() ? synthesis::defaultCacheDir() : fs::path(args.cacheDir);
  bool cached = false;
  std::optional<synthesis::ExemplarAnalysis> analysis;
  std::optional<synthesis::SolidAnalysis> solidAnalysis;
  if (options.mode == render::TextureMode::Surface) {
    const synthesis::AnalysisOptions analysisOptions;
    analysis = args.noCache ? synthesis::analyzeExemplar(exemplar, analysisOptions, ctx)
                            : synthesis::analyzeExemplarCached(exemplar, analysisOptions, cacheDir, ctx, &cached);
  } else {
    const synthesis::SolidAnalysisOptions analysisOptions;
    solidAnalysis = args.noCache
                        ? synthesis::analyzeSolid(exemplar, exemplar, exemplar, analysisOptions, ctx)
                        : synthesis::analyzeSolidCached(exemplar, exemplar, exemplar, analysisOptions, cacheDir,
                                                        ctx, &cached);
  }
  progress.finish(cached ? "(cached)" : "");

  // --feature-size: model units per exemplar.
  if (args.featureSize > 0) options.textureScale = std::max(exemplar.width, exemplar.height) / args.featureSize;
  else options.textureScale = args.scale;

  ex.analysis = analysis ? &*analysis : nullptr;
  ex.solidAnalysis = solidAnalysis ? &*solidAnalysis : nullptr;
  ctx.progress = [&](const ProgressEvent& e) {
    if (e.kind == ProgressEvent::Kind::End) progress.record(std::string(e.stage), e.seconds, std::string(e.detail));
  };
  const render::TextureMeshResult result = render::textureMesh(mesh, ex, options, ctx);
  for (const std::string& repair : result.atlas.report.repairs) progress.note(repair);
  for (const std::string& warning : result.warnings) progress.note("warning: " + warning);

  progress.start("write");
  geometry::MeshWriteOptions writeOptions;
  writeOptions.draco = args.draco;
  geometry::writeMesh(result.mesh, args.output, writeOptions);
  std::string written = args.output;
  if (result.height) {
    const fs::path heightPath = siblingPath(args.output, "_height", ".png");
    writeImage(*result.height, heightPath);
    written += ", " + heightPath.string();
  }
  progress.finish(written);

  if (!args.preview.empty()) {
    progress.start("preview");
    const render::PreviewRenderer renderer(result.mesh);
    writeImage(renderer.render(previewOptions, ctx), args.preview);
    progress.finish(args.preview);
  }

  if (!args.report.empty()) {
    const atlas::AtlasReport& ar = result.atlas.report;
    const render::TextureMeasures& m = result.measures;
    nlohmann::json report;
    report["command"] = "texture";
    report["model"] = {{"path", args.model}, {"vertices", mesh.vertexCount()}, {"triangles", mesh.triangleCount()}};
    report["exemplar"] = {{"path", args.exemplar}, {"width", exemplar.width}, {"height", exemplar.height},
                          {"analysis_cached", cached}};
    report["parameters"] = {{"mode", args.mode}, {"seed", args.seed}, {"width", width}, {"height", height},
                            {"gutter", args.gutter}, {"field", args.field}, {"direction", dir},
                            {"texture_scale", result.textureScale},
                            {"exemplar_pixels_per_texel", result.exemplarPixelsPerTexel}};
    report["atlas"] = {{"charts", ar.charts}, {"utilization", ar.utilization}, {"l2_stretch", ar.l2Stretch},
                       {"max_stretch", ar.maxStretch}, {"texels_per_unit", ar.texelsPerUnit},
                       {"chart_texels", result.sites.size()}, {"repairs", ar.repairs}};
    nlohmann::json measures;
    measures["seams"] = {{"ratio", m.seams.ratio}, {"seam_difference", m.seams.seamDifference},
                         {"interior_difference", m.seams.interiorDifference}, {"seam_pairs", m.seams.seamPairs},
                         {"interior_pairs", m.seams.interiorPairs}};
    if (m.scale)
      measures["scale"] = {{"requested_pixels_per_unit", result.textureScale},
                           {"median_pixels_per_unit", m.scale->medianPixelsPerUnit},
                           {"fraction_within_tolerance", m.scale->fractionWithin},
                           {"fraction_measured", m.scale->fractionMeasured}, {"tolerance", m.scale->tolerance}};
    if (m.fidelity) measures["fidelity"] = {{"exemplar_space", m.fidelity->fidelity}, {"samples", m.fidelity->samples}};
    report["measures"] = measures;
    if (options.mode == render::TextureMode::Solid)
      report["solid"] = {{"voxels_requested", result.voxelsRequested}, {"voxels_synthesized", result.voxelsSynthesized}};
    nlohmann::json levels = nlohmann::json::array();
    for (const synthesis::LevelStats& l : result.synthesisLevels)
      levels.push_back({{"atlas_level", l.level}, {"texels", l.texels}, {"seconds", l.seconds}});
    report["synthesis_levels"] = levels;
    report["warnings"] = result.warnings;
    report["timings"] = progress.timings();
    report["peak_memory_mib"] = peakMemoryMiB();
    writeReport(report, args.report);
  }
}

} // namespace

Command addTextureCommand(CLI::App& root) {
  auto args = std::make_shared<TextureArgs>();
  CLI::App* app = root.add_subcommand(
      "texture", "Synthesize a texture over a mesh from an exemplar and write the textured model "
                 "(surface: anisometric synthesis in the atlas; solid: the matching interior of the material)");
  app->add_option("model", args->model, "Input mesh (.obj .ply .off .stl .gltf .glb)")->required();
  app->add_option("-e,--exemplar", args->exemplar, "Exemplar image (PNG, JPEG, TIFF, EXR, GIMP .pat)")->required();
  app->add_option("-o,--output", args->output, "Textured model (.glb .gltf .obj)")->required();
  app->add_option("--mode", args->mode, "surface (synthesis over the surface) or solid (a 3-D material, seamless)")
      ->capture_default_str();
  app->add_option("--scale", args->scale,
                  "Exemplar pixels per model unit (default: the atlas density, one exemplar pixel per texel)");
  app->add_option("--feature-size", args->featureSize, "Model units one exemplar spans (instead of --scale)");
  app->add_option("--direction", args->direction, "Texture 'up' direction X,Y,Z, projected to the surface (surface mode)")
      ->capture_default_str();
  app->add_option("--field", args->field, "Orientation field: direction, or curvature (minimum principal direction)")
      ->capture_default_str();
  app->add_option("--resolution", args->resolution, "Atlas size N (NxN) or WxH, powers of two")->capture_default_str();
  app->add_option("--gutter", args->gutter, "Minimum empty texels between charts (2-64)")->capture_default_str();
  app->add_option("--seed", args->seed, "Random seed: the only source of variation")->capture_default_str();
  app->add_option("--maps", args->maps,
                  "Companion maps of the exemplar's size, synthesized with the same coordinates: "
                  "normal=N.png,roughness=R.png,height=H.png (height is written as OUTPUT_height.png)");
  app->add_flag("--draco", args->draco, "Compress the geometry with Draco (.glb/.gltf)");
  app->add_option("--preview", args->preview, "Also render the textured model to this PNG");
  app->add_option("--preview-size", args->previewSize, "Preview size N or WxH")->capture_default_str();
  app->add_option("--report", args->report,
                  "Write timings, atlas figures and quality measures (seams, scale, fidelity; measured only "
                  "when a report is asked for) as JSON");
  app->add_option("--threads", args->threads, "Worker threads (0 = all cores); the result does not depend on it")
      ->capture_default_str();
  addBackendFlags(*app, args->backend);
  app->add_option("--cache-dir", args->cacheDir, "Exemplar analysis cache folder (default: ~/.cache/texfab)");
  app->add_flag("--no-cache", args->noCache, "Neither read nor write the analysis cache");
  app->add_flag("-q,--quiet", args->quiet, "No progress output");
  return {app, [args] { runTexture(*args); }};
}

} // namespace texfab::cli
