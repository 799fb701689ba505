// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The jobs that break a model (`texfab fracture`, `texfab cut`): the model made a solid
// (geometry/repair/prepare_mesh.h), its outer faces textured (its own material, or the texture job),
// broken by Voronoi cells or cut by planes (geometry/fracture_mesh.h, geometry/cut_mesh.h), and
// the new faces textured from the solid texture in the outer texture's frame
// (texture_cut_faces.h); and the interactive re-cut, which cuts the pieces again and textures
// only the new faces, with the solid synthesis's coarse levels kept in a cache between calls.

#include "core/context.h"
#include "geometry/fracture/cut_mesh.h"
#include "geometry/fracture/fracture_mesh.h"
#include "geometry/io/mesh_io.h"
#include "geometry/mesh.h"
#include "geometry/repair/prepare_mesh.h"
#include "render/break/texture_cut_faces.h"
#include "render/texture_mesh.h"
#include "synthesis/analyze_exemplar.h"

#include <Eigen/Core>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace texfab::render {

struct BreakModelOptions {
  std::vector<geometry::CutPlane> planes;            ///< cut by these planes, in turn ...
  std::optional<geometry::FractureOptions> fracture;  ///< ... or fracture (exactly one of the two)
  /// How the model is made a solid; its use is always MeshUse::Solid.
  geometry::PrepareMeshOptions preparation;
  TextureMeshOptions outer;          ///< the outer texture, when an outer exemplar is given
  /// The cut faces' atlas and solid texture. Its textureScale 0 = the outer texture's scale when
  /// the job textures the outside, else autoTextureScale of the model.
  CutFaceTextureOptions interior;

  /// One seed and one solid schedule for every texture of the job (the outer texture's surface or
  /// solid synthesis, the cut faces'); the outer atlas takes the cut faces' scale and gutter.
  void shareTextureSettings(uint32_t seed, const synthesis::SolidSynthesisOptions& solid);
};

/// The solid texture the cut faces show.
struct InteriorExemplar {
  const Image* color = nullptr;
  const synthesis::SolidAnalysis* analysis = nullptr;
};

/// The break job's exemplars and their analyses, as the command line and the Python module make
/// them: the outer one (with the analysis its texture mode needs) and the interior one (default:
/// the outer). It owns what the views point to, so it is neither copied nor moved.
struct BreakExemplars {
  std::optional<Image> outer, interior;
  std::optional<synthesis::ExemplarAnalysis> surface;
  std::optional<synthesis::SolidAnalysis> outerSolid, interiorSolid;
  TextureExemplar outerView;
  InteriorExemplar interiorView;
  /// The images are this many times smaller than given (analyze); scales are in their pixels, so a
  /// scale in the given images' pixels is this times larger.
  int downsampling = 1;

  BreakExemplars() = default;
  BreakExemplars(const BreakExemplars&) = delete;
  BreakExemplars& operator=(const BreakExemplars&) = delete;

  /// Analyses what `options` needs (synthesis::analyzeExemplar and analyzeSolid: "analysis" and
  /// "tiles" stages through `cache`). `wrapOf(image)` chooses each image's wrap, once per image, on
  /// the image as given. As `texfab texture` does, where the outer texture's scale puts 2 or more
  /// exemplar pixels in every texel of its atlas (analysisDownsampling), the images are first
  /// replaced by copies that many times smaller and both scales of `options` set in their pixels, so
  /// that the textures are prefiltered (no aliasing) and cheaper; only when the cut faces take the
  /// outer density (their atlas size automatic), which the same copies then suit, and never below
  /// kMinAnalysedSide pixels a side.
  void analyze(const geometry::Mesh& model, BreakModelOptions& options,
               const std::function<synthesis::ExemplarWrap(const Image&)>& wrapOf,
               const synthesis::SolidTileOptions& tiles, const synthesis::AnalysisCacheSettings& cache,
               const Context& ctx);

private:
  void downsampleForScale(const geometry::Mesh& model, BreakModelOptions& options);
};

