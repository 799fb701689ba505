// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Counter-based randomness, the one source of random values in texfab: every random decision (a
// synthesis jitter, a fracture site, a sample of a measure) is a hash of (seed, where, purpose),
// never the state of a generator, so a value depends only on what it is for, not on which values
// were drawn before it or on which thread (docs/design.md#the-determinism-contract). 32-bit
// integer operations only, so the GLSL twin (synthesis/vulkan/shaders) is the same code.
//
// Based on: M. Jarzynski, M. Olano. Hash Functions for GPU Rendering. JCGT 9(3), 2020 (PCG hash).

#include <array>
#include <cstddef>
#include <cstdint>

namespace texfab {

constexpr uint32_t pcgHash(uint32_t v) {
  const uint32_t state = v * 747796405u + 2891336453u;
  const uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

/// A uniformly distributed 32-bit value for one texel, one level and one purpose.
constexpr uint32_t texelHash(uint32_t seed, uint32_t level, int32_t x, int32_t y, uint32_t purpose) {
  return pcgHash(seed ^ pcgHash(level ^ pcgHash(static_cast<uint32_t>(x) ^
                                                pcgHash(static_cast<uint32_t>(y) ^ pcgHash(purpose)))));
}

/// A 3-D variant of texelHash: one voxel of one level, for one purpose.
constexpr uint32_t voxelHash(uint32_t seed, uint32_t level, int32_t x, int32_t y, int32_t z, uint32_t purpose) {
  return pcgHash(seed ^ pcgHash(level ^ pcgHash(static_cast<uint32_t>(x) ^
                                                pcgHash(static_cast<uint32_t>(y) ^
                                                        pcgHash(static_cast<uint32_t>(z) ^ pcgHash(purpose))))));
}

/// A uniformly distributed 32-bit value for a tuple of counters (an index and a purpose, say).
constexpr uint32_t counterHash(uint32_t seed, uint32_t a, uint32_t b = 0, uint32_t c = 0, uint32_t d = 0) {
  return pcgHash(seed ^ pcgHash(a ^ pcgHash(b ^ pcgHash(c ^ pcgHash(d)))));
}

/// A uniform double in [0, 1) from a hash.
constexpr double unitInterval(uint32_t hash) { return double(hash) * 0x1.0p-32; }

/// FNV-1a, 64 bits: the content hash behind the on-disk analysis cache keys (not for randomness).
struct Fnv1a {
  uint64_t h = 1469598103934665603ull;
  void add(const void* data, size_t size) {
    const auto* p = static_cast<const uint8_t*>(data);
    for (size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 1099511628211ull;
  }
  template <class T> void add(const T& value) { add(&value, sizeof(T)); }
};

/// A cell of a 3-D integer grid (a chunk of a solid level) and its hash for unordered containers
/// (not for randomness).
using GridKey = std::array<int64_t, 3>;
struct GridKeyHash {
  size_t operator()(const GridKey& k) const {
    uint64_t h = uint64_t(k[0]) * 0x9E3779B97F4A7C15ull;
    h ^= uint64_t(k[1]) * 0xC2B2AE3D27D4EB4Full + (h >> 29);
    h ^= uint64_t(k[2]) * 0x165667B19E3779F9ull + (h >> 32);
    return size_t(h ^ (h >> 31));
  }
};

} // namespace texfab
