// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6;
//           Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy solid texture synthesis. EGSR 2008.
#include "render/texture_mesh.h"

#include "atlas/compute_jacobians.h"
#include "atlas/surface_domain.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/text.h"
#include "render/bake.h"
#include "synthesis/coord_map.h"
#include "synthesis/refine_solid.h"
#include "synthesis/synthesize_surface.h"
#include "synthesis/synthesize_graph.h"
#include "synthesis/synthesize_surface_graph.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <sstream>

namespace texfab::render {
using namespace atlas;

namespace {

void requireSize(const Image* map, const Image& exemplar, const char* what) {
  if (map && (map->width != exemplar.width || map->height != exemplar.height))
    throw Error(std::string(what) + " map is " + std::to_string(map->width) + "x" + std::to_string(map->height) +
                ", the exemplar " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) +
                ": companion maps must have the exemplar's size");
}

// Pixel x of an image `size` wide: wrapped on a toroidal exemplar, else clamped to it.
int pixelIndex(int x, int size, bool toroidal) {
  return toroidal ? ((x % size) + size) % size : std::clamp(x, 0, size - 1);
}

// Bilinear lookup of `image` at continuous pixel coordinates (pixel centres at whole values).
float bilinear(const Image& image, float u, float v, int channel, bool toroidal) {
  const int x0 = int(std::floor(u)), y0 = int(std::floor(v));
  const float fx = u - float(x0), fy = v - float(y0);
  auto at = [&](int x, int y) {
    return image.at(pixelIndex(x, image.width, toroidal), pixelIndex(y, image.height, toroidal), channel);
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// The input mesh with the atlas's UVs and one PBR material carrying the synthesized maps.
geometry::Mesh texturedMesh(const geometry::Mesh& mesh, const Atlas& atlas, const TextureMeshResult& r) {
  geometry::Mesh out = mesh;
  out.uvs.resize(3 * mesh.triangleCount());
  for (size_t c = 0; c < out.uvs.size(); ++c) out.uvs[c] = atlas.normalizedUv(atlas.texelUvs[c]);
  out.tangents.clear();  // they belonged to the old UVs; readers derive them from the new ones
  geometry::Material m;
  m.name = "texfab";
  m.metallicFactor = 0.0f;
  m.roughnessFactor = r.metallicRoughness ? 1.0f : 0.8f;
  auto texture = [](std::shared_ptr<const Image> image, const char* name) {
    geometry::Texture t;
    t.image = std::move(image);
    t.name = name;
    return t;
  };
  m.baseColorTexture = texture(r.baseColor, "basecolor.png");
  if (r.normal) m.normalTexture = texture(r.normal, "normal.png");
  if (r.metallicRoughness) m.metallicRoughnessTexture = texture(r.metallicRoughness, "metallic_roughness.png");
  out.materials = {m};
  out.faceMaterials.clear();
  return out;
}

} // namespace

void checkCompanionMaps(const TextureExemplar& ex, TextureMode mode) {
  if (!ex.color) throw Error("texture: no exemplar image");
  if (mode == TextureMode::Solid && ex.normal)
    throw Error("a normal map needs surface mode: a solid texture has no tangent frame");
  if (ex.graph && mode == TextureMode::Solid) throw Error("an exemplar graph needs surface mode");
  const Image& size = ex.graph ? ex.graph->colors : *ex.color;  // a graph's maps are packed as its colours
  requireSize(ex.normal, size, "normal");
  requireSize(ex.roughness, size, "roughness");
  requireSize(ex.height, size, "height");
}

double autoTextureScale(const geometry::Mesh& mesh) {
  const double area = geometry::surfaceArea(mesh);
  if (!(area > 0) || !std::isfinite(area)) throw Error("the model has no surface area to scale a texture to");
  return kAutoScaleAtlasSide * std::sqrt(kAutoScaleCoverage / area);
}

double graphScaleAsGiven(const synthesis::ExemplarGraph& graph, double textureScale, double featureSize) {
  return featureSize > 0 ? graph.side() / featureSize : textureScale * graph.rootMagnification;
}

double graphTextureScale(const geometry::Mesh& mesh, int rootSide) {
  const double diagonal = geometry::boundingBox(mesh).diagonal();
  if (!(diagonal > 0) || !std::isfinite(diagonal)) throw Error("the model has no extent to scale a texture to");
  return rootSide / diagonal;
}

double textureScaleFor(const geometry::Mesh& mesh, const TextureMeshOptions& o, const synthesis::GraphAnalysis* graph) {
  if (o.textureScale > 0) return o.textureScale;
  return graph ? graphTextureScale(mesh, graph->side) : autoTextureScale(mesh);
}

// Charts keep their surface area in UV space, so a W x H atlas has at most sqrt(W H / area) texels
// per model unit.
int analysisDownsampling(const geometry::Mesh& mesh, const TextureMeshOptions& o, const Image& exemplar) {
  const double area = geometry::surfaceArea(mesh);
  if (!(area > 0)) return 1;
  return analysisDownsampling(
      textureScaleFor(mesh, o) / std::sqrt(double(o.atlas.pack.width) * double(o.atlas.pack.height) / area), exemplar);
}

int analysisDownsampling(double fewestPixelsPerSample, const Image& exemplar) {
  const int side = std::min(exemplar.width, exemplar.height);
  int factor = 1;
  while (2 * factor <= fewestPixelsPerSample && side / (2 * factor) >= kMinAnalysedSide) factor *= 2;
  return factor;
}

double textureMeshMemoryBytes(const TextureMeshOptions& o) {
  const double texels = double(o.atlas.pack.width) * double(o.atlas.pack.height);
  if (o.mode != TextureMode::Solid) return texels * 220.0;
  return texels * 440.0 + synthesis::refineSolidMemoryBytes(int64_t(texels), o.solid.refinePasses);
}

namespace {

/// textureMesh's stages, in order; each fills its part of the result.
class TextureJob {
 public:
  TextureJob(const geometry::PreparedMesh& model, const TextureExemplar& ex, const TextureMeshOptions& o,
             const Context& ctx)
      : mesh_(model.mesh), ex_(ex), o_(o), ctx_(ctx), exemplar_(*ex.color), surface_(o.mode == TextureMode::Surface) {
    r_.preparation = model.preparation;
    r_.warnings = model.preparation.warnings;  // ctx has them already
  }

  void buildAtlas();
  void checkScale();
  void buildDomain();
  void synthesize();
  void resolveMaps();
  void measure();
  TextureMeshResult finish();

 private:
  /// Warnings go to the report and, at once, to ctx (before the long synthesis).
  void warn(std::string message) {
    ctx_.warn(message);
    r_.warnings.push_back(std::move(message));
  }
  /// Channel `channel` of a companion map (or the exemplar) at a site's synthesized coordinates.
  float lookup(const Image& map, size_t site, int channel, bool magnified) const;

  const geometry::Mesh& mesh_;
  const TextureExemplar& ex_;
  const TextureMeshOptions& o_;
  const Context& ctx_;
  const Image& exemplar_;
  const bool surface_;
  TextureMeshResult r_;
  double pixelsPerTexel_ = 0;
  synthesis::SurfaceDomain domain_; ///< its finest level: the sites (texels) every map is baked at
};

void TextureJob::buildAtlas() {
  Stage stage(ctx_, "atlas");
  r_.atlas = generateAtlas(mesh_, o_.atlas, ctx_.nested());
  const AtlasReport& ar = r_.atlas.report;
  if (ar.flippedTriangles || ar.overlappingTexels)
    throw Error("internal: the atlas has flipped triangles or overlaps; please report this mesh");
  stage.finish(counted(int64_t(ar.charts), "chart") + ", utilization " + figure(ar.utilization) + ", L2 stretch " +
               figure(ar.l2Stretch));
  for (const std::string& repair : ar.repairs) ctx_.warn(repair);
}

// Scale: exemplar pixels per model unit, and per texel.
void TextureJob::checkScale() {
  const Atlas& atlas = r_.atlas.atlas;
  r_.textureScale = textureScaleFor(mesh_, o_, ex_.graph);
  pixelsPerTexel_ = r_.textureScale / atlas.texelsPerUnit;
  const int exemplarSide = std::min(exemplar_.width, exemplar_.height);
  if (pixelsPerTexel_ > exemplarSide / 2.0)
    throw Error("the scale puts " + figure(pixelsPerTexel_) + " exemplar pixels in one texel (the exemplar is " +
                std::to_string(exemplarSide) + " pixels): features would be smaller than a texel; lower "
                "--texture-scale or raise --resolution");
  if (ex_.graph) return;  // finer texels zoom into the graph's finer exemplars
  if (pixelsPerTexel_ > 2.0)
    warn("the exemplar is minified " + figure(pixelsPerTexel_) +
         "x (exemplar pixels per texel): its finest detail is lost; raise --resolution to keep it");
  const double diagonal = geometry::boundingBox(mesh_).diagonal();
  if (exemplarSide / r_.textureScale > diagonal)
    warn("one exemplar spans " + figure(exemplarSide / r_.textureScale) + " model units, more than the model's diagonal (" +
         figure(diagonal) + ")");
}

// Fields: Jacobians (surface mode) and the surface domain.
void TextureJob::buildDomain() {
  const Atlas& atlas = r_.atlas.atlas;
  TexelField<TexelJacobian> jacobians;
  SurfaceDomainOptions domainOptions;
  if (surface_) {
    Stage fieldStage(ctx_, "tangent field");
    const geometry::TangentField field = geometry::computeTangentField(mesh_, o_.field);
    fieldStage.finish(std::to_string(field.singularTriangles.size()) + " singularities");
    jacobians = computeJacobians(mesh_, atlas, r_.atlas.fields, field, r_.textureScale, ctx_);
    // Levels down to the one whose texels span the whole exemplar.
    const int side = std::max(exemplar_.width, exemplar_.height);
    domainOptions.maxLevels = std::clamp(2 + int(std::ceil(std::log2(side / std::max(pixelsPerTexel_, 1e-3)))), 1, 16);
  } else {
    domainOptions.maxLevels = 1;            // texels only (no Jacobians: no texture frame)
    domainOptions.neighbors = o_.measure;  // for the seam measure only
  }
  Stage stage(ctx_, "fields");
  domain_ = buildSurfaceDomain(mesh_, r_.atlas.connectivity, atlas, r_.atlas.fields, jacobians, domainOptions, ctx_);
  stage.finish(std::to_string(domain_.levels[0].size()) + " texels, " + std::to_string(domain_.levels.size()) + " levels");
}

void TextureJob::synthesize() {
  Stage stage(ctx_, "synthesis");
  if (surface_) {
    synthesis::SurfaceSynthesisResult s = ex_.graph ? synthesizeSurfaceGraph(*ex_.graph, domain_, o_.surface, stage.inner())
                                                    : synthesizeSurface(*ex_.analysis, domain_, o_.surface, ctx_);
    r_.coords = std::move(s.coords);
    r_.colorOffsets = std::move(s.colorOffsets);
    r_.exemplarPixelsPerTexel = s.exemplarPixelsPerTexel;
    r_.synthesisLevels = s.levels;
    stage.finish(std::to_string(s.levels.size()) + " levels, " + figure(s.exemplarPixelsPerTexel) +
                 " exemplar pixels per texel");
  } else {
    r_.exemplarPixelsPerTexel = pixelsPerTexel_;
    // Long on large atlases: the engine reports each level inside this stage.
    r_.solid = solidAtSites(domain_.levels[0], r_.atlas.fields, *ex_.solidAnalysis, o_.solid, r_.textureScale,
                            pixelsPerTexel_, stage.inner());
    stage.finish(r_.solid.summary(o_.solid.method));
  }
}

float TextureJob::lookup(const Image& map, size_t site, int channel, bool magnified) const {
  channel = std::min(channel, map.channels - 1);
  if (ex_.graph) return synthesis::sampleSurfaceGraph(*ex_.graph, map, r_.coords[site], channel);
  if (surface_) {
    const float u = synthesis::surfaceU(r_.coords[site]), v = synthesis::surfaceV(r_.coords[site]);
    const bool toroidal = ex_.analysis->wrap == synthesis::ExemplarWrap::Tile;
    if (magnified) return bilinear(map, u, v, channel, toroidal);
    return map.at(pixelIndex(int(std::floor(u + 0.5f)), map.width, toroidal),
                  pixelIndex(int(std::floor(v + 0.5f)), map.height, toroidal), channel);
  }
  // Solid: the mean over the three exemplar coordinates (as solidColors()), blended where trilinear.
  float value = 0;
  r_.solid.sample(site, 1, [&](const synthesis::Triple& t, float* out) {
    float sum = 0;
    for (uint32_t c : t) sum += map.at(int(synthesis::coordU(c)), int(synthesis::coordV(c)), channel);
    *out = sum / 3.0f;
  }, &value);
  return value;
}

// Resolve: colours and companion maps through the same coordinates.
void TextureJob::resolveMaps() {
  Stage stage(ctx_, "resolve");
  const Atlas& atlas = r_.atlas.atlas;
  const synthesis::SurfaceLevel& sites = domain_.levels[0];
  const int gutter = o_.atlas.pack.gutter;
  const int colorChannels = synthesis::solidColorChannels(exemplar_, exemplar_, exemplar_); // 3, or 1 for grey
  // Colours at the nearest exemplar pixel keep the exemplar's sharpness; bilinear filtering only
  // where the exemplar is magnified (a texel finer than its pixels), where nearest looks blocky.
  const bool magnified = r_.exemplarPixelsPerTexel < 0.75;
  const Image& colors = ex_.graph ? ex_.graph->colors : exemplar_;
  auto bake = [&](int channels, auto&& texel) {
    return std::make_shared<const Image>(bakeSites(atlas.width, atlas.height, sites, channels, gutter, ctx_, texel));
  };
  r_.baseColor = bake(colorChannels, [&](size_t s, float* out) {
    for (int ch = 0; ch < colorChannels; ++ch) out[ch] = lookup(colors, s, ch, magnified);
    if (!r_.colorOffsets.empty())  // a graph's transfers
      for (int ch = 0; ch < colorChannels; ++ch)
        out[ch] = synthesis::transferredColor(out[ch], r_.colorOffsets[s][size_t(ch)]);
  });
  if (ex_.normal)
    r_.normal = bake(3, [&](size_t s, float* out) {
      float n[3];
      for (int ch = 0; ch < 3; ++ch) n[ch] = lookup(*ex_.normal, s, ch, magnified);
      rotateNormal(sites.jacobian[s], n, out);
    });
  if (ex_.roughness)
    r_.metallicRoughness = bake(3, [&](size_t s, float* out) {
      out[0] = 1.0f;                                     // unused (occlusion slot)
      out[1] = lookup(*ex_.roughness, s, 0, magnified); // roughness
      out[2] = 0.0f;                                     // metallic
    });
  if (ex_.height)
    r_.height = bake(1, [&](size_t s, float* out) { out[0] = lookup(*ex_.height, s, 0, magnified); });
  stage.finish(std::to_string(atlas.width) + "x" + std::to_string(atlas.height) + " maps");
}

void TextureJob::measure() {
  Stage stage(ctx_, "measures");
  const synthesis::SurfaceLevel& sites = domain_.levels[0];
  r_.measures.seams = measureSeams(sites, *r_.baseColor);
  std::string detail = "seam ratio " + figure(r_.measures.seams.ratio);
  if (surface_ && !ex_.graph) {  // against one exemplar: not a graph's
    r_.measures.scale =
        measureScale(sites, r_.coords, r_.atlas.fields, ex_.analysis->width, ex_.analysis->height, r_.textureScale);
    r_.measures.fidelity =
        measureSurfaceFidelity(sites, *r_.baseColor, exemplar_, r_.atlas.fields, {.samples = 1024}, ctx_);
    detail += ", scale within 15 % on " + figure(100 * r_.measures.scale->fractionWithin) + " % of the surface, fidelity " +
              figure(r_.measures.fidelity->fidelity);
  }
  stage.finish(detail);
}

TextureMeshResult TextureJob::finish() {
  r_.mesh = texturedMesh(mesh_, r_.atlas.atlas, r_);
  r_.sites = std::move(domain_.levels[0]);
  return std::move(r_);
}

} // namespace

TextureMeshResult textureMesh(const geometry::PreparedMesh& model, const TextureExemplar& ex,
                              const TextureMeshOptions& o, const Context& ctx) {
  checkCompanionMaps(ex, o.mode);  // and that there is an exemplar
  const bool surface = o.mode == TextureMode::Surface;
  if (surface && !ex.analysis && !ex.graph) throw Error("texture: surface mode needs the exemplar analysis");
  if (!surface && !ex.solidAnalysis) throw Error("texture: solid mode needs the solid exemplar analysis");
  if (model.mesh.triangleCount() == 0) throw Error("the model has no triangles");
  if (!(o.textureScale >= 0) || !std::isfinite(o.textureScale)) throw Error("texture scale must be >= 0");
  o.surface.validate();
  o.solid.validate();

  TextureJob job(model, ex, o, ctx);
  job.buildAtlas();
  job.checkScale();
  job.buildDomain();
  job.synthesize();
  job.resolveMaps();
  if (o.measure) job.measure();
  return job.finish();
}

TextureMeshResult textureMesh(const geometry::Mesh& mesh, const TextureExemplar& ex, const TextureMeshOptions& o,
                              const Context& ctx) {
  return textureMesh(geometry::preparedCopy(mesh, geometry::MeshUse::Surface, ctx), ex, o, ctx);
}

} // namespace texfab::render
