// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The --report blocks: one toJson per library report, shared by every command that reports it
// (texture and atlas give the same atlas block). Keys are snake_case; units are in the key or in
// the library's documentation of the field.

#include "atlas/generate_atlas.h"
#include "geometry/repair/prepare_mesh.h"
#include "render/texture_mesh.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"
#include "synthesis/synthesize_solid.h"

#include <nlohmann/json.hpp>

#include <span>
#include <string>

namespace texfab::cli {

/// {path, vertices, triangles}
nlohmann::json modelJson(const std::string& path, const geometry::Mesh& mesh);
/// {path, width, height, channels}
nlohmann::json imageJson(const std::string& path, const Image& image);

/// {use, repairs, warnings, rebuilt}
nlohmann::json toJson(const geometry::MeshPreparation& preparation);
nlohmann::json toJson(const atlas::GenerateAtlasResult& atlas);
nlohmann::json toJson(const render::TextureMeasures& measures, double requestedPixelsPerUnit);
nlohmann::json toJson(const synthesis::QualityReport& quality);
/// The measures of `quality`, those of its 2-D synthesis baseline (measureSynthesisBaseline) as
/// "baseline_2d", and "fidelity_ratio": fidelity / the baseline's (1 = as faithful as 2-D synthesis).
nlohmann::json toJson(const synthesis::QualityReport& quality, const synthesis::QualityReport& baseline);
nlohmann::json toJson(std::span<const synthesis::LevelStats> levels);
nlohmann::json toJson(std::span<const synthesis::SolidLevelStats> levels);

} // namespace texfab::cli
