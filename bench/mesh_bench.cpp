// SPDX-License-Identifier: GPL-3.0-or-later
// Mesh benchmarks on a ~1.4M-triangle mesh (CGAL's elephant, bundled, midpoint-subdivided
// 4 times, closed): loading it (binary PLY and GLB) plus building the Embree BVH, inside tests
// per second, and a 1024^2 preview render at 4 samples per pixel.
//   build/bench/mesh_bench --benchmark_counters_tabular=true
#include "geometry/embree_scene.h"
#include "geometry/io/mesh_io.h"
#include "render/preview_renderer.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <map>
#include <random>

namespace {

using namespace texfab;
using namespace texfab::geometry;

// Loop-free 1-to-4 midpoint subdivision; shared edge midpoints keep the mesh closed.
Mesh subdivide(const Mesh& in) {
  Mesh out;
  out.positions = in.positions;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
  auto mid = [&](uint32_t a, uint32_t b) {
    const auto key = std::minmax(a, b);
    const auto [it, inserted] = midpoint.emplace(key, uint32_t(out.positions.size()));
    if (inserted) out.positions.push_back(0.5f * (in.positions[a] + in.positions[b]));
    return it->second;
  };
  for (const auto& t : in.triangles) {
    const uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
    out.triangles.push_back({t[0], ab, ca});
    out.triangles.push_back({ab, t[1], bc});
    out.triangles.push_back({ca, bc, t[2]});
    out.triangles.push_back({ab, bc, ca});
  }
  return out;
}

const Mesh& bigMesh() {
  static const Mesh mesh = [] {
    Mesh m = readMesh(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/meshes/elephant.off");
    for (int i = 0; i < 4; ++i) m = subdivide(m);
    return m;
  }();
  return mesh;
}

std::filesystem::path bigFile(const char* extension) {
  const auto path = std::filesystem::temp_directory_path() / (std::string("texfab_bench_elephant") + extension);
  if (!std::filesystem::exists(path)) writeMesh(bigMesh(), path);
  return path;
}

void BM_LoadAndBuildBvh(benchmark::State& state, const char* extension) {
  const auto path = bigFile(extension);
  double load = 0, build = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh mesh = readMesh(path);
    const auto t1 = std::chrono::steady_clock::now();
    const EmbreeScene scene(mesh);
    const auto t2 = std::chrono::steady_clock::now();
    load += std::chrono::duration<double>(t1 - t0).count();
    build += std::chrono::duration<double>(t2 - t1).count();
    benchmark::DoNotOptimize(scene.triangleCount());
  }
  state.counters["triangles"] = double(bigMesh().triangleCount());
  state.counters["load_s"] = load / double(state.iterations());
  state.counters["bvh_s"] = build / double(state.iterations());
}
BENCHMARK_CAPTURE(BM_LoadAndBuildBvh, ply, ".ply")->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK_CAPTURE(BM_LoadAndBuildBvh, glb, ".glb")->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void BM_InsideTests(benchmark::State& state) {
  static const EmbreeScene scene(bigMesh());
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  const BoundingBox& box = scene.bounds();
  std::vector<Eigen::Vector3f> points(100000);
  for (auto& p : points) p = box.min + Eigen::Vector3f(u(rng), u(rng), u(rng)).cwiseProduct(box.max - box.min);
  for (auto _ : state) benchmark::DoNotOptimize(scene.inside(points, Context{.threads = int(state.range(0))}));
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(points.size()));
}
BENCHMARK(BM_InsideTests)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Render1024(benchmark::State& state) {
  static const render::PreviewRenderer renderer(bigMesh());
  render::RenderOptions options;
  options.width = options.height = 1024;
  options.samplesPerPixel = 4;
  for (auto _ : state) benchmark::DoNotOptimize(renderer.render(options));
  state.counters["Mrays_per_s"] = benchmark::Counter(1024.0 * 1024 * 4 * 3 * double(state.iterations()) / 1e6,
                                                     benchmark::Counter::kIsRate);  // camera + shadow + AO
}
BENCHMARK(BM_Render1024)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

} // namespace

BENCHMARK_MAIN();
