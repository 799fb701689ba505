// SPDX-License-Identifier: GPL-3.0-or-later
// Every solid kernel on a Vulkan device against its CPU twin, on random tables, triples and masks:
// the CPU kernels run on a dense 32^3 grid, the device kernels on the same grid as 2x2x2 chunks.
#include "synthesis/cpu/solid_kernels.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/vulkan/solid_kernels.h"
#include "tests/vulkan/vulkan_test_support.h"

#include <gtest/gtest.h>

#include <cstring>

namespace texfab::synthesis {
namespace {

using test::Random;
using test::VulkanDevice;

constexpr int kSide = 32;  // the dense grid: 2 chunks per axis
constexpr size_t kVoxels = size_t(kSide) * kSide * kSide;

// Random tables of a solid level (valid coordinates, random descriptors and projections).
struct HostSolidTables {
  std::vector<uint8_t> colors;
  std::vector<uint32_t> candidates2d, triples[3];
  std::vector<int8_t> descriptors2d, descriptors3d[3];
  cpu::SolidKernelProjection projection2d, projection3d;
  cpu::SolidTables view;

  HostSolidTables(Random& r, int w, int h, int dims, int k2d, int k2dStride, int k3d, int spacing) {
    const size_t pixels = size_t(w) * size_t(h);
    colors = r.values<uint8_t>(pixels * 3, 0, 255);
    candidates2d = r.coords(pixels * size_t(k2dStride), w, h);
    descriptors2d = r.values<int8_t>(pixels * size_t(k2dStride) * kSolid2dDims, -127, 127);
    projection2d = randomProjection(r, 3 * 25, kSolid2dDims);
    projection3d = randomProjection(r, 3 * kSolidCrossVoxels, dims);
    view.exemplarWidth = w;
    view.exemplarHeight = h;
    view.spacing = spacing;
    view.dims = dims;
    view.k2d = k2d;
    view.k2dStride = k2dStride;
    view.k3d = k3d;
    for (int e = 0; e < 3; ++e) {
      triples[e] = r.coords(pixels * kSolidMaxCandidates * 3, w, h);
      descriptors3d[e] = r.values<int8_t>(pixels * kSolidMaxCandidates * size_t(dims), -127, 127);
      view.colors[e] = colors.data();  // shared, as one image for the three axes
      view.candidates2d[e] = candidates2d.data();
      view.candidateDescriptors2d[e] = descriptors2d.data();
      view.triples[e] = triples[e].data();
      view.descriptors3d[e] = descriptors3d[e].data();
    }
    view.projection2d = &projection2d;
    view.projection3d = &projection3d;
    view.contrastGain16 = r.between(0, 1) ? 16 : int(r.between(17, 64));  // targets as they are, or a gain
  }

