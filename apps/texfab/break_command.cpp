// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/break_command.h"

#include "apps/texfab/analysis.h"
#include "apps/texfab/report_json.h"
#include "core/image_io.h"
#include "core/memory.h"
#include "core/text.h"
#include "geometry/io/mesh_io.h"
#include "render/break/crack_measures.h"
#include "render/break/own_texels.h"

#include <optional>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

nlohmann::json piecesJson(const render::BrokenModel& model) {
  nlohmann::json pieces = nlohmann::json::array();
  for (const render::Piece& p : model.pieces)
    pieces.push_back({{"name", p.name}, {"volume", p.volume}, {"centroid", {p.centroid.x(), p.centroid.y(), p.centroid.z()}},
                      {"cut_area", p.cutArea}, {"triangles", p.mesh.triangleCount()}});
  return pieces;
}

void report(Run& run, const BreakJob& job, const geometry::Mesh& mesh, const render::BrokenModel& model,
            int downsampling) {
  nlohmann::json& r = run.report();
  r["model"] = modelJson(job.model, mesh);
  r["model"]["volume"] = model.modelVolume;
  r["model"]["preparation"] = toJson(model.preparation);
  double volumeSum = 0, cutArea = 0;
  for (const render::Piece& p : model.pieces) volumeSum += p.volume, cutArea += p.cutArea;
  r["pieces"] = piecesJson(model);
  r["piece_count"] = model.pieces.size();
  r["volume_sum"] = volumeSum;
  r["volume_relative_error"] = model.modelVolume != 0 ? (volumeSum - model.modelVolume) / model.modelVolume : 0.0;
  r["cut_area"] = cutArea;
  r["notes"] = model.notes;
  r["parameters"] = {{"seed", job.seed},
                     {"solid_method", synthesis::toString(job.solid.method)},
                     {"contrast_gain", job.contrastGain},
                     {"refine_passes", job.refinePasses},
                     {"mode", job.exemplar.empty() ? "own"
                              : job.options.outer.mode == render::TextureMode::Solid ? "solid" : "surface"},
                     {"interior_scale", model.interiorScale * downsampling},  // in the given image's pixels
                     {"downsampled", downsampling}};
  if (model.outer) r["atlas"] = toJson(model.outer->atlas);
  if (model.interior) {
    const render::CutFaceTexture& t = *model.interior;
    r["interior"] = {{"width", t.atlas.atlas.width}, {"height", t.atlas.atlas.height}, {"charts", t.atlas.report.charts},
                     {"utilization", t.atlas.report.utilization}, {"texels", t.sites.size()},
                     {"texels_per_unit", t.atlas.atlas.texelsPerUnit},
                     {"voxels_requested", t.voxelsRequested}, {"voxels_synthesized", t.voxelsSynthesized},
                     {"sampling", t.trilinear ? "trilinear" : "nearest"}};
    const render::CrackMatch match = render::measureCrackMatch(model);
    const render::CrackSeams seams = render::measureCrackSeams(model);
    r["measures"] = {{"crack_match", {{"difference", match.difference}, {"unrelated_difference", match.unrelatedDifference},
                                      {"samples", match.samples}}},
                     {"crack_edge_seams", {{"ratio", seams.ratio}, {"across", seams.acrossDifference},
                                           {"within", seams.withinDifference}, {"samples", seams.samples}}}};
  }
  if (model.fracture)
    r["fracture"] = {{"sites", model.fracture->sites}, {"merged", model.fracture->merged},
                     {"mean_site_spacing", model.fracture->cells.meanSpacing},
                     {"flattened_faces", model.fracture->cells.flattenedFaces}};
  r["intersect"] = {{"corefined_triangles", model.intersect.corefinedTriangles}, {"kept_whole", model.intersect.keptWhole}};
}

} // namespace

void addBreakInput(Flags& f, BreakJob& job) {
  f.input("model", job.model, "Input mesh (.obj .ply .off .stl .gltf .glb .3mf); repaired into a closed solid, or refused");
  f.text("-o,--output", job.output, "The pieces, one glTF node each (.glb .gltf)")->required();
}

