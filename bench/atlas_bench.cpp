// SPDX-License-Identifier: GPL-3.0-or-later
// Atlas benchmarks: CGAL's bunny00 (75K triangles), armadillo (52K), camel (20K), eight, elephant and a ~1.2M-triangle mesh
// (bunny00 with each triangle split in 16), at 2048² with a 4-texel gutter. Counters: seconds per
// stage, process CPU seconds (all threads), charts, cuts, seam length, utilization, stretch. Run:
//   build-atlas/bench/atlas_bench --benchmark_counters_tabular=true
#include "atlas/build_indirection_map.h"
#include "atlas/compute_jacobians.h"
#include "atlas/generate_atlas.h"
#include "geometry/io/mesh_io.h"
#include "geometry/tangent_field.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <ctime>
#include <filesystem>
#include <map>

namespace {
using namespace texfab;

/// Splits every triangle in 4 (midpoints shared through an edge map) `levels` times.
geometry::Mesh subdivide(geometry::Mesh m, int levels) {
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(0.5f * (m.positions[a] + m.positions[b]));
      return mid[key] = uint32_t(m.positions.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> tris;
    for (const auto& t : m.triangles) {
      const uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      tris.push_back({t[0], ab, ca});
      tris.push_back({ab, t[1], bc});
      tris.push_back({ca, bc, t[2]});
      tris.push_back({ab, bc, ca});
    }
    m.triangles = std::move(tris);
  }
  return m;
}

void runAtlas(benchmark::State& state, const char* name, int subdivisions) {
  const std::filesystem::path path = std::filesystem::path(TEXFAB_SOURCE_DIR) / "models" / "cgal" / name;
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("model absent: run models/fetch");
    return;
  }
  const geometry::Mesh mesh = subdivide(geometry::readMesh(path), subdivisions);
  for (auto _ : state) {
    atlas::GenerateAtlasOptions o;
    const std::clock_t c0 = std::clock(); // process CPU time, all threads
    const auto t0 = std::chrono::steady_clock::now();
    atlas::GenerateAtlasResult r = atlas::generateAtlas(mesh, o);
    const auto t1 = std::chrono::steady_clock::now();
    const geometry::TangentField field = geometry::computeTangentField(mesh, {});
    const auto t2 = std::chrono::steady_clock::now();
    const auto jac = atlas::computeJacobians(mesh, r.atlas, r.fields, field, r.atlas.texelsPerUnit);
    const auto t3 = std::chrono::steady_clock::now();
    const atlas::IndirectionMap map = atlas::buildIndirectionMap(mesh, r.connectivity, r.atlas, r.fields);
    const auto t4 = std::chrono::steady_clock::now();
    const std::clock_t c1 = std::clock();
    benchmark::DoNotOptimize(jac.values.data());
    benchmark::DoNotOptimize(map.targets.data());
    auto secs = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
    state.counters["triangles"] = double(mesh.triangleCount());
    state.counters["charts"] = double(r.report.charts);
    state.counters["utilization"] = r.report.utilization;
    state.counters["l2_stretch"] = r.report.l2Stretch;
    state.counters["max_stretch"] = r.report.maxStretch;
    state.counters["flipped"] = double(r.report.flippedTriangles);
    state.counters["overlaps"] = double(r.report.overlappingTexels);
    for (const auto& [stage, s] : r.report.seconds) state.counters["s_" + stage] = s;
    state.counters["s_atlas"] = secs(t0, t1);
    state.counters["s_tangent_field"] = secs(t1, t2);
    state.counters["s_jacobians"] = secs(t2, t3);
    state.counters["s_indirection"] = secs(t3, t4);
    state.counters["s_total"] = secs(t0, t4);
    state.counters["cpu_total"] = double(c1 - c0) / CLOCKS_PER_SEC;
    state.counters["seam_length"] = r.report.seamLength;
    state.counters["cuts"] = double(r.report.cut.cuts);
  }
}

BENCHMARK_CAPTURE(runAtlas, bunny00, "bunny00.off", 0)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(runAtlas, armadillo, "armadillo.off", 0)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(runAtlas, camel, "camel.off", 0)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(runAtlas, eight, "eight.off", 0)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(runAtlas, elephant, "elephant.off", 0)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(runAtlas, bunny00_x16, "bunny00.off", 2)->Unit(benchmark::kSecond)->Iterations(1);

} // namespace

BENCHMARK_MAIN();
