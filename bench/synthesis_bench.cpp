// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmarks of issue 2: exemplar analysis (64^2, 128^2) and synthesis (512^2 to 4096^2), with the
// process's peak memory. Targets (2 cores, release): analysis 128^2 <= 1 s; 1024^2 <= 0.5 s;
// 4096^2 <= 8 s with peak memory <= 1 GiB.
//   build/bench/synthesis_bench --benchmark_counters_tabular=true
#include "render/image_io.h"
#include "synthesis/synthesize_2d.h"

#include <benchmark/benchmark.h>
#include <sys/resource.h>

namespace {

using namespace texfab;
using namespace texfab::synthesis;

// GIMP's marble1 (128^2), bundled as models/exemplars/marble.png; 64^2 is its top-left quarter.
Image exemplar(int side) {
  static const Image marble = readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/exemplars/marble.png");
  Image out(side, side, marble.channels, marble.format);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      for (int c = 0; c < marble.channels; ++c) out.at(x, y, c) = marble.at(x, y, c);
  return out;
}

double peakMemoryMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

void BM_Analysis(benchmark::State& state) {
  const Image image = exemplar(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(analyzeExemplar(image, {}));
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_Analysis)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Synthesis(benchmark::State& state) {
  static const Image image = exemplar(128);
  static const ExemplarAnalysis analysis = analyzeExemplar(image, {});
  const int side = int(state.range(0));
  for (auto _ : state) {
    const SynthesisResult r = synthesize2d(analysis, {0, 0, side, side}, {});
    benchmark::DoNotOptimize(applyCoords(r.coords, image));
  }
  state.counters["Mtexels_per_s"] =
      benchmark::Counter(double(side) * side * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["peak_MiB"] = peakMemoryMiB();  // peak so far: sizes run in increasing order
}
BENCHMARK(BM_Synthesis)->Arg(512)->Arg(1024)->Arg(2048)->Arg(4096)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

BENCHMARK_MAIN();
