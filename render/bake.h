// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Baking: values computed per atlas texel (a site of the surface domain) into atlas-sized images,
// with the gutters around the charts filled so that bilinear lookups and mip maps never read an
// unsynthesized texel; and the solid texture at the texels' 3-D positions, for every job that
// shows the solid texture on a surface (the texture job's solid mode, cut faces).

#include "atlas/rasterize_atlas.h"
#include "core/context.h"
#include "core/image.h"
#include "core/parallel.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"
#include "synthesis/synthesize_surface.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace texfab::render {

/// Fills the texels of `image` where `filled` is 0 from their filled neighbors, `rounds` rings
/// deep (each ring the mean of the filled 8-neighbors), then the rest with the mean colour.
void fillGutters(Image& image, std::vector<uint8_t> filled, int rounds, const Context& ctx = {});

/// A width x height image of `channels` with one value per site (`value(site, out)` writes
/// `channels` floats at out), the gutters filled `gutter + 4` rings deep around the charts.
template <class Fn>
Image bakeSites(int width, int height, const synthesis::SurfaceLevel& sites, int channels, int gutter,
                const Context& ctx, Fn&& value) {
  Image image(width, height, channels);
  std::vector<uint8_t> filled(size_t(width) * size_t(height), 0);
  parallelFor(0, int(sites.size()), ctx, [&](int b, int e) {
    for (int s = b; s < e; ++s) {
      value(size_t(s), image.pixel(sites.x[size_t(s)], sites.y[size_t(s)]));
      filled[size_t(sites.y[size_t(s)]) * size_t(width) + size_t(sites.x[size_t(s)])] = 1;
    }
  }, 4096);
  fillGutters(image, std::move(filled), gutter + 4, ctx);
  return image;
}

/// A tangent-space normal `in` of the exemplar (RGB in [0, 1], OpenGL convention: x right, y up
/// in the image) expressed in the atlas image's frame at a site whose Jacobian is `j` (atlas
/// offsets to exemplar offsets): the tangential part maps back by J⁻¹ with its scale removed.
void rotateNormal(const std::array<float, 4>& j, const float* in, float* out);

/// The solid texture at the sites' 3-D positions: each site takes its voxel (nearest) or, where a
/// voxel spans several texels, blends the 8 voxels whose centres surround it (trilinear), so that a
/// magnified solid texture shows no voxel squares.
struct SolidSites {
  /// Nearest: one triple per site. Trilinear: one per distinct voxel read.
  std::vector<synthesis::Triple> triples;
  /// Trilinear only: per cell (8 voxel centres: x fastest, then y, then z) its corners' indices
  /// into triples; per site its cell and its position inside it in [0, 1)^3.
  std::vector<std::array<uint32_t, 8>> cells;
  std::vector<uint32_t> cellOfSite;
  std::vector<std::array<float, 3>> fractionOfSite;
  int64_t voxelsRequested = 0;             ///< distinct voxels among the sites' (tiles: every read)
  int64_t voxelsSynthesized = 0;           ///< over all levels (the dependency chains)

  bool trilinear() const { return !cellOfSite.empty(); }
  /// The value at `site` of a function of triples: `value(triple, out)` writes `channels` floats
  /// (at most 8), blended with the trilinear weights (corners in order) where trilinear.
  template <class Value>
  void sample(size_t site, int channels, Value&& value, float* out) const;
  /// "N voxels requested, M synthesized" (lazy), "N voxels read from the tiles" (tiles), and
  /// ", trilinear" where it blends.
  std::string summary(synthesis::SolidMethod method) const;
};

/// Below this many voxels per texel, solidAtSites blends trilinearly (the 2-D bakes' rule).
inline constexpr double kSolidTrilinearBelow = 0.75;

/// The solid texture at `sites`: the voxel of a site is its surface position times `scale` voxels
/// per model unit, floored; trilinear where `voxelsPerTexel` < kSolidTrilinearBelow. Every voxel is
/// synthesized in one request, so texels sharing a voxel share its value. Throws texfab::Error when
/// a position times the scale leaves the solid texture's range. `cache` (may be null) serves and
/// keeps coarse levels across requests (a single request gains nothing from it).
SolidSites solidAtSites(const synthesis::SurfaceLevel& sites, const atlas::AtlasFields& fields,
                        const synthesis::SolidAnalysis& analysis, const synthesis::SolidSynthesisOptions& options,
                        double scale, double voxelsPerTexel, const Context& ctx = {},
                        synthesis::SolidLevelCache* cache = nullptr);

// ---- implementation of the template ----

template <class Value>
void SolidSites::sample(size_t site, int channels, Value&& value, float* out) const {
  if (!trilinear()) {
    value(triples[site], out);
    return;
  }
  const std::array<uint32_t, 8>& corner = cells[cellOfSite[site]];
  const std::array<float, 3>& f = fractionOfSite[site];
  float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0}, v[8];
  for (int k = 0; k < 8; ++k) {
    const float w = ((k & 1) ? f[0] : 1.0f - f[0]) * ((k & 2) ? f[1] : 1.0f - f[1]) * ((k & 4) ? f[2] : 1.0f - f[2]);
    value(triples[corner[size_t(k)]], v);
    for (int c = 0; c < channels; ++c) sum[c] += w * v[c];
  }
  for (int c = 0; c < channels; ++c) out[c] = sum[c];
}

} // namespace texfab::render
