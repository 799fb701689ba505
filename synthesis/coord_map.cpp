// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/coord_map.h"

#include "core/error.h"
#include "core/image_io.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace texfab::synthesis {
namespace fs = std::filesystem;

namespace {
std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}
} // namespace

Image applyCoords(const CoordMap& coords, const Image& source, const Context& ctx) {
  if (source.width != coords.exemplarWidth || source.height != coords.exemplarHeight)
    throw Error("map is " + std::to_string(source.width) + "x" + std::to_string(source.height) +
                " but the exemplar is " + std::to_string(coords.exemplarWidth) + "x" +
                std::to_string(coords.exemplarHeight) + " (companion maps must match the exemplar)");
  Image out(coords.width, coords.height, source.channels, source.format);
  const size_t bytes = size_t(source.channels) * sizeof(float);
  parallelFor(0, coords.height, ctx, [&](int r0, int r1) {
    for (int y = r0; y < r1; ++y)
      for (int x = 0; x < coords.width; ++x) {
        const uint32_t c = coords.at(x, y);
        std::memcpy(out.pixel(x, y), source.pixel(int(coordU(c)), int(coordV(c))), bytes);
      }
  }, 16);
  return out;
}

void writeCoordMap(const CoordMap& coords, const fs::path& path) {
  const std::string ext = lowerExtension(path);
  const bool isFloat = ext == ".exr";
  if (!isFloat && ext != ".png" && ext != ".tif" && ext != ".tiff")
    throw Error(path.string() + ": coordinate maps are written as .png, .tif or .exr");
  Image image(coords.width, coords.height, 3, isFloat ? PixelFormat::Float : PixelFormat::UInt16);
  const float scale = isFloat ? 1.0f : 1.0f / 65535.0f;
  for (int y = 0; y < coords.height; ++y)
    for (int x = 0; x < coords.width; ++x) {
      const uint32_t c = coords.at(x, y);
      float* p = image.pixel(x, y);
      p[0] = float(coordU(c)) * scale;
      p[1] = float(coordV(c)) * scale;
    }
  writeImage(image, path);
}

CoordMap readCoordMap(const fs::path& path, int exemplarWidth, int exemplarHeight) {
  const Image image = readImage(path);
  if (image.channels < 2) throw Error(path.string() + ": a coordinate map needs two channels (u, v)");
  const float scale = image.format == PixelFormat::Float ? 1.0f : 65535.0f;
  if (image.format == PixelFormat::UInt8)
    throw Error(path.string() + ": 8-bit image cannot hold exemplar coordinates (expected 16-bit PNG/TIFF or EXR)");
  CoordMap map;
  map.width = image.width;
  map.height = image.height;
  map.exemplarWidth = exemplarWidth;
  map.exemplarHeight = exemplarHeight;
  map.coords.resize(size_t(image.width) * size_t(image.height));
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float u = std::round(image.at(x, y, 0) * scale), v = std::round(image.at(x, y, 1) * scale);
      if (!(u >= 0 && v >= 0 && u < float(exemplarWidth) && v < float(exemplarHeight)))
        throw Error(path.string() + ": coordinate (" + std::to_string(u) + ", " + std::to_string(v) + ") at pixel (" +
                    std::to_string(x) + ", " + std::to_string(y) + ") lies outside the " +
                    std::to_string(exemplarWidth) + "x" + std::to_string(exemplarHeight) + " exemplar");
      map.coords[size_t(y) * image.width + x] = packCoord(uint32_t(u), uint32_t(v));
    }
  return map;
}

} // namespace texfab::synthesis
