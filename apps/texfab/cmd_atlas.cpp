// SPDX-License-Identifier: GPL-3.0-or-later
// texfab atlas: charts, parameterization (CGAL LSCM / ARAP), packing, texel fields, tangent
// field, Jacobians and indirection maps for synthesis in the atlas (Lefebvre & Hoppe 2006).
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "atlas/build_indirection_map.h"
#include "atlas/compute_jacobians.h"
#include "atlas/generate_atlas.h"
#include "geometry/mesh_io.h"
#include "geometry/tangent_field.h"
#include "render/image/error.h"
#include "render/image/memory.h"
#include "render/image/image_io.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct AtlasArgs {
  std::string model;
  std::string output;
  std::string resolution = "2048";
  int gutter = 4;
  std::string parameterizer = "lscm";
  std::string direction = "0,1,0";
  std::string field = "direction";
  double textureScale = 0;
  int radius = 4;
  double maxAngle = atlas::SegmentChartsOptions{}.maxNormalDeviationDegrees;
  int threads = 0;
  std::string report;
  std::string debugImages;
  bool quiet = false;
};

float hashColor(uint32_t id, int channel) {
  uint32_t h = id * 2654435761u + uint32_t(channel) * 40503u;
  h ^= h >> 15;
  h *= 2246822519u;
  h ^= h >> 13;
  return 0.25f + 0.75f * float(h & 0xffff) / 65535.0f;
}

void writeDebugImages(const fs::path& dir, const geometry::Mesh& mesh, const atlas::Atlas& a,
                      const atlas::AtlasFields& fields, const atlas::TexelField<atlas::TexelJacobian>& jac) {
  const int W = a.width, H = a.height;
  Image charts(W, H, 3), normals(W, H, 3), magnitude(W, H, 1), anisotropy(W, H, 1), checker(W, H, 3);
  // Jacobian magnitude relative to the median over chart texels.
  std::vector<float> mags;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (fields.samples.at(x, y).chart >= 0) mags.push_back(float(atlas::singularValues(jac.at(x, y).j)(0)));
  float median = 1;
  if (!mags.empty()) {
    std::nth_element(mags.begin(), mags.begin() + long(mags.size() / 2), mags.end());
    median = std::max(mags[mags.size() / 2], 1e-30f);
  }
  const double checkerTexels = std::max(8.0, double(W) / 64.0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const atlas::SurfaceSample& s = fields.samples.at(x, y);
      const atlas::Float3& n = fields.normal.at(x, y);
      for (int c = 0; c < 3; ++c) {
        charts.at(x, y, c) = s.chart >= 0 ? hashColor(uint32_t(s.chart), c) : 0.0f;
        normals.at(x, y, c) = std::clamp(0.5f * ((&n.x)[c] + 1.0f), 0.0f, 1.0f);
      }
      const Eigen::Vector2d sv = atlas::singularValues(jac.at(x, y).j);
      magnitude.at(x, y, 0) = std::clamp(float(0.5 * sv(0) / median), 0.0f, 1.0f);
      anisotropy.at(x, y, 0) = sv(1) > 0 ? std::clamp(float((sv(0) / sv(1) - 1) / 3), 0.0f, 1.0f) : 1.0f;
      const bool odd = (int(std::floor(x / checkerTexels)) + int(std::floor(y / checkerTexels))) % 2 != 0;
      const float base = odd ? 0.9f : 0.15f;
      for (int c = 0; c < 3; ++c) checker.at(x, y, c) = s.chart >= 0 ? base * (0.6f + 0.4f * hashColor(uint32_t(s.chart), c)) : base;
    }
  writeImage(charts, dir / "chart_ids.png");
  writeImage(normals, dir / "normals.png");
  writeImage(magnitude, dir / "jacobian_magnitude.png");
  writeImage(anisotropy, dir / "jacobian_anisotropy.png");
  writeImage(checker, dir / "checker.png");
  // The mesh with the checkerboard as its base colour, for `texfab render`.
  geometry::Mesh textured = mesh;
  geometry::Material m;
  m.name = "checker";
  m.metallicFactor = 0;
  m.roughnessFactor = 0.8f;
  m.baseColorTexture.image = std::make_shared<const Image>(std::move(checker));
  m.baseColorTexture.name = "checker.png";
  textured.materials = {m};
  textured.faceMaterials.clear();
  geometry::writeMesh(textured, dir / "checker.glb");
}

