// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The model axis that points up: previews stand a model on it, 3MF files build along it and prints
// stack their layers along it. One type for every command, so that a print stands as its preview.

#include <Eigen/Core>

#include <filesystem>
#include <string>

namespace texfab::geometry {

enum class UpAxis { X, Y, Z, NegX, NegY, NegZ };

/// "x", "y", "z", "-x", "-y", "-z" to UpAxis; throws texfab::Error otherwise.
UpAxis parseUpAxis(const std::string& text);

/// The axis as a unit vector of model space.
Eigen::Vector3f upVector(UpAxis axis);

/// A model file's convention: +Z for STL (3-D printing's), else +Y (glTF's and OBJ's).
UpAxis conventionalUpAxis(const std::filesystem::path& model);

} // namespace texfab::geometry
