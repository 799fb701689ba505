// SPDX-License-Identifier: GPL-3.0-or-later
// texfab texture: synthesize a texture over a mesh (anisometric synthesis in the atlas,
// Lefebvre & Hoppe 2006, or lazy solid synthesis, Dong et al. 2008) and write the textured model.
#include "apps/texfab/analysis.h"
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "apps/texfab/report_json.h"
#include "core/downsample.h"
#include "core/image_io.h"
#include "core/memory.h"
#include "core/text.h"
#include "geometry/io/mesh_io.h"
#include "render/material_mips.h"
#include "render/preview_renderer.h"
#include "render/texture_mesh.h"
#include "synthesis/graph_file.h"
#include "synthesis/synthesize_surface_graph.h"

#include <cmath>
#include <memory>
#include <optional>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct TextureJob {
  std::string model, exemplar, graph, output, maps, preview;
  double featureSize = 0;
  render::TextureMeshOptions options;
  geometry::MeshWriteOptions write;
  render::RenderOptions previewOptions;
  render::FilteredMipsOptions fileMips;  ///< the glTF route of normal-map filtering
  UpChoice up;
  WrapChoice wrap = WrapChoice::Auto;
  SolidMethodChoice method;
  CommonFlags common;
};

// --maps "normal=N.png,roughness=R.png,height=H.png" (any subset, any order).
struct CompanionFiles {
  std::string normal, roughness, height;
};

CompanionFiles parseMaps(const std::string& spec) {
  CompanionFiles files;
  for (size_t begin = 0; !spec.empty() && begin <= spec.size();) {
    const size_t end = std::min(spec.find(',', begin), spec.size());
    const std::string item = spec.substr(begin, end - begin);
    const size_t eq = item.find('=');
    if (eq == std::string::npos || eq + 1 == item.size())
      throw UsageError("--maps: expected KIND=FILE items (normal, roughness, height), got '" + item + "'");
    const std::string kind = item.substr(0, eq);
    std::string* slot = kind == "normal" ? &files.normal : kind == "roughness" ? &files.roughness
                      : kind == "height" ? &files.height : nullptr;
    if (!slot) throw UsageError("--maps: unknown map '" + kind + "' (expected normal, roughness or height)");
    if (!slot->empty()) throw UsageError("--maps: '" + kind + "' given twice");
    *slot = item.substr(eq + 1);
    begin = end + 1;
  }
  return files;
}

struct Inputs {
  geometry::PreparedMesh model;
  Image exemplar;  ///< with a graph, its root exemplar
  std::optional<synthesis::ExemplarGraph> graph;
  std::optional<Image> normal, roughness, height;
  render::TextureExemplar view() const {
    return {&exemplar, nullptr, nullptr, normal ? &*normal : nullptr, roughness ? &*roughness : nullptr,
            height ? &*height : nullptr};
  }
};

Inputs load(const TextureJob& job, const CompanionFiles& maps, const Context& ctx) {
  Stage stage(ctx, "load");
  Inputs in;
  if (!job.graph.empty()) {
    in.graph = synthesis::readExemplarGraph(job.graph);
    in.exemplar = in.graph->exemplars.front();
  } else {
    in.exemplar = readImage(job.exemplar);
    synthesis::validateExemplarSize(in.exemplar);
  }
  auto read = [&](const std::string& path, const char* name, std::optional<Image>& slot) {
    if (!path.empty()) slot = readImage(path);
    if (in.graph) slot = synthesis::graphMapAtlas(*in.graph, name);
  };
  read(maps.normal, "normal", in.normal);
  read(maps.roughness, "roughness", in.roughness);
  read(maps.height, "height", in.height);
  if (in.normal && in.normal->channels < 3)
    throw Error((in.graph ? job.graph + ": the normal maps" : maps.normal) + ": a normal map needs 3 channels");
  if (!in.graph) render::checkCompanionMaps(in.view(), job.options.mode);  // before the (possibly long) analysis
  in.model.mesh = geometry::readMesh(job.model, ctx);
  stage.finish(job.model + ": " + counted(int64_t(in.model.mesh.triangleCount()), "triangle") + "; " +
               (in.graph ? job.graph + ": " + counted(int64_t(in.graph->exemplars.size()), "exemplar") + " of "
                         : job.exemplar + " ") +
               std::to_string(in.exemplar.width) + "x" + std::to_string(in.exemplar.height));
  return in;
}

