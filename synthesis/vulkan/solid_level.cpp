// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §5 (parallel solid synthesis of a sparse level).
#include "synthesis/vulkan/solid_level.h"

#include "core/parallel.h"
#include "synthesis/chunk_index.h"
#include "synthesis/vulkan/solid_kernels.h"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace texfab::synthesis::vulkan {

namespace {

using Key = GridKey;

// The chunks of one part: those it finishes (its centre) first, then its halo.
struct Part {
  std::vector<uint32_t> slots;
  size_t centre = 0;
};

// The chunks within `halo` chunks of the centre chunks, the centre first.
Part withHalo(const ChunkIndex& index, std::vector<uint32_t> centre, int halo) {
  Part p;
  p.centre = centre.size();
  std::unordered_map<uint32_t, bool> seen;
  for (uint32_t s : centre) seen[s] = true;
  p.slots = std::move(centre);
  for (size_t i = 0; i < p.centre; ++i) {
    const Key k = index.keys()[p.slots[i]];
    for (int dz = -halo; dz <= halo; ++dz)
      for (int dy = -halo; dy <= halo; ++dy)
        for (int dx = -halo; dx <= halo; ++dx) {
          const int32_t s = index.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (s >= 0 && seen.emplace(uint32_t(s), true).second) p.slots.push_back(uint32_t(s));
        }
  }
  return p;
}

// Splits `centre` in halves along its longest extent until each part with its halo holds at most
// `maxChunks` chunks.
void split(const ChunkIndex& index, std::vector<uint32_t> centre, int halo, size_t maxChunks, std::vector<Part>& parts) {
  Part part = withHalo(index, centre, halo);
  if (part.slots.size() <= maxChunks) {
    parts.push_back(std::move(part));
    return;
  }
  if (centre.size() == 1) throw std::logic_error("solid level: one chunk and its halo exceed a binding");
  const std::vector<Key>& keys = index.keys();
  int axis = 0;
  int64_t longest = -1;
  for (int a = 0; a < 3; ++a) {
    const auto [lo, hi] = std::minmax_element(centre.begin(), centre.end(),
                                              [&](uint32_t p, uint32_t q) { return keys[p][size_t(a)] < keys[q][size_t(a)]; });
    if (keys[*hi][size_t(a)] - keys[*lo][size_t(a)] > longest) longest = keys[*hi][size_t(a)] - keys[*lo][size_t(a)], axis = a;
  }
  const auto middle = centre.begin() + std::ptrdiff_t(centre.size() / 2);
  std::nth_element(centre.begin(), middle, centre.end(), [&](uint32_t p, uint32_t q) {
    return keys[p][size_t(axis)] < keys[q][size_t(axis)];
  });
  split(index, std::vector<uint32_t>(centre.begin(), middle), halo, maxChunks, parts);
  split(index, std::vector<uint32_t>(middle, centre.end()), halo, maxChunks, parts);
}

// The device's inputs of a part: keys, masks, neighbours (slots within the part), parents.
SolidChunks uploadPart(Commands& commands, const SolidLevelInput& level, const ChunkIndex& index, const Part& part) {
  const uint32_t n = uint32_t(part.slots.size());
  std::unordered_map<uint32_t, int32_t> local;
  for (uint32_t i = 0; i < n; ++i) local[part.slots[i]] = int32_t(i);
  std::vector<int32_t> keys, neighbours;
  std::vector<int8_t> last(size_t(n) * kSolidChunkVoxels);
  std::vector<uint32_t> parents(level.parents ? size_t(n) * 512 * 3 : 0);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t slot = part.slots[i];
    const Key k = index.keys()[slot];
    for (int a = 0; a < 3; ++a) keys.push_back(int32_t(k[size_t(a)]));
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int32_t s = index.find({k[0] + dx, k[1] + dy, k[2] + dz});
          const auto l = s < 0 ? local.end() : local.find(uint32_t(s));
          neighbours.push_back(l == local.end() ? -1 : l->second);
        }
    std::copy_n(level.last(slot), kSolidChunkVoxels, last.begin() + std::ptrdiff_t(i) * kSolidChunkVoxels);
    if (level.parents) std::copy_n(level.parents(slot), 512 * 3, parents.begin() + std::ptrdiff_t(i) * 512 * 3);
  }
  return uploadChunks(commands, n, keys, last, neighbours, parents);
}

