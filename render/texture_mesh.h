// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The main job of texfab (`texfab texture`): synthesize a texture over a mesh and return the mesh
// with an atlas and a PBR material carrying the synthesized maps
// (docs/design.md#data-flow-of-the-main-job).
//
//   surface mode: atlas -> tangent field -> Jacobians J = (t b)⁺ J_f -> surface domain (sites,
//     neighbors across seams) -> anisometric synthesis in the atlas (Lefebvre & Hoppe 2006 §5–6)
//     -> exemplar coordinates per texel -> colours and companion maps (same coordinates).
//   solid mode: atlas -> each texel's 3D position times the scale is a voxel of lazy solid
//     synthesis (Dong et al. 2008) -> colours. Seamless by construction: a cut shows the same.
// Gutters are filled by dilating the charts' colours, so bilinear lookups and mip maps never read
// unsynthesized texels.

#include "atlas/generate_atlas.h"
#include "core/context.h"
#include "core/image.h"
#include "geometry/mesh.h"
#include "geometry/repair/prepare_mesh.h"
#include "geometry/tangent_field.h"
#include "render/bake.h"
#include "render/surface_measures.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/exemplar_graph.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"
#include "synthesis/synthesize_surface.h"

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace texfab::render {

enum class TextureMode { Surface, Solid };

struct TextureMeshOptions {
  TextureMode mode = TextureMode::Surface;
  /// Exemplar pixels per model unit (solid mode: voxels per model unit); 0 = autoTextureScale.
  double textureScale = 0;
  atlas::GenerateAtlasOptions atlas;
  geometry::TangentFieldOptions field;        ///< orientation of the texture (surface mode)
  synthesis::SurfaceSynthesisOptions surface;
  synthesis::SolidSynthesisOptions solid;
  bool measure = true;  ///< compute TextureMeasures (seams always; scale and fidelity in surface mode)
};

/// The exemplar and what synthesis knows about it. Companion maps must have the exemplar's size.
/// With an exemplar graph (surface mode), `color` is its root exemplar and `analysis` unused.
struct TextureExemplar {
  const Image* color = nullptr;
  const synthesis::ExemplarAnalysis* analysis = nullptr;   ///< needed in surface mode without a graph
  const synthesis::SolidAnalysis* solidAnalysis = nullptr; ///< needed in solid mode
  /// Companion maps, the exemplar's size; with a graph, the graph's maps packed as its colours
  /// (synthesis::graphMapAtlas).
  const Image* normal = nullptr;    ///< tangent-space normal map, OpenGL convention (+Y up); surface mode
  const Image* roughness = nullptr; ///< first channel
  const Image* height = nullptr;    ///< first channel
  /// Multiscale synthesis (Han et al. 2008), surface mode; `color` is then its root exemplar.
  const synthesis::GraphAnalysis* graph = nullptr;
};

struct TextureMeasures {
  SeamMeasure seams;
  std::optional<ScaleMeasure> scale;         ///< surface mode
  std::optional<SurfaceFidelity> fidelity;   ///< surface mode
};

struct TextureMeshResult {
  geometry::Mesh mesh;                      ///< the input with atlas UVs and one material with the maps
  std::shared_ptr<const Image> baseColor;   ///< atlas-sized maps (also referenced by mesh.materials[0])
  std::shared_ptr<const Image> normal, metallicRoughness, height; ///< null unless requested
  geometry::MeshPreparation preparation;  ///< what made the input a surface to texture (prepareMesh)
  atlas::GenerateAtlasResult atlas;
  /// The finest level of the surface domain (one site per chart texel; in solid mode its
  /// neighbors are linked only when measures are asked for).
  synthesis::SurfaceLevel sites;
  std::vector<uint32_t> coords;             ///< surface mode: exemplar coordinate per site
  /// With a graph's transfers: the RGB offset each site's colour is shown with (not the maps')
  std::vector<std::array<float, 3>> colorOffsets;
  SolidSites solid;                         ///< solid mode: the solid texture at the sites
  double textureScale = 0;                  ///< exemplar pixels per model unit used
  double exemplarPixelsPerTexel = 0;
  std::vector<synthesis::LevelStats> synthesisLevels; ///< surface mode: per atlas level, coarsest first
  TextureMeasures measures;
  std::vector<std::string> warnings;        ///< e.g. a scale at which features are smaller than a texel
};

/// Throws texfab::Error unless the companion maps suit the mode (no normal map in solid mode, none
/// with a graph yet, a graph only in surface mode) and have the exemplar's size. textureMesh()
/// checks this too; callers may check before the analysis.
void checkCompanionMaps(const TextureExemplar& exemplar, TextureMode mode);

/// Peak memory of textureMesh at the options' atlas size and mode, in bytes. Measured at 2048^2 on
/// an 89K-triangle mesh (texture_bench): 218 bytes per atlas texel in surface mode, 440 in solid
/// mode (lazy synthesis of about one voxel per texel), plus refinement's slab
/// (synthesis::refineSolidMemoryBytes).
double textureMeshMemoryBytes(const TextureMeshOptions& options);

/// The scale at textureScale 0: the texel density of a kAutoScaleAtlasSide² atlas whose charts
/// cover kAutoScaleCoverage of it, kAutoScaleAtlasSide * sqrt(kAutoScaleCoverage / area) exemplar
/// pixels per model unit (about one exemplar pixel per texel at texfab texture's default
/// resolution). It depends on the model's surface area alone, not on the atlas nor on the
/// orientation: a higher resolution only sharpens the same pattern, and texture, fracture, cut and
/// slice give one model the same pattern size. Throws texfab::Error for a model without area.
inline constexpr int kAutoScaleAtlasSide = 2048;
inline constexpr double kAutoScaleCoverage = 0.7;
double autoTextureScale(const geometry::Mesh& mesh);

/// The scale at textureScale 0 with an exemplar graph: the root exemplar (`rootSide` pixels) spans
/// the model's bounding-box diagonal once, so that its structure is the model's largest and the
/// exemplars that detail it appear where texels are finer.
double graphTextureScale(const geometry::Mesh& mesh, int rootSide);

/// A texture scale given for `graph` in a user's units, as pixels of exemplars[0] per model unit:
/// `textureScale` counts pixels of the root as given (times ExemplarGraph::rootMagnification);
/// `featureSize` > 0, the model units the root spans, replaces it. 0 stays 0 (graphTextureScale).
double graphScaleAsGiven(const synthesis::ExemplarGraph& graph, double textureScale, double featureSize);

/// options.textureScale, or where it is 0 graphTextureScale (with `graph`) or autoTextureScale.
double textureScaleFor(const geometry::Mesh& mesh, const TextureMeshOptions& options,
                       const synthesis::GraphAnalysis* graph = nullptr);

/// The factor (a power of two) by which the exemplar and its maps are best analysed and synthesized
/// smaller: where options.textureScale puts at least that many exemplar pixels in every texel,
/// whatever the atlas, detail finer than a texel would cost analysis time and memory for nothing.
/// Never below kMinAnalysedSide pixels a side. Callers downsample the exemplar and its maps by it
/// and use textureScaleFor(mesh, options) divided by it as the scale.
inline constexpr int kMinAnalysedSide = 32;
int analysisDownsampling(const geometry::Mesh& mesh, const TextureMeshOptions& options, const Image& exemplar);
/// The rule under analysisDownsampling (and the print job's): the largest power of two at most
/// `fewestPixelsPerSample` (exemplar pixels across the smallest texel or voxel) that leaves
/// `exemplar` at least kMinAnalysedSide pixels a side.
int analysisDownsampling(double fewestPixelsPerSample, const Image& exemplar);

/// Stages reported through ctx: atlas, tangent field (surface mode), fields, synthesis (solid mode:
/// each level inside it), resolve, measures. Throws texfab::Error on bad input (no triangles, a
/// missing analysis, maps of the wrong size, a scale that puts a whole exemplar inside one texel).
/// `model`: prepared for any use (a solid is a surface too); callers that analyse the exemplar
/// first prepare it before (geometry::preparedCopy with MeshUse::Surface).
TextureMeshResult textureMesh(const geometry::PreparedMesh& model, const TextureExemplar& exemplar,
                              const TextureMeshOptions& options, const Context& ctx = {});
/// The same, with the model prepared first (stage: preparation).
TextureMeshResult textureMesh(const geometry::Mesh& mesh, const TextureExemplar& exemplar,
                              const TextureMeshOptions& options, const Context& ctx = {});

} // namespace texfab::render
