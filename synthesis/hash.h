// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Counter-based randomness: every random decision in synthesis is a hash of
// (seed, level, position, purpose), never the state of a generator, so a value depends only on
// where it is, not on which texels were computed before it or on which thread (DESIGN.md, the
// determinism contract). 32-bit integer operations only, so the GLSL twin is the same code.
//
// Based on: M. Jarzynski, M. Olano. Hash Functions for GPU Rendering. JCGT 9(3), 2020 (PCG hash).

#include <cstdint>

namespace texfab::synthesis {

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

} // namespace texfab::synthesis
