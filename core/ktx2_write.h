// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// KTX 2.0 files holding UASTC LDR 4x4 textures with their own MIP chains: the image format of
// glTF's KHR_texture_basisu. Layout per the KTX File Format Specification 2.0 (section 3: header,
// index, level index, DFD, key/value data, level images smallest first, each at a multiple of
// 16 bytes = lcm(texel block size, 4), or 1 when supercompressed); supercompressionScheme 0 (none)
// or 2 (Zstandard: each level compressed on its own, no global data), vkFormat 0 (undefined),
// one Khronos basic Data Format Descriptor (Khronos Data Format Specification 1.3, section 5)
// with colour model KHR_DF_MODEL_UASTC (166), one 128-bit sample KHR_DF_CHANNEL_UASTC_RGB, and
// one KTXwriter key. Blocks come from core/uastc_encode.h (opaque RGB modes only).
//
// KHR_texture_basisu ("KTX v2 Images with Basis Universal Supercompression") also requires:
//   - the base level's pixelWidth and pixelHeight MUST be multiples of 4 (checked unless
//     Ktx2Options::gltf is false; lower levels may be any size, partial blocks are padded);
//   - non-colour data (roughness/metallic, normals): primaries KHR_DF_PRIMARIES_UNSPECIFIED and
//     transfer KHR_DF_TRANSFER_LINEAR (the default here); colour data: BT709 and sRGB
//     (Ktx2Options::srgb);
//   - a full MIP pyramid SHOULD be present when the sampler minifies with mipmaps.

#include "core/image.h"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace texfab {

/// The first 12 bytes of every KTX 2.0 file (section 3.1): «KTX 20»\r\n\x1A\n.
inline constexpr std::array<uint8_t, 12> kKtx2Identifier = {0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32,
                                                            0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};

struct Ktx2Options {
  bool srgb = false;  ///< colour data (sRGB transfer, BT.709 primaries); false: linear, unspecified
  bool gltf = true;   ///< enforce KHR_texture_basisu's base size rule (multiples of 4)
  std::string writer = "texfab";  ///< the KTXwriter value
  /// Zstandard supercompression (supercompressionScheme 2, which KHR_texture_basisu allows for
  /// UASTC) of each level at this level, 1 to ZSTD_maxCLevel(); 0: none. The compressed bytes may
  /// differ between libzstd versions; the blocks they inflate to do not.
  int zstdLevel = 0;
};

/// A KTX2 file of UASTC blocks from a MIP chain: levels[0] is the base, each next level is
/// max(1, previous / 2) in each dimension (as many levels as wanted, down to 1x1 at most). Images
/// are 1 (grey), 3 (RGB) or 4 (RGBA, alpha 1) channels of 0..1 values (clamped, rounded to 8
/// bits). Throws texfab::Error on an empty chain, a level of the wrong size, too many levels, a
/// base that is not a multiple of 4 (with gltf), or a level uastc::encodeImage refuses (NaN,
/// alpha, channels), naming the level.
std::vector<uint8_t> encodeKtx2Uastc(std::span<const Image> levels, const Ktx2Options& options = {});

} // namespace texfab