struct Piece {
  std::string name;    ///< "piece_007"; a re-cut piece adds ".0" (behind the plane) or ".1"
  geometry::Mesh mesh; ///< the model's frame; every piece has the same materials (outer..., interior...)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< of its volume
  double volume = 0;   ///< model units³
  double cutArea = 0;  ///< area of its interior faces (cuts and filled holes), model units²
};

struct BrokenModel {
  std::vector<Piece> pieces;
  double modelVolume = 0;
  /// The frame of the interior texture: every cut face, now or in a re-cut, shows the solid
  /// texture at its position times this scale, with these options.
  double interiorScale = 0;
  synthesis::SolidSynthesisOptions interiorSolid;
  // Figures for reports.
  geometry::MeshPreparation preparation;  ///< what made the model a solid
  std::vector<std::string> notes;  ///< e.g. "plane 2 misses the model"
  std::optional<geometry::FractureReport> fracture;
  geometry::IntersectCellsReport intersect;
  std::optional<TextureMeshResult> outer;  ///< when the job textured the outside (its mesh emptied)
  std::optional<CutFaceTexture> interior;  ///< absent when nothing was cut
};

/// Peak memory of breakModel's textures, in bytes (meant as an upper bound): the cut faces' atlas
/// as a solid texture job's (textureMeshMemoryBytes; an automatic size counted as 1.5 times the
/// outer atlas per side, or 2048^2), plus the outer texture's when `texturesOutside`.
double breakModelMemoryBytes(const BreakModelOptions& options, bool texturesOutside);

/// The job's first stage, the model made a solid: geometry::prepareMesh with options.preparation as
/// MeshUse::Solid. Callers that analyse exemplars first run it before. Stage: preparation.
geometry::PreparedMesh prepareBreakSolid(const geometry::Mesh& model, const BreakModelOptions& options,
                                         const Context& ctx = {});

/// Throws texfab::Error for bad options (neither or both of planes and fracture) or a missing
/// interior exemplar when there are faces to texture. `outer.color` null keeps the model's own
/// materials and UVs on the outer faces. Stages: texture (its own stages inside),
/// sites/cells/intersect or intersect per plane, interior.
BrokenModel breakModel(const geometry::PreparedMesh& solid, const TextureExemplar& outer, const InteriorExemplar& interior,
                       const BreakModelOptions& options, const Context& ctx = {},
                       synthesis::SolidLevelCache* cache = nullptr);
/// Both stages (prepareBreakSolid, then the job); also throws when the model cannot be made a solid.
BrokenModel breakModel(const geometry::Mesh& model, const TextureExemplar& outer, const InteriorExemplar& interior,
                       const BreakModelOptions& options, const Context& ctx = {},
                       synthesis::SolidLevelCache* cache = nullptr);

struct RecutReport {
  size_t piecesCut = 0;    ///< pieces the plane crossed (each became two)
  size_t newFaces = 0;     ///< new cut triangles
  size_t texels = 0;       ///< chart texels of their atlas
  int64_t voxelsRequested = 0, voxelsSynthesized = 0;
  int64_t cacheHits = 0, cacheMisses = 0;  ///< coarse-level cache bricks, during this call
};

/// Cuts the pieces the plane crosses and textures only the new faces: an atlas of their own
/// (`atlas`, e.g. 256²) and a new material "interior.N", filled from the solid texture in the
/// model's frame (interiorScale, interiorSolid). `cache` keeps the synthesis's coarse levels
/// between calls (and from breakModel): cuts near earlier ones synthesize little more than their
/// finest level. A plane that crosses no piece leaves the model as it is.
RecutReport recutModel(BrokenModel& model, const geometry::CutPlane& plane, const InteriorExemplar& interior,
                       const atlas::GenerateAtlasOptions& atlas, synthesis::SolidLevelCache& cache,
                       const Context& ctx = {});

/// The pieces as scene nodes: each piece's mesh relative to its centroid, placed at the centroid
/// moved `explode` times its offset from the model's centre (0 = assembled).
std::vector<geometry::SceneNode> sceneOf(const BrokenModel& model, double explode = 0);

/// All pieces in one mesh, exploded as sceneOf (for the preview renderer).
geometry::Mesh mergedPieces(const BrokenModel& model, double explode = 0);

} // namespace texfab::render
