// SPDX-License-Identifier: GPL-3.0-or-later
// Packed exemplar coordinates and integer helpers: the GLSL twin of synthesis/coord_map.h
// (packCoord, coordU, coordV) and of synthesis/cpu/synthesis_kernels.h (floorMod, floorShift,
// reflectInto).
// GLSL leaves % undefined for negative operands, and Mesa 22.3's lavapipe computes a 64-bit signed
// % as a truncated remainder: floorMod takes unsigned remainders of non-negative values only.
#ifndef TEXFAB_COORD_MAP_GLSL
#define TEXFAB_COORD_MAP_GLSL

/// Packs exemplar coordinates (u, v), each < 65536, into one word: u | v << 16.
uint packCoord(uint u, uint v) { return u | (v << 16); }
uint coordU(uint c) { return c & 0xffffu; }
uint coordV(uint c) { return c >> 16; }

/// a mod m in [0, m), for any sign of a (m > 0).
int64_t floorMod(int64_t a, int64_t m) {
  return a >= 0 ? int64_t(uint64_t(a) % uint64_t(m)) : m - 1 - int64_t(uint64_t(-a - 1) % uint64_t(m));
}
int floorMod(int a, int m) { return a >= 0 ? int(uint(a) % uint(m)) : m - 1 - int(uint(-a - 1) % uint(m)); }
/// floor(a / 2^s) for any sign of a.
int64_t floorShift(int64_t a, int s) { return a >> s; }

/// A non-toroidal coordinate pushed back into [lo, hi]: mirrored at the bound it crossed, then
/// clamped (a step longer than the region). 32-bit: coordinates and their steps stay below 2^18.
int reflectInto(int v, int lo, int hi) {
  if (v < lo) v = 2 * lo - v;
  if (v > hi) v = 2 * hi - v;
  return v < lo ? lo : v > hi ? hi : v;
}

/// (a + b) mod m for a, b < m.
uint wrapAdd(uint a, uint b, uint m) {
  const uint s = a + b;
  return s >= m ? s - m : s;
}

#endif