  static cpu::SolidKernelProjection randomProjection(Random& r, int inputs, int dims) {
    const std::vector<int32_t> mean = r.values<int32_t>(size_t(inputs), 0, 1530);
    const std::vector<int16_t> basis = r.values<int16_t>(size_t(inputs) * size_t(dims), -2048, 2047);
    return cpu::prepareSolidProjection(mean.data(), basis.data(), inputs, dims, 1 << 20);
  }
};

// The chunk slot and local index of dense voxel (x, y, z).
size_t chunkIndex(int x, int y, int z) {
  const size_t slot = size_t(((z >> 4) * 2 + (y >> 4)) * 2 + (x >> 4));
  return slot * vulkan::kSolidChunkVoxels + size_t(((z & 15) * 16 + (y & 15)) * 16 + (x & 15));
}

template <class T> std::vector<T> toChunks(const std::vector<T>& dense, int per) {
  std::vector<T> out(dense.size());
  for (int z = 0; z < kSide; ++z)
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x)
        for (int i = 0; i < per; ++i)
          out[chunkIndex(x, y, z) * size_t(per) + size_t(i)] = dense[(size_t((z * kSide + y) * kSide + x)) * size_t(per) + size_t(i)];
  return out;
}

// The 8 chunks: keys from the grid's origin (a multiple of 16), neighbours among themselves.
void chunkFrame(const cpu::VolumeGrid& g, std::vector<int32_t>& keys, std::vector<int32_t>& neighbours) {
  for (int slot = 0; slot < 8; ++slot) {
    const int c[3] = {slot & 1, (slot >> 1) & 1, slot >> 2};
    keys.push_back(int32_t(g.x0 / 16 + c[0]));
    keys.push_back(int32_t(g.y0 / 16 + c[1]));
    keys.push_back(int32_t(g.z0 / 16 + c[2]));
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int n[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
          const bool inside = n[0] >= 0 && n[0] < 2 && n[1] >= 0 && n[1] < 2 && n[2] >= 0 && n[2] < 2;
          neighbours.push_back(inside ? (n[2] * 2 + n[1]) * 2 + n[0] : -1);
        }
  }
}

// Random masks in [-1, T]; voxels within 2 of the grid's border are -1 (their 3-neighborhood
// leaves the grid).
std::vector<int8_t> randomMask(Random& r, int T) {
  std::vector<int8_t> last(kVoxels);
  for (int z = 0; z < kSide; ++z)
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x) {
        const bool border = std::min({x, y, z}) < 2 || std::max({x, y, z}) >= kSide - 2;
        last[size_t((z * kSide + y) * kSide + x)] = border ? int8_t(-1) : int8_t(r.between(-1, T));
      }
  return last;
}

struct Case {
  int w, h, dims, k2d, k2dStride, k3d, spacing, interleave;
};