// Replaces the exemplar and its maps by the copy render::analysisDownsampling asks for (and the scale by
// the copy's), says so, and returns the factor.
int downsampleForAnalysis(render::TextureMeshOptions& o, Inputs& in, const Run& run) {
  const int factor = render::analysisDownsampling(in.model.mesh, o, in.exemplar);
  if (factor == 1) return 1;
  for (std::optional<Image>* map : {&in.normal, &in.roughness, &in.height})
    if (*map) **map = downsample(**map, factor);
  in.exemplar = downsample(in.exemplar, factor);
  o.textureScale /= factor;
  const std::string times = std::to_string(factor);
  run.note("the scale puts at least " + times + " exemplar pixels in every texel: the exemplar is synthesized from a " +
           "copy " + times + " times smaller (" + std::to_string(in.exemplar.width) + "x" +
           std::to_string(in.exemplar.height) + ")");
  return factor;
}

// What synthesis reads: the exemplar's analysis (surface or solid mode) or the graph's, with the
// texture scale set (a feature size or the default turned into exemplar pixels per unit).
struct Analyses {
  std::optional<synthesis::ExemplarAnalysis> surface;
  std::optional<synthesis::SolidAnalysis> solid;
  std::optional<synthesis::GraphAnalysis> graph;
  int downsampling = 1;  ///< 1: synthesized from the exemplar as given
  /// Pixels of the exemplar (or the graph's root) as given per pixel synthesized from: the
  /// downsampling, or 1 / the graph's rootMagnification.
  double pixelsAsGiven = 1;
  nlohmann::json report; ///< the report's "exemplar" (or "graph") part
};

Analyses analyze(TextureJob& job, Inputs& in, Run& run) {
  render::TextureMeshOptions& o = job.options;
  Analyses a;
  bool cached = false;
  if (in.graph) {
    o.textureScale = render::graphScaleAsGiven(*in.graph, o.textureScale, job.featureSize);
    if (o.textureScale == 0) o.textureScale = render::graphTextureScale(in.model.mesh, in.graph->side());
    a.graph = synthesis::analyzeGraph(*in.graph, {}, run.analysisCache(), run.ctx(), &cached);
    a.report = {{"file", job.graph}, {"exemplars", in.graph->names}, {"edges", in.graph->edges.size()},
                {"colors", synthesis::graphColorsName(*in.graph)}, {"side", in.graph->side()},
                {"root_magnification", in.graph->rootMagnification}, {"analysis_cached", cached}};
    a.pixelsAsGiven = 1.0 / in.graph->rootMagnification;
    return a;
  }
  if (job.featureSize > 0) o.textureScale = std::max(in.exemplar.width, in.exemplar.height) / job.featureSize;
  a.report = imageJson(job.exemplar, in.exemplar);  // as given
  const WrapChoice wrap = wrapAsGiven(job.wrap, in.exemplar, run);
  o.textureScale = render::textureScaleFor(in.model.mesh, o);
  a.downsampling = downsampleForAnalysis(o, in, run);
  a.pixelsAsGiven = a.downsampling;
  if (o.mode == render::TextureMode::Surface) {
    synthesis::AnalysisOptions options;
    options.wrap = chooseWrap(wrap, in.exemplar, run);
    a.surface = analyzeExemplar(run, in.exemplar, options, cached);
  } else {
    a.solid = analyzeSolid(run, in.exemplar, in.exemplar, in.exemplar, {}, wrap, cached, job.method);
  }
  a.report["analysis_cached"] = cached;
  a.report["downsampled"] = a.downsampling;
  return a;
}

// The mesh as written: for a glTF output with normal-map filtering on, each normal-mapped material
// carries roughness and anisotropy MIP chains widened by its normals' spread (render/material_mips.h).
geometry::Mesh forFile(const geometry::Mesh& mesh, const TextureJob& job, const Run& run, const Context& ctx) {
  if (job.previewOptions.normalMapFiltering == render::NormalMapFiltering::Mip ||
      !geometry::meshFormatIsGltf(geometry::meshFormatOf(job.output)))
    return mesh;
  std::vector<std::string> notes;
  geometry::Mesh out = render::withFilteredMips(mesh, job.fileMips, ctx, &notes);
  for (const std::string& note : notes) run.note(note);
  return out;
}

