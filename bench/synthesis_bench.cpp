// SPDX-License-Identifier: GPL-3.0-or-later
// 2-D synthesis benchmarks: exemplar analysis (64^2, 128^2) and synthesis (512^2 to 4096^2),
// with the process's peak memory. Targets (2 cores, release): analysis 128^2 <= 1 s;
// 1024^2 <= 0.5 s; 4096^2 <= 8 s with peak memory <= 1 GiB.
//   build/bench/synthesis_bench --benchmark_counters_tabular=true
#include "bench/bench_support.h"
#include "render/image/image_io.h"
#include "synthesis/synthesize_2d.h"

#include <benchmark/benchmark.h>

namespace {

using namespace texfab;
using namespace texfab::synthesis;

using bench::marbleExemplar;
using bench::peakMemoryMiB;

void BM_Analysis(benchmark::State& state) {
  const Image image = marbleExemplar(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(analyzeExemplar(image, {}));
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_Analysis)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Synthesis(benchmark::State& state) {
  static const Image image = marbleExemplar(128);
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
