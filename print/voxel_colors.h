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

/// How a print voxel reads the solid texture: the voxel under its centre (Nearest); where the
/// print's finest pitch spans fewer than render::kSolidTrilinearBelow solid voxels (magnified), the 8
/// voxels whose centres surround its centre, with trilinear weights (Trilinear, as texture bakes
/// do); where it spans at least kSolidBoxFrom (minified, once the exemplar's smallest copy is
/// reached: PrintJob::analysisDownsampling), the voxels its box overlaps, weighted by the overlap
/// (Box: the mean colour of its footprint, up to SolidVoxelColors::kMaxTaps voxels per axis).
enum class SolidSampling { Nearest, Trilinear, Box };
const char* toString(SolidSampling sampling);
inline constexpr double kSolidBoxFrom = 2.0;

/// The solid texture in the frame of `texfab texture --mode solid`: a point p of the model (model
/// units) has the colour of solid voxel floor(p * scale), synthesized lazily for the shell voxels
/// of the prepared layers only, its colour the solid engine's colour of its triple
/// (synthesis::solidColors) read as sRGB; print voxels sample it as SolidSampling says, blending in
/// linear light.
class SolidVoxelColors : public VoxelColorSource {
public:
  /// Voxels per axis a footprint blends at most.
  static constexpr int kMaxTaps = 5;

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
  SolidSampling sampling() const { return sampling_; }

private:
  struct Samples;
  /// The solid voxels a print voxel reads along one model axis: `count` of them from `first`,
  /// `stride` apart, with their weights.
  struct Taps {
    int64_t first = 0, stride = 1;
    int count = 1;
    std::array<float, kMaxTaps> weight{1.0f};
    int64_t voxel(int k) const { return first + int64_t(k) * stride; }
    int64_t last() const { return voxel(count - 1); }
  };
  Taps taps(double coordinate, int axis) const;                 // at a model coordinate along model axis `axis`
  std::array<Taps, 2> rowTaps(int y, int layer) const;          // of grid row y, along the two slow axes
  Taps fastTaps(int x) const;                                   // along modelAxisOfX (the print's x)
  const synthesis::SolidAnalysis& analysis_;
  const Image &ex_, &ey_, &ez_;
  synthesis::SolidSynthesisOptions options_;
  double scale_;
  print::PrintGrid grid_;
  Eigen::Vector3d modelPitch_;  // the print voxel's size along each model axis
  SolidSampling sampling_ = SolidSampling::Nearest;
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
