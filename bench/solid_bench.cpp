// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmarks of lazy solid synthesis against the paper's figures (Dong et al. 2008:
// Core 2 6400 CPU for the precomputation, GeForce 8800 Ultra for synthesis):
//   precomputation 64^2: paper 7 s; 128^2: paper 25-35 s (target: faster);
//   full volume 64^3: paper 0.22 s; 128^3: paper 1.7 s (target: within 2x);
//   a 256^2 planar cut with coarse levels cached: paper 8 ms, 14.4 MB (target: <= 16 ms);
//   voxels synthesized per requested voxel for a plane and a thin shell; peak memory.
// Exemplar: GIMP's marble (bundled as models/exemplars/marble.png), 64^2 = its top-left quarter.
//   build/bench/solid_bench --benchmark_counters_tabular=true
// Arguments: interleave (1: Jacobi passes, the default; 2: the paper's 8 sub-passes per pass) and
// the finest level's passes (1, the default; 2, the paper's), so that the default and the paper's
// schedule are both measured.
#include "bench/bench_support.h"
#include "core/image_io.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/refine_solid.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <benchmark/benchmark.h>

#include <cmath>

#include <sys/resource.h>

namespace {

using namespace texfab;
using namespace texfab::synthesis;

using bench::marbleExemplar;
using bench::peakMemoryMiB;

// CPU seconds of the whole process (every thread): on the shared 2-core machine wall times are
// noisy, and the benchmark library's CPU column counts the main thread only.
double processCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Voxels synthesized per level (coarsest first), per requested voxel: where the chain's work goes.
void levelCounters(benchmark::State& state, const SolidSynthesisResult& r, double requested) {
  static const char* const names[] = {"L0_per_requested", "L1_per_requested", "L2_per_requested", "L3_per_requested",
                                      "L4_per_requested", "L5_per_requested", "L6_per_requested", "L7_per_requested"};
  for (size_t l = 0; l < r.levels.size() && l < 8; ++l) state.counters[names[l]] = double(r.levels[l].voxels) / requested;
}

// The analysis synthesis benchmarks use, through the on-disk cache (computed once).
const SolidAnalysis& analysis(int side) {
  static std::map<int, SolidAnalysis> analyses;
  auto it = analyses.find(side);
  if (it == analyses.end()) {
    const Image e = marbleExemplar(side);
    it = analyses.emplace(side, analyzeSolidCached(e, e, e, {}, defaultCacheDir())).first;
  }
  return it->second;
}

// interleave 1 (Jacobi, the default) or 2 (the paper's 8 sub-passes); finest-level passes 1 (the
// default) or 2 (the paper's).
SolidSynthesisOptions optionsFor(int64_t interleave, int64_t finestPasses) {
  SolidSynthesisOptions o;
  o.interleave = int(interleave);
  o.finestPasses = int(finestPasses);
  return o;
}

void BM_SolidPrecomputation(benchmark::State& state) {
  const Image image = marbleExemplar(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(analyzeSolid(image, image, image, {}));
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_SolidPrecomputation)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// A full N^3 volume from nothing (no coarse cache), exemplar N^2 as in the paper's Fig. 8.
void BM_SolidVolume(benchmark::State& state) {
  const int n = int(state.range(0));
  const SolidAnalysis& a = analysis(n);
  const SolidSynthesisOptions o = optionsFor(state.range(1), state.range(2));
  int64_t synthesized = 0;
  const double cpu0 = processCpuSeconds();
  for (auto _ : state) {
    const SolidSynthesisResult r = synthesizeSolidBox(a, {0, 0, 0, n, n, n}, o);
    synthesized = r.voxelsSynthesized();
    benchmark::DoNotOptimize(r.triples.data());
  }
  state.counters["process_cpu_s"] = (processCpuSeconds() - cpu0) / double(state.iterations());
  state.counters["synth_per_voxel"] = double(synthesized) / (double(n) * n * n);
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_SolidVolume)
    ->Args({64, 1, 1})->Args({64, 1, 2})->Args({64, 2, 2})->Args({128, 1, 1})->Args({128, 1, 2})->Args({128, 2, 2})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// The 128^3 volume at contrast gain range(0)/16 (SolidSynthesisOptions::contrastGain): 16 is the
// default, so the pair measures what a gain costs in the same run.
void BM_SolidVolumeContrastGain(benchmark::State& state) {
  const SolidAnalysis& a = analysis(128);
  SolidSynthesisOptions o;
  o.contrastGain = float(state.range(0)) / 16.0f;
  for (auto _ : state) benchmark::DoNotOptimize(synthesizeSolidBox(a, {0, 0, 0, 128, 128, 128}, o).triples.data());
}
BENCHMARK(BM_SolidVolumeContrastGain)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

std::vector<Voxel> zPlane(int side, int64_t z) {
  std::vector<Voxel> v;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) v.push_back({x, y, z});
  return v;
}

// The interactive-cutting case (§6.4): a 256^2 axis-aligned cut with the coarse levels already in
// the cache, 128^2 exemplar (256^3 equivalent volume).
void BM_SolidCut256Cached(benchmark::State& state) {
  const SolidAnalysis& a = analysis(int(state.range(1)));
  const SolidSynthesisOptions o = optionsFor(state.range(0), state.range(2));
  SolidLevelCache cache(size_t(1) << 30);
  // Warm the coarse levels of the 8 cuts z = 36..43 (as the paper's precomputed coarse volume),
  // then time the cuts themselves: only their finest level is synthesized.
  for (int64_t z = 36; z < 44; ++z) synthesizeSolid(a, zPlane(256, z), o, &cache);
  int64_t z = 0, finest = 0, all = 0, corrections = 0;
  double seconds = 0;
  const double cpu0 = processCpuSeconds();
  for (auto _ : state) {
    const SolidSynthesisResult r = synthesizeSolid(a, zPlane(256, z++ % 8 + 36), o, &cache);
    finest = r.levels.back().voxels;
    corrections = r.levels.back().corrections;
    seconds = r.levels.back().seconds;
    all = r.voxelsSynthesized();
    benchmark::DoNotOptimize(r.triples.data());
  }
  state.counters["process_cpu_ms"] = (processCpuSeconds() - cpu0) * 1e3 / double(state.iterations());
  state.counters["finest_voxels_per_pixel"] = double(finest) / (256.0 * 256.0);
  state.counters["coarse_voxels"] = double(all - finest);
  state.counters["finest_corrections"] = double(corrections);
  state.counters["finest_ms"] = seconds * 1e3;
  state.counters["cache_MiB"] = double(cache.bytes()) / double(1 << 20);
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_SolidCut256Cached)->Args({1, 128, 1})->Args({1, 128, 2})->Args({2, 128, 2})->Args({1, 64, 1})->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// Cost of laziness: voxels synthesized (all levels) per requested voxel, cold cache.
void BM_SolidPlaneCold(benchmark::State& state) {
  const SolidAnalysis& a = analysis(128);
  const SolidSynthesisOptions o = optionsFor(state.range(0), state.range(1));
  int64_t synthesized = 0;
  for (auto _ : state) {
    const SolidSynthesisResult r = synthesizeSolid(a, zPlane(256, 40), o);
    synthesized = r.voxelsSynthesized();
  }
  state.counters["synth_per_requested"] = double(synthesized) / (256.0 * 256.0);
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_SolidPlaneCold)->Args({1, 1})->Args({1, 2})->Args({2, 2})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// A thin shell: the voxels at distance [r - 0.5, r + 0.5) from a centre, one voxel thick; r = 48
// (~29,000 voxels) and r = 200 (~503,000 voxels, the case of `texfab texture --mode solid`: a
// surface's voxels in one request). Cold: a fresh coarse cache per run, shared by the request's
// tiles.
void BM_SolidShell(benchmark::State& state) {
  const SolidAnalysis& a = analysis(128);
  const SolidSynthesisOptions o = optionsFor(state.range(0), state.range(2));
  const int r = int(state.range(1));
  std::vector<Voxel> shell;
  for (int z = -r - 1; z <= r + 1; ++z)
    for (int y = -r - 1; y <= r + 1; ++y)
      for (int x = -r - 1; x <= r + 1; ++x) {
        const double d2 = double(x) * x + double(y) * y + double(z) * z;
        if (d2 >= (r - 0.5) * (r - 0.5) && d2 < (r + 0.5) * (r + 0.5)) shell.push_back({x + 300, y + 300, z + 300});
      }
  int64_t synthesized = 0, corrections = 0;
  const double cpu0 = processCpuSeconds();
  for (auto _ : state) {
    SolidLevelCache cache(size_t(1) << 30);
    const SolidSynthesisResult res = synthesizeSolid(a, shell, o, &cache);
    synthesized = res.voxelsSynthesized();
    corrections = 0;
    for (const auto& l : res.levels) corrections += l.corrections;
    levelCounters(state, res, double(shell.size()));
  }
  state.counters["process_cpu_s"] = (processCpuSeconds() - cpu0) / double(state.iterations());
  state.counters["voxels"] = double(shell.size());
  state.counters["synth_per_requested"] = double(synthesized) / double(shell.size());
  state.counters["corrections_per_requested"] = double(corrections) / double(shell.size());
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_SolidShell)->Args({1, 48, 1})->Args({2, 48, 2})->Args({1, 200, 1})->Args({1, 200, 2})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// Slice refinement (SolidSynthesisOptions::refinePasses = range(1), at contrast gain 2) on the
// 128^3 volume (range(0) = 0), a 256^2 cut with its coarse levels cached (1), the r = 48 shell (2);
// 0 passes is the same request unrefined, in the same run.
void BM_SolidRefinement(benchmark::State& state) {
  const SolidAnalysis& a = analysis(128);
  SolidSynthesisOptions o;
  o.contrastGain = 2;
  o.refinePasses = int(state.range(1));
  std::vector<Voxel> voxels;
  const int kind = int(state.range(0));
  if (kind == 1) voxels = zPlane(256, 40);
  if (kind == 2)
    for (int z = -49; z <= 49; ++z)
      for (int y = -49; y <= 49; ++y)
        for (int x = -49; x <= 49; ++x) {
          const double d2 = double(x) * x + double(y) * y + double(z) * z;
          if (d2 >= 47.5 * 47.5 && d2 < 48.5 * 48.5) voxels.push_back({x + 300, y + 300, z + 300});
        }
  SolidLevelCache cache(size_t(1) << 30);
  if (kind == 1) {
    SolidSynthesisOptions warm = o;
    warm.refinePasses = 0;
    std::vector<Voxel> slab;
    for (int64_t z = 40 - refineMargin(2); z <= 40 + refineMargin(2); ++z)
      for (const Voxel& v : zPlane(256, z)) slab.push_back(v);
    synthesizeSolid(a, slab, warm, &cache);
  }
  int64_t synthesized = 0;
  for (auto _ : state) {
    const SolidSynthesisResult r = kind == 0 ? synthesizeSolidBox(a, {0, 0, 0, 128, 128, 128}, o)
                                             : synthesizeSolid(a, voxels, o, kind == 1 ? &cache : nullptr);
    synthesized = r.voxelsSynthesized();
    benchmark::DoNotOptimize(r.triples.data());
  }
  state.counters["synthesized_voxels"] = double(synthesized);
  state.counters["peak_MiB"] = peakMemoryMiB();
}
BENCHMARK(BM_SolidRefinement)->ArgsProduct({{0, 1, 2}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

} // namespace

BENCHMARK_MAIN();
