// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/solid_volume.h"

#include "synthesis/refine_solid.h"

#include <algorithm>
#include <cmath>

namespace texfab::render {
using namespace synthesis;

namespace {
constexpr int kSlab = 128;  // slices synthesized at once
}

Image solidColorImage(std::span<const Triple> triples, const SolidExemplars& e, int width, int height) {
  const bool bytes = e.x.format == PixelFormat::UInt8 && e.y.format == PixelFormat::UInt8 && e.z.format == PixelFormat::UInt8;
  Image image(width, height, solidColorChannels(e.x, e.y, e.z), bytes ? PixelFormat::UInt8 : PixelFormat::UInt16);
  image.pixels.clear();
  solidColors(triples, e.x, e.y, e.z, image.pixels);
  return image;
}

SolidVolumeResult synthesizeSolidVolume(const SolidAnalysis& analysis, const SolidExemplars& e, int n, double scale,
                                        const SolidSynthesisOptions& options, SolidLevelCache* cache,
                                        const std::function<void(const Image&)>& slice, const Context& ctx) {
  SolidVolumeResult result;
  result.requestedVoxels = int64_t(n) * n * n;
  auto voxelOf = [&](int i) { return int64_t(std::floor((i + 0.5) / scale)); };
  const int side = int(voxelOf(n - 1) - voxelOf(0) + 1);
  const int channels = solidColorChannels(e.x, e.y, e.z);
  for (int z0 = 0; z0 < n; z0 += kSlab) {
    const int z1 = std::min(n, z0 + kSlab);
    const VoxelBox box{voxelOf(0), voxelOf(0), voxelOf(z0), side, side, int(voxelOf(z1 - 1) - voxelOf(z0) + 1)};
    const SolidSynthesisResult r = synthesizeSolidBox(analysis, box, options, cache, ctx);
    addLevelStats(result.levels, r);
    const Image colors = solidColorImage(r.triples, e, box.nx, int(box.count() / box.nx));
    for (int z = z0; z < z1; ++z) {
      Image image(n, n, channels, colors.format);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const size_t i = (size_t(voxelOf(z) - box.z) * size_t(box.ny) + size_t(voxelOf(y) - box.y)) * size_t(box.nx) +
                           size_t(voxelOf(x) - box.x);
          for (int c = 0; c < channels; ++c) image.at(x, y, c) = colors.pixels[i * size_t(channels) + size_t(c)];
        }
      slice(image);
    }
  }
  return result;
}

double solidVolumeMemoryBytes(int n, double scale, int refinePasses) {
  // One slab of triples (12 bytes) at the synthesized resolution, a slab of colours at the
  // output's, and 512 MiB for the synthesis of one slab's dependency chain; refinement works in
  // slabs of its own (refineSolidBox), about 100 bytes per voxel of their region.
  const double side = std::ceil(n / scale) + 1, slab = std::ceil(std::min(n, kSlab) / scale) + 1;
  double refine = 0;
  if (refinePasses > 0) {
    const double margin = synthesis::refineMargin(refinePasses);
    const double depth = std::min(slab, std::max(double(1 << 20) / (side * side), 4 * margin));
    refine = side * side * (depth + 2 * margin) * 100.0;
  }
  return side * side * slab * 12 + double(n) * n * std::min(n, kSlab) * 12 + 512.0 * (1 << 20) + refine;
}

} // namespace texfab::render