void runTexture(TextureJob& job) {
  Run run("texture", job.common);
  checkPrintSize(job.write, job.output);
  render::TextureMeshOptions& o = job.options;
  o.solid.method = job.method.method;
  // Everything checkable is checked, and every output reserved, before any work.
  if (o.textureScale > 0 && job.featureSize > 0) throw UsageError("give --texture-scale or --feature-size, not both");
  if (job.exemplar.empty() == job.graph.empty())
    throw UsageError(job.graph.empty() ? "give an exemplar (--exemplar) or an exemplar graph (--graph)"
                                       : "give --exemplar or --graph, not both");
  if (!job.graph.empty() && (o.mode == render::TextureMode::Solid || !job.maps.empty() || job.wrap != WrapChoice::Auto))
    throw UsageError("--graph synthesizes over the surface, with the companion maps its file gives: it does not take "
                     "--mode solid, --maps or --exemplar-wrap");
  if (!geometry::meshFormatCarriesTextures(geometry::meshFormatOf(job.output)))
    throw UsageError(job.output + ": " + geometry::meshFormatName(geometry::meshFormatOf(job.output)) +
                     " files cannot carry the texture; write .glb, .gltf, .obj or .3mf");
  run.checkMemory(render::textureMeshMemoryBytes(o), "a " + std::to_string(o.atlas.pack.width) + "x" +
                                                         std::to_string(o.atlas.pack.height) + " atlas");
  const CompanionFiles maps = parseMaps(job.maps);
  const fs::path out = run.output(job.output);
  const auto reserveHeight = [&] {
    return run.output(fs::path(job.output).replace_filename(fs::path(job.output).stem().string() + "_height.png"));
  };
  fs::path heightOut = maps.height.empty() ? fs::path() : reserveHeight();
  if (!job.preview.empty()) checkImageWritable(job.preview);
  const fs::path previewOut = job.preview.empty() ? fs::path() : run.output(job.preview);
  o.solid.seed = o.surface.seed;
  o.measure = run.reporting();  // the measures (seconds on a 2048² atlas) go to the report

  Inputs in = load(job, maps, run.ctx());
  in.model.preparation = geometry::prepareMesh(in.model.mesh, geometry::MeshUse::Surface, run.ctx());  // before the analysis
  if (in.graph) {
    if (in.height) heightOut = reserveHeight();  // the graph's height maps
    synthesis::checkSurfaceGraphSize(int(in.graph->exemplars.size()), in.graph->side());
    run.checkMemory(render::textureMeshMemoryBytes(o) +
                        synthesis::graphAnalysisMemoryBytes(int(in.graph->exemplars.size()), in.graph->side()),
                    "a " + std::to_string(o.atlas.pack.width) + "x" + std::to_string(o.atlas.pack.height) +
                        " atlas from a graph of " + counted(int64_t(in.graph->exemplars.size()), "exemplar"));
  }
  Analyses analyses = analyze(job, in, run);
  render::TextureExemplar ex = in.view();
  ex.analysis = analyses.surface ? &*analyses.surface : nullptr;
  ex.solidAnalysis = analyses.solid ? &*analyses.solid : nullptr;
  ex.graph = analyses.graph ? &*analyses.graph : nullptr;
  const render::TextureMeshResult result = render::textureMesh(in.model, ex, o, run.ctx());

  Stage write(run.ctx(), "write");
  job.write.up = geometry::upVector(upAxisFor(job.up, job.model));
  geometry::writeMesh(forFile(result.mesh, job, run, write.inner()), out, job.write);
  if (result.height) writeImage(*result.height, heightOut);
  write.finish(job.output + (result.height ? ", " + heightOut.filename().string() : ""));
  if (!job.preview.empty()) {
    Stage preview(run.ctx(), "preview");
    render::RenderOptions view = job.previewOptions;
    view.up = geometry::upVector(upAxisFor(job.up, job.model));
    view.normalMapCache = run.analysisCache();
    writeImage(render::PreviewRenderer(result.mesh).render(view, preview.inner()), previewOut);
    preview.finish(job.preview);
  }

  nlohmann::json& r = run.report();
  r["model"] = modelJson(job.model, in.model.mesh);
  r["model"]["preparation"] = toJson(result.preparation);
  r[analyses.graph ? "graph" : "exemplar"] = analyses.report;
  const double asGiven = analyses.pixelsAsGiven;
  r["parameters"] = {{"mode", o.mode == render::TextureMode::Solid ? "solid" : "surface"}, {"seed", o.surface.seed},
                     {"solid_method", synthesis::toString(o.solid.method)}, {"contrast_gain", o.solid.contrastGain},
                     {"refine_passes", o.solid.refinePasses},
                     {"exemplar_wrap", toString(analyses.surface ? analyses.surface->wrap
                                                : analyses.solid ? analyses.solid->wrap
                                                                 : synthesis::ExemplarWrap::Tile)},
                     {"texture_scale", result.textureScale * asGiven},
                     {"exemplar_pixels_per_texel", result.exemplarPixelsPerTexel * asGiven}};
  r["atlas"] = toJson(result.atlas);
  r["measures"] = toJson(result.measures, result.textureScale);
  if (o.mode == render::TextureMode::Solid)
    r["solid"] = {{"voxels_requested", result.solid.voxelsRequested},
                  {"voxels_synthesized", result.solid.voxelsSynthesized},
                  {"sampling", result.solid.trilinear() ? "trilinear" : "nearest"}};
  r["synthesis_levels"] = toJson(result.synthesisLevels);
  r["warnings"] = result.warnings;
  run.finish();
}

} // namespace

