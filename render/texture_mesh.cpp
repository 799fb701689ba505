// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6;
//           Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy solid texture synthesis. EGSR 2008.
#include "render/texture_mesh.h"

#include "atlas/compute_jacobians.h"
#include "atlas/surface_domain.h"
#include "render/bake.h"
#include "render/image/error.h"
#include "render/image/parallel.h"
#include "synthesis/coord_map.h"
#include "synthesis/synthesize_surface.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

namespace texfab::render {
using namespace atlas;

namespace {

std::string format(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

void requireSize(const Image* map, const Image& exemplar, const char* what) {
  if (map && (map->width != exemplar.width || map->height != exemplar.height))
    throw Error(std::string(what) + " map is " + std::to_string(map->width) + "x" + std::to_string(map->height) +
                ", the exemplar " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) +
                ": companion maps must have the exemplar's size");
}

// Bilinear lookup of `image` at continuous pixel coordinates (pixel centres at whole values), wrapping.
float bilinearToroidal(const Image& image, float u, float v, int channel) {
  const int x0 = int(std::floor(u)), y0 = int(std::floor(v));
  const float fx = u - float(x0), fy = v - float(y0);
  auto at = [&](int x, int y) {
    return image.at(((x % image.width) + image.width) % image.width, ((y % image.height) + image.height) % image.height,
                    channel);
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
  m.baseColorTexture = {r.baseColor, "basecolor.png"};
  if (r.normal) m.normalTexture = {r.normal, "normal.png"};
  if (r.metallicRoughness) m.metallicRoughnessTexture = {r.metallicRoughness, "metallic_roughness.png"};
  out.materials = {m};
  out.faceMaterials.clear();
  return out;
}

} // namespace

void checkCompanionMaps(const TextureExemplar& ex, TextureMode mode) {
  if (!ex.color) throw Error("texture: no exemplar image");
  if (mode == TextureMode::Solid && ex.normal)
    throw Error("a normal map needs surface mode: a solid texture has no tangent frame");
  requireSize(ex.normal, *ex.color, "normal");
  requireSize(ex.roughness, *ex.color, "roughness");
  requireSize(ex.height, *ex.color, "height");
}

TextureMeshResult textureMesh(const geometry::Mesh& mesh, const TextureExemplar& ex, const TextureMeshOptions& o,
                              const Context& ctx) {
  checkCompanionMaps(ex, o.mode);  // and that there is an exemplar
  const Image& exemplar = *ex.color;
  const bool surface = o.mode == TextureMode::Surface;
  if (surface && !ex.analysis) throw Error("texture: surface mode needs the exemplar analysis");
  if (!surface && !ex.solidAnalysis) throw Error("texture: solid mode needs the solid exemplar analysis");
  if (mesh.triangleCount() == 0) throw Error("the model has no triangles");
  if (!(o.textureScale >= 0) || !std::isfinite(o.textureScale)) throw Error("texture scale must be >= 0");
  o.surface.validate();
  o.solid.validate();

  TextureMeshResult r;
  Stage atlasStage(ctx, "atlas");
  r.atlas = generateAtlas(mesh, o.atlas, ctx.nested());
  const Atlas& atlas = r.atlas.atlas;
  const AtlasReport& ar = r.atlas.report;
  if (ar.flippedTriangles || ar.overlappingTexels)
    throw Error("internal: the atlas has flipped triangles or overlaps; please report this mesh");
  atlasStage.finish(std::to_string(ar.charts) + " charts, utilization " + format(ar.utilization) +
                             ", L2 stretch " + format(ar.l2Stretch));

  // Scale: exemplar pixels per model unit, and per texel.
  r.textureScale = o.textureScale > 0 ? o.textureScale : atlas.texelsPerUnit;
  const double pixelsPerTexel = r.textureScale / atlas.texelsPerUnit;
  const int exemplarSide = std::min(exemplar.width, exemplar.height);
  if (pixelsPerTexel > exemplarSide / 2.0)
    throw Error("the scale puts " + format(pixelsPerTexel) + " exemplar pixels in one texel (the exemplar is " +
                std::to_string(exemplarSide) + " pixels): features would be smaller than a texel; lower the scale "
                "or raise the resolution");
  if (pixelsPerTexel > 2.0)
    r.warnings.push_back("the exemplar is minified " + format(pixelsPerTexel) +
                         "x (exemplar pixels per texel): its finest detail is lost; raise --resolution to keep it");
  const double diagonal = geometry::boundingBox(mesh).diagonal();
  if (exemplarSide / r.textureScale > diagonal)
    r.warnings.push_back("one exemplar spans " + format(exemplarSide / r.textureScale) +
                         " model units, more than the model's diagonal (" + format(diagonal) + ")");

  // Fields: Jacobians and the surface domain.
  TexelField<TexelJacobian> jacobians;
  SurfaceDomainOptions domainOptions;
  if (surface) {
    Stage fieldStage(ctx, "tangent field");
    const geometry::TangentField field = geometry::computeTangentField(mesh, o.field);
    fieldStage.finish(std::to_string(field.singularTriangles.size()) + " singularities");
    jacobians = computeJacobians(mesh, atlas, r.atlas.fields, field, r.textureScale, ctx);
    // Levels down to the one whose texels span the whole exemplar.
    const int side = std::max(exemplar.width, exemplar.height);
    domainOptions.maxLevels = std::clamp(2 + int(std::ceil(std::log2(side / std::max(pixelsPerTexel, 1e-3)))), 1, 16);
  } else {
    domainOptions.maxLevels = 1;  // texels only (no Jacobians: no texture frame)
    domainOptions.neighbors = o.measure;  // for the seam measure only
  }
  Stage domainStage(ctx, "fields");
  synthesis::SurfaceDomain domain =
      buildSurfaceDomain(mesh, r.atlas.adjacency, atlas, r.atlas.fields, jacobians, domainOptions, ctx);
  jacobians = {};
  domainStage.finish(std::to_string(domain.levels[0].size()) + " texels, " +
                              std::to_string(domain.levels.size()) + " levels");

  const synthesis::SurfaceLevel& sites = domain.levels[0];
  const int gutter = o.atlas.pack.gutter;
  Stage synthesisStage(ctx, "synthesis");
  if (surface) {
    synthesis::SurfaceSynthesisResult s = synthesizeSurface(*ex.analysis, domain, o.surface, ctx);
    r.coords = std::move(s.coords);
    r.exemplarPixelsPerTexel = s.exemplarPixelsPerTexel;
    r.synthesisLevels = s.levels;
    synthesisStage.finish(std::to_string(s.levels.size()) + " levels, " + format(s.exemplarPixelsPerTexel) +
                                   " exemplar pixels per texel");
  } else {
    r.exemplarPixelsPerTexel = pixelsPerTexel;
    // Long on large atlases: the engine reports each level inside this stage.
    SolidSites solid =
        solidTriplesAtSites(sites, r.atlas.fields, *ex.solidAnalysis, o.solid, r.textureScale, synthesisStage.inner());
    r.triples = std::move(solid.triples);
    r.voxelsRequested = solid.voxelsRequested;
    r.voxelsSynthesized = solid.voxelsSynthesized;
    synthesisStage.finish(std::to_string(r.voxelsRequested) + " voxels requested, " +
                                   std::to_string(r.voxelsSynthesized) + " synthesized");
  }

  // Resolve: colours and companion maps through the same coordinates.
  Stage resolveStage(ctx, "resolve");
  const int colourChannels = synthesis::solidColorChannels(exemplar, exemplar, exemplar);  // 3, or 1 for grey
  // Colours at the nearest exemplar pixel keep the exemplar's sharpness; bilinear filtering only
  // where the exemplar is magnified (a texel finer than its pixels), where nearest looks blocky.
  const bool magnified = r.exemplarPixelsPerTexel < 0.75;
  auto lookup = [&](const Image& map, size_t site, int channel) -> float {
    channel = std::min(channel, map.channels - 1);
    if (surface) {
      const float u = synthesis::surfaceU(r.coords[site]), v = synthesis::surfaceV(r.coords[site]);
      if (magnified) return bilinearToroidal(map, u, v, channel);
      return map.at(int(std::floor(u + 0.5f)) % map.width, int(std::floor(v + 0.5f)) % map.height, channel);
    }
    // Solid: the mean over the three exemplar coordinates (as solidColors()).
    float sum = 0;
    for (uint32_t c : r.triples[site]) sum += map.at(int(synthesis::coordU(c)), int(synthesis::coordV(c)), channel);
    return sum / 3.0f;
  };
  r.baseColor = std::make_shared<const Image>(bakeSites(atlas.width, atlas.height, sites, colourChannels, gutter, ctx, [&](size_t s, float* out) {
    for (int ch = 0; ch < colourChannels; ++ch) out[ch] = lookup(exemplar, s, ch);
  }));
  if (ex.normal)
    r.normal = std::make_shared<const Image>(bakeSites(atlas.width, atlas.height, sites, 3, gutter, ctx, [&](size_t s, float* out) {
      float n[3];
      for (int ch = 0; ch < 3; ++ch) n[ch] = lookup(*ex.normal, s, ch);
      rotateNormal(sites.jacobian[s], n, out);
    }));
  if (ex.roughness)
    r.metallicRoughness = std::make_shared<const Image>(bakeSites(atlas.width, atlas.height, sites, 3, gutter, ctx, [&](size_t s, float* out) {
      out[0] = 1.0f;                        // unused (occlusion slot)
      out[1] = lookup(*ex.roughness, s, 0); // roughness
      out[2] = 0.0f;                        // metallic
    }));
  if (ex.height)
    r.height = std::make_shared<const Image>(bakeSites(atlas.width, atlas.height, sites, 1, gutter, ctx, [&](size_t s, float* out) {
      out[0] = lookup(*ex.height, s, 0);
    }));
  resolveStage.finish(std::to_string(atlas.width) + "x" + std::to_string(atlas.height) + " maps");

  if (o.measure) {
    Stage measureStage(ctx, "measures");
    r.measures.seams = measureSeams(sites, *r.baseColor);
    std::string detail = "seam ratio " + format(r.measures.seams.ratio);
    if (surface) {
      r.measures.scale = measureScale(sites, r.coords, r.atlas.fields, ex.analysis->width, ex.analysis->height,
                                      r.textureScale);
      r.measures.fidelity = measureSurfaceFidelity(sites, *r.baseColor, exemplar, r.atlas.fields, 1024, ctx);
      detail += ", scale within 15 % on " + format(100 * r.measures.scale->fractionWithin) + " % of the surface, fidelity " +
                format(r.measures.fidelity->fidelity);
    }
    measureStage.finish(detail);
  }

  r.mesh = texturedMesh(mesh, atlas, r);
  r.sites = std::move(domain.levels[0]);
  return r;
}

} // namespace texfab::render
