// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: RFC 1950 (zlib stream, Adler-32), RFC 1951 (deflate, fixed Huffman codes §3.2.6),
//   ISO/IEC 15948 (PNG: chunks, CRC-32, filter type 0).
#include "print/png_row_encoder.h"

#include "core/error.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <string>

namespace texfab::print {

namespace {

constexpr uint32_t kAdlerBase = 65521;

uint32_t reverseBits(uint32_t code, int length) {
  uint32_t r = 0;
  for (int i = 0; i < length; ++i, code >>= 1) r = (r << 1) | (code & 1);
  return r;
}

// Deflate's fixed Huffman code (RFC 1951 §3.2.6), bit-reversed for LSB-first output: literal and
// length symbols, and for each copy length 3..258 its symbol plus extra bits as one code.
struct FixedCodes {
  uint32_t symbol[288];
  int symbolBits[288];
  uint32_t length[259];
  int lengthBits[259];

  FixedCodes() {
    for (int s = 0; s < 288; ++s) {
      const int bits = s < 144 ? 8 : s < 256 ? 9 : s < 280 ? 7 : 8;
      const uint32_t code = s < 144 ? 0x30 + s : s < 256 ? 0x190 + s - 144 : s < 280 ? s - 256 : 0xC0 + s - 280;
      symbol[s] = reverseBits(code, bits);
      symbolBits[s] = bits;
    }
    static const int base[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                 31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
    static const int extra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
    for (int n = 3; n <= 258; ++n) {
      int k = 28;
      while (base[k] > n) --k;
      const int s = 257 + k;
      length[n] = symbol[s] | uint32_t(n - base[k]) << symbolBits[s];
      lengthBits[n] = symbolBits[s] + extra[k];
    }
  }
};
const FixedCodes kCodes;

void appendBigEndian(std::vector<uint8_t>& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(uint8_t(v >> shift));
}

void appendChunk(std::vector<uint8_t>& out, const char type[4], const uint8_t* data, size_t size) {
  appendBigEndian(out, uint32_t(size));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data, data + size);
  appendBigEndian(out, uint32_t(crc32(0, out.data() + start, uInt(size + 4))));
}

// (x * y) mod 65521 for x, y < 2^32.
uint64_t mulMod(uint64_t x, uint64_t y) { return (x % kAdlerBase) * (y % kAdlerBase) % kAdlerBase; }

} // namespace

PngRowEncoder::PngRowEncoder(int width, int height, int channels, std::span<const Rgba8> palette,
                             std::array<uint32_t, 2> pixelsPerMetre)
    : width_(width), height_(height), channels_(channels) {
  if (width < 1 || height < 1 || width > (1 << 24) || height > (1 << 24))
    throw Error("PNG size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range");
  if (channels != 1 && channels != 3 && channels != 4) throw Error("PNG: 1, 3 or 4 channels, not " + std::to_string(channels));
  if (channels == 1 && (palette.empty() || palette.size() > 256)) throw Error("PNG: an indexed image needs 1-256 colours");
  static const uint8_t signature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
  header_.assign(signature, signature + 8);
  std::vector<uint8_t> ihdr;
  appendBigEndian(ihdr, uint32_t(width));
  appendBigEndian(ihdr, uint32_t(height));
  ihdr.insert(ihdr.end(), {8, uint8_t(channels == 1 ? 3 : channels == 3 ? 2 : 6), 0, 0, 0});
  appendChunk(header_, "IHDR", ihdr.data(), ihdr.size());
  if (channels == 1) {
    std::vector<uint8_t> plte, trns;
    for (const Rgba8& c : palette) plte.insert(plte.end(), c.begin(), c.begin() + 3);
    for (const Rgba8& c : palette) trns.push_back(c[3]);
    while (!trns.empty() && trns.back() == 255) trns.pop_back();  // trailing opaque entries may be left out
    appendChunk(header_, "PLTE", plte.data(), plte.size());
    if (!trns.empty()) appendChunk(header_, "tRNS", trns.data(), trns.size());
  }
  if (pixelsPerMetre[0] > 0 && pixelsPerMetre[1] > 0) {
    std::vector<uint8_t> phys;
    appendBigEndian(phys, pixelsPerMetre[0]);
    appendBigEndian(phys, pixelsPerMetre[1]);
    phys.push_back(1);  // unit: the metre
    appendChunk(header_, "pHYs", phys.data(), phys.size());
  }
  stream_ = {0x78, 0x01};  // deflate, 32 KiB window, no dictionary, fastest
  put(1, 1);               // final block
  put(1, 2);               // fixed Huffman codes
}

void PngRowEncoder::put(uint32_t bits, int count) {
  bitBuffer_ |= uint64_t(bits) << bitCount_;
  bitCount_ += count;
  if (bitCount_ >= 32) {
    const uint32_t word = uint32_t(bitBuffer_);
    for (int i = 0; i < 4; ++i) stream_.push_back(uint8_t(word >> (8 * i)));
    bitBuffer_ >>= 32;
    bitCount_ -= 32;
  }
}

void PngRowEncoder::literal(uint8_t byte) { put(kCodes.symbol[byte], kCodes.symbolBits[byte]); }

// A copy of `length` >= 3 bytes at distance channels_ (distance codes 0-3 are distances 1-4, 5
// bits, no extra bits), in pieces of 3 to 258 bytes.
void PngRowEncoder::copy(int64_t length) {
  const uint32_t distanceCode = reverseBits(uint32_t(channels_ - 1), 5);
  while (length >= 3) {
    const int n = int(length > 258 ? (length - 258 < 3 ? length - 3 : 258) : length);
    put(kCodes.length[n], kCodes.lengthBits[n]);
    put(distanceCode, 5);
    length -= n;
  }
}

void PngRowEncoder::adlerLiterals(const uint8_t* bytes, int64_t n) {
  adlerA_ = uint32_t(adler32(uLong(adlerA_) | uLong(adlerB_) << 16, bytes, uInt(n)));
  adlerB_ = adlerA_ >> 16;
  adlerA_ &= 0xFFFF;
}

// Adler-32 over a pixel of channels_ bytes repeated n times, in closed form: with S the pixel's
// byte sum and P its prefix sums, a += n S and b += n c a + S c n (n - 1) / 2 + n sum(P).
void PngRowEncoder::adlerRun(const uint8_t* pixel, int64_t n) {
  uint64_t sum = 0, prefixSum = 0;
  for (int i = 0; i < channels_; ++i) prefixSum += (sum += pixel[i]);
  const uint64_t un = uint64_t(n), pairs = un % 2 ? mulMod(un, (un - 1) / 2) : mulMod(un / 2, un - 1);
  const uint64_t b = adlerB_ + mulMod(mulMod(un, uint64_t(channels_)), adlerA_) + mulMod(mulMod(sum, uint64_t(channels_)), pairs) +
                     mulMod(un, prefixSum);
  adlerA_ = uint32_t((adlerA_ + mulMod(un, sum)) % kAdlerBase);
  adlerB_ = uint32_t(b % kAdlerBase);
}

namespace {

// The end of the run of pixels equal to pixel x (c bytes each) in a row of `width` pixels.
int64_t runEnd(const uint8_t* row, int64_t x, int64_t width, int c) {
  const uint8_t* p = row + x * c;
  int64_t end = x + 1;
  if (c == 1) {
    const uint64_t pattern = 0x0101010101010101ull * p[0];
    for (uint64_t word; end + 8 <= width; end += 8) {
      std::memcpy(&word, row + end, 8);
      if (const uint64_t diff = word ^ pattern) return end + __builtin_ctzll(diff) / 8;
    }
    while (end < width && row[end] == p[0]) ++end;
    return end;
  }
  while (end < width && std::memcmp(row + end * c, p, size_t(c)) == 0) ++end;
  return end;
}

} // namespace

void PngRowEncoder::addRow(const uint8_t* pixels) {
  if (rows_ >= height_) throw Error("PNG: more rows than the image's height");
  ++rows_;
  const uint8_t filter = 0;
  literal(filter);
  adlerLiterals(&filter, 1);
  const int c = channels_;
  // Adler-32: short runs (noise) go through zlib's adler32 together, long ones in closed form.
  constexpr int64_t kClosedFormRun = 16;
  int64_t pending = 0;  // first pixel not yet in the checksum
  for (int64_t x = 0; x < width_;) {
    const int64_t end = runEnd(pixels, x, width_, c);
    const uint8_t* p = pixels + x * c;
    for (int i = 0; i < c; ++i) literal(p[i]);
    // The other n - 1 pixels: one copy at the distance of a pixel; a copy needs 3 bytes or more.
    const int64_t copied = (end - x - 1) * c;
    if (copied >= 3) copy(copied);
    else
      for (int64_t i = 0; i < copied; ++i) literal(p[i % c]);
    if (end - x >= kClosedFormRun) {
      if (pending < x) adlerLiterals(pixels + pending * c, (x - pending) * c);
      adlerRun(p, end - x);
      pending = end;
    }
    x = end;
  }
  if (pending < width_) adlerLiterals(pixels + pending * c, (width_ - pending) * c);
}

std::vector<uint8_t> PngRowEncoder::finish() {
  if (rows_ != height_) throw Error("PNG: " + std::to_string(rows_) + " of " + std::to_string(height_) + " rows added");
  put(kCodes.symbol[256], kCodes.symbolBits[256]);  // end of block
  while (bitCount_ > 0) {
    stream_.push_back(uint8_t(bitBuffer_));
    bitBuffer_ >>= 8;
    bitCount_ -= 8;
  }
  bitCount_ = 0;
  appendBigEndian(stream_, adlerB_ << 16 | adlerA_);
  std::vector<uint8_t> png = std::move(header_);
  constexpr size_t kChunk = size_t(1) << 30;
  for (size_t at = 0; at < stream_.size(); at += kChunk)
    appendChunk(png, "IDAT", stream_.data() + at, std::min(kChunk, stream_.size() - at));
  appendChunk(png, "IEND", nullptr, 0);
  stream_.clear();
  return png;
}

} // namespace texfab::print