// The voxels of a part's centre chunks whose final values the caller reads (last == steps), as
// indices into the part's chunks (chunk * 4096 + local), chunk by chunk: chunk i's are
// [first[i], first[i + 1]).
struct Listed {
  std::vector<uint32_t> voxels;
  std::vector<size_t> first;
};

Listed listFinished(const SolidLevelInput& level, const Part& part, const Context& ctx) {
  const auto steps = int8_t(level.steps);
  const int n = int(part.centre);
  Listed l;
  l.first.assign(size_t(n) + 1, 0);
  parallelFor(0, n, ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) {
      const int8_t* last = level.last(part.slots[size_t(i)]);
      l.first[size_t(i) + 1] = size_t(std::count(last, last + kSolidChunkVoxels, steps));
    }
  });
  for (int i = 0; i < n; ++i) l.first[size_t(i) + 1] += l.first[size_t(i)];
  l.voxels.resize(l.first[size_t(n)]);
  parallelFor(0, n, ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) {
      const int8_t* last = level.last(part.slots[size_t(i)]);
      size_t k = l.first[size_t(i)];
      for (int v = 0; v < kSolidChunkVoxels; ++v)
        if (last[v] == steps) l.voxels[k++] = uint32_t(i) * kSolidChunkVoxels + uint32_t(v);
    }
  });
  return l;
}

// One part: every step on the device, then its centre's final triples to `finish`.
void synthesizePart(Device& device, const SolidTables& tables, int contrastGain16, const SolidLevelInput& level,
                    const ChunkIndex& index, const Part& part, const SolidChunkSink& finish, const Context& ctx) {
  // Only the voxels the caller reads (last == steps) come back, packed, centre chunk by chunk; a
  // part whose centre holds none has nothing to compute.
  const Listed listed = listFinished(level, part, ctx);
  if (listed.voxels.empty()) return;
  Commands commands(device);
  const SolidChunks chunks = uploadPart(commands, level, index, part);
  if (level.parents) solidUpsampleKernel(commands, chunks, tables);
  else solidInitKernel(commands, chunks, tables, level.init);
  solidColorKernel(commands, chunks, tables, 0);
  for (int t = 1; t <= level.steps; ++t) {
    solidCorrectKernel(commands, chunks, tables, level.interleave, t, contrastGain16);
    solidCommitKernel(commands, chunks, level.interleave, t);
  }
  const Buffer list = commands.uploaded(std::span<const uint32_t>(listed.voxels));
  const Buffer packed(device, listed.voxels.size() * 12);
  solidGatherKernel(commands, chunks, list, uint32_t(listed.voxels.size()), packed);
  std::vector<uint32_t> values(listed.voxels.size() * 3);
  commands.download(packed, 0, values.data(), values.size() * 4);
  commands.submit(ctx);
  // Each chunk's values at their places in a chunk-sized scratch (its other voxels are not read).
  parallelFor(0, int(part.centre), ctx, [&](int b, int e) {
    std::vector<uint32_t> scratch(size_t(kSolidChunkVoxels) * 3);
    for (int i = b; i < e; ++i) {
      const size_t from = listed.first[size_t(i)], to = listed.first[size_t(i) + 1];
      if (from == to) continue;
      for (size_t k = from; k < to; ++k)
        std::copy_n(values.data() + k * 3, 3, scratch.data() + (listed.voxels[k] % kSolidChunkVoxels) * 3);
      finish(part.slots[size_t(i)], scratch.data());
    }
  });
}

} // namespace

void synthesizeSolidLevel(Device& device, const cpu::SolidTables& tables, const SolidLevelInput& level,
                          const SolidChunkSink& finish, const Context& ctx) {
  const ChunkIndex& index = *level.chunks;
  const size_t n = index.size();
  if (n == 0) return;
  // A correction step reads 2 voxels around each voxel: T steps reach ceil(2T / 16) chunks.
  const int halo = (2 * level.steps + 15) / 16;
  std::vector<uint32_t> all(n);
  for (uint32_t s = 0; s < n; ++s) all[s] = s;
  std::vector<Part> parts;
  split(index, std::move(all), halo, SolidChunks::maxCount(device), parts);

  const auto deviceTables = device.resident<SolidTables>(level.tablesKey, [&] {
    Commands commands(device);
    auto t = std::make_shared<const SolidTables>(uploadSolidTables(commands, tables));
    commands.submit(ctx);
    return std::pair{t, t->data.bytes()};
  });
  for (const Part& part : parts)
    synthesizePart(device, *deviceTables, tables.contrastGain16, level, index, part, finish, ctx);
}

} // namespace texfab::synthesis::vulkan