void runAtlas(const AtlasArgs& args) {
  Progress progress("texfab atlas", args.quiet);
  Context ctx{.threads = args.threads};
  // Everything checkable is checked before reading the model.
  geometry::meshFormatOf(args.output);
  const auto [width, height] = parseSize(args.resolution, "--resolution");
  atlas::GenerateAtlasOptions options;
  options.pack.width = width;
  options.pack.height = height;
  options.pack.gutter = args.gutter;
  options.segment.maxNormalDeviationDegrees = args.maxAngle;
  if (args.parameterizer == "lscm") options.parameterize.parameterizer = atlas::Parameterizer::Lscm;
  else if (args.parameterizer == "arap") options.parameterize.parameterizer = atlas::Parameterizer::Arap;
  else throw Error("--parameterizer: expected lscm or arap, got '" + args.parameterizer + "'");
  try {
    options.pack.validate();
    options.segment.validate();
  } catch (const Error& e) {
    throw Error(std::string("--resolution/--gutter/--max-angle: ") + e.what());
  }
  geometry::TangentFieldOptions fieldOptions;
  const std::vector<double> dir = parseNumberList(args.direction, "--direction");
  if (dir.size() != 3) throw Error("--direction: expected X,Y,Z, got '" + args.direction + "'");
  fieldOptions.direction = Eigen::Vector3f(float(dir[0]), float(dir[1]), float(dir[2]));
  if (!(fieldOptions.direction.norm() > 0) || !fieldOptions.direction.allFinite())
    throw Error("--direction: must be a finite non-zero vector, got '" + args.direction + "'");
  if (args.field == "direction") fieldOptions.kind = geometry::TangentFieldKind::Direction;
  else if (args.field == "curvature") fieldOptions.kind = geometry::TangentFieldKind::Curvature;
  else throw Error("--field: expected direction or curvature, got '" + args.field + "'");
  if (!(args.textureScale >= 0) || !std::isfinite(args.textureScale))
    throw Error("--texture-scale: must be >= 0 (0 = one exemplar pixel per texel)");
  atlas::IndirectionOptions indirectionOptions;
  indirectionOptions.radius = args.radius;
  indirectionOptions.validate();
  const double needed = double(width) * height * (sizeof(atlas::SurfaceSample) + 2 * sizeof(atlas::Float3) +
                                                 sizeof(atlas::TexelJacobian) + sizeof(int32_t) + 16.0);
  if (needed > 0.8 * double(physicalMemoryBytes()))
    throw Error("a " + std::to_string(width) + "x" + std::to_string(height) + " atlas needs about " +
                std::to_string(int(needed / double(1 << 30)) + 1) + " GiB of texel fields, more than this machine's memory");
  if (!args.debugImages.empty()) {
    std::error_code ec;
    fs::create_directories(args.debugImages, ec);
    if (ec || !fs::is_directory(args.debugImages))
      throw Error("--debug-images: cannot create folder " + args.debugImages);
  }

  progress.start("read");
  geometry::Mesh mesh = geometry::readMesh(args.model);
  progress.finish(args.model + ": " + std::to_string(mesh.vertexCount()) + " vertices, " +
                  std::to_string(mesh.triangleCount()) + " triangles");

  progress.start("atlas");
  atlas::GenerateAtlasResult result = atlas::generateAtlas(mesh, options, ctx);
  const atlas::AtlasReport& r = result.report;
  progress.finish(std::to_string(r.charts) + " charts, utilization " + std::to_string(r.utilization) + ", L2 stretch " +
                  std::to_string(r.l2Stretch) + ", max " + std::to_string(r.maxStretch));
  for (const std::string& repair : r.repairs) progress.note(repair);
  if (r.flippedTriangles || r.overlappingTexels)
    throw Error("internal: the atlas has flipped triangles or overlaps; please report this mesh");

  progress.start("tangent field");
  const geometry::TangentField field = geometry::computeTangentField(mesh, fieldOptions);
  progress.finish(std::to_string(field.singularTriangles.size()) + " singularities");

  progress.start("jacobians");
  const double textureScale = args.textureScale > 0 ? args.textureScale : result.atlas.texelsPerUnit;
  const auto jacobians = atlas::computeJacobians(mesh, result.atlas, result.fields, field, textureScale, ctx);
  progress.finish();

  progress.start("indirection");
  const atlas::IndirectionMap indirection = atlas::buildIndirectionMap(mesh, result.adjacency, result.atlas, result.fields,
                                                                       indirectionOptions, ctx);
  progress.finish(std::to_string(indirection.targets.size()) + " border texels, " +
                  std::to_string(indirection.seamCrossings) + " seam crossings");

  progress.start("write");
  geometry::Mesh out = mesh;
  out.uvs.resize(3 * mesh.triangleCount());
  for (size_t c = 0; c < out.uvs.size(); ++c) out.uvs[c] = result.atlas.normalizedUv(result.atlas.texelUvs[c]);
  out.tangents.clear();
  bool droppedTextures = false;
  for (geometry::Material& m : out.materials)
    for (geometry::Texture* t : {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture})
      if (*t) *t = geometry::Texture{}, droppedTextures = true;
  if (droppedTextures) progress.note("the input's textures were dropped: they belong to its old UVs");
  geometry::writeMesh(out, args.output);
  if (!args.debugImages.empty()) writeDebugImages(args.debugImages, out, result.atlas, result.fields, jacobians);
  progress.finish(args.output);

  if (!args.report.empty()) {
    nlohmann::json report;
    report["command"] = "atlas";
    report["model"] = {{"path", args.model}, {"vertices", mesh.vertexCount()}, {"triangles", mesh.triangleCount()}};
    report["parameters"] = {{"width", width}, {"height", height}, {"gutter", args.gutter},
                            {"parameterizer", args.parameterizer}, {"field", args.field},
                            {"direction", dir}, {"texture_scale", textureScale}, {"indirection_radius", args.radius},
                            {"max_angle", args.maxAngle}};
    report["atlas"] = {{"charts", r.charts},
                       {"utilization", r.utilization},
                       {"l2_stretch", r.l2Stretch},
                       {"max_stretch", r.maxStretch},
                       {"flipped_triangles", r.flippedTriangles},
                       {"overlapping_texels", r.overlappingTexels},
                       {"non_disk_charts", r.nonDiskCharts},
                       {"seam_length", r.seamLength},
                       {"texels_per_unit", r.texelsPerUnit},
                       {"chart_texels", result.fields.chartTexels},
                       {"packing_passes", r.pack.passes},
                       {"packed_mask_fill", double(r.pack.maskTexels) / (double(width) * height)},
                       {"used_height", r.pack.usedHeight},
                       {"splits", {{"disks", r.segment.splitsForDisks},
                                   {"flips", r.parameterize.splitsForFlips},
                                   {"overlaps", r.parameterize.splitsForOverlaps},
                                   {"stretch", r.parameterize.splitsForStretch},
                                   {"solver", r.parameterize.splitsForSolver},
                                   {"cut_to_triangles", r.parameterize.chartsCutToTriangles}}}};
    report["input"] = {{"degenerate_triangles", r.segment.degenerateTriangles},
                       {"non_manifold_edges", r.segment.nonManifoldEdges},
                       {"inconsistent_edges", r.segment.inconsistentEdges},
                       {"repairs", r.repairs}};
    report["tangent_field"] = {{"kind", args.field}, {"singularities", field.singularTriangles.size()},
                               {"total_index", field.totalIndex()}};
    report["indirection"] = {{"border_texels", indirection.targets.size()},
                             {"seam_crossings", indirection.seamCrossings},
                             {"boundary_stops", indirection.boundaryStops}};
    nlohmann::json stages = nlohmann::json::object();
    for (const auto& [stage, seconds] : r.seconds) stages[stage] = seconds;
    report["atlas_stage_seconds"] = stages;
    report["timings"] = progress.timings();
    report["peak_memory_mib"] = peakMemoryMiB();
    writeReport(report, args.report);
  }
}

} // namespace

