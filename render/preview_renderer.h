// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The preview renderer: an Embree ray tracer that shows a textured mesh the way a person wants to
// look at it. Auto-framed perspective camera on an orbit (azimuth/elevation around the model's
// bounding sphere), stratified supersampling, textures filtered with mip maps whose level comes
// from the ray footprint [Igehy 1999, "Tracing Ray Differentials"], tangent-space normal maps,
// a key light with shadows, and a sky light with ambient occlusion. Deterministic: the same
// inputs give the same image on any thread count.

#include "geometry/embree_scene.h"
#include "geometry/mesh.h"
#include "render/image/context.h"
#include "render/image/image.h"
#include "render/mip_pyramid.h"

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace texfab::render {

struct RenderOptions {
  int width = 800;        ///< pixels
  int height = 800;
  int samplesPerPixel = 16; ///< stratified (a square number is used fully; others round down to one)
  float azimuthDegrees = 30.0f;   ///< camera orbit angle around +Y, 0 = looking from +Z
  float elevationDegrees = 20.0f; ///< above the horizontal plane, in (-90, 90)
  float fovYDegrees = 35.0f;      ///< vertical field of view
  float margin = 1.08f;           ///< framing: bounding sphere radius times this fills the view
  bool transparentBackground = false; ///< RGBA output with alpha = coverage
  Eigen::Vector3f background{1.0f, 1.0f, 1.0f}; ///< sRGB background colour when not transparent
  int aoSamples = 1;              ///< ambient-occlusion rays per camera sample (0 = no AO)
  bool shadows = true;            ///< key-light shadow rays
};

class PreviewRenderer {
public:
  /// Builds the Embree scene and the texture pyramids once; render() can then be called for many
  /// views (turntables). The mesh must outlive the renderer.
  explicit PreviewRenderer(const geometry::Mesh& mesh);
  ~PreviewRenderer();

  /// Renders one view: 8-bit sRGB, 4 channels (RGBA) when the background is transparent, else 3.
  Image render(const RenderOptions& options, const Context& ctx = {}) const;

private:
  struct MaterialMaps {
    MipPyramid baseColor, metallicRoughness, normal;
  };
  const geometry::Mesh& mesh_;
  geometry::EmbreeScene scene_;
  std::vector<MaterialMaps> maps_;
  std::vector<float> uvDensity_; ///< per triangle: sqrt(uv area / world area)
  std::vector<Eigen::Vector3f> normals_; ///< per corner: the mesh's, or crease-angle normals if it has none
  std::vector<Eigen::Vector4f> tangents_; ///< per corner: the mesh's, or computed when a normal map needs them
};

} // namespace texfab::render
