// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/ktx2_write.h"

#include "core/error.h"
#include "core/uastc_encode.h"

#include <zstd.h>

#include <algorithm>
#include <array>
#include <string>

namespace texfab {
namespace {

constexpr uint32_t kHeaderBytes = 80;      // identifier, 9 header words, index (4 x 32 + 2 x 64 bits)
constexpr uint32_t kLevelIndexBytes = 24;  // byteOffset, byteLength, uncompressedByteLength
constexpr uint32_t kLevelAlignment = 16;   // lcm(16-byte UASTC blocks, 4); 1 when supercompressed
constexpr uint32_t kSupercompressionZstd = 2;

// Khronos Data Format Specification 1.3, section 5 (basic descriptor block) and 5.6-5.8.
constexpr uint32_t kDfModelUastc = 166;
constexpr uint32_t kDfChannelUastcRgb = 0;
constexpr uint32_t kDfPrimariesUnspecified = 0, kDfPrimariesBt709 = 1;
constexpr uint32_t kDfTransferLinear = 1, kDfTransferSrgb = 2;
constexpr uint32_t kDfVersion13 = 2;
constexpr uint32_t kDfBlockBytes = 24 + 16;  // basic block with one sample

void put32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}
void put64(std::vector<uint8_t>& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(uint8_t(v >> (8 * i)));
}
void set64(std::vector<uint8_t>& out, size_t at, uint64_t v) {
  for (int i = 0; i < 8; ++i) out[at + size_t(i)] = uint8_t(v >> (8 * i));
}
void pad(std::vector<uint8_t>& out, size_t alignment) {
  while (out.size() % alignment) out.push_back(0);
}

std::string size(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

std::vector<uint8_t> zstdCompressed(const std::vector<uint8_t>& data, int level) {
  std::vector<uint8_t> out(ZSTD_compressBound(data.size()));
  const size_t n = ZSTD_compress(out.data(), out.size(), data.data(), data.size(), level);
  if (ZSTD_isError(n)) throw Error(std::string("KTX2: Zstandard: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

} // namespace

std::vector<uint8_t> encodeKtx2Uastc(std::span<const Image> levels, const Ktx2Options& options) {
  if (levels.empty()) throw Error("KTX2: no MIP levels");
  const int width = levels[0].width, height = levels[0].height;
  if (width <= 0 || height <= 0) throw Error("KTX2: empty base level");
  if (options.gltf && (width % 4 || height % 4))
    throw Error("KTX2: base level " + size(width, height) + " is not a multiple of 4 (KHR_texture_basisu requires it)");
  int maxLevels = 1;
  while (std::max(width, height) >> maxLevels) ++maxLevels;
  if (options.zstdLevel < 0 || options.zstdLevel > ZSTD_maxCLevel())
    throw Error("KTX2: Zstandard level " + std::to_string(options.zstdLevel) + " is out of range (0 to " +
                std::to_string(ZSTD_maxCLevel()) + ")");
  if (int(levels.size()) > maxLevels)
    throw Error("KTX2: " + std::to_string(levels.size()) + " MIP levels for a " + size(width, height) + " base (at most " +
                std::to_string(maxLevels) + ")");
  std::vector<std::vector<uint8_t>> blocks(levels.size()), stored(levels.size());
  for (size_t i = 0; i < levels.size(); ++i) {
    const int w = std::max(1, width >> i), h = std::max(1, height >> i);
    if (levels[i].width != w || levels[i].height != h)
      throw Error("KTX2: MIP level " + std::to_string(i) + " is " + size(levels[i].width, levels[i].height) + ", expected " + size(w, h));
    try {
      blocks[i] = uastc::encodeImage(levels[i]);
    } catch (const Error& e) {
      throw Error("KTX2: MIP level " + std::to_string(i) + ": " + e.what());
    }
    stored[i] = options.zstdLevel > 0 ? zstdCompressed(blocks[i], options.zstdLevel) : blocks[i];
  }

  const uint32_t levelCount = uint32_t(levels.size());
  const uint32_t dfdOffset = kHeaderBytes + kLevelIndexBytes * levelCount;
  const uint32_t dfdBytes = 4 + kDfBlockBytes;
  std::vector<uint8_t> out(kKtx2Identifier.begin(), kKtx2Identifier.end());
  put32(out, 0);  // vkFormat: VK_FORMAT_UNDEFINED (Basis Universal payload)
  put32(out, 1);  // typeSize
  put32(out, uint32_t(width));
  put32(out, uint32_t(height));
  put32(out, 0);  // pixelDepth: 2D
  put32(out, 0);  // layerCount: not an array
  put32(out, 1);  // faceCount
  put32(out, levelCount);
  put32(out, options.zstdLevel > 0 ? kSupercompressionZstd : 0);  // supercompressionScheme
  // Index: DFD, key/value data (filled below), no supercompression global data.
  put32(out, dfdOffset);
  put32(out, dfdBytes);
  const size_t kvdIndexAt = out.size();
  put32(out, 0);
  put32(out, 0);
  put64(out, 0);
  put64(out, 0);
  const size_t levelIndexAt = out.size();
  out.resize(out.size() + kLevelIndexBytes * levelCount, 0);

  // Data Format Descriptor: total size, then one basic descriptor block.
  put32(out, dfdBytes);
  put32(out, 0);  // vendorId KHR (0), descriptorType basic (0)
  put32(out, kDfVersion13 | (kDfBlockBytes << 16));
  put32(out, kDfModelUastc | ((options.srgb ? kDfPrimariesBt709 : kDfPrimariesUnspecified) << 8) |
                 ((options.srgb ? kDfTransferSrgb : kDfTransferLinear) << 16));  // flags 0: straight alpha
  put32(out, 3 | (3 << 8));  // texelBlockDimension0..3 minus one: 4x4x1x1
  put32(out, 16);            // bytesPlane0: one 16-byte block
  put32(out, 0);             // bytesPlane4..7
  put32(out, 0 | (127u << 16) | (kDfChannelUastcRgb << 24));  // bitOffset 0, bitLength 128 - 1, channel, no qualifiers
  put32(out, 0);             // samplePosition0..3
  put32(out, 0);             // sampleLower
  put32(out, 0xFFFFFFFFu);   // sampleUpper

  // Key/value data (section 3.11): KTXwriter, NUL-terminated key and value, padded to 4.
  const uint32_t kvdOffset = uint32_t(out.size());
  const std::string key = "KTXwriter";
  put32(out, uint32_t(key.size() + 1 + options.writer.size() + 1));
  out.insert(out.end(), key.begin(), key.end());
  out.push_back(0);
  out.insert(out.end(), options.writer.begin(), options.writer.end());
  out.push_back(0);
  pad(out, 4);
  const uint32_t kvdBytes = uint32_t(out.size()) - kvdOffset;
  for (int i = 0; i < 4; ++i) {
    out[kvdIndexAt + size_t(i)] = uint8_t(kvdOffset >> (8 * i));
    out[kvdIndexAt + 4 + size_t(i)] = uint8_t(kvdBytes >> (8 * i));
  }

  // Level images, smallest first (section 3.9.7), each aligned; the index lists the base first.
  for (size_t i = levels.size(); i-- > 0;) {
    pad(out, options.zstdLevel > 0 ? 1 : kLevelAlignment);
    const size_t at = levelIndexAt + kLevelIndexBytes * i;
    set64(out, at, out.size());
    set64(out, at + 8, stored[i].size());
    set64(out, at + 16, blocks[i].size());
    out.insert(out.end(), stored[i].begin(), stored[i].end());
  }
  return out;
}

} // namespace texfab
