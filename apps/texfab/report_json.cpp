// SPDX-License-Identifier: GPL-3.0-or-later
#include "apps/texfab/report_json.h"

#include <cmath>

namespace texfab::cli {
using nlohmann::json;

json modelJson(const std::string& path, const geometry::Mesh& mesh) {
  return {{"path", path}, {"vertices", mesh.vertexCount()}, {"triangles", mesh.triangleCount()}};
}

json imageJson(const std::string& path, const Image& image) {
  return {{"path", path}, {"width", image.width}, {"height", image.height}, {"channels", image.channels}};
}

json toJson(const geometry::MeshPreparation& p) {
  return {{"use", geometry::meshUseName(p.use)}, {"repairs", p.repairs}, {"warnings", p.warnings}, {"rebuilt", p.rebuilt}};
}

json toJson(const atlas::GenerateAtlasResult& result) {
  const atlas::AtlasReport& r = result.report;
  const double texels = double(result.atlas.width) * double(result.atlas.height);
  json stages = json::object();
  for (const auto& [stage, seconds] : r.seconds) stages[stage] = seconds;
  return {{"width", result.atlas.width},
          {"height", result.atlas.height},
          {"charts", r.charts},
          {"utilization", r.utilization},
          {"l2_stretch", r.l2Stretch},
          {"max_stretch", r.maxStretch},
          {"flipped_triangles", r.flippedTriangles},
          {"collapsed_triangles", r.collapsedTriangles},
          {"overlapping_texels", r.overlappingTexels},
          {"non_disk_charts", r.nonDiskCharts},
          {"seam_length", r.seamLength},
          {"texels_per_unit", r.texelsPerUnit},
          {"chart_texels", result.fields.chartTexels},
          {"packing_passes", r.pack.passes},
          {"packed_mask_fill", texels > 0 ? double(r.pack.maskTexels) / texels : 0.0},
          {"used_height", r.pack.usedHeight},
          {"splits",
           {{"disks", r.segment.splitsForDisks},
            {"flips", r.parameterize.splitsForFlips},
            {"overlaps", r.parameterize.splitsForOverlaps},
            {"stretch", r.parameterize.splitsForStretch},
            {"solver", r.parameterize.splitsForSolver},
            {"cut_to_triangles", r.parameterize.chartsCutToTriangles}}},
          {"input",
           {{"degenerate_triangles", r.segment.degenerateTriangles},
            {"non_manifold_edges", r.segment.nonManifoldEdges},
            {"inconsistent_edges", r.segment.inconsistentEdges}}},
          {"repairs", r.repairs},
          {"stage_seconds", stages}};
}

json toJson(const render::TextureMeasures& m, double requestedPixelsPerUnit) {
  json j;
  j["seams"] = {{"ratio", m.seams.ratio},
                {"seam_difference", m.seams.seamDifference},
                {"interior_difference", m.seams.interiorDifference},
                {"seam_pairs", m.seams.seamPairs},
                {"interior_pairs", m.seams.interiorPairs}};
  if (m.scale)
    j["scale"] = {{"requested_pixels_per_unit", requestedPixelsPerUnit},
                  {"median_pixels_per_unit", m.scale->medianPixelsPerUnit},
                  {"fraction_within_tolerance", m.scale->fractionWithin},
                  {"fraction_measured", m.scale->fractionMeasured},
                  {"tolerance", m.scale->tolerance}};
  if (m.fidelity) j["fidelity"] = {{"exemplar_space", m.fidelity->fidelity}, {"samples", m.fidelity->samples}};
  return j;
}

json toJson(const synthesis::QualityReport& q) {
  json j = {{"fidelity", q.fidelity},
            {"completeness", q.completeness},
            {"histogram_distance", q.histogramDistance},
            {"contrast_ratio", q.contrast}};
  j["shifted_correlation"] = std::isnan(q.shiftedCorrelation) ? json(nullptr) : json(q.shiftedCorrelation);
  if (q.coherence) j["coherence"] = *q.coherence;
  if (q.coverage) j["coverage"] = *q.coverage;
  return j;
}

json toJson(const synthesis::QualityReport& q, const synthesis::QualityReport& baseline) {
  json j = toJson(q);
  j["baseline_2d"] = toJson(baseline);
  j["fidelity_ratio"] = q.fidelity / baseline.fidelity;
  j["completeness_ratio"] = q.completeness / baseline.completeness;
  return j;
}

json toJson(std::span<const synthesis::LevelStats> levels) {
  json j = json::array();
  for (const synthesis::LevelStats& l : levels) j.push_back({{"level", l.level}, {"texels", l.texels}, {"seconds", l.seconds}});
  return j;
}

json toJson(std::span<const synthesis::SolidLevelStats> levels) {
  json j = json::array();
  for (const synthesis::SolidLevelStats& l : levels)
    j.push_back({{"stack_level", l.stackLevel}, {"voxels", l.voxels}, {"corrections", l.corrections}, {"seconds", l.seconds}});
  return j;
}

} // namespace texfab::cli
