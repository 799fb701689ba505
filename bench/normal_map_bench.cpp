// SPDX-License-Identifier: GPL-3.0-or-later
// Normal-map filtering (render/filter_normal_map.h): fitting the vMF lobes of every MIP level of a
// 1024^2 normal map (issue 38's target: at most 10 s on this 2-core machine), with the default
// 4 lobes and 10 EM iterations, on 1 and on all threads; and the glTF route for a 1024^2 map:
// its roughness MIP chain (render/material_mips.h) and the chain's KTX2 (UASTC) encoding.
//   build/bench/normal_map_bench --benchmark_counters_tabular=true
#include "core/hash.h"
#include "core/ktx2_write.h"
#include "render/filter_normal_map.h"
#include "render/material_mips.h"

#include <benchmark/benchmark.h>

#include <cmath>

namespace {

using namespace texfab;

// A bumpy normal map: hashed slopes smoothed over 3x3 texels, as a synthesized stone's.
Image bumpyNormalMap(int size) {
  const auto slope = [&](int x, int y, uint32_t axis) {
    double s = 0;
    for (int j = -1; j <= 1; ++j)
      for (int i = -1; i <= 1; ++i)
        s += unitInterval(counterHash(5, uint32_t((x + i + size) % size), uint32_t((y + j + size) % size), axis)) - 0.5;
    return s / 3;
  };
  Image map(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const Eigen::Vector3d n = Eigen::Vector3d(slope(x, y, 0), slope(x, y, 1), 1).normalized();
      for (int c = 0; c < 3; ++c) map.at(x, y, c) = float((n[c] + 1) / 2);
    }
  return map;
}

void BM_FilterNormalMap(benchmark::State& state) {
  static const Image map = bumpyNormalMap(1024);
  const Context ctx{.threads = int(state.range(0))};
  for (auto _ : state) benchmark::DoNotOptimize(render::filterNormalMap(map, {}, ctx));
  state.counters["threads"] = double(state.range(0));
  state.counters["Mnormals/s"] = benchmark::Counter(double(map.width) * map.height / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_FilterNormalMap)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

geometry::Material glossyMaterial() {
  geometry::Material m;
  m.metallicFactor = 1, m.roughnessFactor = 0.3f;
  m.normalTexture.image = std::make_shared<const Image>(bumpyNormalMap(1024));
  return m;
}

void BM_MaterialMips(benchmark::State& state) {
  static const geometry::Material m = glossyMaterial();
  for (auto _ : state) benchmark::DoNotOptimize(render::withFilteredMips(m));
}
BENCHMARK(BM_MaterialMips)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

void BM_EncodeKtx2(benchmark::State& state) {
  static const geometry::Material m = render::withFilteredMips(glossyMaterial());
  for (auto _ : state) benchmark::DoNotOptimize(encodeKtx2Uastc(*m.metallicRoughnessTexture.mips));
}
BENCHMARK(BM_EncodeKtx2)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

} // namespace

BENCHMARK_MAIN();
