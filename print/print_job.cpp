// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/print_job.h"

#include "print/voxel_colors.h"
#include "render/texture_mesh.h"
#include "synthesis/refine_solid.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace texfab::print {

namespace {

// Pixels of `exemplar` per model unit (textureScale 0 was resolved by PrintJob; it counts the pixels
// of the exemplar given, `downsampling` times those of `exemplar`).
double exemplarScale(const PrintJobOptions& o, const Image& exemplar, int downsampling = 1) {
  return o.featureSize > 0 ? std::max(exemplar.width, exemplar.height) / o.featureSize : o.textureScale / downsampling;
}

// The model coloured by surface synthesis (the texture job's surface mode).
geometry::Mesh surfaceTextured(const geometry::Mesh& mesh, const PrintExemplar& ex, const PrintJobOptions& o,
                               const Context& ctx) {
  if (!ex.surface) throw Error("surface colours need the exemplar's 2-D analysis");
  render::TextureMeshOptions t;
  t.atlas.pack.width = t.atlas.pack.height = o.resolution;
  t.surface.seed = o.seed;
  t.measure = false;
  t.textureScale = exemplarScale(o, *ex.color, ex.downsampling);
  render::TextureExemplar texture;
  texture.color = ex.color;
  texture.analysis = ex.surface;
  Stage stage(ctx, "surface texture");
  geometry::Mesh textured = render::textureMesh(mesh, texture, t, stage.inner()).mesh;
  stage.finish();
  return textured;
}

} // namespace

void PrintJobOptions::validate() const {
  grid.validate();
  voxelize.validate();
  slice.validate();
  solid.validate();
  if (!(textureScale >= 0) || !(featureSize >= 0) || !std::isfinite(textureScale) || !std::isfinite(featureSize))
    throw Error("texture scale and feature size must be finite and >= 0");
  if (textureScale > 0 && featureSize > 0) throw Error("give a texture scale or a feature size, not both");
  if (resolution < 64 || resolution > 16384) throw Error("the surface atlas must be 64 to 16384 texels a side");
}

PrintJob::PrintJob(geometry::Mesh mesh, const PrintJobOptions& options, const Context& ctx)
    : mesh_(std::move(mesh)), options_(options) {
  options_.validate();
  options_.solid.seed = options_.seed;
  if (mesh_.triangles.empty()) throw Error("the model has no triangles");
  // The scale of the model as given (texture's), not of its closed copy.
  if (options_.colors != PrintColors::Model && options_.textureScale == 0 && options_.featureSize == 0)
    options_.textureScale = render::autoTextureScale(mesh_);
  // Prepared as every job prepares its model; a surface that must be rebuilt from its volume is
  // rebuilt at the print's finest pitch (up to kMaxRebuildVoxels along its longest side).
  geometry::PrepareMeshOptions prepare(geometry::MeshUse::Print);
  const geometry::BoundingBox box = geometry::boundingBox(mesh_);
  const double finest = print::printGrid(box, options_.grid).pitch.minCoeff();
  prepare.remesh.resolution = int(std::clamp(std::ceil(double((box.max - box.min).maxCoeff()) / finest), 16.0,
                                             double(kMaxRebuildVoxels)));
  preparation_ = geometry::prepareMesh(mesh_, prepare, ctx);
  grid_ = print::printGrid(geometry::boundingBox(mesh_), options_.grid);
}

int PrintJob::analysisDownsampling(const Image& exemplar) const {
  if (options_.colors != PrintColors::Solid) return 1;
  return render::analysisDownsampling(exemplarScale(options_, exemplar) * grid_.pitch.minCoeff(), exemplar);
}

double PrintJob::memoryBytes(const Context& ctx) const {
  // A batch's solid voxels are about its print voxels (its shell voxels, a fraction of the batch,
  // each read one to 5^3 solid voxels: SolidSampling); refinement's slab is the part that grows.
  const int64_t batchVoxels = int64_t(grid_.width) * grid_.height * options_.slice.batchLayers;
  const double refinement = options_.colors == PrintColors::Solid
                                ? synthesis::refineSolidMemoryBytes(batchVoxels, options_.solid.refinePasses)
                                : 0.0;
  return double(sliceMemoryBytes(grid_, options_.slice, ctx)) + refinement;
}

PrintJobResult PrintJob::slice(const PrintExemplar& ex, int first, int count, SliceWriter& writer,
                               const std::string& modelName, const Context& ctx) const {
  const PrintJobOptions& o = options_;
  if (o.colors != PrintColors::Model && !ex.color) throw Error("textured colours need an exemplar");
  PrintJobResult result;
  PrintSource& source = result.source;
  source.model = modelName;
  source.colors = o.colors;
  geometry::Mesh surface;  // Surface: the model with its synthesized texture
  std::unique_ptr<VoxelColorSource> colors;
  const SolidVoxelColors* solid = nullptr;
  if (o.colors == PrintColors::Solid) {
    if (!ex.solid) throw Error("solid colours need the exemplar's solid analysis");
    const double scale = exemplarScale(o, *ex.color, ex.downsampling);
    source.exemplar = ex.name, source.seed = o.seed, source.method = o.solid.method;
    source.contrastGain = o.solid.contrastGain, source.refinePasses = o.solid.refinePasses;
    source.textureScale = scale * ex.downsampling, source.downsampling = ex.downsampling;
    auto s = std::make_unique<SolidVoxelColors>(*ex.solid, *ex.color, *ex.color, *ex.color, o.solid, scale, grid_);
    source.sampling = s->sampling();
    solid = s.get();
    colors = std::move(s);
  } else {
    if (o.colors == PrintColors::Surface) surface = surfaceTextured(mesh_, ex, o, ctx);
    if (o.colors == PrintColors::Surface) source.exemplar = ex.name, source.seed = o.seed;
    colors = std::make_unique<SurfaceVoxelColors>(o.colors == PrintColors::Surface ? surface : mesh_, grid_,
                                                  o.voxelize.shellMm);
  }

  Stage prepare(ctx, "voxelizer");
  const print::LayerVoxelizer voxelizer(o.colors == PrintColors::Surface ? surface : mesh_, grid_, o.voxelize);
  for (const std::string& repair : voxelizer.report().repairs) ctx.warn(repair);
  prepare.finish();

  SliceOptions slice = o.slice;
  slice.firstLayer = first;
  slice.layerCount = count;
  result.slice = sliceModel(voxelizer, *colors, slice, writer, source, ctx);
  if (solid) result.voxelsRequested = solid->voxelsRequested(), result.voxelsSynthesized = solid->voxelsSynthesized();
  return result;
}

} // namespace texfab::print
