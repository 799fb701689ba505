// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What the solid texture tests share: crops of the bundled marble, and boxes as voxel lists.

#include "core/crop.h"
#include "core/image_io.h"
#include "synthesis/synthesize_solid.h"

#include <filesystem>
#include <vector>

namespace texfab::test {

/// A square crop of GIMP's marble (bundled as models/exemplars/marble.png).
inline Image marble(int side, int x0 = 0, int y0 = 0) {
  static const Image full = readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/exemplars/marble.png");
  return crop(full, x0, y0, side, side);
}

/// The voxels of `b`, x fastest, then y, then z (the order of synthesizeSolidBox).
inline std::vector<synthesis::Voxel> boxVoxels(const synthesis::VoxelBox& b) {
  std::vector<synthesis::Voxel> v;
  for (int z = 0; z < b.nz; ++z)
    for (int y = 0; y < b.ny; ++y)
      for (int x = 0; x < b.nx; ++x) v.push_back({b.x + x, b.y + y, b.z + z});
  return v;
}

} // namespace texfab::test
