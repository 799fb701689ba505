// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Where the colour of a print's shell voxels comes from: the model's own texture at the nearest
// surface point, or the solid texture at the voxel's position. A colour is a pure function of the
// voxel's position (and the inputs), so any layer coloured alone gets the same colours as in a
// full run.

#include "core/context.h"
#include "core/image.h"
#include "core/mip_pyramid.h"
#include "geometry/embree_scene.h"
#include "geometry/mesh.h"
#include "print/print_grid.h"
#include "print/voxelize_layers.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <array>
#include <memory>
#include <span>
#include <vector>

namespace texfab::print {

/// Colours of shell voxels, in linear light, RGBA (alpha 1 unless the texture is transparent).
class VoxelColorSource {
public:
  virtual ~VoxelColorSource() = default;
  /// Called with the spans of the layers about to be coloured (consecutive layers), before any
  /// colors() call for them; a source may do their work at once (solid synthesis). Not
  /// thread-safe.
  virtual void prepare(std::span<const print::LayerSpans> layers, const Context& ctx) = 0;
  /// Colours of voxels [begin, end) of grid row y (grid index, not image row) of `layer`, one of
  /// the layers last prepared: 4 floats per voxel into `rgba`. Thread-safe.
  virtual void colors(int layer, int y, int begin, int end, float* rgba) const = 0;
};

/// The solid texture in the frame of `texfab texture --mode solid`: a point p of the model (model
/// units) has the colour of solid voxel floor(p * scale), synthesized lazily for the shell voxels
/// of the prepared layers only, its colour the solid engine's colour of its triple
/// (synthesis::solidColors) read as sRGB. Where the print's finest pitch is under
/// render::kSolidTrilinearBelow solid voxels (a magnified texture), a print voxel blends the 8
/// solid voxels whose centres surround its centre, in linear light, as texture bakes do, so that
/// prints show no voxel blocks.
class SolidVoxelColors : public VoxelColorSource {
public:
  /// `scale`: solid voxels (exemplar pixels) per model unit, > 0. The exemplars and analysis must
  /// outlive the source. Throws texfab::Error when the print reaches beyond the solid texture's
  /// range (|position * scale| > 2^30).
  SolidVoxelColors(const synthesis::SolidAnalysis& analysis, const Image& ex, const Image& ey, const Image& ez,
                   const synthesis::SolidSynthesisOptions& options, double scale, const print::PrintGrid& grid);
  ~SolidVoxelColors() override;
  void prepare(std::span<const print::LayerSpans> layers, const Context& ctx) override;
  void colors(int layer, int y, int begin, int end, float* rgba) const override;
  /// Distinct solid voxels requested so far, and voxels synthesized for them (all levels).
  int64_t voxelsRequested() const { return requested_; }
  int64_t voxelsSynthesized() const { return synthesized_; }
  /// Whether print voxels blend 8 solid voxels (a magnified texture) or take the one under them.
  bool trilinear() const { return trilinear_; }

private:
  struct Samples;
  /// A model coordinate in solid voxels: the voxel below it (trilinear: the lower of the two
  /// centres around it) and the fraction of the way to the next.
  struct Position {
    int64_t voxel;
    float fraction;
  };
  Position solidPosition(double coordinate) const;
  std::array<Position, 2> rowPosition(int y, int layer) const;  // of grid row y, along the two slow axes
  Position fastPosition(int x) const;                          // along modelAxisOfX (the print's x)
  const synthesis::SolidAnalysis& analysis_;
  const Image &ex_, &ey_, &ez_;
  synthesis::SolidSynthesisOptions options_;
  double scale_;
  print::PrintGrid grid_;
  bool trilinear_;
  std::unique_ptr<synthesis::SolidLevelCache> cache_;
  std::unique_ptr<Samples> samples_;
  int64_t requested_ = 0, synthesized_ = 0;
};

/// The model's own colour at the surface point nearest to each voxel: the base colour factor of
/// its material times its base colour texture (bilinear, at the mip level whose texels match the
/// voxel size). A model without materials is white.
class SurfaceVoxelColors : public VoxelColorSource {
public:
  /// `maxDistanceMm`: how far from the surface colours are asked for (the shell), to bound the
  /// nearest-point search. The mesh must outlive the source.
  SurfaceVoxelColors(const geometry::Mesh& mesh, const print::PrintGrid& grid, double maxDistanceMm);
  ~SurfaceVoxelColors() override;
  void prepare(std::span<const print::LayerSpans>, const Context&) override {}
  void colors(int layer, int y, int begin, int end, float* rgba) const override;

private:
  const geometry::Mesh& mesh_;
  print::PrintGrid grid_;
  float maxDistance_;                  // model units
  geometry::EmbreeScene scene_;
  std::vector<MipPyramid> pyramids_;   // per material (empty without a texture)
  std::vector<float> lod_;             // per triangle: mip level of a voxel-sized footprint
};

} // namespace texfab::print
