// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The coordinate map: what parallel synthesis produces. Each output texel stores the exemplar
// pixel it shows, so colours (and companion maps: normals, roughness, height) are a lookup.

#include "core/context.h"
#include "core/image.h"

#include <cstdint>
#include <filesystem>
#include <vector>

namespace texfab::synthesis {

/// Packs exemplar coordinates (u, v), each < 65536, into one word: u | v << 16.
constexpr uint32_t packCoord(uint32_t u, uint32_t v) { return u | (v << 16); }
constexpr uint32_t coordU(uint32_t c) { return c & 0xffffu; }
constexpr uint32_t coordV(uint32_t c) { return c >> 16; }

struct CoordMap {
  int width = 0;            ///< output size in texels
  int height = 0;
  int exemplarWidth = 0;    ///< coordinates lie in [0, exemplarWidth) x [0, exemplarHeight)
  int exemplarHeight = 0;
  std::vector<uint32_t> coords;  ///< width*height packed coordinates, row-major, top row first

  uint32_t at(int x, int y) const { return coords[static_cast<size_t>(y) * width + x]; }
};

/// Colours (or any companion map of the exemplar's size) looked up through the coordinates.
/// The result has `source`'s channels and format. Throws texfab::Error if the sizes differ.
Image applyCoords(const CoordMap& coords, const Image& source, const Context& ctx = {});

/// Writes the map as an image: EXR holds u, v as floats; PNG/TIFF hold them as 16-bit integers
/// (R = u, G = v, B = 0). Other extensions are refused.
void writeCoordMap(const CoordMap& coords, const std::filesystem::path& path);

/// Reads a map written by writeCoordMap; the exemplar size is needed to validate it.
CoordMap readCoordMap(const std::filesystem::path& path, int exemplarWidth, int exemplarHeight);

} // namespace texfab::synthesis
