// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Colouring the voxels of lazy solid synthesis (Dong et al. 2008): an image of any set of voxels,
// and a whole N^3 volume synthesized slab by slab, delivered slice by slice.

#include "core/context.h"
#include "core/image.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace texfab::render {

/// The three exemplars of a solid texture (one image may serve several axes).
struct SolidExemplars {
  const Image& x;
  const Image& y;
  const Image& z;
};

/// The colours of `triples` (synthesis::solidColors) as a width x height image, row by row: 8-bit
/// when the three exemplars are, else 16-bit.
Image solidColorImage(std::span<const synthesis::Triple> triples, const SolidExemplars& exemplars, int width,
                      int height);

struct SolidVolumeResult {
  std::vector<synthesis::SolidLevelStats> levels;  ///< summed over slabs, coarsest first
  int64_t requestedVoxels = 0;                     ///< n^3
};

/// The n^3 grid at the origin: slice z holds output voxels (x, y, z), 0 <= x, y, z < n; an output
/// voxel shows the synthesized voxel floor((i + 0.5) / scale) on each axis (scale = output voxels
/// per synthesized voxel). Synthesized in slabs of 128 slices; each slice goes to `slice` in z
/// order as soon as its slab is done. Coarse levels are kept across slabs in `cache` (may be
/// null). Stages through ctx: those of synthesizeSolidBox, per slab.
SolidVolumeResult synthesizeSolidVolume(const synthesis::SolidAnalysis& analysis, const SolidExemplars& exemplars,
                                        int n, double scale, const synthesis::SolidSynthesisOptions& options,
                                        synthesis::SolidLevelCache* cache,
                                        const std::function<void(const Image&)>& slice, const Context& ctx = {});

/// Peak memory of synthesizeSolidVolume, in bytes: a slab of triples and colours plus one
/// synthesis working set (and the refinement's slab, refine_solid.h, with refinement passes).
double solidVolumeMemoryBytes(int n, double scale, int refinePasses = 0);

} // namespace texfab::render
