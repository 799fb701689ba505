// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/solid_tile_measures.h"

#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_solid.h"

#include <algorithm>
#include <vector>

namespace texfab::synthesis {

SolidTileLattice measureSolidTileLattice(const SolidTileSet& tiles, const Image& ex, const Image& ey, const Image& ez,
                                         const Context& ctx) {
  const int n = tiles.layout.side, side = 8 * n;
  const int64_t across = 3 * n + n / 3;  // inside a cell, off its faces
  SolidTileLattice m;
  for (int axis = 0; axis < 3; ++axis) {
    // Pixel (i, j) is voxel i along the axis after `axis` and j along the one after that.
    std::vector<Voxel> voxels;
    voxels.reserve(size_t(side) * size_t(side));
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        int64_t p[3];
        p[axis] = across;
        p[(axis + 1) % 3] = i;
        p[(axis + 2) % 3] = j;
        voxels.push_back({p[0], p[1], p[2]});
      }
    std::vector<Triple> triples(voxels.size());
    evaluateSolidTiles(tiles, 1, voxels, triples, ctx);
    Image slice(side, side, solidColorChannels(ex, ey, ez));
    slice.pixels.clear();  // solidColors appends
    solidColors(triples, ex, ey, ez, slice.pixels);
    const LatticeSteps steps = latticeSteps(slice, n, 0, 0);
    m.seamRatio = std::max(m.seamRatio, steps.seamRatio());
    m.peakStep = std::max(m.peakStep, steps.peak());
    m.correlation = std::max(m.correlation, latticeCorrelation(slice, n));
  }
  return m;
}

} // namespace texfab::synthesis
