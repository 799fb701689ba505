// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §4.3, §5.1, §5.2.
#include "synthesis/vulkan/solid_kernels.h"

#include "core/error.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/vulkan/shaders/kernel_params.h"

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace texfab::synthesis::vulkan {

namespace {

constexpr uint32_t kInitSpirv[] =
#include "synthesis/vulkan/shaders/solid_init_kernel.spv.inc"
    ;
constexpr uint32_t kUpsampleSpirv[] =
#include "synthesis/vulkan/shaders/solid_upsample_kernel.spv.inc"
    ;
constexpr uint32_t kColorSpirv[] =
#include "synthesis/vulkan/shaders/solid_color_kernel.spv.inc"
    ;
constexpr uint32_t kCorrectSpirv[] =
#include "synthesis/vulkan/shaders/solid_correct_kernel.spv.inc"
    ;
constexpr uint32_t kCommitSpirv[] =
#include "synthesis/vulkan/shaders/solid_commit_kernel.spv.inc"
    ;
constexpr uint32_t kGatherSpirv[] =
#include "synthesis/vulkan/shaders/solid_gather_kernel.spv.inc"
    ;
constexpr uint32_t kTilesSpirv[] =
#include "synthesis/vulkan/shaders/solid_tiles_kernel.spv.inc"
    ;
constexpr uint32_t kTilesCellsSpirv[] =
#include "synthesis/vulkan/shaders/solid_tiles_cells_kernel.spv.inc"
    ;
constexpr uint32_t kTilesListSpirv[] =
#include "synthesis/vulkan/shaders/solid_tiles_list_kernel.spv.inc"
    ;

const Kernel kInit{"solidInitKernel", kInitSpirv, {1, 1, 1, 1}, sizeof(SolidParams)};
const Kernel kUpsample{"solidUpsampleKernel", kUpsampleSpirv, {1, 1, 1}, sizeof(SolidParams)};
const Kernel kColor{"solidColorKernel", kColorSpirv, {1, 1, 1, 3, 1}, sizeof(SolidParams)};
const Kernel kCorrect{"solidCorrectKernel", kCorrectSpirv, {1, 1, 1, 1, 1, 1, 3, 3, 3, 3, 3, 1, 1}, sizeof(SolidParams)};
const Kernel kCommit{"solidCommitKernel", kCommitSpirv, {1, 1, 1, 1, 1}, sizeof(SolidParams)};
const Kernel kGather{"solidGatherKernel", kGatherSpirv, {1, 1, 1}, sizeof(GatherParams)};
const Kernel kTiles{"solidTilesKernel", kTilesSpirv, {1, 1, 1}, sizeof(TilesParams)};
const Kernel kTilesCells{"solidTilesCellsKernel", kTilesCellsSpirv, {1}, sizeof(TilesParams)};
const Kernel kTilesList{"solidTilesListKernel", kTilesListSpirv, {1, 1, 1}, sizeof(TilesParams)};

constexpr uint64_t kTilesResidentSalt = 0x54494c4553ull;  // "TILES": a tile set's key among the resident data

constexpr int kPlaneInputs = 3 * 25;
constexpr int kCrossInputs = 3 * kSolidCrossVoxels;

// The tables of one level laid out in one buffer, each at a multiple of 256 bytes.
struct Layout {
  std::vector<uint8_t> bytes;

  Slice add(const void* data, uint64_t size) {
    const Slice s{(bytes.size() + 255) / 256 * 256, (size + 3) / 4 * 4};
    bytes.resize(s.offset + s.bytes, 0);
    std::memcpy(bytes.data() + s.offset, data, size);
    return s;
  }
};

// basis[d][j] of a prepared projection (its weights are stored chunk by chunk for SIMD).
int32_t weight(const cpu::SolidKernelProjection& p, int d, int j) {
  constexpr int kChunk = cpu::SolidKernelProjection::kChunk;
  return p.weights[(size_t(j / kChunk) * size_t(p.rows) + size_t(d)) * kChunk + size_t(j % kChunk)];
}

std::vector<int32_t> projectionWords(const cpu::SolidTables& t) {
  const cpu::SolidKernelProjection &p2 = *t.projection2d, &p3 = *t.projection3d;
  std::vector<int32_t> w(p2.offset, p2.offset + 8);
  w.insert(w.end(), p3.offset, p3.offset + 16);
  for (int d = 0; d < 8; ++d)
    for (int j = 0; j < kPlaneInputs; ++j) w.push_back(weight(p2, d, j));
  for (int d = 0; d < t.dims; ++d)
    for (int j = 0; j < kCrossInputs; ++j) w.push_back(weight(p3, d, j));
  return w;
}

SolidParams paramsOf(const SolidChunks& c, const SolidTables* t) {
  SolidParams p{};
  p.chunks = c.count;
  if (t) {
    p.spacing = t->spacing;
    p.exemplarWidth = t->exemplarWidth;
    p.exemplarHeight = t->exemplarHeight;
    p.dims = t->dims;
    p.k2d = t->k2d;
    p.k2dStride = t->k2dStride;
    p.k3d = t->k3d;
    p.shift2d = t->shift2d;
    p.shift3d = t->shift3d;
    p.clampMargin = t->clampMargin;
  }
  return p;
}

uint64_t voxels(const SolidChunks& c) { return uint64_t(c.count) * kSolidChunkVoxels; }

} // namespace

SolidTables uploadSolidTables(Commands& commands, const cpu::SolidTables& t) {
  if (t.dims > kSolidMaxDims || t.projection2d->dims != kSolid2dDims)
    throw std::logic_error("uploadSolidTables: projections of other neighbourhoods");
  SolidTables d;
  d.exemplarWidth = t.exemplarWidth;
  d.exemplarHeight = t.exemplarHeight;
  d.spacing = t.spacing;
  d.dims = t.dims;
  d.k2d = t.k2d;
  d.k2dStride = t.k2dStride;
  d.k3d = t.k3d;
  d.clampMargin = t.clampMargin;
  d.shift2d = t.projection2d->shift;
  d.shift3d = t.projection3d->shift;
  const uint64_t pixels = uint64_t(t.exemplarWidth) * uint64_t(t.exemplarHeight);
  Layout layout;
  // One image for the three axes shares its per-pixel tables: laid out once.
  auto add = [&](const auto* const(&tables)[3], uint64_t bytes, std::array<Slice, 3>& slices) {
    for (int e = 0; e < 3; ++e) {
      const auto* first = std::find(tables, tables + e, tables[e]);
      slices[size_t(e)] = first < tables + e ? slices[size_t(first - tables)] : layout.add(tables[e], bytes);
    }
  };
  add(t.colors, pixels * 3, d.colors);
  add(t.candidates2d, pixels * uint64_t(t.k2dStride) * 4, d.candidates2d);
  add(t.candidateDescriptors2d, pixels * uint64_t(t.k2dStride) * kSolid2dDims, d.candidateDescriptors2d);
  add(t.triples, pixels * kSolidMaxCandidates * 3 * 4, d.triples);
  add(t.descriptors3d, pixels * kSolidMaxCandidates * uint64_t(t.dims), d.descriptors3d);
  const std::vector<int32_t> projection = projectionWords(t);
  d.projection = layout.add(projection.data(), projection.size() * 4);
  std::vector<int32_t> searchColors(3 * kSolidColorSums);
  for (size_t i = 0; i < searchColors.size(); ++i)
    searchColors[i] = t.searchColors ? t.searchColors[i] : int32_t(2 * (i % kSolidColorSums));
  d.searchColors = layout.add(searchColors.data(), searchColors.size() * 4);
  for (const auto& s : {d.colors, d.candidates2d, d.candidateDescriptors2d, d.triples, d.descriptors3d})
    if (s[0].bytes > commands.device().maxRangeBytes())
      throw Error("solid exemplar tables (" + std::to_string(s[0].bytes >> 20) +
                  " MiB each) exceed the Vulkan device's storage-buffer range");
  d.data = commands.uploaded(std::span<const uint8_t>(layout.bytes));
  return d;
}

uint32_t SolidChunks::maxCount(const Device& device) {
  return uint32_t(std::min<uint64_t>(device.maxRangeBytes() / (kSolidChunkVoxels * 12), UINT32_MAX / kSolidChunkVoxels));
}

SolidChunks uploadChunks(Commands& commands, uint32_t count, std::span<const int32_t> keys, std::span<const int8_t> last,
                         std::span<const int32_t> neighbours, std::span<const uint32_t> parents) {
  if (count > SolidChunks::maxCount(commands.device()) || keys.size() != size_t(count) * 3 ||
      last.size() != size_t(count) * kSolidChunkVoxels || neighbours.size() != size_t(count) * 27 ||
      !(parents.empty() || parents.size() == size_t(count) * 512 * 3))
    throw std::logic_error("uploadChunks: arrays of another size, or too many chunks for one binding");
  Device& device = commands.device();
  SolidChunks c;
  c.count = count;
  c.keys = commands.uploaded(keys);
  c.last = commands.uploaded(last);
  c.neighbours = commands.uploaded(neighbours);
  c.parents = commands.uploaded(parents);
  const uint64_t n = std::max<uint64_t>(voxels(c), 1);
  c.triples = Buffer(device, n * 12);
  c.colors = Buffer(device, n * 8);
  c.corrected = Buffer(device, n * 12);
  c.correctedColors = Buffer(device, n * 8);
  return c;
}

void solidInitKernel(Commands& commands, const SolidChunks& c, const SolidTables& t, const cpu::SolidInit& init) {
  SolidParams p = paramsOf(c, &t);
  p.seed = init.seed;
  p.jitter256 = init.jitter256;
  p.offsetCells = init.offsetCells;
  commands.dispatch(kInit, p, {c.keys, c.last, t.range(t.triples[2]), c.triples}, voxels(c));
}

void solidUpsampleKernel(Commands& commands, const SolidChunks& c, const SolidTables& t) {
  commands.dispatch(kUpsample, paramsOf(c, &t), {c.last, c.parents, c.triples}, voxels(c));
}

void solidColorKernel(Commands& commands, const SolidChunks& c, const SolidTables& t, int minLast) {
  SolidParams p = paramsOf(c, &t);
  p.minLast = minLast;
  commands.dispatch(kColor, p,
                    {c.last, c.triples, c.colors, t.range(t.colors[0]), t.range(t.colors[1]), t.range(t.colors[2]),
                     t.range(t.searchColors)},
                    voxels(c));
}

void solidCorrectKernel(Commands& commands, const SolidChunks& c, const SolidTables& t, int interleave, int step,
                        int contrastGain16) {
  SolidParams p = paramsOf(c, &t);
  p.interleave = interleave;
  p.step = step;
  p.contrastGain16 = contrastGain16;
  commands.dispatch(kCorrect, p,
                    {c.last, c.neighbours, c.triples, c.colors, c.corrected, c.correctedColors,
                     t.range(t.colors[0]), t.range(t.colors[1]), t.range(t.colors[2]),
                     t.range(t.candidates2d[0]), t.range(t.candidates2d[1]), t.range(t.candidates2d[2]),
                     t.range(t.candidateDescriptors2d[0]), t.range(t.candidateDescriptors2d[1]),
                     t.range(t.candidateDescriptors2d[2]),
                     t.range(t.triples[0]), t.range(t.triples[1]), t.range(t.triples[2]),
                     t.range(t.descriptors3d[0]), t.range(t.descriptors3d[1]), t.range(t.descriptors3d[2]),
                     t.range(t.projection), t.range(t.searchColors)},
                    voxels(c));
}

void solidCommitKernel(Commands& commands, const SolidChunks& c, int interleave, int step) {
  SolidParams p = paramsOf(c, nullptr);
  p.interleave = interleave;
  p.step = step;
  commands.dispatch(kCommit, p, {c.last, c.corrected, c.correctedColors, c.triples, c.colors}, voxels(c));
}

void solidGatherKernel(Commands& commands, const SolidChunks& c, const Buffer& listed, uint32_t count,
                       const Buffer& packed) {
  commands.dispatch(kGather, GatherParams{count}, {listed, c.triples, packed}, count);
}

namespace {

// The tile set's elements, uploaded once and kept resident under its key.
std::shared_ptr<const Buffer> residentTiles(Device& device, const SolidTileSet& tiles, const Context& ctx) {
  return device.resident<Buffer>(tiles.key ^ kTilesResidentSalt, [&] {
    Commands commands(device);
    auto b = std::make_shared<const Buffer>(commands.uploaded(std::span<const Triple>(tiles.elements)));
    commands.submit(ctx);
    return std::pair{b, b->bytes()};
  });
}

TilesParams tilesParams(const SolidTileSet& tiles, uint32_t seed, uint32_t count) {
  const SolidTileLayout& l = tiles.layout;
  return TilesParams{0, 0, 0, 0, 0, 0, seed, l.shift, l.variants, uint32_t(l.faces), uint32_t(l.interiors), count};
}

} // namespace

void evaluateSolidTilesBox(Device& device, const SolidTileSet& tiles, uint32_t seed, const VoxelBox& box,
                           std::span<Triple> out, const Context& ctx, uint64_t slabVoxels) {
  if (int64_t(out.size()) != box.count()) throw Error("evaluateSolidTilesBox: one output per voxel");
  const auto elements = residentTiles(device, tiles, ctx);
  // Slabs of whole layers whose triples fit one binding.
  const int shift = tiles.layout.shift;
  const uint64_t layer = uint64_t(box.nx) * uint64_t(box.ny);
  const uint64_t perSlab = std::min<uint64_t>(device.maxRangeBytes() / sizeof(Triple), slabVoxels);
  if (layer > perSlab) throw Error("evaluateSolidTilesBox: a layer of the box exceeds the device's binding range");
  const int layers = int(std::min<uint64_t>(uint64_t(box.nz), perSlab / layer));
  for (int z = 0; z < box.nz; z += layers) {
    const int nz = std::min(layers, box.nz - z);
    const uint32_t count = uint32_t(layer * uint64_t(nz));
    TilesParams params = tilesParams(tiles, seed, count);
    params.x0 = int32_t(box.x);
    params.y0 = int32_t(box.y);
    params.z0 = int32_t(box.z + z);
    params.nx = box.nx;
    params.ny = box.ny;
    params.nz = nz;
    // The codes of the slab's cells first (solid_tiles.glsl: cellCounts), so that voxels hash nothing.
    const auto cellsAlong = [&](int64_t first, int n) { return uint32_t(((first + n - 1) >> shift) - (first >> shift) + 1); };
    TilesParams cellParams = params;
    cellParams.count = cellsAlong(box.x, box.nx) * cellsAlong(box.y, box.ny) * cellsAlong(box.z + z, nz);
    Commands commands(device);
    Buffer codes(device, uint64_t(cellParams.count) * sizeof(uint32_t));
    Buffer triples(device, uint64_t(count) * sizeof(Triple));
    commands.dispatch(kTilesCells, cellParams, {codes}, cellParams.count);
    commands.dispatch(kTiles, params, {*elements, codes, triples}, count);
    commands.download(triples, 0, out.data() + layer * uint64_t(z), uint64_t(count) * sizeof(Triple));
    commands.submit(ctx);
  }
}

void evaluateSolidTiles(Device& device, const SolidTileSet& tiles, uint32_t seed, std::span<const Voxel> voxels,
                        std::span<Triple> out, const Context& ctx, uint64_t batchVoxels) {
  if (out.size() != voxels.size()) throw Error("evaluateSolidTiles: one output per voxel");
  const auto elements = residentTiles(device, tiles, ctx);
  const uint64_t perBatch = std::max<uint64_t>(1, std::min<uint64_t>(device.maxRangeBytes() / sizeof(Triple), batchVoxels));
  std::vector<int32_t> positions;
  for (size_t first = 0; first < voxels.size(); first += perBatch) {
    const size_t count = std::min<size_t>(perBatch, voxels.size() - first);
    positions.resize(3 * count);
    for (size_t i = 0; i < count; ++i)  // |coordinates| <= kMaxSolidPosition = 2^30
      for (int a = 0; a < 3; ++a) positions[3 * i + size_t(a)] = int32_t(voxels[first + i][a]);
    Commands commands(device);
    const Buffer listed = commands.uploaded(std::span<const int32_t>(positions));
    Buffer triples(device, uint64_t(count) * sizeof(Triple));
    commands.dispatch(kTilesList, tilesParams(tiles, seed, uint32_t(count)), {*elements, listed, triples},
                      uint32_t(count));
    commands.download(triples, 0, out.data() + first, uint64_t(count) * sizeof(Triple));
    commands.submit(ctx);
  }
}

} // namespace texfab::synthesis::vulkan
