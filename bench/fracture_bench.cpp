// SPDX-License-Identifier: GPL-3.0-or-later
// The fracture job on CGAL's bunny00 (75,408 triangles): 10 and 50 pieces with a 2048² atlas of
// the cut faces (the solid precomputation of the 128² marble done before timing, as the cache
// holds it in real use), seconds per stage and peak memory; and the interactive re-cut: one new
// plane through the 10 pieces, its faces textured at 256², cold and while the plane is dragged
// (the coarse levels of the previous positions in the cache). Targets (issue 15): 10 pieces <= 1 s,
// 50 <= 3 s, a re-cut <= 50 ms; Blender 3.4's Cell Fracture: 5.75 s and 13.3 s, cut faces untextured.
//   build/bench/fracture_bench --benchmark_counters_tabular=true
#include "bench/bench_support.h"
#include "geometry/io/mesh_io.h"
#include "render/break/break_model.h"
#include "synthesis/solid_analysis.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <ctime>
#include <map>
#include <mutex>

namespace {
using namespace texfab;
namespace fs = std::filesystem;

struct Fixture {
  geometry::Mesh bunny;
  Image exemplar = bench::marbleExemplar(128);
  synthesis::SolidAnalysis solid;
  bool ok = false;
  Fixture() {
    const fs::path model = fs::path(TEXFAB_SOURCE_DIR) / "models" / "cgal" / "bunny00.off";
    if (!fs::exists(model)) return;
    bunny = geometry::readMesh(model);
    solid = synthesis::analyzeSolid(exemplar, exemplar, exemplar, {});
    ok = true;
  }
  render::InteriorExemplar interior() const { return {&exemplar, &solid}; }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Seconds of every stage (nested ones prefixed by their depth), from the context's progress.
struct StageTimes {
  std::mutex mutex;
  std::map<std::string, double> seconds;
  Context context(int threads = 0) {
    Context ctx{.threads = threads};
    ctx.progress = [this](const ProgressEvent& e) {
      if (e.kind != ProgressEvent::Kind::End || e.depth > 1) return;
      std::lock_guard lock(mutex);
      seconds[(e.depth ? "  " : "") + std::string(e.stage)] += e.seconds;
    };
    return ctx;
  }
};

render::BreakModelOptions fractureOptions(int pieces) {
  render::BreakModelOptions o;
  o.fracture.emplace();
  o.fracture->pieces = pieces;
  o.interior.atlas.pack.width = o.interior.atlas.pack.height = 2048;
  return o;
}

void BM_FractureBunny(benchmark::State& state) {
  const Fixture& f = fixture();
  if (!f.ok) return state.SkipWithError("models/cgal/bunny00.off absent: run models/fetch");
  const int pieces = int(state.range(0));
  for (auto _ : state) {
    StageTimes times;
    const double cpu0 = processCpuSeconds();
    const auto t0 = std::chrono::steady_clock::now();
    const render::BrokenModel m = render::breakModel(f.bunny, {}, f.interior(), fractureOptions(pieces), times.context());
    state.counters["total_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    state.counters["cpu_s"] = processCpuSeconds() - cpu0;
    for (const auto& [stage, s] : times.seconds) state.counters[stage + "_s"] = s;
    state.counters["pieces"] = double(m.pieces.size());
    state.counters["texels"] = double(m.interior->sites.size());
    state.counters["voxels"] = double(m.interior->voxelsRequested);
  }
  state.counters["peak_MiB"] = bench::peakMemoryMiB();
}
BENCHMARK(BM_FractureBunny)->Arg(10)->Arg(50)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// One re-cut of the 10 pieces at 256²: the first position cold (counter cold_ms), then the plane
// dragged by half a voxel per iteration, each from the same 10 pieces.
void BM_RecutBunny256(benchmark::State& state) {
  const Fixture& f = fixture();
  if (!f.ok) return state.SkipWithError("models/cgal/bunny00.off absent: run models/fetch");
  synthesis::SolidLevelCache cache(size_t(1) << 30, synthesis::SolidLevelCache::Fill::WholeBricks);
  const render::BrokenModel pieces = render::breakModel(f.bunny, {}, f.interior(), fractureOptions(10), {}, &cache);
  atlas::GenerateAtlasOptions atlas;
  atlas.pack.width = atlas.pack.height = 256;
  const geometry::BoundingBox box = geometry::boundingBox(f.bunny);
  const Eigen::Vector3d normal = Eigen::Vector3d(1, 0.3, 0.2).normalized();
  const double step = 0.5 / pieces.interiorScale;
  int position = 0;
  auto plane = [&] { return geometry::CutPlane{box.center().cast<double>() + position * step * normal, normal}; };
  render::BrokenModel cold = pieces;
  const auto t0 = std::chrono::steady_clock::now();
  render::recutModel(cold, plane(), f.interior(), atlas, cache);
  state.counters["cold_ms"] = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  render::RecutReport report;
  StageTimes times;
  for (auto _ : state) {
    state.PauseTiming();
    render::BrokenModel m = pieces;
    ++position;
    state.ResumeTiming();
    report = render::recutModel(m, plane(), f.interior(), atlas, cache, times.context());
  }
  for (const auto& [stage, s] : times.seconds) state.counters[stage + "_ms"] = 1e3 * s / double(state.iterations());
  state.counters["pieces_cut"] = double(report.piecesCut);
  state.counters["texels"] = double(report.texels);
  state.counters["voxels"] = double(report.voxelsRequested);
  state.counters["cache_hit_rate"] = double(report.cacheHits) / double(std::max<int64_t>(1, report.cacheHits + report.cacheMisses));
  state.counters["peak_MiB"] = bench::peakMemoryMiB();
}
BENCHMARK(BM_RecutBunny256)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(10);

} // namespace

BENCHMARK_MAIN();