void checkCase(vulkan::Device& device, Random& r, const Case& c) {
  const HostSolidTables tables(r, c.w, c.h, c.dims, c.k2d, c.k2dStride, c.k3d, c.spacing);
  const cpu::VolumeGrid grid{16 * r.between(-50, 50), 16 * r.between(-50, 50), 16 * r.between(-50, 50), kSide, kSide, kSide};
  const cpu::VolumeGrid parentGrid{grid.x0 / 2, grid.y0 / 2, grid.z0 / 2, kSide / 2, kSide / 2, kSide / 2};
  const int T = c.interleave == 2 ? 8 : 2;
  const std::vector<int8_t> last = randomMask(r, T);
  const std::vector<uint32_t> parents = r.coords(parentGrid.size() * 3, c.w, c.h);
  const cpu::SolidInit initParams{9, r.between(0, 1024), int(r.between(0, 12))};  // offsetCells 0: one tiling

  // The CPU: init, upsample, colours, a correction and its commit at a random step.
  std::vector<uint32_t> init(kVoxels * 3, 0), up(kVoxels * 3, 0), out(kVoxels * 3, 0);
  std::vector<int16_t> colors(kVoxels * 4, 0), outColors(kVoxels * 4, 0);
  cpu::solidInitKernel(init.data(), last.data(), grid, tables.view, initParams, 0, grid.rows());
  cpu::solidUpsampleKernel(parents.data(), parentGrid, up.data(), last.data(), grid, c.spacing, c.w, c.h, 0, grid.rows());
  cpu::solidColorKernel(up.data(), colors.data(), last.data(), 0, grid, tables.view, 0, grid.rows());
  const int step = int(r.between(1, T));
  cpu::solidCorrectKernel(up.data(), colors.data(), out.data(), outColors.data(), last.data(), grid, tables.view,
                          c.interleave, step, 0, grid.rows());
  std::vector<uint32_t> committed = up;
  std::vector<int16_t> committedColors = colors;
  cpu::solidCommitKernel(out.data(), outColors.data(), committed.data(), committedColors.data(), last.data(), grid,
                         c.interleave, step, 0, grid.rows());

  // The device, on chunks: init; then upsample, colours, correct, commit.
  std::vector<int32_t> keys, neighbours;
  chunkFrame(grid, keys, neighbours);
  std::vector<uint32_t> chunkParents;
  for (int slot = 0; slot < 8; ++slot)
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          const size_t p = size_t((((slot >> 2) * 8 + z) * 16 + ((slot >> 1) & 1) * 8 + y) * 16 + (slot & 1) * 8 + x);
          chunkParents.insert(chunkParents.end(), parents.begin() + std::ptrdiff_t(p * 3), parents.begin() + std::ptrdiff_t(p * 3 + 3));
        }
  const std::vector<int8_t> chunkLast = toChunks(last, 1);
  vulkan::Commands commands(device);
  const vulkan::SolidTables deviceTables = vulkan::uploadSolidTables(commands, tables.view);
  const vulkan::SolidChunks chunks = vulkan::uploadChunks(commands, 8, keys, chunkLast, neighbours, chunkParents);
  std::vector<uint32_t> gpuInit(kVoxels * 3), gpuUp(kVoxels * 3), gpuOut(kVoxels * 3), gpuCommitted(kVoxels * 3);
  // Colour records are 4 int16 on the CPU, 3 (in 2 words) on the device: compare the first 3.
  std::vector<uint32_t> colorWords(kVoxels * 2), outColorWords(kVoxels * 2), committedColorWords(kVoxels * 2);
  // Voxels outside the mask read as zeros, as the CPU's zero-initialized grids (the engine's masks
  // guarantee that no such voxel is read).
  for (const vulkan::Buffer* b : {&chunks.triples, &chunks.colors}) commands.fill(*b, 0);
  vulkan::solidInitKernel(commands, chunks, deviceTables, initParams);
  commands.download(chunks.triples, 0, gpuInit.data(), kVoxels * 12);
  vulkan::solidUpsampleKernel(commands, chunks, deviceTables);
  vulkan::solidColorKernel(commands, chunks, deviceTables, 0);
  commands.download(chunks.triples, 0, gpuUp.data(), kVoxels * 12);
  commands.download(chunks.colors, 0, colorWords.data(), kVoxels * 8);
  vulkan::solidCorrectKernel(commands, chunks, deviceTables, c.interleave, step, tables.view.contrastGain16);
  commands.download(chunks.corrected, 0, gpuOut.data(), kVoxels * 12);
  commands.download(chunks.correctedColors, 0, outColorWords.data(), kVoxels * 8);
  vulkan::solidCommitKernel(commands, chunks, c.interleave, step);
  commands.download(chunks.triples, 0, gpuCommitted.data(), kVoxels * 12);
  commands.download(chunks.colors, 0, committedColorWords.data(), kVoxels * 8);
  commands.submit();

  int compared[3] = {0, 0, 0};
  for (int z = 0; z < kSide; ++z)
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x) {
        const size_t v = size_t((z * kSide + y) * kSide + x), g = chunkIndex(x, y, z);
        if (last[v] < 0) continue;
        const auto triple = [&](const std::vector<uint32_t>& t, size_t i) { return std::array{t[i * 3], t[i * 3 + 1], t[i * 3 + 2]}; };
        const auto color = [&](const std::vector<uint32_t>& words) {
          return std::array{int16_t(words[g * 2] & 0xffff), int16_t(words[g * 2] >> 16), int16_t(words[g * 2 + 1] & 0xffff)};
        };
        const auto cpuColor = [&](const std::vector<int16_t>& c4) { return std::array{c4[v * 4], c4[v * 4 + 1], c4[v * 4 + 2]}; };
        ASSERT_EQ(triple(gpuInit, g), triple(init, v)) << "init at " << x << "," << y << "," << z;
        ASSERT_EQ(triple(gpuUp, g), triple(up, v)) << "upsample at " << x << "," << y << "," << z;
        ASSERT_EQ(color(colorWords), cpuColor(colors)) << "colour at " << x << "," << y << "," << z;
        ASSERT_EQ(triple(gpuCommitted, g), triple(committed, v)) << "commit at " << x << "," << y << "," << z;
        ASSERT_EQ(color(committedColorWords), cpuColor(committedColors)) << "commit at " << x << "," << y << "," << z;
        ++compared[0];
        const bool corrected = last[v] >= step && (c.interleave == 1 || ((x & 1) | (y & 1) << 1 | (z & 1) << 2) == (step - 1) % 8);
        if (!corrected) continue;
        ASSERT_EQ(triple(gpuOut, g), triple(out, v)) << "correct at " << x << "," << y << "," << z;
        ASSERT_EQ(color(outColorWords), cpuColor(outColors)) << "correct at " << x << "," << y << "," << z;
        ++compared[1];
        compared[2] += triple(out, v) != triple(up, v);
      }
  EXPECT_GT(compared[0], 10000);
  EXPECT_GT(compared[1], 100);
  EXPECT_GT(compared[2], compared[1] / 2);  // the correction did change most voxels
}

