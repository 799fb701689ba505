// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/up_axis.h"

#include "core/error.h"

#include <cctype>
#include <utility>

namespace texfab::geometry {

UpAxis parseUpAxis(const std::string& text) {
  static const std::pair<const char*, UpAxis> names[] = {{"x", UpAxis::X},     {"y", UpAxis::Y},     {"z", UpAxis::Z},
                                                         {"-x", UpAxis::NegX}, {"-y", UpAxis::NegY}, {"-z", UpAxis::NegZ}};
  for (const auto& [name, axis] : names)
    if (text == name) return axis;
  throw Error("up axis must be x, y, z, -x, -y or -z, got '" + text + "'");
}

Eigen::Vector3f upVector(UpAxis axis) {
  switch (axis) {
  case UpAxis::X: return Eigen::Vector3f::UnitX();
  case UpAxis::Y: return Eigen::Vector3f::UnitY();
  case UpAxis::Z: return Eigen::Vector3f::UnitZ();
  case UpAxis::NegX: return -Eigen::Vector3f::UnitX();
  case UpAxis::NegY: return -Eigen::Vector3f::UnitY();
  case UpAxis::NegZ: return -Eigen::Vector3f::UnitZ();
  }
  return Eigen::Vector3f::UnitY();
}

UpAxis conventionalUpAxis(const std::filesystem::path& model) {
  std::string ext = model.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".stl" ? UpAxis::Z : UpAxis::Y;
}

} // namespace texfab::geometry
