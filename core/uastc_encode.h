// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A small UASTC LDR 4x4 encoder (the payload KHR_texture_basisu carries in KTX2), for opaque,
// smooth, non-colour data such as glTF metallicRoughness maps. Written from the UASTC Texture
// Specification (basis_universal wiki, "UASTC Texture Specification": "Mode Table", "Block
// Encoding", "Endpoint and weight encoding", "Hint bits") and the ASTC LDR decoding rules it
// builds on (Khronos Data Format Specification 1.3, section 23 "ASTC": 23.11 endpoint
// unquantization, 23.12 weight unquantization, 23.13 weight interpolation).
//
// Deliberate subset (all blocks are opaque, RGB, one subset):
//   mode 0  - RGB, endpoints 0..191 (6 bits + a trit), 16 weight levels: the all-rounder;
//   mode 5  - RGB, endpoints 0..255 (8 bits), 8 weight levels: few, exact colours;
//   mode 18 - RGB, endpoints 0..31 (5 bits), 32 weight levels: long smooth ramps;
//   mode 6  - RGB dual plane (one channel, ccs, has its own weights), endpoints 0..159 (5 bits
//             + a quint), 4 weight levels per plane: unrelated channels such as roughness (G) and
//             metallic (B), whose colours in a block span a plane rather than a line;
//   mode 8  - solid colour: constant blocks, bit-exact.
// Every block tries each (mode 6 with each ccs) and keeps the one whose decoded pixels are nearest
// the input (sum of squared RGB errors, ties to the earlier in the order 8, 0, 5, 18, 6). Not
// used: the 2- and 3-subset modes (edges) and every alpha/LA mode; input alpha is ignored and
// decodes as 255.
// Endpoints: the principal axis of the block's colours (of the plane-0 channels, for mode 6;
// integer power iteration), then least squares for the endpoints given the chosen weights, then
// a ±1 step search on each quantized endpoint value. Weights: each texel takes the level whose decoded colour is nearest, using the
// exact ASTC interpolation, so the encoder's error is the decoder's error.
// Hints: BC1 hints are 0 (the transcoder re-encodes BC1 from the pixels); the ETC1 hints (flip,
// diff, intensity tables, neutral bias 13) are chosen by trying them on the block, solid blocks
// get the best ETC1 colour, intensity and selector. The test checks that every target transcodes,
// but compares pixels only for RGBA32 (which equal decodeBlock's, bit for bit).
// Everything is integer arithmetic: the same input gives the same bytes on every machine.

#include "core/image.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace texfab::uastc {

/// One 128-bit UASTC block, as stored (bit 0 = least significant bit of byte 0).
using Block = std::array<uint8_t, 16>;

/// 16 texels of a 4x4 block, row-major, RGBA8 (alpha ignored).
using Texels = std::array<uint8_t, 64>;

/// Encodes one block (see the header comment for the modes used).
Block encodeBlock(const Texels& texels);

/// Decodes a block written by encodeBlock (modes 0, 5, 6, 8 and 18) to RGBA8, as the UASTC
/// specification and basis_universal's transcoder do. Returns false for any other mode.
bool decodeBlock(const Block& block, Texels& texels);

/// The mode a block holds (0..18), or -1 for the reserved codes.
int blockMode(const Block& block);

/// Converts an Image (1 channel: grey, 3: RGB, 4: RGBA with alpha 1) to RGBA8 (values clamped
/// to 0..1, rounded to nearest) and encodes its blocks, row-major, 16 bytes each. Sizes that are
/// not multiples of 4 (including levels under 4x4) are padded by repeating the last row and
/// column. Throws texfab::Error on an empty image, another channel count, NaN or infinite values,
/// or alpha other than 1.
std::vector<uint8_t> encodeImage(const Image& image);

/// Decodes the blocks of a width x height image (as encodeImage lays them out) to RGBA8, row-major,
/// the padding cropped. Throws texfab::Error when the blocks do not cover that size or one holds a
/// mode decodeBlock does not decode.
std::vector<uint8_t> decodeImage(std::span<const uint8_t> blocks, int width, int height);

} // namespace texfab::uastc
