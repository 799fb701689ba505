// SPDX-License-Identifier: GPL-3.0-or-later
// The dither's quality, measured (issue 16): a 192 x 96 x 128 block of shell voxels at the J750's
// pitch (600 x 300 dpi, 0.027 mm) coloured three ways (the solid texture of the bundled marble,
// a smooth ramp through the printable colours, a flat colour), dithered to CMYKW by
//   blue-noise   the 3-D ordered dither texfab uses (position-based: shards are exact),
//   fs-layer     Floyd-Steinberg within each layer (the baseline the issue names; also exact),
//   white-noise  thresholds from a hash (the bad baseline: no structure, all noise).
// Measures, in linear RGB:
//   block_err    mean over 16^3 blocks of |mean dithered colour - mean target colour| (Euclidean);
//   block_max    the worst block;
//   seen_xy      RMS of (dithered - target) low-passed by the eye at a reading distance (Gaussian,
//                sigma 0.1 mm: ~1 arc minute at 30 cm) in a layer: visible structure in a layer;
//   seen_xz      the same on a vertical section (what a side wall shows: rows of many layers).
// Run: build/bench/dither_bench --benchmark_counters_tabular=true
#include "bench/bench_support.h"
#include "core/mip_pyramid.h"
#include "print/blue_noise.h"
#include "print/dither_measures.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <benchmark/benchmark.h>

#include <cmath>

namespace {
using namespace texfab;
using namespace texfab::print;

constexpr int kW = 192, kH = 96, kL = 128;  // voxels
const Eigen::Vector3d kPitch(25.4 / 600, 25.4 / 300, 0.027);

size_t at(int x, int y, int z) { return (size_t(z) * kH + size_t(y)) * kW + size_t(x); }

// Target colours (linear RGB, 3 per voxel).
std::vector<float> target(int kind) {
  std::vector<float> c(3 * size_t(kW) * kH * kL);
  if (kind == 0) {  // the solid texture of the marble, 10 exemplar pixels per mm
    const Image marble = bench::marbleExemplar(128);
    const synthesis::SolidAnalysis a = synthesis::analyzeSolidCached(marble, marble, marble, {}, synthesis::defaultCacheDir());
    const double scale = 10.0;
    const synthesis::VoxelBox box{0, 0, 0, int(kW * kPitch.x() * scale) + 1, int(kH * kPitch.y() * scale) + 1,
                                  int(kL * kPitch.z() * scale) + 1};
    const synthesis::SolidSynthesisResult r = synthesis::synthesizeSolidBox(a, box, {});
    std::vector<float> colors;
    synthesis::solidColors(r.triples, marble, marble, marble, colors);
    const size_t channels = size_t(synthesis::solidColorChannels(marble, marble, marble));
    for (int z = 0; z < kL; ++z)
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
          const int sx = int((x + 0.5) * kPitch.x() * scale), sy = int((y + 0.5) * kPitch.y() * scale),
                    sz = int((z + 0.5) * kPitch.z() * scale);
          const size_t s = (size_t(sz) * size_t(box.ny) + size_t(sy)) * size_t(box.nx) + size_t(sx);
          for (size_t k = 0; k < 3; ++k) c[3 * at(x, y, z) + k] = srgbToLinear(colors[channels * s + std::min(k, channels - 1)]);
        }
  } else {
    for (int z = 0; z < kL; ++z)
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
          const float u = float(x) / kW, v = float(y) / kH, w = float(z) / kL;
          const float rgb[3] = {kind == 1 ? 0.15f + 0.8f * u : 0.5f, kind == 1 ? 0.2f + 0.6f * v : 0.3f,
                                kind == 1 ? 0.9f - 0.7f * w : 0.2f};
          for (int k = 0; k < 3; ++k) c[3 * at(x, y, z) + size_t(k)] = rgb[k];
        }
  }
  return c;
}

uint32_t hashVoxel(int x, int y, int z) {
  uint64_t h = (uint64_t(uint32_t(x)) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(uint32_t(y)) * 0xC2B2AE3D27D4EB4Full) ^
               (uint64_t(uint32_t(z)) * 0x165667B19E3779F9ull);
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ull;
  return uint32_t(h >> 32);
}

// White noise: each voxel's threshold from a hash of its position.
std::vector<float> whiteNoise(const std::vector<float>& colors, const MaterialMixer& mixer) {
  std::vector<float> out(colors.size());
  for (int z = 0; z < kL; ++z)
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const size_t v = 3 * at(x, y, z);
        const float rgba[4] = {colors[v], colors[v + 1], colors[v + 2], 1.0f};
        const std::array<float, 3>& c = mixer.linearColor(mixer.pick(rgba, (hashVoxel(x, y, z) + 0.5f) / 4294967296.0f));
        std::copy(c.begin(), c.end(), &out[v]);
      }
  return out;
}

void BM_Dither(benchmark::State& state) {
  const MaterialMixer mixer({{"C", {0, 255, 255, 255}}, {"M", {255, 0, 255, 255}}, {"Y", {255, 255, 0, 255}},
                             {"K", {0, 0, 0, 255}}, {"W", {255, 255, 255, 255}}});
  const DitherBox box{kW, kH, kL, kPitch};
  const std::vector<float> colors = target(int(state.range(0)));
  const std::vector<float> printable = reproducedColors(colors, mixer);  // the measures' reference
  const BlueNoiseVolume noise = blueNoiseVolume(32, kPitch);
  const int method = int(state.range(1));
  std::vector<float> dithered;
  for (auto _ : state)
    dithered = method == 2 ? whiteNoise(colors, mixer)
                           : ditherBox(box, colors, mixer, method == 1 ? DitherMode::FloydSteinberg : DitherMode::BlueNoise, &noise);
  const BlockColorError blocks = blockColorError(box, dithered, printable);
  state.counters["block_err"] = blocks.mean;
  state.counters["block_max"] = blocks.worst;
  state.counters["seen_xy"] = visibleError(box, dithered, printable, false, kL / 2);
  state.counters["seen_xz"] = visibleError(box, dithered, printable, true, kH / 2);
}
BENCHMARK(BM_Dither)
    ->ArgNames({"target", "method"})
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

} // namespace

BENCHMARK_MAIN();
