// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Texturing of the faces a cut or a fracture made: one atlas for the chosen faces of all pieces,
// each texel the solid texture at its 3-D position, in the frame, seed and scale of the texture
// job's solid mode (texture_mesh.h), so a cut face shows the interior of the material the outer
// faces show, and the two faces of one crack show the same material at the same points.
//
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//   §1 and §7 (new surfaces of cut and broken objects textured on demand, coarse levels cached).

#include "atlas/generate_atlas.h"
#include "core/context.h"
#include "core/image.h"
#include "geometry/mesh.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"
#include "synthesis/synthesize_surface.h"

#include <Eigen/Core>

#include <memory>
#include <span>
#include <vector>

namespace texfab::render {

struct CutFaceTextureOptions {
  atlas::GenerateAtlasOptions atlas;       ///< resolution and gutter of the cut faces' atlas
  synthesis::SolidSynthesisOptions solid;  ///< seed and schedule, as the texture job's solid mode
  /// Voxels of the solid texture per model unit; 0 = the atlas density (one voxel per texel).
  /// breakModel gives the outer texture's scale (autoTextureScale of the model without one).
  double textureScale = 0;
};

struct CutFaceTexture {
  std::shared_ptr<const Image> baseColor;  ///< atlas-sized, gutters filled
  atlas::GenerateAtlasResult atlas;        ///< of the faces, in the order given (piece by piece)
  synthesis::SurfaceLevel sites;           ///< one per chart texel
  double textureScale = 0;                 ///< voxels per model unit used
  int64_t voxelsRequested = 0, voxelsSynthesized = 0;
  bool trilinear = false;                  ///< voxels larger than texels, blended (solidAtSites)
  /// Per piece, per face given: the UVs of its three corners (glTF/OBJ style, v up).
  std::vector<std::vector<std::array<Eigen::Vector2f, 3>>> uvs;
};

/// Textures faces[p] (triangle indices) of each pieces[p]; positions are the model's frame.
/// `cache` (may be null) keeps coarse levels of the solid synthesis between calls with the same
/// analysis and options: a later cut near earlier ones computes little more than its finest level.
/// Stages: atlas, fields, synthesis, resolve. Throws texfab::Error when there is no face.
CutFaceTexture textureCutFaces(std::span<const geometry::Mesh> pieces, std::span<const std::vector<uint32_t>> faces,
                               const Image& exemplar, const synthesis::SolidAnalysis& analysis,
                               const CutFaceTextureOptions& options, const Context& ctx = {},
                               synthesis::SolidLevelCache* cache = nullptr);

} // namespace texfab::render
