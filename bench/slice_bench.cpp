// SPDX-License-Identifier: GPL-3.0-or-later
// The whole `texfab slice` job (print::PrintJob: the model made printable, voxelize, colour from the solid texture, dither to CMYKW + clear,
// encode and write one PNG per layer, manifest) on CGAL's bunny00 (75K triangles), 50 mm tall,
// written to a temporary folder. The solid analysis of the bundled marble (128^2) is computed
// before timing (cached in real use). Counters: wall seconds, layers per second, peak memory, and
// CPU seconds per stage summed over threads (voxelize, prepare = solid synthesis wall time,
// colours, dither, encode, write).
//
// Targets (issue 16), on the project's 2-core machine:
//   bunny 50 mm, 600 dpi, 0.05 mm (1000 layers): <= 11.7 s (PrusaSlicer 2.5's monochrome SLA
//   export of the same print, the anchor) and <= 1 GiB;
//   bunny 50 mm, 600 x 300 dpi, 0.027 mm (1,852 layers): time, memory and where the time goes;
//   layers per second at 1 and 2 threads.
// Run: build/bench/slice_bench --benchmark_counters_tabular=true
#include "bench/bench_support.h"
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "print/print_grid.h"
#include "print/print_job.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>

namespace {
using namespace texfab;
namespace fs = std::filesystem;

constexpr double kFeatureMm = 20.0;  // one 128-pixel exemplar spans 20 mm of the print

// Arguments: dpi y, layer thickness in micrometres, threads (0 = all).
void BM_SliceBunny(benchmark::State& state) {
  const fs::path model = fs::path(TEXFAB_SOURCE_DIR) / "models" / "cgal" / "bunny00.off";
  if (!fs::exists(model)) {
    state.SkipWithError("model absent: run models/fetch");
    return;
  }
  const geometry::Mesh mesh = geometry::readMesh(model);
  const Image exemplar = readImage(fs::path(TEXFAB_SOURCE_DIR) / "models" / "exemplars" / "marble.png");
  const synthesis::SolidAnalysis analysis =
      synthesis::analyzeSolidCached(exemplar, exemplar, exemplar, {}, synthesis::defaultCacheDir());
  print::PrintGridOptions go;
  go.up = geometry::UpAxis::Y;  // the bunny sits on its feet
  go.heightMm = 50;
  go.dpiX = 600;
  go.dpiY = double(state.range(0));
  go.layerMm = double(state.range(1)) / 1000.0;
  const print::PrintGrid grid = print::printGrid(geometry::boundingBox(mesh), go);
  print::PrintJobOptions o;
  o.grid = go;
  o.colors = print::PrintColors::Solid;
  o.textureScale = exemplar.width / (kFeatureMm / grid.mmPerUnit);  // exemplar pixels per model unit
  const fs::path out = fs::temp_directory_path() / "texfab_slice_bench";
  for (auto _ : state) {
    fs::remove_all(out);
    const auto t0 = std::chrono::steady_clock::now();
    const Context ctx{.threads = int(state.range(2))};
    const print::PrintJob job(mesh, o, ctx);
    print::SliceWriter writer(out, true);
    const print::PrintJobResult r = job.slice({&exemplar, &analysis, nullptr, "marble.png"}, 0, -1, writer,
                                               model.filename().string(), ctx);
    writer.publish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const print::SliceReport& s = r.slice.report;
    state.counters["seconds"] = seconds;
    state.counters["layers"] = s.layers;
    state.counters["layers_per_s"] = s.layers / seconds;
    state.counters["Mvoxels"] = double(grid.voxels()) * 1e-6;
    state.counters["shell_Mvox"] = double(s.shellVoxels) * 1e-6;
    state.counters["solid_Mvox"] = double(r.voxelsRequested) * 1e-6;
    state.counters["voxelize_cpu"] = s.voxelizeSeconds;
    state.counters["prepare_s"] = s.prepareSeconds;
    state.counters["colors_cpu"] = s.colorSeconds;
    state.counters["dither_cpu"] = s.ditherSeconds;
    state.counters["encode_cpu"] = s.encodeSeconds;
    state.counters["write_cpu"] = s.writeSeconds;
    state.counters["MB_written"] = double(s.bytes) * 1e-6;
  }
  state.counters["peak_MiB"] = bench::peakMemoryMiB();
  fs::remove_all(out);
}
BENCHMARK(BM_SliceBunny)
    ->ArgNames({"dpi_y", "layer_um", "threads"})
    ->Args({600, 50, 0})
    ->Args({300, 27, 0})
    ->Args({600, 50, 1})
    ->Args({600, 50, 2})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

} // namespace

BENCHMARK_MAIN();