Command addAtlasCommand(CLI::App& root) {
  auto args = std::make_shared<AtlasArgs>();
  CLI::App* app = root.add_subcommand("atlas", "Build a texture atlas (charts, LSCM/ARAP parameterization, packing) "
                                               "and the surface fields for synthesis in it");
  app->add_option("model", args->model, "Input mesh (.obj .ply .off .stl .gltf .glb)")->required();
  app->add_option("-o,--output", args->output, "Output mesh with the atlas UVs (.glb .gltf .obj .ply)")->required();
  app->add_option("--resolution", args->resolution, "Atlas size N (NxN) or WxH, powers of two")->capture_default_str();
  app->add_option("--gutter", args->gutter, "Minimum empty texels between charts (0-64)")->capture_default_str();
  app->add_option("--parameterizer", args->parameterizer, "lscm (Lévy et al. 2002) or arap (Liu et al. 2008, slower)")
      ->capture_default_str();
  app->add_option("--direction", args->direction, "Tangent field direction X,Y,Z (projected to the surface)")
      ->capture_default_str();
  app->add_option("--field", args->field, "Tangent field: direction or curvature (minimum principal direction)")
      ->capture_default_str();
  app->add_option("--texture-scale", args->textureScale,
                  "Exemplar pixels per model unit for the Jacobians (0 = the atlas density: one pixel per texel)")
      ->capture_default_str();
  app->add_option("--indirection-radius", args->radius, "Texels from chart borders with indirection entries (1-64)")
      ->capture_default_str();
  app->add_option("--max-angle", args->maxAngle, "Largest normal deviation within a chart, degrees")->capture_default_str();
  app->add_option("--threads", args->threads, "Worker threads (0 = all cores); the atlas does not depend on it")
      ->capture_default_str();
  app->add_option("--report", args->report, "Write charts, utilization, stretch, flips, overlaps, seams and timings as JSON");
  app->add_option("--debug-images", args->debugImages,
                  "Write chart ids, normals, Jacobian magnitude/anisotropy, a checkerboard and checker.glb to this folder");
  app->add_flag("-q,--quiet", args->quiet, "No progress output");
  return {app, [args] { runAtlas(*args); }};
}

} // namespace texfab::cli