TEST(VulkanKernels, SolidKernelsEqualTheCpu) {
  VulkanDevice d;
  TEXFAB_REQUIRE_VULKAN(d);
  Random r(5);
  // Exemplar sizes, dimensions (8 at the finest level, up to 12 above), 2-D and 3-D candidate
  // counts, spacings, both schedules.
  for (const Case& c : {Case{16, 16, 8, 2, 2, 12, 1, 1}, Case{23, 17, 12, 4, 4, 12, 4, 1}, Case{31, 9, 11, 3, 4, 7, 2, 2},
                        Case{12, 40, 9, 1, 1, 5, 8, 2}}) {
    SCOPED_TRACE("exemplar " + std::to_string(c.w) + "x" + std::to_string(c.h) + ", dims " + std::to_string(c.dims));
    checkCase(*d.device, r, c);
  }
}

// The tile kernels against SolidTileReader: random tile sets of two and three face variants, boxes
// across cells on both sides of the origin in slabs of a few layers, lists of scattered voxels in
// batches, several seeds.
TEST(VulkanKernels, SolidTilesKernelReadsTheCpusTriples) {
  VulkanDevice d;
  TEXFAB_REQUIRE_VULKAN(d);
  Random r(9);
  for (int variants : {2, 3}) {
    SolidTileSet tiles;
    tiles.width = tiles.height = 64;
    tiles.layout = SolidTileLayout(8, variants);
    tiles.key = 0x5eed0000u + uint64_t(variants);
    tiles.elements.resize(tiles.layout.elements);
    const std::vector<uint32_t> coords = r.coords(tiles.layout.elements * 3, 64, 64);
    std::memcpy(tiles.elements.data(), coords.data(), coords.size() * sizeof(uint32_t));
    for (const VoxelBox& box : {VoxelBox{-13, -7, -21, 37, 29, 23}, VoxelBox{1000, -2000, 5, 17, 9, 40}}) {
      for (uint32_t seed : {1u, 5u}) {
        SCOPED_TRACE(std::to_string(variants) + " variants, seed " + std::to_string(seed) + ", box at " +
                     std::to_string(box.x));
        std::vector<Triple> cpu(size_t(box.count())), gpu(size_t(box.count()));
        evaluateSolidTilesBox(tiles, seed, box, cpu);
        vulkan::evaluateSolidTilesBox(*d.device, tiles, seed, box, gpu, {}, uint64_t(box.nx) * uint64_t(box.ny) * 3);
        ASSERT_EQ(gpu, cpu);
      }
    }
    // Lists: scattered voxels up to the largest position allowed, in batches of a few hundred.
    std::vector<Voxel> voxels;
    for (int i = 0; i < 2000; ++i) {
      const int64_t range = i % 2 ? 40 : kMaxSolidPosition;
      voxels.push_back({r.between(-range, range), r.between(-range, range), r.between(-range, range)});
    }
    voxels.push_back({kMaxSolidPosition, -kMaxSolidPosition, kMaxSolidPosition});
    for (uint32_t seed : {1u, 7u}) {
      SCOPED_TRACE(std::to_string(variants) + " variants, seed " + std::to_string(seed) + ", a list");
      std::vector<Triple> cpu(voxels.size()), gpu(voxels.size());
      evaluateSolidTiles(tiles, seed, voxels, cpu);
      vulkan::evaluateSolidTiles(*d.device, tiles, seed, voxels, gpu, {}, 300);
      ASSERT_EQ(gpu, cpu);
    }
  }
}

} // namespace
} // namespace texfab::synthesis
