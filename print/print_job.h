// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The print job (`texfab slice`, texfab.slice in Python): a model made printable
// (geometry::prepareMesh: wound outward, holes closed), its print grid, the colour of its voxels
// (the model's own materials, the solid texture, or a surface synthesized first) and the slices of
// a layer range (slice_model.h) committed with their manifest. Callers make the exemplar's analyses (through their cache).

#include "core/context.h"
#include "core/image.h"
#include "geometry/mesh.h"
#include "geometry/repair/prepare_mesh.h"
#include "print/print_grid.h"
#include "print/slice_model.h"
#include "print/slice_writer.h"
#include "print/voxelize_layers.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

namespace texfab::print {

struct PrintJobOptions {
  print::PrintGridOptions grid;
  print::VoxelizeOptions voxelize;
  SliceOptions slice;
  /// Model: the model's own materials; Solid: the solid texture (texfab texture --mode solid);
  /// Surface: a texture synthesized over the surface first.
  PrintColors colors = PrintColors::Model;
  /// Exemplar pixels (voxels) per model unit, or featureSize, model units one exemplar spans;
  /// both 0 = render::autoTextureScale, as texfab texture's, so the print shows the GLB's pattern.
  double textureScale = 0;
  double featureSize = 0;
  uint32_t seed = 1;
  synthesis::SolidSynthesisOptions solid;  ///< Solid; its seed is `seed`
  int resolution = 2048;                   ///< Surface: the atlas size

  void validate() const;  ///< throws texfab::Error naming the bad option
};

/// The exemplar of the Solid and Surface colours, with the analysis that mode needs.
struct PrintExemplar {
  const Image* color = nullptr;
  const synthesis::SolidAnalysis* solid = nullptr;
  const synthesis::ExemplarAnalysis* surface = nullptr;
  std::string name;  ///< for the manifest, e.g. the file name
  /// `color` (and its analysis) is the exemplar given, this many times smaller
  /// (PrintJob::analysisDownsampling); a texture scale counts the given exemplar's pixels.
  int downsampling = 1;
};

struct PrintJobResult {
  SliceResult slice;
  PrintSource source;  ///< as the manifest records it
  int64_t voxelsRequested = 0, voxelsSynthesized = 0;  ///< Solid
};

class PrintJob {
public:
  /// Makes `mesh` printable and lays out its grid; repairs are reported as warnings through ctx.
  /// Throws texfab::Error on bad options or a mesh with nothing to print.
  PrintJob(geometry::Mesh mesh, const PrintJobOptions& options, const Context& ctx = {});

  const print::PrintGrid& grid() const { return grid_; }
  const geometry::Mesh& mesh() const { return mesh_; }
  /// What made the model printable (geometry::prepareMesh, MeshUse::Print).
  const geometry::MeshPreparation& preparation() const { return preparation_; }
  /// Solid colours: the power of two (1, 2, 4, ...) by which `exemplar`, as given, is best analysed
  /// and synthesized smaller. Where the scale puts at least that many solid voxels along the print's
  /// finest pitch, every print voxel would point-sample detail finer than itself (aliasing, and a
  /// dependency chain per voxel); a copy that much smaller is the prefiltered texture. Never below
  /// render::kMinAnalysedSide pixels a side (where that stops it, print voxels average their
  /// footprint: SolidSampling::Box); 1 for the other colours.
  int analysisDownsampling(const Image& exemplar) const;
  /// Memory the slicing needs at worst, with a layer in flight per thread of `ctx`.
  double memoryBytes(const Context& ctx) const;
  /// Slices layers [first, first + count) (count -1: through the last) into `writer` and seals it
  /// (the caller publishes it: SliceWriter::publish). `modelName` goes to the manifest. Stages: "surface texture" (Surface), "voxelizer", "slice".
  PrintJobResult slice(const PrintExemplar& exemplar, int first, int count, SliceWriter& writer,
                       const std::string& modelName, const Context& ctx = {}) const;

private:
  /// The finest grid of a volume rebuild (OpenVDB's narrow band grows with its square).
  static constexpr int kMaxRebuildVoxels = 1024;

  geometry::Mesh mesh_;
  geometry::MeshPreparation preparation_;
  PrintJobOptions options_;
  print::PrintGrid grid_;
};

} // namespace texfab::print
