// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The materials a full-colour printer deposits, one per voxel: a name and the colour it shows
// (sRGB), and whether it is opaque. The built-in set is the CMYK + white + clear of Stratasys'
// Vero colour materials with nominal colours; a JSON file can give measured ones:
//   {"materials": [{"name": "VeroCyan", "color": "#00A0E0"}, ...,
//                  {"name": "VeroClear", "color": "#FFFFFF", "opacity": 0}]}
// (a bare list is accepted too; "color" may also be [r, g, b] in 0-255).

#include "print/png_row_encoder.h"

#include <filesystem>
#include <string>
#include <vector>

namespace texfab::print {

struct PrintMaterial {
  std::string name;
  Rgba8 color{255, 255, 255, 255};  ///< sRGB, 8 bits; alpha is 255
  /// 1 = opaque (mixed to reproduce colours); below 1 a translucent material, used where the
  /// colour itself is transparent (alpha < 1). [0, 1].
  double opacity = 1.0;
  bool opaque() const { return opacity >= 1.0; }
};

/// Largest number of materials (palette index 0 is empty space).
inline constexpr size_t kMaxPrintMaterials = 255;

/// VeroCyan, VeroMagenta, VeroYellow, VeroBlack, VeroWhite (pure colours), VeroClear (opacity 0,
/// #E0F0F0: a translucent material's colour only names it in the images, and Voxel Print tells
/// materials apart by colour, so it differs from VeroWhite's).
std::vector<PrintMaterial> defaultPrintMaterials();

/// Reads a materials file. Throws texfab::Error naming the file and the entry at fault.
std::vector<PrintMaterial> readPrintMaterials(const std::filesystem::path& path);

/// Throws texfab::Error unless the list has 1 to 255 materials, unique non-empty names, opacities
/// in [0, 1] and at least one opaque material. `source` prefixes messages.
void validatePrintMaterials(const std::vector<PrintMaterial>& materials, const std::string& source);

/// The index of the material named `name` (case-insensitive), or texfab::Error listing the names.
size_t findPrintMaterial(const std::vector<PrintMaterial>& materials, const std::string& name);

/// "#RRGGBB".
std::string hexColor(const Rgba8& color);

} // namespace texfab::print
