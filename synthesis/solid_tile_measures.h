// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// How a solid tile set's lattice shows in its slices: issue 33's seam ratio, peak step and shifted
// self-correlation at the tile period (docs/measurements.md#seams-at-the-tiles-faces).

#include "core/context.h"
#include "core/image.h"
#include "synthesis/solid_tiles.h"

namespace texfab::synthesis {

struct SolidTileLattice {
  /// The largest over the slices of LatticeSteps::seamRatio and LatticeSteps::peak.
  double seamRatio = 0, peakStep = 0;
  /// The largest shifted self-correlation (shiftedSelfCorrelation) at the tile period and its
  /// multiples below half a slice: 1 when every cell looks alike.
  double correlation = 0;
};

/// The measures on three axis-aligned slices (x, y and z = 3 1/3 tiles) of 8 x 8 cells, read with
/// seed 1 and coloured as synthesis colours voxels (solidColors of ex, ey, ez).
SolidTileLattice measureSolidTileLattice(const SolidTileSet& tiles, const Image& ex, const Image& ey, const Image& ez,
                                         const Context& ctx = {});

} // namespace texfab::synthesis
