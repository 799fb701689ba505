// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The slice job (`texfab slice`): a closed model, a source of colour and a set of printer
// materials in; one image per layer out, each voxel one material (or the continuous colour), for
// full-colour material-jetting printers.
//
// Streaming (after OpenFab, Vidimce et al. 2013, §4): layers go through in batches; a batch is
// voxelized (inside and shell, per layer), its shell coloured (the solid texture is synthesized
// for the batch's shell voxels only, in one request), and its layers rendered row by row straight
// into the PNG encoder, several layers at a time. Memory holds a batch's spans and colours and a
// few rows per thread, whatever the number of layers.
//
// Determinism: every output byte is a function of the inputs and the layer's index alone: inside
// and shell come from the mesh, colours from the voxel's position, the default dither from a
// position-based threshold array (DitherMode). A run over any layer range writes exactly the
// files a full run writes for those layers, whatever the thread count or batch size.

#include "core/context.h"
#include "core/image.h"
#include "print/blue_noise.h"
#include "print/dither_layer.h"
#include "print/mix_materials.h"
#include "print/print_materials.h"
#include "print/slice_writer.h"
#include "print/voxel_colors.h"
#include "print/voxelize_layers.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace texfab::print {

/// How layers are written. Indexed: 8-bit palette PNGs, index 0 transparent (empty), index i the
/// i-th material's colour. VoxelPrint: GrabCAD Voxel Print's conventions as texfab reads them:
/// 8-bit RGBA PNGs, each material a distinct opaque colour, empty voxels transparent. With
/// DitherMode::None both write RGBA with the continuous colour.
enum class SliceFormat { Indexed, VoxelPrint };

struct SliceOptions {
  int firstLayer = 0;   ///< first layer written, [0, layers)
  int layerCount = -1;  ///< layers written from firstLayer; -1 = through the last layer
  DitherMode dither = DitherMode::BlueNoise;
  SliceFormat format = SliceFormat::Indexed;
  std::vector<PrintMaterial> materials = defaultPrintMaterials();
  /// Material of voxels deeper than the shell (found by name, case-insensitive; "white" finds
  /// VeroWhite).
  std::string coreMaterial = "white";
  int blueNoiseSize = 32;  ///< period of the threshold array in voxels; 16, 24, 32, ... 64
  int batchLayers = 64;    ///< layers per batch; 1-4096. Larger batches synthesize fewer, larger requests
  bool preview = false;    ///< also render SliceResult::preview
  /// How dithered modes choose a colour's mix of materials: by the smallest CIELAB error
  /// (Perceptual) or linear-RGB error (LinearRgb, the former choice), see mix_materials.h.
  MixSpace mixSpace = MixSpace::Perceptual;
  /// The printer's ICC output profile (empty: none): dithered mixes aim at the colour it says the
  /// printer reproduces for each requested colour (IccProfile). validate() refuses a file that is
  /// not a usable profile and materials outside its gamut.
  std::filesystem::path iccProfile;

  void validate() const;
};

/// Where the time went, summed over threads (seconds of CPU), and what was written.
/// The colour a print shows against the colour asked for, as a person sees it: over blocks of
/// 16^3 voxels at least half of which are opaque shell voxels, the mean requested colour against
/// the mean of the materials the dither chose (both in linear light, as the eye mixes them), as
/// CIEDE2000. Measured in dithered modes only. With an ICC profile the request is still the
/// requested colour, not the profile's reproduction of it.
struct PrintColorError {
  size_t blocks = 0;
  double mean = 0, p95 = 0, max = 0;  ///< ΔE2000 over the blocks
};

struct SliceReport {
  int layers = 0;             ///< layers written
  PrintColorError colorError;
  int64_t insideVoxels = 0, shellVoxels = 0;
  uint64_t bytes = 0;         ///< PNG bytes written
  double voxelizeSeconds = 0; ///< inside and shell spans (and the blue-noise array, built beside them)
  double prepareSeconds = 0;  ///< colour source preparation (solid synthesis), wall clock
  double colorSeconds = 0;    ///< shell colours
  double ditherSeconds = 0;   ///< material choice and row assembly
  double encodeSeconds = 0;   ///< PNG encoding
  double writeSeconds = 0;    ///< checksums and file writes
  double seconds = 0;         ///< wall clock of the whole job
};

struct SliceResult {
  SliceReport report;
  std::optional<Image> preview;  ///< when SliceOptions::preview
};

/// Where a print's colours come from, as its manifest records them ("print"."source").
enum class PrintColors { Model, Solid, Surface };
struct PrintSource {
  std::string model;                        ///< the model's name (e.g. its file name)
  PrintColors colors = PrintColors::Model;  ///< Model: the model's own materials
  std::string exemplar;                     ///< Solid and Surface: its name
  uint32_t seed = 0;                        ///< Solid and Surface
  synthesis::SolidMethod method = synthesis::SolidMethod::Lazy;  ///< Solid
  float contrastGain = 0;                   ///< Solid
  int refinePasses = 0;                     ///< Solid
  double textureScale = 0;                  ///< Solid: the given exemplar's pixels per model unit
  int downsampling = 1;                     ///< Solid: synthesized from a copy this many times smaller
  SolidSampling sampling = SolidSampling::Nearest;  ///< Solid: how print voxels read the solid texture
};

/// Memory the job needs beyond its inputs, in bytes, at worst (a layer of noise), with a layer in
/// flight per thread of `ctx`. Callers refuse prints whose layers do not fit.
uint64_t sliceMemoryBytes(const print::PrintGrid& grid, const SliceOptions& options, const Context& ctx);

/// Slices the layer range of `options` into `writer` and seals it with the manifest (the caller
/// publishes it: SliceWriter::publish). Stages
/// reported through ctx: "slice" (advancing per layer written). Throws texfab::Error on bad
/// options or a failed write (nothing is committed then).
/// The manifest's "print" block (grid, materials, options and `source`) is written from the
/// arguments: equal inputs give equal blocks, so shards of one print can be checked against each
/// other (mergeSliceFolders).
SliceResult sliceModel(const print::LayerVoxelizer& voxelizer, VoxelColorSource& colors, const SliceOptions& options,
                       SliceWriter& writer, const PrintSource& source, const Context& ctx = {});

} // namespace texfab::print