Command addTextureCommand(CLI::App& root) {
  auto job = std::make_shared<TextureJob>();
  render::TextureMeshOptions& o = job->options;
  Flags f(root.add_subcommand(
      "texture", "Synthesize a texture over a mesh from an exemplar and write the textured model "
                 "(surface: anisometric synthesis in the atlas; solid: the matching interior of the material)"));
  f.input("model", job->model, "Input mesh (.obj .ply .off .stl .gltf .glb .3mf)");
  f.text("-e,--exemplar", job->exemplar, "Exemplar image (PNG, JPEG, TIFF, EXR, GIMP .pat)");
  f.text("--graph", job->graph,
         "An exemplar graph instead (JSON: exemplars at several scales and the edges between them; "
         "docs/exemplar-graphs.md): the root's structure at the model's scale, the finer exemplars where texels "
         "are finer (surface mode; with the companion maps the file gives; default scale: the root spans the model's "
         "diagonal)");
  f.text("-o,--output", job->output, "Textured model (.glb .gltf .obj .3mf)")->required();
  f.choice("--mode", o.mode, {{"surface", render::TextureMode::Surface}, {"solid", render::TextureMode::Solid}},
           "surface (synthesis over the surface) or solid (a 3-D material, seamless)");
  f.option("--texture-scale,--scale", o.textureScale,
           "Exemplar pixels per model unit (0 = auto: 2048*sqrt(0.7/area), one per texel of a 2048² atlas, whatever "
           "--resolution, so a higher resolution only sharpens); a scale that puts 2 or more exemplar pixels in every "
           "texel synthesizes from a copy of the exemplar 2, 4, ... times smaller",
           {0, kUnbounded})->default_str("0 (auto)");
  f.option("--feature-size", job->featureSize, "Model units one exemplar spans (instead of --texture-scale)", positive())
      ->default_str("");
  f.option("--direction", o.field.direction, "Texture 'up' direction, projected to the surface (surface mode)");
  f.choice("--field", o.field.kind,
           {{"direction", geometry::TangentFieldKind::Direction}, {"curvature", geometry::TangentFieldKind::Curvature}},
           "Orientation field: direction, or curvature (minimum principal direction)");
  f.size("--resolution", o.atlas.pack.width, o.atlas.pack.height, "Atlas size",
         {atlas::PackChartsOptions::kMinSide, atlas::PackChartsOptions::kMaxSide}, true);
  f.option("--gutter", o.atlas.pack.gutter, "Minimum empty texels between charts (filtering reads across borders)",
           {2, atlas::PackChartsOptions::kMaxGutter});
  f.option("--seed", o.surface.seed, "Random seed: the only source of variation");
  wrapFlag(f, job->wrap);
  solidFidelityFlags(f, job->method, o.solid.contrastGain, o.solid.refinePasses, " (--mode solid)");
  f.text("--maps", job->maps,
         "Companion maps of the exemplar's size, synthesized with the same coordinates: "
         "normal=N.png,roughness=R.png,height=H.png (height is written as OUTPUT_height.png); with --graph, the "
         "maps its exemplars give (docs/exemplar-graphs.md)");
  f.modelOutput(job->write);
  f.printSize(job->write);
  f.text("--preview", job->preview, "Also render the textured model to this image");
  f.size("--preview-size", job->previewOptions.width, job->previewOptions.height, "Preview size", {1, 16384});
  f.camera(job->previewOptions);
  f.app()->add_flag_function(
      "--no-anisotropy", [job](int64_t) { job->fileMips.anisotropy = false; },
      "Where a normal map's normals spread one way (grooves), widen a .glb/.gltf's roughness chain for one "
      "isotropic lobe per texel instead of writing KHR_materials_anisotropy beside it (for viewers that read "
      "KHR_texture_basisu but not anisotropy, which would see only the narrower widening)");
  f.up(job->up);
  f.common(job->common, Common::Threads | Common::Memory | Common::Report | Common::Cache | Common::Backend | Common::Quiet);
  return {f.app(), [job] { runTexture(*job); }};
}

} // namespace texfab::cli
