// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/break/texture_cut_faces.h"

#include "atlas/surface_domain.h"
#include "core/error.h"
#include "render/bake.h"

#include <unordered_map>

namespace texfab::render {
namespace {

// The chosen faces of all pieces as one mesh (vertices shared within a piece).
geometry::Mesh collectFaces(std::span<const geometry::Mesh> pieces, std::span<const std::vector<uint32_t>> faces) {
  geometry::Mesh out;
  for (size_t p = 0; p < pieces.size(); ++p) {
    std::unordered_map<uint32_t, uint32_t> local;
    for (uint32_t t : faces[p]) {
      std::array<uint32_t, 3> tri;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = pieces[p].triangles[t][size_t(k)];
        const auto [it, inserted] = local.emplace(v, uint32_t(out.positions.size()));
        if (inserted) out.positions.push_back(pieces[p].positions[v]);
        tri[size_t(k)] = it->second;
      }
      out.triangles.push_back(tri);
    }
  }
  return out;
}

} // namespace

CutFaceTexture textureCutFaces(std::span<const geometry::Mesh> pieces, std::span<const std::vector<uint32_t>> faces,
                               const Image& exemplar, const synthesis::SolidAnalysis& analysis,
                               const CutFaceTextureOptions& o, const Context& ctx, synthesis::SolidLevelCache* cache) {
  if (pieces.size() != faces.size()) throw Error("internal: textureCutFaces needs a face list per piece");
  if (!(o.textureScale >= 0) || !std::isfinite(o.textureScale)) throw Error("the interior's scale must be >= 0");
  o.solid.validate();
  const geometry::Mesh mesh = collectFaces(pieces, faces);
  if (mesh.triangles.empty()) throw Error("there are no cut faces to texture");

  CutFaceTexture r;
  Stage atlasStage(ctx, "atlas");
  try {
    r.atlas = atlas::generateAtlas(mesh, o.atlas, ctx.nested());
  } catch (const atlas::AtlasTooSmall& e) {
    throw atlas::AtlasTooSmall(std::string("the cut faces' atlas: ") + e.what(), "interior");
  }
  const atlas::Atlas& at = r.atlas.atlas;
  atlasStage.finish(std::to_string(r.atlas.report.charts) + " charts, utilization " +
                    std::to_string(int(100 * r.atlas.report.utilization)) + " %");

  Stage fieldStage(ctx, "fields");
  atlas::SurfaceDomainOptions domainOptions;
  domainOptions.maxLevels = 1;  // texels only: the solid texture needs no texture frame
  domainOptions.neighbors = false;
  synthesis::SurfaceDomain domain =
      atlas::buildSurfaceDomain(mesh, r.atlas.connectivity, at, r.atlas.fields, {}, domainOptions, ctx);
  r.sites = std::move(domain.levels[0]);
  fieldStage.finish(std::to_string(r.sites.size()) + " texels");

  Stage synthesisStage(ctx, "synthesis");
  r.textureScale = o.textureScale > 0 ? o.textureScale : at.texelsPerUnit;
  const SolidSites solid = solidAtSites(r.sites, r.atlas.fields, analysis, o.solid, r.textureScale,
                                       r.textureScale / at.texelsPerUnit, ctx, cache);
  r.voxelsRequested = solid.voxelsRequested;
  r.voxelsSynthesized = solid.voxelsSynthesized;
  r.trilinear = solid.trilinear();
  synthesisStage.finish(solid.summary(o.solid.method));

  Stage resolveStage(ctx, "resolve");
  const int channels = synthesis::solidColorChannels(exemplar, exemplar, exemplar);
  const auto color = [&](const synthesis::Triple& t, float* out) { synthesis::solidColor(t, exemplar, exemplar, exemplar, out); };
  r.baseColor = std::make_shared<const Image>(
      bakeSites(at.width, at.height, r.sites, channels, o.atlas.pack.gutter, ctx,
                [&](size_t s, float* out) { solid.sample(s, channels, color, out); }));
  size_t corner = 0;
  r.uvs.resize(pieces.size());
  for (size_t p = 0; p < pieces.size(); ++p)
    for (size_t i = 0; i < faces[p].size(); ++i, corner += 3)
      r.uvs[p].push_back({at.normalizedUv(at.texelUvs[corner]), at.normalizedUv(at.texelUvs[corner + 1]),
                          at.normalizedUv(at.texelUvs[corner + 2])});
  resolveStage.finish(std::to_string(at.width) + "x" + std::to_string(at.height) + " map");
  return r;
}

} // namespace texfab::render
