// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/print_materials.h"

#include "core/error.h"
#include "core/mip_pyramid.h"
#include "print/color_difference.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>

namespace texfab::print {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

Rgba8 parseColor(const nlohmann::json& value, const std::string& where) {
  if (value.is_string()) {
    const std::string text = value.get<std::string>();
    unsigned r = 0, g = 0, b = 0;
    char end = 0;
    if (text.size() == 7 && text[0] == '#' &&
        std::all_of(text.begin() + 1, text.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)); }) &&
        std::sscanf(text.c_str() + 1, "%2x%2x%2x%c", &r, &g, &b, &end) == 3)
      return {uint8_t(r), uint8_t(g), uint8_t(b), 255};
    throw Error(where + ": colour '" + text + "' is not #RRGGBB");
  }
  if (value.is_array() && value.size() == 3 &&
      std::all_of(value.begin(), value.end(), [](const nlohmann::json& v) {
        return v.is_number_integer() && v.get<int64_t>() >= 0 && v.get<int64_t>() <= 255;
      }))
    return {uint8_t(value[0].get<int>()), uint8_t(value[1].get<int>()), uint8_t(value[2].get<int>()), 255};
  throw Error(where + ": colour must be \"#RRGGBB\" or [r, g, b] with integers 0-255, got " + value.dump());
}

// A measured CIELAB colour (D50, as spectrophotometers and ICC profiles give print colours) as
// 8-bit sRGB; refused outside sRGB, the space texfab mixes in.
Rgba8 parseLab(const nlohmann::json& value, const std::string& where) {
  if (!value.is_array() || value.size() != 3 ||
      !std::all_of(value.begin(), value.end(), [](const nlohmann::json& v) { return v.is_number(); }))
    throw Error(where + ": \"lab\" must be [L, a, b] (CIELAB, D50), got " + value.dump());
  const Lab lab{value[0].get<double>(), value[1].get<double>(), value[2].get<double>()};
  if (!(lab[0] >= 0 && lab[0] <= 100) || !std::isfinite(lab[1]) || !std::isfinite(lab[2]))
    throw Error(where + ": \"lab\" " + value.dump() + " has L outside [0, 100]");
  const std::array<double, 3> linear = linearSrgbFromLabD50(lab);
  Rgba8 out{0, 0, 0, 255};
  for (int c = 0; c < 3; ++c) {
    if (!(linear[size_t(c)] >= -1.0 / 255 && linear[size_t(c)] <= 1 + 1.0 / 255))
      throw Error(where + ": \"lab\" " + value.dump() + " lies outside sRGB, the colour space texfab mixes in");
    out[size_t(c)] = uint8_t(std::lround(255.0 * linearToSrgb(float(std::clamp(linear[size_t(c)], 0.0, 1.0)))));
  }
  return out;
}

PrintMaterial parseMaterial(const nlohmann::json& entry, const std::string& where) {
  if (!entry.is_object()) throw Error(where + ": expected an object with \"name\" and \"color\" or \"lab\"");
  for (const auto& [key, value] : entry.items())
    if (key != "name" && key != "color" && key != "lab" && key != "opacity")
      throw Error(where + ": unknown field \"" + key + "\"");
  if (!entry.contains("name") || !entry["name"].is_string()) throw Error(where + ": \"name\" (a string) is missing");
  if (entry.contains("color") == entry.contains("lab"))
    throw Error(where + ": give \"color\" (sRGB) or \"lab\" (measured CIELAB), one of the two");
  PrintMaterial m;
  m.name = entry["name"].get<std::string>();
  m.color = entry.contains("lab") ? parseLab(entry["lab"], where + " (" + m.name + ")")
                                  : parseColor(entry["color"], where + " (" + m.name + ")");
  if (entry.contains("opacity")) {
    if (!entry["opacity"].is_number()) throw Error(where + " (" + m.name + "): \"opacity\" must be a number in [0, 1]");
    m.opacity = entry["opacity"].get<double>();
  }
  return m;
}

} // namespace

std::string hexColor(const Rgba8& c) {
  char text[8];
  std::snprintf(text, sizeof text, "#%02X%02X%02X", c[0], c[1], c[2]);
  return text;
}

std::vector<PrintMaterial> defaultPrintMaterials() {
  return {{"VeroCyan", {0, 255, 255, 255}, 1.0},  {"VeroMagenta", {255, 0, 255, 255}, 1.0},
          {"VeroYellow", {255, 255, 0, 255}, 1.0}, {"VeroBlack", {0, 0, 0, 255}, 1.0},
          {"VeroWhite", {255, 255, 255, 255}, 1.0}, {"VeroClear", {224, 240, 240, 255}, 0.0}};
}

void validatePrintMaterials(const std::vector<PrintMaterial>& materials, const std::string& source) {
  if (materials.empty()) throw Error(source + ": no materials");
  if (materials.size() > kMaxPrintMaterials)
    throw Error(source + ": " + std::to_string(materials.size()) + " materials, more than " +
                std::to_string(kMaxPrintMaterials));
  std::set<std::string> names;
  for (const PrintMaterial& m : materials) {
    if (m.name.empty()) throw Error(source + ": a material has an empty name");
    if (!names.insert(lower(m.name)).second) throw Error(source + ": material '" + m.name + "' is listed twice");
    if (!(m.opacity >= 0 && m.opacity <= 1))
      throw Error(source + ": material '" + m.name + "' has opacity " + std::to_string(m.opacity) + ", not in [0, 1]");
  }
  if (std::none_of(materials.begin(), materials.end(), [](const PrintMaterial& m) { return m.opaque(); }))
    throw Error(source + ": no opaque material (opacity 1) to print colours with");
}

std::vector<PrintMaterial> readPrintMaterials(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw Error(path.string() + ": cannot open materials file");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(path.string() + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  const nlohmann::json* list = &doc;
  if (doc.is_object()) {
    if (!doc.contains("materials")) throw Error(path.string() + ": expected {\"materials\": [...]} or a list");
    list = &doc["materials"];
  }
  if (!list->is_array()) throw Error(path.string() + ": \"materials\" must be a list");
  std::vector<PrintMaterial> materials;
  for (size_t i = 0; i < list->size(); ++i)
    materials.push_back(parseMaterial((*list)[i], path.string() + ": material " + std::to_string(i + 1)));
  validatePrintMaterials(materials, path.string());
  return materials;
}

size_t findPrintMaterial(const std::vector<PrintMaterial>& materials, const std::string& name) {
  std::string known;
  for (size_t i = 0; i < materials.size(); ++i) {
    if (lower(materials[i].name) == lower(name)) return i;
    known += (i ? ", " : "") + materials[i].name;
  }
  // Short names for the built-in set: "white" finds VeroWhite.
  for (size_t i = 0; i < materials.size(); ++i)
    if (lower(materials[i].name) == "vero" + lower(name)) return i;
  throw Error("no material named '" + name + "' (materials: " + known + ")");
}

} // namespace texfab::print
