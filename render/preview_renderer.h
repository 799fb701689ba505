// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The preview renderer: an Embree ray tracer that shows a textured mesh the way a person wants to
// look at it. Perspective camera on an orbit (azimuth/elevation around the model's up axis, from
// its front), framed tightly on the model's projected vertices, stratified supersampling, textures
// filtered with mip maps whose level comes from the ray footprint [Igehy 1999, "Tracing Ray
// Differentials"], tangent-space normal maps whose highlights are shaded from their filtered normal
// distributions where the map is minified (filter_normal_map.h: bumps seen from afar stay rough), a
// key light with shadows, a weak fill light from the camera, and a sky light with ambient
// occlusion. Deterministic: the same inputs give the same image on any thread count.

#include "core/context.h"
#include "core/image.h"
#include "core/mip_pyramid.h"
#include "geometry/embree_scene.h"
#include "geometry/mesh.h"
#include "render/filter_normal_map.h"

#include <Eigen/Core>

#include <memory>
#include <mutex>
#include <vector>

namespace texfab::render {

/// How a minified tangent-space normal map shades its highlights.
enum class NormalMapFiltering {
  Mip,     ///< the MIP-mapped normal, renormalized: from afar bumps turn flat and shiny
  Toksvig, ///< one lobe around the MIP-mapped mean normal, widened by its shortening [Toksvig 2005]
  Lobes,   ///< the fitted distribution of normals, several vMF lobes (filter_normal_map.h)
};

/// The key light's specular reflection.
enum class SpecularModel {
  BlinnPhong,  ///< normalized Blinn-Phong of exponent 2/α² - 2 (α = roughness²), no Fresnel
  Microfacet,  ///< glTF's metallic-roughness BRDF: GGX of α, Smith's height-correlated masking, Schlick's Fresnel
};

struct RenderOptions {
  int width = 800;        ///< pixels
  int height = 800;
  int samplesPerPixel = 16; ///< stratified (a square number is used fully; others round down to one)
  /// The model's up direction (non-zero; need not be unit): +Y for glTF and OBJ, +Z for most STL.
  Eigen::Vector3f up{0.0f, 1.0f, 0.0f};
  float azimuthDegrees = 30.0f;   ///< camera orbit angle around `up`, 0 = looking at the model's front
  float elevationDegrees = 20.0f; ///< above the horizontal plane, in (-90, 90)
  float fovYDegrees = 35.0f;      ///< vertical field of view
  float margin = 1.08f;           ///< framing: the model's projected extent times this fills the view (< 1: zoomed in)
  bool transparentBackground = false; ///< RGBA output with alpha = coverage
  Eigen::Vector3f background{1.0f, 1.0f, 1.0f}; ///< sRGB background colour when not transparent
  int aoSamples = 1;              ///< ambient-occlusion rays per camera sample (0 = no AO)
  bool shadows = true;            ///< key-light shadow rays
  /// Lobes: minified normal maps shade from their filtered normal distributions (fitted on the
  /// first render that asks, about 3-5 s for a 1024^2 map on 2 cores, and not for rough
  /// dielectrics, where it cannot show: those shade as Mip). Textures with a MIP chain of their own
  /// (geometry::Texture::mips) are sampled from it, as a viewer of the written file samples them;
  /// Mip then shows what such a viewer shows.
  NormalMapFiltering normalMapFiltering = NormalMapFiltering::Lobes;
  /// Filtered normal maps widen either model's lobe by each vMF lobe (Han et al. 2007, Eq. 7.20).
  SpecularModel specular = SpecularModel::BlinnPhong;
  /// Where fitted normal distributions are kept between runs (the analysis cache); none: fitted
  /// every time.
  synthesis::AnalysisCacheSettings normalMapCache;
};

/// The model's front for an up direction: +Z (glTF's forward) made orthogonal to `up`, or -Y when
/// `up` is along Z (+Y when it points down): the side a Y-up or Z-up model is usually seen from.
Eigen::Vector3f frontFor(const Eigen::Vector3f& up);

/// Peak memory of a PreviewRenderer of `mesh` rendering one view with `options`, in bytes, beyond
/// the mesh itself (meant as an upper bound): the picture, the BVH and per-corner shading data, the
/// textures' MIP pyramids, and the fitted normal distributions of normal maps when filtered.
double renderMemoryBytes(const geometry::Mesh& mesh, const RenderOptions& options);

class PreviewRenderer {
public:
  /// Builds the Embree scene and the texture pyramids once; render() can then be called for many
  /// views (turntables). The mesh must outlive the renderer.
  explicit PreviewRenderer(const geometry::Mesh& mesh);
  ~PreviewRenderer();

  /// Renders one view: 8-bit sRGB, 4 channels (RGBA) when the background is transparent, else 3.
  Image render(const RenderOptions& options, const Context& ctx = {}) const;

private:
  struct View;    ///< one render()'s camera, lights and sampling
  struct Surface; ///< what a camera ray hit: position, normals, material
  void addSample(const View& view, int px, int py, int s, Eigen::Vector3f& sum, float& coverage) const;
  Surface surfaceAt(const View& view, const geometry::RayHit& hit, const Eigen::Vector3f& dir) const;
  Eigen::Vector3f lightSurface(const View& view, const Surface& surface, const Eigen::Vector3f& dir, int px, int py,
                               int s) const;

  struct MaterialMaps {
    MipPyramid baseColor, metallicRoughness, normal, anisotropy;
    std::shared_ptr<const NdfMipChain> normalDistribution;  ///< of `normal`, once a render asks
  };
  void filterNormalMaps(const RenderOptions& o, const Context& ctx) const;
  const geometry::Mesh& mesh_;
  geometry::EmbreeScene scene_;
  mutable std::vector<MaterialMaps> maps_;  ///< normalDistribution filled by the first render that filters
  mutable std::once_flag filtered_;
  std::vector<float> uvDensity_; ///< per triangle: sqrt(uv area / world area)
  std::vector<Eigen::Vector3f> normals_; ///< per corner: the mesh's, or crease-angle normals if it has none
  std::vector<Eigen::Vector4f> tangents_; ///< per corner: the mesh's, or computed when a normal map needs them
};

} // namespace texfab::render
