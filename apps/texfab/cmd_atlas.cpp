// SPDX-License-Identifier: GPL-3.0-or-later
// texfab atlas: charts, parameterization (CGAL LSCM / ARAP), packing, texel fields, tangent
// field, Jacobians and indirection maps for synthesis in the atlas (Lefebvre & Hoppe 2006).
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "apps/texfab/report_json.h"
#include "atlas/build_indirection_map.h"
#include "atlas/compute_jacobians.h"
#include "atlas/generate_atlas.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/memory.h"
#include "core/text.h"
#include "geometry/io/mesh_io.h"
#include "geometry/repair/prepare_mesh.h"
#include "geometry/tangent_field.h"
#include "render/texture_mesh.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct AtlasJob {
  std::string model, output, debugImages;
  atlas::GenerateAtlasOptions options;
  geometry::TangentFieldOptions field;
  atlas::IndirectionOptions indirection;
  double textureScale = 0;
  geometry::MeshWriteOptions write;
  CommonFlags common;
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
  // Anisotropy as log(σ1/σ2), white at the 99th percentile over chart texels (most meshes are
  // nearly isotropic: a fixed scale leaves the image black).
  auto logRatio = [&](int x, int y) {
    const Eigen::Vector2d sv = atlas::singularValues(jac.at(x, y).j);
    return sv(1) > 0 ? float(std::log(sv(0) / sv(1))) : 0.0f;
  };
  std::vector<float> ratios;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (fields.samples.at(x, y).chart >= 0) ratios.push_back(logRatio(x, y));
  float ratioWhite = 1e-3f;
  if (!ratios.empty()) {
    const auto p99 = ratios.begin() + long(ratios.size() * 99 / 100);
    std::nth_element(ratios.begin(), p99, ratios.end());
    ratioWhite = std::max(*p99, 1e-3f);
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
      anisotropy.at(x, y, 0) = s.chart >= 0 ? std::clamp(logRatio(x, y) / ratioWhite, 0.0f, 1.0f) : 0.0f;
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

// The input with the atlas UVs; its textures are dropped (they belong to its old UVs).
geometry::Mesh withAtlasUvs(const geometry::Mesh& mesh, const atlas::Atlas& a, const Context& ctx) {
  geometry::Mesh out = mesh;
  out.uvs.resize(3 * mesh.triangleCount());
  for (size_t c = 0; c < out.uvs.size(); ++c) out.uvs[c] = a.normalizedUv(a.texelUvs[c]);
  out.tangents.clear();
  bool dropped = false;
  for (geometry::Material& m : out.materials) {
    for (geometry::Texture* t : m.textures())
      if (*t) *t = geometry::Texture{}, dropped = true;
    m.anisotropy = {};  // its direction is in the old UVs' tangent frame
  }
  if (dropped) ctx.warn("the input's textures were dropped: they belong to its old UVs");
  return out;
}

void runAtlas(AtlasJob& job) {
  Run run("atlas", job.common);
  checkPrintSize(job.write, job.output);
  const atlas::PackChartsOptions& pack = job.options.pack;
  run.checkMemory(atlas::atlasMemoryBytes(pack.width, pack.height),
                  "a " + std::to_string(pack.width) + "x" + std::to_string(pack.height) + " atlas");
  const fs::path out = run.output(job.output);
  const fs::path debug = job.debugImages.empty() ? fs::path() : run.outputs().addFolder(job.debugImages);

  Stage read(run.ctx(), "read");
  geometry::Mesh mesh = geometry::readMesh(job.model, run.ctx());
  read.finish(job.model + ": " + counted(int64_t(mesh.vertexCount()), "vertex", "vertices") + ", " +
              counted(int64_t(mesh.triangleCount()), "triangle"));
  const geometry::MeshPreparation preparation = geometry::prepareMesh(mesh, geometry::MeshUse::Surface, run.ctx());

  Stage stage(run.ctx(), "atlas");
  atlas::GenerateAtlasResult result = atlas::generateAtlas(mesh, job.options, stage.inner());
  const atlas::AtlasReport& r = result.report;
  stage.finish(counted(int64_t(r.charts), "chart") + ", utilization " + figure(r.utilization) + ", L2 stretch " +
               figure(r.l2Stretch) + ", max " + figure(r.maxStretch));
  for (const std::string& repair : r.repairs) run.ctx().warn(repair);
  if (r.flippedTriangles || r.overlappingTexels)
    throw Error("internal: the atlas has flipped triangles or overlaps; please report this mesh");

  Stage fieldStage(run.ctx(), "tangent field");
  const geometry::TangentField field = geometry::computeTangentField(mesh, job.field);
  fieldStage.finish(counted(int64_t(field.singularTriangles.size()), "singularity", "singularities"));
  Stage jacobianStage(run.ctx(), "jacobians");
  const double textureScale = job.textureScale > 0 ? job.textureScale : render::autoTextureScale(mesh);
  const auto jacobians = atlas::computeJacobians(mesh, result.atlas, result.fields, field, textureScale, run.ctx());
  jacobianStage.finish();
  Stage indirectionStage(run.ctx(), "indirection");
  const atlas::IndirectionMap indirection =
      atlas::buildIndirectionMap(mesh, result.connectivity, result.atlas, result.fields, job.indirection, run.ctx());
  indirectionStage.finish(counted(int64_t(indirection.targets.size()), "border texel") + ", " +
                          counted(int64_t(indirection.seamCrossings), "seam crossing"));

  Stage write(run.ctx(), "write");
  const geometry::Mesh textured = withAtlasUvs(mesh, result.atlas, run.ctx());
  job.write.up = geometry::upVector(geometry::conventionalUpAxis(job.model));
  geometry::writeMesh(textured, out, job.write);
  if (!debug.empty()) writeDebugImages(debug, textured, result.atlas, result.fields, jacobians);
  write.finish(job.output);

  nlohmann::json& report = run.report();
  report["model"] = modelJson(job.model, mesh);
  report["model"]["preparation"] = toJson(preparation);
  report["atlas"] = toJson(result);
  report["parameters"] = {{"texture_scale", textureScale}};
  report["tangent_field"] = {{"singularities", field.singularTriangles.size()}, {"total_index", field.totalIndex()}};
  report["indirection"] = {{"border_texels", indirection.targets.size()},
                           {"seam_crossings", indirection.seamCrossings},
                           {"boundary_stops", indirection.boundaryStops}};
  run.finish();
}

} // namespace

