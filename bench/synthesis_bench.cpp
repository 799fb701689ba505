// SPDX-License-Identifier: GPL-3.0-or-later
// 2-D synthesis benchmarks: exemplar analysis (64^2 to 4096^2 exemplars) and synthesis (512^2 to
// 4096^2 outputs), with the process's peak memory. Targets (2 cores, release): analysis of a 128^2
// exemplar <= 1 s, of a 1024^2 one <= 10 s and 1 GiB; synthesis 1024^2 <= 0.5 s; 4096^2 <= 8 s
// with peak memory <= 1 GiB.
//   build/bench/synthesis_bench --benchmark_counters_tabular=true
#include "bench/bench_support.h"
#include "core/image_io.h"
#include "core/memory.h"
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

// Large exemplars: the bundled rock photograph magnified (bilinear) to side x side, analysed once,
// with analysisMemoryBytes (the bound synth checks up front) beside the measured peak. A size
// whose bound exceeds 80% of this machine's memory is skipped, as synth would refuse it.
void BM_AnalysisLarge(benchmark::State& state) {
  const int side = int(state.range(0));
  const double bound = analysisMemoryBytes(side, side, {});
  state.counters["bound_MiB"] = bound / (1 << 20);
  if (bound > 0.8 * double(physicalMemoryBytes())) return state.SkipWithError("the memory bound exceeds 80% of RAM");
  const Image image = bench::magnified(readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models/exemplars/photos/rock.png"), side);
  for (auto _ : state) benchmark::DoNotOptimize(analyzeExemplar(image, {}));
  state.counters["peak_MiB"] = peakMemoryMiB();  // peak so far: sizes run in increasing order
}
BENCHMARK(BM_AnalysisLarge)->Arg(256)->Arg(512)->Arg(1024)->Arg(4096)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

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
