// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Counter-based randomness for geometry (fracture sites, crack relief): a value is a hash of
// (seed, counter, purpose), never the state of a generator, so it does not depend on the order in
// which values are drawn or on threads (the determinism contract).
//
// Based on: G. Steele, D. Lea, C. Flood. Fast splittable pseudorandom number generators.
// OOPSLA 2014 (the SplitMix64 finalizer).

#include <cstdint>

namespace texfab::geometry {

constexpr uint64_t splitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// A hash of several integers, each mixed in turn.
constexpr uint64_t counterHash(uint64_t seed, uint64_t a, uint64_t b = 0, uint64_t c = 0, uint64_t d = 0) {
  return splitMix64(splitMix64(splitMix64(splitMix64(splitMix64(seed) ^ a) ^ b) ^ c) ^ d);
}

/// A uniform double in [0, 1) from a hash (its top 53 bits).
constexpr double unitInterval(uint64_t hash) { return double(hash >> 11) * 0x1.0p-53; }

} // namespace texfab::geometry