Command addAtlasCommand(CLI::App& root) {
  auto job = std::make_shared<AtlasJob>();
  atlas::GenerateAtlasOptions& o = job->options;
  Flags f(root.add_subcommand("atlas", "Build a texture atlas (charts, LSCM/ARAP parameterization, packing) "
                                      "and the surface fields for synthesis in it"));
  f.input("model", job->model, "Input mesh (.obj .ply .off .stl .gltf .glb .3mf)");
  f.text("-o,--output", job->output, "Output mesh with the atlas UVs (.glb .gltf .obj .ply .3mf)")->required();
  f.size("--resolution", o.pack.width, o.pack.height, "Atlas size",
         {atlas::PackChartsOptions::kMinSide, atlas::PackChartsOptions::kMaxSide}, true);
  f.option("--gutter", o.pack.gutter, "Minimum empty texels between charts", {0, atlas::PackChartsOptions::kMaxGutter});
  f.choice("--parameterizer", o.parameterize.parameterizer,
           {{"lscm", atlas::Parameterizer::Lscm}, {"arap", atlas::Parameterizer::Arap}},
           "lscm (Lévy et al. 2002) or arap (Liu et al. 2008, slower)");
  f.option("--max-angle", o.segment.maxNormalDeviationDegrees, "Largest normal deviation within a chart, degrees",
           {0, 90, true});
  f.option("--direction", job->field.direction, "Tangent field direction (projected to the surface)");
  f.choice("--field", job->field.kind,
           {{"direction", geometry::TangentFieldKind::Direction}, {"curvature", geometry::TangentFieldKind::Curvature}},
           "Tangent field: direction, or curvature (minimum principal direction)");
  f.option("--texture-scale", job->textureScale,
           "Exemplar pixels per model unit for the Jacobians (default: as texfab texture's)", positive())
      ->default_str("auto");
  f.option("--indirection-radius", job->indirection.radius, "Texels from chart borders with indirection entries",
           {1, 64});
  f.text("--debug-images", job->debugImages,
         "Write chart ids, normals, Jacobian magnitude/anisotropy, a checkerboard and checker.glb into this new folder");
  f.modelOutput(job->write);
  f.printSize(job->write);
  f.common(job->common, Common::Threads | Common::Memory | Common::Report | Common::Quiet);
  return {f.app(), [job] { runAtlas(*job); }};
}

} // namespace texfab::cli
