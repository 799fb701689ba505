// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/break/break_model.h"

#include "core/downsample.h"

#include "core/error.h"
#include "geometry/fracture/measure_solid.h"

#include <cmath>
#include <cstdio>

namespace texfab::render {
namespace {

constexpr uint32_t kCutTag = 1;  // faceTags of cut faces and filled holes (PrepareMeshOptions::holeTag)

std::string pieceName(size_t i) {
  char name[32];
  std::snprintf(name, sizeof name, "piece_%03zu", i);
  return name;
}

Piece measured(std::string name, geometry::Mesh mesh) {
  const geometry::SolidMeasures m = geometry::measureSolid(mesh, kCutTag);
  return {std::move(name), std::move(mesh), m.centroid, m.volume, m.taggedArea};
}

geometry::Material interiorMaterial(std::string name, std::shared_ptr<const Image> image) {
  geometry::Material m;
  m.name = std::move(name);
  m.metallicFactor = 0.0f;
  m.roughnessFactor = 0.8f;
  m.baseColorTexture.image = std::move(image);
  m.baseColorTexture.name = m.name + ".png";
  return m;
}

// The interior faces of each piece: `isNew` says which triangles need the interior texture.
template <class IsNew>
std::vector<std::vector<uint32_t>> facesToTexture(const std::vector<Piece>& pieces, IsNew&& isNew) {
  std::vector<std::vector<uint32_t>> faces(pieces.size());
  for (size_t p = 0; p < pieces.size(); ++p)
    for (uint32_t t = 0; t < pieces[p].mesh.triangles.size(); ++t)
      if (isNew(p, t)) faces[p].push_back(t);
  return faces;
}

// Gives the faces the cut-face texture's UVs and `material`.
void applyInterior(std::vector<Piece>& pieces, const std::vector<std::vector<uint32_t>>& faces, const CutFaceTexture& tex,
                   uint32_t material) {
  for (size_t p = 0; p < pieces.size(); ++p) {
    geometry::Mesh& m = pieces[p].mesh;
    if (m.uvs.empty()) m.uvs.assign(3 * m.triangles.size(), Eigen::Vector2f::Zero());
    if (m.faceMaterials.empty()) m.faceMaterials.assign(m.triangles.size(), 0);
    for (size_t i = 0; i < faces[p].size(); ++i) {
      const uint32_t t = faces[p][i];
      for (int k = 0; k < 3; ++k) m.uvs[3 * t + size_t(k)] = tex.uvs[p][i][size_t(k)];
      m.faceMaterials[t] = material;
    }
  }
}

// The solid the job cuts, with its outer texture when an exemplar is given.
geometry::Mesh outerSolid(const geometry::PreparedMesh& solid, const TextureExemplar& outer, const BreakModelOptions& o,
                          const Context& ctx, BrokenModel& r) {
  geometry::Mesh mesh;
  if (outer.color) {
    Stage stage(ctx, "texture");
    r.outer = textureMesh(solid, outer, o.outer, stage.inner());
    mesh = std::move(r.outer->mesh);
    r.outer->mesh = {};
    stage.finish();
  } else {
    mesh = solid.mesh;
  }
  if (mesh.materials.empty()) {
    geometry::Material m;
    m.name = "outer";
    m.metallicFactor = 0.0f;
    mesh.materials.push_back(m);
  }
  return mesh;
}

// The pieces of the solid, their new faces tagged 1 with material `interior`.
std::vector<Piece> splitSolid(const geometry::Mesh& solid, const BreakModelOptions& o, uint32_t interior, const Context& ctx,
                              BrokenModel& r) {
  const geometry::IntersectCellsOptions cut{kCutTag, interior};
  std::vector<geometry::CellPiece> parts;
  if (o.fracture) {
    geometry::FractureOptions f = *o.fracture;
    f.cut = cut;
    geometry::FractureResult fr = geometry::fractureMesh(solid, f, ctx);
    r.fracture = fr.report;
    r.intersect = fr.report.intersect;
    parts = std::move(fr.pieces);
  } else {
    geometry::CutMeshResult cr = geometry::cutMesh(std::span<const geometry::Mesh>(&solid, 1), o.planes, cut, ctx);
    for (int k : cr.missed) r.notes.push_back("plane " + std::to_string(k + 1) + " misses the model");
    r.intersect = cr.intersect;
    parts = std::move(cr.pieces);
  }
  std::vector<Piece> pieces;
  for (size_t i = 0; i < parts.size(); ++i) pieces.push_back(measured(pieceName(i), std::move(parts[i].mesh)));
  return pieces;
}

} // namespace

void BreakModelOptions::shareTextureSettings(uint32_t seed, const synthesis::SolidSynthesisOptions& solid) {
  outer.atlas.pack.gutter = interior.atlas.pack.gutter;
  outer.textureScale = interior.textureScale;
  outer.solid = interior.solid = solid;
  outer.surface.seed = outer.solid.seed = interior.solid.seed = seed;
}

void BreakExemplars::downsampleForScale(const geometry::Mesh& model, BreakModelOptions& o) {
  const CutFaceTextureOptions& in = o.interior;
  const bool interiorAuto = in.atlas.pack.width == 0 && in.atlas.pack.height == 0 && in.atlas.pack.texelsPerUnit == 0;
  if (!outer || !interiorAuto) return;
  int factor = analysisDownsampling(model, o.outer, *outer);
  while (factor > 1 && interior && std::min(interior->width, interior->height) / factor < kMinAnalysedSide) factor /= 2;
  if (factor == 1) return;
  const double scale = textureScaleFor(model, o.outer);
  o.outer.textureScale = scale / factor;
  o.interior.textureScale = (o.interior.textureScale > 0 ? o.interior.textureScale : scale) / factor;
  for (std::optional<Image>* image : {&outer, &interior})
    if (*image) **image = downsample(**image, factor);
  downsampling = factor;
}

void BreakExemplars::analyze(const geometry::Mesh& model, BreakModelOptions& o,
                             const std::function<synthesis::ExemplarWrap(const Image&)>& wrapOf,
                             const synthesis::SolidTileOptions& tiles, const synthesis::AnalysisCacheSettings& cache,
                             const Context& ctx) {
  const auto solidOf = [&](const Image& image, synthesis::ExemplarWrap wrap) {
    synthesis::validateSolidExemplars(image, image, image);
    synthesis::SolidAnalysisOptions options;
    options.wrap = wrap;
    return synthesis::analyzeSolid(image, image, image, options, o.interior.solid.method, tiles, cache, ctx);
  };
  // Each image's wrap is chosen once, on the image as given (a smaller copy hides part of its seam),
  // though the outer one may need two analyses.
  const synthesis::ExemplarWrap outerWrap = outer ? wrapOf(*outer) : synthesis::ExemplarWrap::Tile;
  const synthesis::ExemplarWrap interiorWrap = interior ? wrapOf(*interior) : synthesis::ExemplarWrap::Tile;
  downsampleForScale(model, o);
  if (outer) {
    outerView.color = &*outer;
    if (o.outer.mode == TextureMode::Surface) {
      synthesis::AnalysisOptions options;
      options.wrap = outerWrap;
      outerView.analysis = &surface.emplace(synthesis::analyzeExemplar(*outer, options, cache, ctx));
    } else {
      outerView.solidAnalysis = &outerSolid.emplace(solidOf(*outer, outerWrap));
    }
  }
  if (interior) {
    interiorView = {&*interior, &interiorSolid.emplace(solidOf(*interior, interiorWrap))};
  } else if (outer) {
    if (!outerSolid) outerSolid.emplace(solidOf(*outer, outerWrap));
    interiorView = {&*outer, &*outerSolid};
  }
}

double breakModelMemoryBytes(const BreakModelOptions& options, bool texturesOutside) {
  TextureMeshOptions interior;  // the cut faces' atlas costs as a solid texture job's
  interior.mode = TextureMode::Solid;
  interior.atlas = options.interior.atlas;
  if (interior.atlas.pack.width == 0) {  // auto: at most 1.5 times the outer atlas per side, or 2048^2
    interior.atlas.pack.width = texturesOutside ? int(1.5 * options.outer.atlas.pack.width) : 2048;
    interior.atlas.pack.height = texturesOutside ? int(1.5 * options.outer.atlas.pack.height) : 2048;
  }
  interior.solid = options.interior.solid;
  return textureMeshMemoryBytes(interior) + (texturesOutside ? textureMeshMemoryBytes(options.outer) : 0.0);
}

geometry::PreparedMesh prepareBreakSolid(const geometry::Mesh& model, const BreakModelOptions& o, const Context& ctx) {
  geometry::PrepareMeshOptions solid = o.preparation;
  solid.use = geometry::MeshUse::Solid;
  return geometry::preparedCopy(model, solid, ctx);
}

BrokenModel breakModel(const geometry::Mesh& model, const TextureExemplar& outer, const InteriorExemplar& interior,
                       const BreakModelOptions& o, const Context& ctx, synthesis::SolidLevelCache* cache) {
  return breakModel(prepareBreakSolid(model, o, ctx), outer, interior, o, ctx, cache);
}

BrokenModel breakModel(const geometry::PreparedMesh& prepared, const TextureExemplar& outer, const InteriorExemplar& interior,
                       const BreakModelOptions& o, const Context& ctx, synthesis::SolidLevelCache* cache) {
  if (o.planes.empty() == !o.fracture) throw Error("break: give cutting planes or fracture options (one of the two)");
  if (o.fracture) o.fracture->validate();
  BrokenModel r;
  r.preparation = prepared.preparation;
  const geometry::Mesh solid = outerSolid(prepared, outer, o, ctx, r);
  r.modelVolume = geometry::measureSolid(solid).volume;
  const uint32_t interiorIndex = uint32_t(solid.materials.size());
  r.pieces = splitSolid(solid, o, interiorIndex, ctx, r);

  // New cut faces and filled holes (tag 1) show the interior.
  const auto faces = facesToTexture(r.pieces, [&](size_t p, uint32_t t) { return r.pieces[p].mesh.tagOf(t) == kCutTag; });
  size_t count = 0;
  for (const auto& f : faces) count += f.size();
  std::vector<geometry::Material> materials = solid.materials;
  // The cut faces' solid texture: the scale given, else the outer texture's, else the model's default.
  r.interiorScale = o.interior.textureScale > 0 ? o.interior.textureScale
                    : r.outer                  ? r.outer->textureScale
                                               : autoTextureScale(solid);
  if (count) {
    if (!interior.color || !interior.analysis) throw Error("the cut faces need an interior exemplar (--interior or --exemplar)");
    CutFaceTextureOptions io = o.interior;
    if (io.atlas.pack.width == 0 && io.atlas.pack.height == 0 && io.atlas.pack.texelsPerUnit == 0) {
      // Auto: the outer surface's texel density (an atlas sized to fit), else a 2048^2 atlas.
      if (r.outer) io.atlas.pack.texelsPerUnit = r.outer->atlas.atlas.texelsPerUnit;
      else io.atlas.pack.width = io.atlas.pack.height = 2048;
    }
    io.textureScale = r.interiorScale;
    if (r.outer && o.outer.mode == TextureMode::Solid) io.solid = o.outer.solid;  // continuous across the crack edges
    Stage stage(ctx, "interior");
    std::vector<geometry::Mesh> meshes;
    for (const Piece& p : r.pieces) meshes.push_back(p.mesh);
    r.interior = textureCutFaces(meshes, faces, *interior.color, *interior.analysis, io, stage.inner(), cache);
    stage.finish(std::to_string(r.interior->sites.size()) + " texels");
    const double inner = r.interior->atlas.atlas.texelsPerUnit;
    if (r.outer && inner < 0.9 * r.outer->atlas.atlas.texelsPerUnit)
      r.notes.push_back("the cut faces get " + std::to_string(int(std::lround(inner))) + " texels per unit, the outer "
                        "surface " + std::to_string(int(std::lround(r.outer->atlas.atlas.texelsPerUnit))) +
                        ": a larger interior atlas shows them as sharply");
    r.interiorSolid = io.solid;
    applyInterior(r.pieces, faces, *r.interior, interiorIndex);
    materials.push_back(interiorMaterial("interior", r.interior->baseColor));
  } else {
    r.interiorSolid = o.interior.solid;
  }
  for (Piece& p : r.pieces) p.mesh.materials = materials;
  return r;
}

RecutReport recutModel(BrokenModel& model, const geometry::CutPlane& plane, const InteriorExemplar& interior,
                       const atlas::GenerateAtlasOptions& atlasOptions, synthesis::SolidLevelCache& cache, const Context& ctx) {
  if (!interior.color || !interior.analysis) throw Error("re-cut: the interior exemplar is missing");
  if (model.pieces.empty()) throw Error("re-cut: the model has no pieces");
  RecutReport report;
  std::vector<geometry::Mesh> solids;
  for (const Piece& p : model.pieces) solids.push_back(p.mesh);
  const uint32_t material = uint32_t(model.pieces.front().mesh.materials.size());
  geometry::CutMeshResult cut =
      geometry::cutMesh(solids, std::span<const geometry::CutPlane>(&plane, 1), {kCutTag, material}, ctx);
  if (!cut.missed.empty()) return report;

  std::vector<Piece> pieces;
  std::vector<int> parts(model.pieces.size(), 0);
  for (int from : cut.inputOf) ++parts[size_t(from)];
  std::vector<int> seen(model.pieces.size(), 0);
  for (size_t i = 0; i < cut.pieces.size(); ++i) {
    const int from = cut.inputOf[i];
    std::string name = model.pieces[size_t(from)].name;
    if (parts[size_t(from)] > 1) name.append(".").append(std::to_string(seen[size_t(from)]++));
    pieces.push_back(parts[size_t(from)] > 1 ? measured(name, std::move(cut.pieces[i].mesh))
                                             : std::move(model.pieces[size_t(from)]));
  }
  for (int n : parts) report.piecesCut += n > 1;
  const auto faces = facesToTexture(pieces, [&](size_t p, uint32_t t) { return cut.cut[p][t] == 0; });
  for (const auto& f : faces) report.newFaces += f.size();

  CutFaceTextureOptions io;
  io.atlas = atlasOptions;
  io.solid = model.interiorSolid;
  io.textureScale = model.interiorScale;
  std::vector<geometry::Mesh> meshes;
  for (const Piece& p : pieces) meshes.push_back(p.mesh);
  const int64_t hits = cache.hits(), misses = cache.misses();
  const CutFaceTexture tex = textureCutFaces(meshes, faces, *interior.color, *interior.analysis, io, ctx, &cache);
  report.texels = tex.sites.size();
  report.voxelsRequested = tex.voxelsRequested;
  report.voxelsSynthesized = tex.voxelsSynthesized;
  report.cacheHits = cache.hits() - hits;
  report.cacheMisses = cache.misses() - misses;
  applyInterior(pieces, faces, tex, material);
  std::vector<geometry::Material> materials = pieces.front().mesh.materials;
  materials.push_back(interiorMaterial(std::string("interior.").append(std::to_string(material)), tex.baseColor));
  for (Piece& p : pieces) p.mesh.materials = materials;
  model.pieces = std::move(pieces);
  return report;
}

std::vector<geometry::SceneNode> sceneOf(const BrokenModel& model, double explode) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double volume = 0;
  for (const Piece& p : model.pieces) centre += p.volume * p.centroid, volume += p.volume;
  if (volume > 0) centre /= volume;
  std::vector<geometry::SceneNode> nodes;
  for (const Piece& p : model.pieces) {
    geometry::SceneNode node{p.name, p.mesh, (p.centroid + explode * (p.centroid - centre)).cast<float>()};
    const Eigen::Vector3f origin = p.centroid.cast<float>();
    for (auto& v : node.mesh.positions) v -= origin;
    nodes.push_back(std::move(node));
  }
  return nodes;
}

geometry::Mesh mergedPieces(const BrokenModel& model, double explode) {
  geometry::Mesh out;
  for (const geometry::SceneNode& node : sceneOf(model, explode)) {
    const geometry::Mesh& m = node.mesh;
    const uint32_t base = uint32_t(out.positions.size());
    for (const auto& v : m.positions) out.positions.push_back(v + node.translation);
    for (auto t : m.triangles) out.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    out.uvs.insert(out.uvs.end(), m.uvs.begin(), m.uvs.end());
    out.normals.insert(out.normals.end(), m.normals.begin(), m.normals.end());
    for (size_t t = 0; t < m.triangles.size(); ++t) out.faceMaterials.push_back(m.materialOf(t)), out.faceTags.push_back(m.tagOf(t));
    out.materials = m.materials;
  }
  if (out.uvs.size() != 3 * out.triangles.size()) out.uvs.clear();
  if (out.normals.size() != 3 * out.triangles.size()) out.normals.clear();
  return out;
}

} // namespace texfab::render
