// SPDX-License-Identifier: GPL-3.0-or-later
// The atlas pipeline (staged as in xatlas, github.com/jpcy/xatlas); the metric is Sander et al.
// 2001, "Texture Mapping Progressive Meshes".
#include "atlas/generate_atlas.h"

#include "atlas/chart_mesh.h"
#include "atlas/compute_jacobians.h"
#include "atlas/measure_stretch.h"

#include <chrono>

namespace texfab::atlas {

void measureAtlas(const geometry::Mesh& mesh, const geometry::MeshConnectivity& conn, const Atlas& atlas, AtlasReport& report) {
  // The triangles of the charts (degenerate ones are mapped to a point); atlas texel coordinates
  // are y-down: flipped to v-up for orientation.
  std::vector<uint32_t> faces;
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    if (atlas.faceChart[t] >= 0) faces.push_back(uint32_t(t));
  const StretchStats s = measureStretch(
      mesh, faces,
      [&](size_t c) {
        const Eigen::Vector2f p = atlas.texelUvs[c];
        return Eigen::Vector2d(p.x(), -p.y());
      },
      atlas.texelUvRounding());
  report.l2Stretch = s.l2;
  report.maxStretch = s.max;
  report.flippedTriangles = s.flipped;
  report.collapsedTriangles = s.collapsed;
  report.charts = atlas.charts.size();
  report.texelsPerUnit = atlas.texelsPerUnit;
  report.seamLength = 0;
  report.boundaryLength = 0;
  report.nonDiskCharts = 0;
  for (const Chart& c : atlas.charts) {
    report.boundaryLength += c.boundaryLength;
    if (!c.disk) ++report.nonDiskCharts;
  }
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int32_t g = conn.neighbor(t, k);
      if (g > int32_t(t) && atlas.faceChart[size_t(g)] != atlas.faceChart[t])
        report.seamLength += double((mesh.corner(t, k) - mesh.corner(t, (k + 1) % 3)).norm());
    }
}

double atlasMemoryBytes(int width, int height) {
  const double perTexel = sizeof(SurfaceSample) + 2 * sizeof(Float3) + sizeof(TexelJacobian) + sizeof(int32_t) + 16.0;
  return double(width) * double(height) * perTexel;
}

GenerateAtlasResult generateAtlas(const geometry::Mesh& mesh, const GenerateAtlasOptions& options, const Context& ctx) {
  options.segment.validate();
  options.parameterize.validate();
  options.cut.validate();
  options.pack.validate();
  GenerateAtlasResult r;
  auto clock = std::chrono::steady_clock::now();
  auto lap = [&](const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    r.report.seconds.push_back({stage, std::chrono::duration<double>(now - clock).count()});
    clock = now;
  };
  r.report.triangles = mesh.triangleCount();
  r.connectivity = geometry::computeConnectivity(mesh);
  lap("connectivity");
  r.report.segment = segmentCharts(mesh, r.connectivity, r.atlas, options.segment);
  lap("charts");
  r.report.parameterize = parameterizeCharts(mesh, r.connectivity, r.atlas, options.parameterize, ctx);
  lap("parameterization");
  r.report.cut = cutChartsForPacking(mesh, r.connectivity, r.atlas, options.pack.width, options.pack.height,
                                     options.pack.gutter, options.cut, ctx);
  lap("cutting");
  r.report.pack = packCharts(mesh, r.atlas, options.pack, ctx);
  lap("packing");
  r.fields = rasterizeAtlas(mesh, r.atlas, ctx);
  lap("texel fields");
  measureAtlas(mesh, r.connectivity, r.atlas, r.report);
  r.report.utilization = r.fields.utilization();
  r.report.overlappingTexels = r.fields.overlappingTexels;
  lap("measures");
  const geometry::MeshConnectivity& a = r.connectivity;
  if (a.degenerateTriangles)
    r.report.repairs.push_back(std::to_string(a.degenerateTriangles) +
                               " degenerate (zero-area) triangles mapped to a point (they cover no texel)");
  if (a.nonManifoldEdges)
    r.report.repairs.push_back(std::to_string(a.nonManifoldEdges) + " non-manifold edges made chart borders");
  if (a.inconsistentEdges)
    r.report.repairs.push_back(std::to_string(a.inconsistentEdges) +
                               " edges between inconsistently oriented triangles made chart borders");
  if (r.report.parameterize.chartsCutToTriangles)
    r.report.repairs.push_back(std::to_string(r.report.parameterize.chartsCutToTriangles) +
                               " charts that could not be flattened without flips were cut into single triangles");
  if (r.report.collapsedTriangles)
    r.report.repairs.push_back(std::to_string(r.report.collapsedTriangles) +
                               " triangles thinner than the precision of atlas coordinates mapped to a line");
  if (const size_t n = r.report.pack.chartsShrunk)
    r.report.repairs.push_back(std::to_string(n) + (n == 1 ? " thin chart" : " thin charts") +
                               " longer than the atlas side laid out at a lower density");
  if (r.report.pack.chartsBelowOneTexel)
    r.report.repairs.push_back(std::to_string(r.report.pack.chartsBelowOneTexel) +
                               " charts are smaller than one texel at this resolution");
  return r;
}

} // namespace texfab::atlas