void addBreakOptions(Flags& f, BreakJob& job) {
  render::BreakModelOptions& o = job.options;
  o.outer.mode = render::TextureMode::Solid;
  o.interior.atlas.pack.width = o.interior.atlas.pack.height = 0;  // auto
  f.text("-e,--exemplar", job.exemplar,
         "Texture the outer faces from this exemplar (default: keep the model's own material and UVs)");
  f.choice("--mode", o.outer.mode, {{"solid", render::TextureMode::Solid}, {"surface", render::TextureMode::Surface}},
           "Outer texture with --exemplar: solid (the material's interior, continuous into the cuts) or surface");
  f.text("--interior", job.interior, "Exemplar of the cut faces' solid texture (default: the --exemplar)");
  f.option("--texture-scale,--scale", o.interior.textureScale,
           "Exemplar pixels (voxels) per model unit of both textures (0 = auto, as texfab texture's)", {0, 1e9})
      ->default_str("0 (auto)");
  f.size("--resolution", o.outer.atlas.pack.width, o.outer.atlas.pack.height, "Outer atlas size (with --exemplar)",
         {atlas::PackChartsOptions::kMinSide, atlas::PackChartsOptions::kMaxSide}, true);
  f.size("--interior-resolution", o.interior.atlas.pack.width, o.interior.atlas.pack.height,
         "Atlas size of the cut faces (one atlas for all pieces); auto: the size that gives them the outer "
         "texture's texel density (with --exemplar; else 2048)",
         {atlas::PackChartsOptions::kMinSide, atlas::PackChartsOptions::kMaxSide}, true, true);
  f.option("--gutter", o.interior.atlas.pack.gutter, "Minimum empty texels between charts",
           {2, atlas::PackChartsOptions::kMaxGutter});
  f.option("--seed", job.seed, "Random seed of the textures (and of the fracture's sites)");
  wrapFlag(f, job.wrap);
  solidFidelityFlags(f, job.solid, job.contrastGain, job.refinePasses, " on the cut faces (and outside with --mode solid)");
  f.option("--explode", job.explode, "Move the pieces apart by this factor of their offset from the centre", {0, 100});
  f.text("--separate", job.separate,
         "Also write each piece to its own file in this new (or empty) folder, with only its own part of the textures");
  f.modelOutput(job.write);
  f.text("--preview", job.preview, "Also render the pieces, exploded, to this image");
  f.size("--preview-size", job.previewOptions.width, job.previewOptions.height, "Preview size", {1, 16384});
  f.camera(job.previewOptions);
  f.up(job.up);
  f.common(job.common, Common::Threads | Common::Memory | Common::Report | Common::Cache | Common::Backend | Common::Quiet);
}

void runBreak(const std::string& command, BreakJob& job) {
  Run run(command, job.common);
  render::BreakModelOptions& o = job.options;
  // Everything checkable is checked, and every output reserved, before any work.
  if (!geometry::meshFormatIsGltf(geometry::meshFormatOf(job.output)))
    throw UsageError(job.output + ": the pieces are glTF nodes; write .glb or .gltf");
  if (job.exemplar.empty() && job.interior.empty())
    throw UsageError("the cut faces show a solid texture: give --interior EX (or --exemplar EX to texture the outside too)");
  if (o.fracture) {
    o.fracture->seed = job.seed;
    try {
      o.fracture->validate();
    } catch (const Error& e) {
      throw UsageError(e.what());
    }
  }
  synthesis::SolidSynthesisOptions solid;
  solid.method = job.solid.method;
  solid.contrastGain = job.contrastGain;
  solid.refinePasses = job.refinePasses;
  o.shareTextureSettings(job.seed, solid);
  o.outer.measure = false;
  run.checkMemory(render::breakModelMemoryBytes(o, !job.exemplar.empty()), "the atlases of the outer and the cut faces");
  const fs::path out = run.output(job.output);
  const fs::path separate = job.separate.empty() ? fs::path() : run.outputs().addFolder(job.separate);
  if (!job.preview.empty()) checkImageWritable(job.preview);
  const fs::path preview = job.preview.empty() ? fs::path() : run.output(job.preview);

  Stage load(run.ctx(), "load");
  const geometry::Mesh mesh = geometry::readMesh(job.model, run.ctx());
  render::BreakExemplars ex;
  if (!job.exemplar.empty()) ex.outer = readImage(job.exemplar);
  if (!job.interior.empty()) ex.interior = readImage(job.interior);
  load.finish(job.model + ": " + counted(int64_t(mesh.triangleCount()), "triangle"));
  const geometry::PreparedMesh prepared = render::prepareBreakSolid(mesh, o, run.ctx());  // its repairs before the analyses
  ex.analyze(prepared.mesh, o, [&](const Image& image) { return chooseWrap(job.wrap, image, run); }, job.solid.tiles,
             run.analysisCache(), run.ctx());
  if (ex.downsampling > 1)
    run.note("the scale puts at least " + std::to_string(ex.downsampling) + " exemplar pixels in every texel: the " +
             "textures are synthesized from copies " + std::to_string(ex.downsampling) + " times smaller");

  const render::BrokenModel model = render::breakModel(prepared, ex.outerView, ex.interiorView, o, run.ctx());
  for (const std::string& note : model.notes) run.ctx().warn(note);

  Stage write(run.ctx(), "write");
  geometry::writeScene(render::sceneOf(model, job.explode), out, job.write);
  if (!separate.empty())
    for (geometry::SceneNode node : render::sceneOf(model)) {
      node.mesh = render::keepOwnTexels(node.mesh);  // its own part of the shared atlases
      geometry::writeScene(std::span(&node, 1), separate / (node.name + fs::path(job.output).extension().string()),
                           job.write);
    }
  write.finish(job.output + (separate.empty() ? "" : ", " + counted(int64_t(model.pieces.size()), "file") + " in " +
                                                         job.separate));
  if (!job.preview.empty()) {
    Stage stage(run.ctx(), "preview");
    render::RenderOptions view = job.previewOptions;
    view.up = geometry::upVector(upAxisFor(job.up, job.model));
    view.normalMapCache = run.analysisCache();
    const geometry::Mesh merged = render::mergedPieces(model, job.explode > 0 ? job.explode : 0.4);
    writeImage(render::PreviewRenderer(merged).render(view, stage.inner()), preview);
    stage.finish(job.preview);
  }
  run.note(counted(int64_t(model.pieces.size()), "piece") + " in " + job.output);
  if (run.reporting()) report(run, job, mesh, model, ex.downsampling);
  run.finish();
}

} // namespace texfab::cli
