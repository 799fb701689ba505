// SPDX-License-Identifier: GPL-3.0-or-later
// The texfab_oiio module: image decoding and encoding through OpenImageIO (oiio_codec.h).
#include "core/oiio_codec.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string_view>
#include <vector>

namespace texfab::detail {
namespace {

// OIIO error texts can span several lines, often repeating one another ("Read error: hit end of
// file", then "PNG read error: IDAT: Read error: hit end of file"), and a corrupt file can give one
// per scanline or tile (thousands); texfab errors are one line: the first distinct lines that no
// other contains, joined by "; ", and how many more there were.
std::string oneLine(const std::string& text) {
  constexpr size_t kMostLines = 16;
  std::vector<std::string> lines;
  size_t more = 0;
  for (size_t begin = 0; begin < text.size();) {
    const size_t end = std::min(text.find('\n', begin), text.size());
    std::string line = text.substr(begin, end - begin);
    begin = end + 1;
    while (!line.empty() && line.back() == ' ') line.pop_back();
    if (line.empty() || std::find(lines.begin(), lines.end(), line) != lines.end()) continue;
    if (lines.size() < kMostLines) lines.push_back(std::move(line));
    else ++more;
  }
  std::string joined;
  for (size_t i = 0; i < lines.size(); ++i) {
    bool repeated = false;
    for (size_t j = 0; j < lines.size() && !repeated; ++j) repeated = j != i && lines[j].find(lines[i]) != std::string::npos;
    if (!repeated) joined += (joined.empty() ? "" : "; ") + lines[i];
  }
  if (more) joined += "; (" + std::to_string(more) + " more)";
  return joined.empty() ? std::string("unknown error") : joined;
}

// Image libraries under OIIO print their own diagnostics on stderr ("libpng error: ..."); texfab
// says what went wrong in its one-line error. While an image is decoded, stderr goes to /dev/null
// (one decode at a time: the redirection is process-wide).
class QuietStderr {
public:
  QuietStderr() : lock_(mutex()) {
    std::fflush(stderr);
    saved_ = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    std::fflush(stderr);
    if (saved_ >= 0) {
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  int saved_ = -1;
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string extensionOf(const std::string& name) {
  const size_t dot = name.find_last_of('.'), slash = name.find_last_of('/');
  return dot == std::string::npos || (slash != std::string::npos && dot < slash) ? "" : lower(name.substr(dot));
}

PixelFormat formatOf(OIIO::TypeDesc type) {
  switch (type.basetype) {
  case OIIO::TypeDesc::UINT8:
  case OIIO::TypeDesc::INT8: return PixelFormat::UInt8;
  case OIIO::TypeDesc::UINT16:
  case OIIO::TypeDesc::INT16: return PixelFormat::UInt16;
  default: return PixelFormat::Float;
  }
}

// Texture data: alpha kept unassociated (as stored), never premultiplied.
OIIO::ImageSpec readConfig() {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  return config;
}

// The most pixels a file of `bytes` bytes in this format can encode, or 0 where there is no such
// bound (WebP's lossless mode needs no bits per pixel): PNG's deflate expands at most 1032 times
// and a pixel takes at least 1 bit; a Huffman-coded JPEG block of 64 pixels takes at least 1 bit
// (its DC code; arithmetic coding, rare, could take less); a GIF LZW code of at least 3 bits yields
// at most 4096 pixels; BMP's run-length codes at most 255 pixels per 2 bytes. TIFF has no such
// bound (fax coding, sparse tiles): 65536 pixels per byte, 30 times a blank fax page's, keeps 227
// bytes from claiming gigabytes.
uint64_t mostPixels(std::string_view format, uint64_t bytes) {
  if (bytes == 0) return 0;  // unknown
  if (format == "png") return bytes * 1032 * 8;
  if (format == "jpeg") return bytes * 8 * 64;
  if (format == "gif") return bytes * 8 / 3 * 4096;
  if (format == "tiff") return bytes * 65536;
  if (format == "bmp") return bytes * 128;
  return 0;
}

// Throws when a `format` image of `bytes` bytes claims width x height pixels of `channels`, more
// than it can encode. PNG's and TIFF's bounds hold per sample stored, and a stored sample (a
// palette index) gives at most 4 channels: so per 4 channels too (a TIFF of 769 channels in 194
// bytes); JPEG's per pixel, whatever its channels (subsampled chroma).
void checkClaimedPixels(std::string_view format, uint64_t width, uint64_t height, uint64_t channels, uint64_t bytes,
                        const std::string& name) {
  const uint64_t most = mostPixels(format, bytes);
  const uint64_t perPixel = format == "tiff" || format == "png" ? (channels + 3) / 4 : 1;
  if (most > 0 && width * height * std::max<uint64_t>(perPixel, 1) > most)
    throw Error(name + ": corrupt " + std::string(format) + ": it claims " + std::to_string(width) + "x" +
                std::to_string(height) + " pixels" + (channels > 4 ? " of " + std::to_string(channels) + " channels" : "") +
                ", more than its " + std::to_string(bytes) + " bytes can hold");
}

// `sourceBytes`: the size of the file or memory the image is read from.
Image decode(OIIO::ImageInput& in, const std::string& name, uint64_t sourceBytes, uint64_t maxBytes) {
  const OIIO::ImageSpec& spec = in.spec();
  checkImageSize(spec.width, spec.height, name);
  // A corrupt header that claims a huge image: decoders allocate what it claims before they find
  // the data missing.
  checkClaimedPixels(in.format_name(), uint64_t(spec.width), uint64_t(spec.height), uint64_t(std::max(spec.nchannels, 0)),
                     sourceBytes, name);
  if (spec.depth > 1) throw Error(name + ": volume images are not supported");
  if (spec.nchannels < 1) throw Error(name + ": image has no channels");
  const uint64_t bytes = uint64_t(spec.width) * uint64_t(spec.height) * uint64_t(spec.nchannels) * sizeof(float);
  if (bytes > maxBytes)
    throw Error(name + ": image is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                ", too large to load in this machine's memory");
  const auto failed = [&] { return Error(name + ": cannot decode image: " + oneLine(in.geterror())); };
  Image image;
  if (spec.channelformats.empty() && spec.format != OIIO::TypeDesc::FLOAT) {
    // A read that converts goes through a 64 MB staging buffer in OpenImageIO 2.4, whatever the
    // image's size. The file's own format is read instead, into memory left untouched until the
    // decoder writes it, and converted once it has decoded: a corrupt file that claims a huge image
    // costs little.
    const std::unique_ptr<std::byte[]> native(new std::byte[spec.image_bytes(true)]);
    if (!in.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UNKNOWN, native.get())) throw failed();
    image = Image(spec.width, spec.height, spec.nchannels, formatOf(spec.format));
    const size_t row = size_t(spec.width) * size_t(spec.nchannels);
    for (size_t y = 0; y < size_t(spec.height); ++y)
      OIIO::convert_pixel_values(spec.format, native.get() + y * row * spec.format.size(), OIIO::TypeDesc::FLOAT,
                                 image.pixels.data() + y * row, int(row));
  } else {
    image = Image(spec.width, spec.height, spec.nchannels, formatOf(spec.format));
    if (!in.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) throw failed();
  }
  return image;
}

// OpenEXR 3.1 allocates and clears the chunk-offset table its header implies before reading it: a
// few hundred corrupt bytes that claim 10^9 scanlines cost seconds. The table holds 8 bytes per chunk,
// so a file too small for it is refused here, as is an attribute longer than the file (which OpenEXR
// would allocate before finding the file too short), and a data window wider or taller than texfab
// reads (a 266-byte file claiming 8388617 x 7 pixels, zip-compressed, cost OpenEXR's open 35 s of
// line buffers). Parses the first part's header as far as `head` holds it (OpenEXR file layout,
// "Header Attributes" and "Offset Tables"); returns quietly where it cannot decide, leaving the
// verdict to OpenEXR.
void checkExrHeader(std::span<const uint8_t> head, uint64_t fileSize, const std::string& name) {
  if (head.size() < 8 || std::memcmp(head.data(), "\x76\x2f\x31\x01", 4) != 0) return;
  auto int32At = [&](size_t at) {
    int32_t v;
    std::memcpy(&v, head.data() + at, 4);
    return int64_t(v);
  };
  const bool tiled = (int32At(4) >> 8) & 0x2;
  int64_t width = 0, height = 0, tileWidth = 0, tileHeight = 0, chunkCount = -1, linesPerChunk = -1;
  // Where `head` ends: the file's end (a header cut short is corrupt), or only what was read.
  const auto stop = [&] {
    if (head.size() == fileSize) throw Error(name + ": corrupt EXR: its header runs past the end of the file");
  };
  size_t at = 8;
  while (at < head.size() && head[at] != 0) {
    const auto nameEnd = std::find(head.begin() + at, head.end(), 0);
    const auto typeEnd = nameEnd == head.end() ? head.end() : std::find(nameEnd + 1, head.end(), 0);
    if (typeEnd == head.end() || size_t(typeEnd - head.begin()) + 5 > head.size()) return stop();
    const std::string_view attribute(reinterpret_cast<const char*>(&head[at]), size_t(nameEnd - head.begin()) - at);
    const size_t value = size_t(typeEnd - head.begin()) + 5;
    const int64_t size = int32At(value - 4);
    if (size < 0 || value + uint64_t(size) > fileSize)
      throw Error(name + ": corrupt EXR: its attribute '" + std::string(attribute) + "' runs past the end of the file");
    if (value + uint64_t(size) > head.size()) return;
    if (attribute == "dataWindow" && size == 16) {
      width = int32At(value + 8) - int32At(value) + 1;
      height = int32At(value + 12) - int32At(value + 4) + 1;
      checkImageSize(width, height, name);
    } else if (attribute == "tiles" && size == 9) {
      tileWidth = uint32_t(int32At(value));
      tileHeight = uint32_t(int32At(value + 4));
    } else if (attribute == "chunkCount" && size == 4) {
      chunkCount = int32At(value);
    } else if (attribute == "compression" && size == 1) {
      static constexpr int64_t kLines[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};  // NONE … DWAB
      linesPerChunk = head[value] < std::size(kLines) ? kLines[head[value]] : -1;
    }
    at = value + size_t(size);
  }
  if (at >= head.size()) return stop();  // the header goes on beyond what was read
  int64_t chunks = chunkCount;  // multi-part and deep files name it; others imply it
  if (chunks < 0) {
    if (width <= 0 || height <= 0) return;
    if (tiled && tileWidth > 0 && tileHeight > 0)
      chunks = ((width + tileWidth - 1) / tileWidth) * ((height + tileHeight - 1) / tileHeight);
    else if (!tiled && linesPerChunk > 0)
      chunks = (height + linesPerChunk - 1) / linesPerChunk;
    else
      return;
  }
  if (uint64_t(chunks) * 8 > fileSize)
    throw Error(name + ": corrupt EXR: its header names " + std::to_string(chunks) + " chunks, more than its " +
                std::to_string(fileSize) + " bytes can hold");
}

// OpenImageIO's GIF reader decodes the first frame when it opens the file, into a canvas of the
// logical screen's size: a screen larger than the file can fill is refused before.
void checkGifScreen(std::span<const uint8_t> head, uint64_t fileSize, const std::string& name) {
  if (head.size() < 10 || std::memcmp(head.data(), "GIF8", 4) != 0) return;
  checkClaimedPixels("gif", head[6] | unsigned(head[7]) << 8, head[8] | unsigned(head[9]) << 8, 1, fileSize, name);
}

// OpenImageIO 2.4 decompresses a TIFF's strips (or tiles) by the positions and sizes its first
// directory states: a 180-byte file whose 1 strip offset and 33 strip sizes disagree, zip-compressed,
// corrupted its heap and crashed texfab (the image_file fuzz target). A directory whose offsets and
// sizes differ in number, or name a strip past the file's end, is refused here (TIFF 6.0, section 2,
// "Image File Directory"); returns quietly where `head` does not hold what it needs (BigTIFF too).
void checkTiffStrips(std::span<const uint8_t> head, uint64_t fileSize, const std::string& name) {
  if (head.size() < 8) return;
  const bool little = head[0] == 'I' && head[1] == 'I';
  if (!little && !(head[0] == 'M' && head[1] == 'M')) return;
  const auto u16 = [&](uint64_t at) { return little ? uint32_t(head[at] | head[at + 1] << 8) : uint32_t(head[at] << 8 | head[at + 1]); };
  const auto u32 = [&](uint64_t at) { return little ? u16(at) | u16(at + 2) << 16 : u16(at) << 16 | u16(at + 2); };
  if (u16(2) != 42) return;
  const uint64_t ifd = u32(4);
  if (ifd + 2 > head.size() || ifd + 2 + 12 * uint64_t(u16(ifd)) > head.size()) return;
  struct Values {
    uint32_t type = 0, count = 0;
    uint64_t at = 0;  // where the values start
  } offsets, sizes;
  for (uint64_t e = ifd + 2, end = e + 12 * uint64_t(u16(ifd)); e < end; e += 12) {
    const uint32_t tag = u16(e), type = u16(e + 2), count = u32(e + 4);
    Values* v = tag == 273 || tag == 324 ? &offsets : tag == 279 || tag == 325 ? &sizes : nullptr;  // strips, tiles
    if (!v) continue;
    if (type != 3 && type != 4) return;  // SHORT or LONG; anything else is libtiff's to judge
    *v = {type, count, uint64_t(count) * (type == 3 ? 2 : 4) <= 4 ? e + 8 : uint64_t(u32(e + 8))};
  }
  if (offsets.type == 0 || sizes.type == 0) return;
  if (offsets.count != sizes.count)
    throw Error(name + ": corrupt TIFF: it states " + std::to_string(offsets.count) + " strip positions but " +
                std::to_string(sizes.count) + " strip sizes");
  const auto value = [&](const Values& v, uint32_t i) { return v.type == 3 ? u16(v.at + 2 * i) : u32(v.at + 4 * i); };
  for (uint32_t i = 0; i < offsets.count; ++i) {
    if (offsets.at + 4 * (uint64_t(i) + 1) > head.size() || sizes.at + 4 * (uint64_t(i) + 1) > head.size()) return;
    if (uint64_t(value(offsets, i)) + value(sizes, i) > fileSize)
      throw Error(name + ": corrupt TIFF: its strip " + std::to_string(i + 1) + " of " + std::to_string(offsets.count) +
                  " lies past the end of the file");
  }
}

// The checks above, on what a file's or a buffer's first bytes claim.
void checkClaims(std::span<const uint8_t> head, uint64_t size, const std::string& name) {
  checkExrHeader(head, size, name);
  checkGifScreen(head, size, name);
  checkTiffStrips(head, size, name);
}

// checkClaims on a file's first 64 KB; returns the file's size (0 when the system does not say).
uint64_t checkFileClaims(const std::string& file) {
  std::error_code error;
  const uint64_t size = std::filesystem::file_size(file, error);
  if (error) return 0;
  std::vector<uint8_t> head(std::min<uint64_t>(size, 1 << 16));
  if (FILE* f = std::fopen(file.c_str(), "rb")) {
    head.resize(std::fread(head.data(), 1, head.size(), f));
    std::fclose(f);
    checkClaims(head, size, file);
  }
  return size;
}

// The extension of the format a file's first bytes name, or null (TGA, for one, has no signature).
const char* extensionBySignature(const std::string& file) {
  unsigned char b[12] = {};
  if (FILE* f = std::fopen(file.c_str(), "rb")) {
    const size_t n = std::fread(b, 1, sizeof b, f);
    std::fclose(f);
    if (n < sizeof b) return nullptr;
  }
  auto starts = [&](std::string_view magic) { return std::memcmp(b, magic.data(), magic.size()) == 0; };
  if (starts("\x89PNG")) return "png";
  if (starts("\xff\xd8\xff")) return "jpg";
  if (starts("RIFF") && std::memcmp(b + 8, "WEBP", 4) == 0) return "webp";
  if (starts(std::string_view("II*\0", 4)) || starts(std::string_view("MM\0*", 4))) return "tif";
  if (starts("\x76\x2f\x31\x01")) return "exr";
  if (starts("#?")) return "hdr";
  if (starts("BM")) return "bmp";
  if (starts("GIF8")) return "gif";
  return nullptr;
}

// The reader of the file's extension, else the one its signature names (a JPEG saved as .png).
// Not OIIO's own fallback (try_all_readers, off in this module), which tries every reader it has:
// some take seconds to refuse a corrupt file of a few hundred bytes.
Image read(const std::string& name, uint64_t maxBytes) {
  const uint64_t bytes = checkFileClaims(name);
  const OIIO::ImageSpec config = readConfig();
  const QuietStderr quiet;
  auto in = OIIO::ImageInput::open(name, &config);
  if (!in) {
    const std::string why = OIIO::geterror();
    const char* extension = extensionBySignature(name);
    if (extension && extensionOf(name) != std::string(".") + extension) {  // not the reader that refused it
      in = OIIO::ImageInput::create(extension, false, &config);
      OIIO::ImageSpec spec;
      if (in && !in->open(name, spec, config)) in.reset();
    }
    if (!in) throw Error(name + ": cannot read image: " + oneLine(why));
  }
  return decode(*in, name, bytes, maxBytes);
}

Image decodeBytes(std::span<const uint8_t> bytes, const std::string& pseudoName, const std::string& name,
                  uint64_t maxBytes) {
  checkClaims(bytes, bytes.size(), name);
  OIIO::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
  OIIO::ImageSpec config = readConfig();
  // OIIO 2.4 ignores open()'s proxy argument when a configuration is given; the hint carries it.
  void* proxyPointer = &proxy;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxyPointer);
  const QuietStderr quiet;
  // The reader of the format the bytes' signature named, and no other: OIIO's open() would try
  // every reader it has on bytes its first choice refuses (LibRaw's alone costs ~30 ms).
  auto in = OIIO::ImageInput::create(pseudoName, false, &config, &proxy);
  OIIO::ImageSpec spec;
  if (!in || !in->open(pseudoName, spec, config)) {
    const std::string why = in ? in->geterror() : OIIO::geterror();
    throw Error(name + ": cannot decode image: " + oneLine(why));
  }
  return decode(*in, name, bytes.size(), maxBytes);
}

bool canWrite(const std::string& name) { return OIIO::ImageOutput::create(name) != nullptr; }

void write(const Image& image, const std::string& file, const std::string& name) {
  auto out = OIIO::ImageOutput::create(name);
  if (!out) throw Error(name + ": no image writer for this file extension");
  const std::string ext = extensionOf(name);
  OIIO::TypeDesc type = OIIO::TypeDesc::UINT8;
  if (ext == ".exr" || ext == ".hdr") type = OIIO::TypeDesc::FLOAT;
  else if (image.format != PixelFormat::UInt8 && (ext == ".png" || ext == ".tif" || ext == ".tiff"))
    type = OIIO::TypeDesc::UINT16;
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
  if (ext == ".png") spec.attribute("png:compressionLevel", 6);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // our alpha is not premultiplied
  if (!out->open(file, spec)) throw Error(name + ": cannot create file: " + oneLine(out->geterror()));
  const bool written = out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
  const bool closed = out->close();
  if (!written || !closed) throw Error(name + ": cannot write image: " + oneLine(out->geterror()));
}

std::vector<uint8_t> encode(const Image& image, int channels, const std::string& pseudoName, int quality,
                            const std::string& format) {
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  auto out = OIIO::ImageOutput::create(pseudoName, &proxy);
  if (!out) throw Error(format + " encoding is not available");
  OIIO::ImageSpec spec(image.width, image.height, channels, OIIO::TypeDesc::UINT8);
  if (extensionOf(pseudoName) == ".png") spec.attribute("png:compressionLevel", 6);
  else spec.attribute("CompressionQuality", std::clamp(quality, 1, 100));
  spec.attribute("oiio:UnassociatedAlpha", 1);
  void* proxyPointer = &proxy;
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxyPointer);
  const OIIO::stride_t pixelStride = OIIO::stride_t(image.channels * sizeof(float));
  if (!out->open(pseudoName, spec) ||
      !out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data(), pixelStride) || !out->close())
    throw Error(format + " encoding failed: " + oneLine(out->geterror()));
  if (bytes.empty()) throw Error(format + " encoding produced no bytes");
  return {bytes.begin(), bytes.end()};
}

constexpr OiioCodec kCodec{read, decodeBytes, canWrite, write, encode};

} // namespace
} // namespace texfab::detail

extern "C" __attribute__((visibility("default"))) const texfab::detail::OiioCodec* texfab_oiio_codec() {
  OIIO::attribute("try_all_readers", 0);  // see read()
  return &texfab::detail::kCodec;
}
