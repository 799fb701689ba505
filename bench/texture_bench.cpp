// SPDX-License-Identifier: GPL-3.0-or-later
// The whole `texfab texture` job on CGAL's refined_elephant (88,928 triangles) at 2048², in
// surface and solid mode: seconds per stage (load, atlas, tangent field, fields, synthesis,
// resolve, write) and peak memory. The exemplar analyses are computed before timing (cached in
// real use). Targets: surface ≤ 20 s, solid ≤ 10 s. Run:
//   build/bench/texture_bench --benchmark_counters_tabular=true
#include "bench/bench_support.h"
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "render/texture_mesh.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <map>

namespace {
using namespace texfab;
namespace fs = std::filesystem;

void runTexture(benchmark::State& state, render::TextureMode mode) {
  const fs::path model = fs::path(TEXFAB_SOURCE_DIR) / "models" / "cgal" / "refined_elephant.off";
  if (!fs::exists(model)) {
    state.SkipWithError("model absent: run models/fetch");
    return;
  }
  const Image exemplar = readImage(fs::path(TEXFAB_SOURCE_DIR) / "models" / "exemplars" / "marble.png");
  render::TextureExemplar ex;
  ex.color = &exemplar;
  synthesis::ExemplarAnalysis analysis;
  synthesis::SolidAnalysis solid;
  if (mode == render::TextureMode::Surface) {
    analysis = synthesis::analyzeExemplar(exemplar, {});
    ex.analysis = &analysis;
  } else {
    solid = synthesis::analyzeSolid(exemplar, exemplar, exemplar, {});
    ex.solidAnalysis = &solid;
  }
  const fs::path out = fs::temp_directory_path() / "texfab_texture_bench.glb";
  for (auto _ : state) {
    std::map<std::string, double> seconds;
    const auto t0 = std::chrono::steady_clock::now();
    const geometry::Mesh mesh = geometry::readMesh(model);
    seconds["load"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    render::TextureMeshOptions options;
    options.mode = mode;
    options.measure = false;
    Context ctx;
    ctx.progress = [&](const ProgressEvent& e) {
      if (e.kind == ProgressEvent::Kind::End) seconds[std::string(e.stage)] = e.seconds;
    };
    const render::TextureMeshResult r = render::textureMesh(mesh, ex, options, ctx);
    const auto t1 = std::chrono::steady_clock::now();
    geometry::writeMesh(r.mesh, out);
    seconds["write"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    seconds["total"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const auto& [stage, s] : seconds) state.counters[stage + "_s"] = s;
    state.counters["texels"] = double(r.sites.size());
    if (mode == render::TextureMode::Solid) state.counters["voxels"] = double(r.solid.voxelsRequested);
  }
  state.counters["peak_MiB"] = bench::peakMemoryMiB();
  fs::remove(out);
}

} // namespace

BENCHMARK_CAPTURE(runTexture, surface_refined_elephant_2048, render::TextureMode::Surface)
    ->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(runTexture, solid_refined_elephant_2048, render::TextureMode::Solid)
    ->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_MAIN();
