// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §5–6;
//           Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy solid texture synthesis. EGSR 2008.
#include "atlas/texture_mesh.h"

#include "atlas/compute_jacobians.h"
#include "atlas/surface_domain.h"
#include "render/error.h"
#include "render/parallel.h"
#include "synthesis/coord_map.h"
#include "synthesis/synthesize_surface.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <sstream>

namespace texfab::atlas {

namespace {

using Clock = std::chrono::steady_clock;

class Stages {
public:
  explicit Stages(const StageCallback& callback) : callback_(callback) {}
  void finish(const std::string& stage, const std::string& detail = {}) {
    const auto now = Clock::now();
    if (callback_) callback_(stage, std::chrono::duration<double>(now - start_).count(), detail);
    start_ = now;
  }

private:
  const StageCallback& callback_;
  Clock::time_point start_ = Clock::now();
};

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

// An atlas-sized image of `channels` with one value set per site (from `value(site, out)`), the
// gutters filled around the charts.
template <class Fn>
Image bake(const Atlas& atlas, const synthesis::SurfaceLevel& sites, int channels, int gutter, int threads,
           Fn&& value) {
  Image image(atlas.width, atlas.height, channels);
  std::vector<uint8_t> filled(size_t(atlas.width) * size_t(atlas.height), 0);
  parallelFor(0, int(sites.size()), threads, [&](int b, int e) {
    for (int s = b; s < e; ++s) {
      value(size_t(s), image.pixel(sites.x[size_t(s)], sites.y[size_t(s)]));
      filled[size_t(sites.y[size_t(s)]) * size_t(atlas.width) + size_t(sites.x[size_t(s)])] = 1;
    }
  }, 4096);
  fillGutters(image, std::move(filled), gutter + 4, threads);
  return image;
}

// The exemplar normal n (OpenGL convention: x right, y up in the image) at a site, expressed in
// the atlas image's frame. J maps atlas offsets to exemplar offsets (both y down); the exemplar's
// tangential direction (nx, -ny) maps back by J⁻¹, scale removed, and is flipped to y up again.
void rotateNormal(const std::array<float, 4>& j, const float* in, float* out) {
  const double nx = 2.0 * in[0] - 1.0, ny = -(2.0 * in[1] - 1.0), nz = 2.0 * in[2] - 1.0;
  const double det = double(j[0]) * j[3] - double(j[1]) * j[2];
  double tx = nx, ty = ny;
  if (det != 0) {
    const double s = std::sqrt(std::fabs(det)) / det;  // J⁻¹ · sqrt|det J|
    tx = s * (j[3] * nx - j[1] * ny);
    ty = s * (-j[2] * nx + j[0] * ny);
  }
  double vx = tx, vy = -ty, vz = nz;
  const double len = std::sqrt(vx * vx + vy * vy + vz * vz);
  if (len > 0) vx /= len, vy /= len, vz /= len;
  else vx = 0, vy = 0, vz = 1;
  out[0] = float(0.5 * vx + 0.5);
  out[1] = float(0.5 * vy + 0.5);
  out[2] = float(0.5 * vz + 0.5);
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

// Solid mode: the triple of each texel's voxel (its 3-D position times the scale), in one
// request (texels sharing a voxel share its value: values do not depend on how voxels are
// requested, and the engine computes each voxel once).
std::vector<synthesis::Triple> solidTexelTriples(const synthesis::SurfaceLevel& sites, const AtlasFields& fields,
                                                 const synthesis::SolidAnalysis& analysis,
                                                 const synthesis::SolidSynthesisOptions& options, double scale,
                                                 int threads, const synthesis::SolidLevelCallback& onLevel,
                                                 int64_t& requested, int64_t& synthesized) {
  std::vector<synthesis::Voxel> voxels(sites.size());
  for (size_t s = 0; s < sites.size(); ++s) {
    const Float3& p = fields.position.at(sites.x[s], sites.y[s]);
    voxels[s] = {int64_t(std::floor(double(p.x) * scale)), int64_t(std::floor(double(p.y) * scale)),
                 int64_t(std::floor(double(p.z) * scale))};
    for (int64_t c : {voxels[s].x, voxels[s].y, voxels[s].z})
      if (std::abs(c) > synthesis::kMaxSolidPosition)
        throw Error("the scale puts the model outside the solid texture's range (|position × scale| <= 2^30)");
  }
  // One request: a coarse-level cache could not serve it (it only serves later requests).
  synthesis::SolidSynthesisResult result = synthesizeSolid(analysis, voxels, options, nullptr, threads, onLevel);
  requested = result.distinctVoxels;
  synthesized = result.voxelsSynthesized();
  return std::move(result.triples);
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

void fillGutters(Image& image, std::vector<uint8_t> filled, int rounds, int threads) {
  const int w = image.width, h = image.height, c = image.channels;
  std::vector<uint8_t> next = filled;
  for (int round = 0; round < rounds; ++round) {
    std::atomic<bool> grew{false};
    parallelFor(0, h, threads, [&](int y0, int y1) {
      for (int y = y0; y < y1; ++y)
        for (int x = 0; x < w; ++x) {
          if (filled[size_t(y) * w + x]) continue;
          float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0};
          int n = 0;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int nx = x + dx, ny = y + dy;
              if (nx < 0 || ny < 0 || nx >= w || ny >= h || !filled[size_t(ny) * w + nx]) continue;
              const float* p = image.pixel(nx, ny);
              for (int ch = 0; ch < std::min(c, 8); ++ch) sum[ch] += p[ch];
              ++n;
            }
          if (!n) continue;
          float* out = image.pixel(x, y);  // not read this round: only filled texels are read
          for (int ch = 0; ch < std::min(c, 8); ++ch) out[ch] = sum[ch] / float(n);
          next[size_t(y) * w + x] = 1;
          grew = true;
        }
    }, 16);
    filled = next;
    if (!grew) break;
  }
  std::vector<double> mean(size_t(c), 0.0);
  size_t count = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (filled[size_t(y) * w + x]) {
        for (int ch = 0; ch < c; ++ch) mean[size_t(ch)] += image.at(x, y, ch);
        ++count;
      }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (!filled[size_t(y) * w + x])
        for (int ch = 0; ch < c; ++ch) image.at(x, y, ch) = count ? float(mean[size_t(ch)] / double(count)) : 0.0f;
}

TextureMeshResult textureMesh(const geometry::Mesh& mesh, const TextureExemplar& ex, const TextureMeshOptions& o,
                              const StageCallback& onStage) {
  checkCompanionMaps(ex, o.mode);  // and that there is an exemplar
  const Image& exemplar = *ex.color;
  const bool surface = o.mode == TextureMode::Surface;
  if (surface && !ex.analysis) throw Error("texture: surface mode needs the exemplar analysis");
  if (!surface && !ex.solidAnalysis) throw Error("texture: solid mode needs the solid exemplar analysis");
  if (mesh.triangleCount() == 0) throw Error("the model has no triangles");
  if (!(o.textureScale >= 0) || !std::isfinite(o.textureScale)) throw Error("texture scale must be >= 0");
  o.surface.validate();
  o.solid.validate();

  Stages stages(onStage);
  TextureMeshResult r;
  r.atlas = generateAtlas(mesh, o.atlas);
  const Atlas& atlas = r.atlas.atlas;
  const AtlasReport& ar = r.atlas.report;
  if (ar.flippedTriangles || ar.overlappingTexels)
    throw Error("internal: the atlas has flipped triangles or overlaps; please report this mesh");
  stages.finish("atlas", std::to_string(ar.charts) + " charts, utilization " + format(ar.utilization) +
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
    const geometry::TangentField field = geometry::computeTangentField(mesh, o.field);
    stages.finish("tangent field", std::to_string(field.singularTriangles.size()) + " singularities");
    jacobians = computeJacobians(mesh, atlas, r.atlas.fields, field, r.textureScale, o.threads);
    // Levels down to the one whose texels span the whole exemplar.
    const int side = std::max(exemplar.width, exemplar.height);
    domainOptions.maxLevels = std::clamp(2 + int(std::ceil(std::log2(side / std::max(pixelsPerTexel, 1e-3)))), 1, 16);
  } else {
    domainOptions.maxLevels = 1;  // texels only (no Jacobians: no texture frame)
    domainOptions.neighbors = o.measure;  // for the seam measure only
  }
  synthesis::SurfaceDomain domain =
      buildSurfaceDomain(mesh, r.atlas.adjacency, atlas, r.atlas.fields, jacobians, domainOptions, o.threads);
  jacobians = {};
  stages.finish("fields", std::to_string(domain.levels[0].size()) + " texels, " +
                              std::to_string(domain.levels.size()) + " levels");

  const synthesis::SurfaceLevel& sites = domain.levels[0];
  const int gutter = o.atlas.pack.gutter;
  if (surface) {
    synthesis::SurfaceSynthesisResult s = synthesizeSurface(*ex.analysis, domain, o.surface, o.threads);
    r.coords = std::move(s.coords);
    r.exemplarPixelsPerTexel = s.exemplarPixelsPerTexel;
    r.synthesisLevels = s.levels;
    stages.finish("synthesis", std::to_string(s.levels.size()) + " levels, " + format(s.exemplarPixelsPerTexel) +
                                   " exemplar pixels per texel");
  } else {
    r.exemplarPixelsPerTexel = pixelsPerTexel;
    // Long on large atlases: each level is reported as it ends.
    auto onLevel = [&](const synthesis::SolidLevelStats& level, int number, int levels) {
      if (onStage)
        onStage("level " + std::to_string(number) + "/" + std::to_string(levels), level.seconds,
                std::to_string(level.voxels) + " voxels, " + std::to_string(level.corrections) + " corrections");
    };
    r.triples = solidTexelTriples(sites, r.atlas.fields, *ex.solidAnalysis, o.solid, r.textureScale, o.threads, onLevel,
                                  r.voxelsRequested, r.voxelsSynthesized);
    stages.finish("synthesis", std::to_string(r.voxelsRequested) + " voxels requested, " +
                                   std::to_string(r.voxelsSynthesized) + " synthesized");
  }

  // Resolve: colours and companion maps through the same coordinates.
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
  r.baseColor = std::make_shared<const Image>(bake(atlas, sites, colourChannels, gutter, o.threads, [&](size_t s, float* out) {
    for (int ch = 0; ch < colourChannels; ++ch) out[ch] = lookup(exemplar, s, ch);
  }));
  if (ex.normal)
    r.normal = std::make_shared<const Image>(bake(atlas, sites, 3, gutter, o.threads, [&](size_t s, float* out) {
      float n[3];
      for (int ch = 0; ch < 3; ++ch) n[ch] = lookup(*ex.normal, s, ch);
      rotateNormal(sites.jacobian[s], n, out);
    }));
  if (ex.roughness)
    r.metallicRoughness = std::make_shared<const Image>(bake(atlas, sites, 3, gutter, o.threads, [&](size_t s, float* out) {
      out[0] = 1.0f;                        // unused (occlusion slot)
      out[1] = lookup(*ex.roughness, s, 0); // roughness
      out[2] = 0.0f;                        // metallic
    }));
  if (ex.height)
    r.height = std::make_shared<const Image>(bake(atlas, sites, 1, gutter, o.threads, [&](size_t s, float* out) {
      out[0] = lookup(*ex.height, s, 0);
    }));
  stages.finish("resolve", std::to_string(atlas.width) + "x" + std::to_string(atlas.height) + " maps");

  if (o.measure) {
    r.measures.seams = measureSeams(sites, *r.baseColor);
    std::string detail = "seam ratio " + format(r.measures.seams.ratio);
    if (surface) {
      r.measures.scale = measureScale(sites, r.coords, r.atlas.fields, ex.analysis->width, ex.analysis->height,
                                      r.textureScale);
      r.measures.fidelity = measureSurfaceFidelity(sites, *r.baseColor, exemplar, r.atlas.fields, 1024, o.threads);
      detail += ", scale within 15 % on " + format(100 * r.measures.scale->fractionWithin) + " % of the surface, fidelity " +
                format(r.measures.fidelity->fidelity);
    }
    stages.finish("measures", detail);
  }

  r.mesh = texturedMesh(mesh, atlas, r);
  r.sites = std::move(domain.levels[0]);
  return r;
}

} // namespace texfab::atlas
