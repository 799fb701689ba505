// SPDX-License-Identifier: GPL-3.0-or-later
// The Vulkan backend against the CPU, with the targets for a GPU (256^2 cut with coarse levels
// cached <= 1 ms, 128^3 volume <= 20 ms, 2-D 4096^2 window <= 50 ms):
//   2d      a 2-D window (default 4096^2)
//   cut     a 256^2 solid cut plane, coarse levels cached by the neighbouring plane
//   volume  a solid box (default 128^3)
//   job     a solid texture job's request: the voxels of a thin spherical shell, about as many as
//           the texels a 2048^2 atlas fills (default radius 400: ~2M voxels)
//   tiles-box, tiles-cut, tiles-job   the same three requests read from a solid tile set
//           (--solid-method tiles; the box 512^3 by default); after the box, the kernel's rate in
//           voxels per second and the bytes it writes per second against --peak-gbs
// Each case runs on the CPU and on the device; both outputs must be equal, byte for byte (the
// program exits 1 otherwise). Device times come from timestamps around every copy and dispatch
// (Device::setProfiling): upload, dispatch, download, and the host's wall time inside submits.
//
// A plain program (no Google Benchmark, no image library): it links the synthesis library only,
// so that it can be carried to a GPU machine with libvulkan and libtbb (bench/README.md). The
// exemplar is a binary PPM/PGM or, by default, a procedural marble.
#include "core/error.h"
#include "core/hash.h"
#include "synthesis/backend.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/solid_tiles.h"
#include "synthesis/synthesize_2d.h"
#include "synthesis/synthesize_solid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace {

using namespace texfab;
using namespace texfab::synthesis;
using Clock = std::chrono::steady_clock;

struct Args {
  std::string exemplar;  // PPM or PGM; empty: procedural
  int exemplarSide = 64;
  std::vector<std::string> cases{"2d", "cut", "volume", "job", "tiles-box", "tiles-cut", "tiles-job"};
  int size2d = 4096, cut = 256, volume = 128, shellRadius = 400, tilesBox = 512, tileSide = 32;
  double peakGBs = 4800;  // the device's memory bandwidth, GB/s (NVIDIA H200: 4.8 TB/s)
  int reps = 3;
  int threads = 0;
  int device = -1;
};

[[noreturn]] void usage(const char* message) {
  std::fprintf(stderr,
               "vulkan_bench: error: %s\n"
               "usage: vulkan_bench [--cases 2d,cut,volume,job,tiles-box,tiles-cut,tiles-job] [--2d N] [--cut N]\n"
               "                    [--volume N] [--shell R] [--tiles-box N] [--tile-side N] [--peak-gbs GB/s]\n"
               "                    [--reps N] [--threads N] [--device N] [--exemplar FILE.ppm|pgm] [--exemplar-side N]\n",
               message);
  std::exit(1);
}

Args parseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) usage(("missing value after " + flag).c_str());
    const std::string value = argv[++i];
    const auto number = [&] {
      char* end = nullptr;
      const long v = std::strtol(value.c_str(), &end, 10);
      if (*end || v < 0 || v > 1 << 20) usage((flag + ": expected a whole number, got '" + value + "'").c_str());
      return int(v);
    };
    if (flag == "--cases") {
      a.cases.clear();
      for (size_t b = 0, e; b <= value.size(); b = e + 1) {
        e = std::min(value.find(',', b), value.size());
        a.cases.push_back(value.substr(b, e - b));
      }
    } else if (flag == "--2d") a.size2d = number();
    else if (flag == "--cut") a.cut = number();
    else if (flag == "--volume") a.volume = number();
    else if (flag == "--shell") a.shellRadius = number();
    else if (flag == "--tiles-box") a.tilesBox = number();
    else if (flag == "--tile-side") a.tileSide = number();
    else if (flag == "--peak-gbs") a.peakGBs = std::max(1, number());
    else if (flag == "--reps") a.reps = std::max(1, number());
    else if (flag == "--threads") a.threads = number();
    else if (flag == "--device") a.device = number();
    else if (flag == "--exemplar") a.exemplar = value;
    else if (flag == "--exemplar-side") a.exemplarSide = number();
    else usage(("unknown flag " + flag).c_str());
  }
  return a;
}

// A binary PPM (P6) or PGM (P5) with 8-bit samples, its top-left side^2 crop.
Image readPnm(const std::string& path, int side) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  std::string magic;
  int w = 0, h = 0, maxval = 0;
  in >> magic >> w >> h >> maxval;
  const int channels = magic == "P6" ? 3 : magic == "P5" ? 1 : 0;
  if (!channels || w <= 0 || h <= 0 || w > 1 << 16 || h > 1 << 16 || maxval != 255)
    throw Error(path + ": not a binary 8-bit PPM (P6) or PGM (P5)");
  in.get();
  std::vector<unsigned char> bytes(size_t(w) * size_t(h) * size_t(channels));
  if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size()))) throw Error(path + ": truncated");
  side = std::min({side, w, h});
  Image out(side, side, channels);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      for (int c = 0; c < channels; ++c)
        out.at(x, y, c) = float(bytes[(size_t(y) * size_t(w) + size_t(x)) * size_t(channels) + size_t(c)]) / 255.0f;
  return out;
}

// Tileable value noise at (x, y) with `cells` cells across `side` pixels.
double noise(int x, int y, int side, int cells) {
  const double fx = double(x) * cells / side, fy = double(y) * cells / side;
  const int x0 = int(fx), y0 = int(fy);
  const double tx = fx - x0, ty = fy - y0;
  const auto at = [&](int i, int j) { return double(texelHash(17u, 0, i % cells, j % cells, 0) >> 8) / double(1 << 24); };
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  return (at(x0, y0) * (1 - sx) + at(x0 + 1, y0) * sx) * (1 - sy) + (at(x0, y0 + 1) * (1 - sx) + at(x0 + 1, y0 + 1) * sx) * sy;
}

// A tileable grey marble: veins along a turbulent sine.
Image proceduralMarble(int side) {
  Image out(side, side, 3);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const double turbulence = noise(x, y, side, 4) + 0.5 * noise(x, y, side, 8) + 0.25 * noise(x, y, side, 16);
      const double vein = std::pow(std::abs(std::sin(6.283185307179586 * (double(x + y) / side + 1.5 * turbulence))), 0.35);
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = float(0.25 + 0.7 * vein - 0.05 * c * (1 - vein));
    }
  return out;
}

// The stages a run reports through its context (masks, level k/n), with their seconds.
struct StageLog {
  std::mutex mutex;
  std::vector<std::pair<std::string, double>> stages;
  ProgressSink sink() {
    return [this](const ProgressEvent& e) {
      if (e.kind != ProgressEvent::Kind::End) return;
      const std::lock_guard lock(mutex);
      stages.emplace_back(std::string(e.stage), e.seconds);
    };
  }
};

struct Timing {
  double seconds = 1e300;  // best of the repetitions
  vulkan::DeviceProfile profile;
  std::vector<std::pair<std::string, double>> stages;
};

// The best of `reps` runs of `run` (whose `prepare` is not timed); on the device, its profile.
template <class Result>
Timing timeRuns(int reps, const std::function<void()>& prepare, const std::function<Result()>& run, Result& result,
                vulkan::Device* device, StageLog& log) {
  Timing t;
  for (int r = 0; r < reps; ++r) {
    prepare();
    log.stages.clear();
    if (device) device->setProfiling(true);
    const auto start = Clock::now();
    result = run();
    const double s = std::chrono::duration<double>(Clock::now() - start).count();
    if (s < t.seconds) {
      t.seconds = s;
      t.stages = log.stages;
      if (device) t.profile = device->profile();
    }
  }
  if (device) device->setProfiling(false);
  return t;
}

void printHeader() {
  std::printf("%-7s %-22s %10s %10s %7s | %9s %9s %9s %9s %8s %8s %6s | %s\n", "case", "size", "cpu_ms", "vulkan_ms",
              "ratio", "upload", "dispatch", "download", "submits", "up_MiB", "down_MiB", "n_sub", "identical");
}

void printRow(const std::string& name, const std::string& size, const Timing& cpu, const Timing& gpu, bool identical) {
  const vulkan::DeviceProfile& p = gpu.profile;
  std::printf("%-7s %-22s %10.2f %10.2f %7.2f | %9.2f %9.2f %9.2f %9.2f %8.1f %8.1f %6llu | %s\n", name.c_str(),
              size.c_str(), cpu.seconds * 1e3, gpu.seconds * 1e3, gpu.seconds / cpu.seconds, p.uploadSeconds * 1e3,
              p.dispatchSeconds * 1e3, p.downloadSeconds * 1e3, p.submitSeconds * 1e3, double(p.uploadBytes) / (1 << 20),
              double(p.downloadBytes) / (1 << 20), static_cast<unsigned long long>(p.submits), identical ? "yes" : "NO");
  std::fflush(stdout);
}

// Where the time of the best run went: its stages, and on the device the buffers it created.
void printStages(const char* backend, const Timing& t) {
  std::printf("  %-6s", backend);
  for (const auto& [stage, seconds] : t.stages) std::printf(" %s %.2f,", stage.c_str(), seconds * 1e3);
  if (t.profile.allocations)
    std::printf(" buffers %.2f (%llu)", t.profile.allocateSeconds * 1e3,
                static_cast<unsigned long long>(t.profile.allocations));
  std::printf("\n");
}

// Runs one case on both backends (a warm-up run on the device first: pipelines compile at their
// first dispatch) and prints its row; returns whether the outputs are equal.
template <class Result>
bool compare(const Args& args, vulkan::Device& device, const std::string& name, const std::string& size,
             const std::function<void()>& prepare, const std::function<Result(const Context&)>& run,
             Timing* deviceTiming = nullptr) {
  StageLog log;
  const Context cpuCtx{.threads = args.threads, .progress = log.sink()};
  const Context gpuCtx{.threads = args.threads, .backend = Backend::Vulkan, .device = args.device, .progress = log.sink()};
  Result cpu, gpu;
  const Timing tc = timeRuns<Result>(args.reps, prepare, [&] { return run(cpuCtx); }, cpu, nullptr, log);
  prepare();
  run(gpuCtx);
  const Timing tg = timeRuns<Result>(args.reps, prepare, [&] { return run(gpuCtx); }, gpu, &device, log);
  printRow(name, size, tc, tg, cpu == gpu);
  printStages("cpu", tc);
  printStages("vulkan", tg);
  if (deviceTiming) *deviceTiming = tg;
  return cpu == gpu;
}

std::vector<Voxel> shell(int r) {
  std::vector<Voxel> v;
  for (int z = -r - 1; z <= r + 1; ++z)
    for (int y = -r - 1; y <= r + 1; ++y)
      for (int x = -r - 1; x <= r + 1; ++x) {
        const double d2 = double(x) * x + double(y) * y + double(z) * z;
        if (d2 >= (r - 0.5) * (r - 0.5) && d2 < (r + 0.5) * (r + 0.5)) v.push_back({x, y, z});
      }
  return v;
}

// The tile cases: a box (with the kernel's rate and bandwidth), a cut plane and a shell.
bool runTiles(const Args& args, vulkan::Device& device, const SolidAnalysis& lazy,
              const std::function<bool(const char*)>& wants) {
  SolidAnalysis a = lazy;
  const auto start = Clock::now();
  a.tiles = std::make_shared<const SolidTileSet>(
      buildSolidTiles(a, SolidTileOptions{.tileSide = args.tileSide}, Context{.threads = args.threads}));
  std::printf("tile set: %d-voxel tiles, %.1f MiB, built in %.1f s\n", a.tiles->layout.side,
              double(a.tiles->elements.size() * sizeof(Triple)) / (1 << 20),
              std::chrono::duration<double>(Clock::now() - start).count());
  const SolidSynthesisOptions o{.method = SolidMethod::Tiles};
  const std::function<void()> nothing = [] {};
  bool identical = true;
  if (wants("tiles-box")) {
    const int n = args.tilesBox;
    Timing t;
    identical &= compare<std::vector<Triple>>(
        args, device, "tiles-box", std::to_string(n) + "^3", nothing,
        [&](const Context& ctx) { return synthesizeSolidBox(a, {0, 0, 0, n, n, n}, o, nullptr, ctx).triples; }, &t);
    const double voxels = double(n) * n * n, kernel = t.profile.dispatchSeconds;
    if (kernel > 0) {
      const double written = voxels * double(sizeof(Triple)) / kernel / 1e9;
      std::printf("  kernel: %.2f G voxels/s; %.1f GB/s written, %.2f %% of %.0f GB/s\n", voxels / kernel / 1e9, written,
                  100 * written / args.peakGBs, args.peakGBs);
    }
  }
  if (wants("tiles-cut")) {
    const int n = args.cut;
    std::vector<Voxel> plane;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) plane.push_back({x, y, 17});
    identical &= compare<std::vector<Triple>>(args, device, "tiles-cut", std::to_string(n) + "^2", nothing,
                                              [&](const Context& ctx) { return synthesizeSolid(a, plane, o, nullptr, ctx).triples; });
  }
  if (wants("tiles-job")) {
    const std::vector<Voxel> voxels = shell(args.shellRadius);
    identical &= compare<std::vector<Triple>>(
        args, device, "tiles-job", "shell r" + std::to_string(args.shellRadius) + " " + std::to_string(voxels.size()) + "vx",
        nothing, [&](const Context& ctx) { return synthesizeSolid(a, voxels, o, nullptr, ctx).triples; });
  }
  return identical;
}

int runBench(const Args& args) {
  const std::shared_ptr<vulkan::Device> device = vulkan::sharedDevice(args.device);
  const vulkan::DeviceInfo& info = device->info();
  std::printf("device %d: %s (%s; %s; Vulkan %s; %.1f GiB)\n", info.index, info.name.c_str(), info.type.c_str(),
              info.driver.c_str(), info.apiVersion.c_str(), double(info.memoryBytes) / double(1 << 30));
  const Image exemplar = args.exemplar.empty() ? proceduralMarble(args.exemplarSide) : readPnm(args.exemplar, args.exemplarSide);
  std::printf("exemplar: %s, %dx%d; best of %d runs; times in ms (device columns: timestamps; submits: host wall)\n",
              args.exemplar.empty() ? "procedural marble" : args.exemplar.c_str(), exemplar.width, exemplar.height,
              args.reps);
  const auto wants = [&](const char* c) { return std::find(args.cases.begin(), args.cases.end(), c) != args.cases.end(); };
  const Context analysisCtx{.threads = args.threads};
  bool identical = true;
  const std::function<void()> nothing = [] {};
  printHeader();
  if (wants("2d")) {
    const ExemplarAnalysis a = analyzeExemplar(exemplar, {}, analysisCtx);
    const int n = args.size2d;
    identical &= compare<std::vector<uint32_t>>(args, *device, "2d", std::to_string(n) + "^2", nothing,
                                                [&](const Context& ctx) {
                                                  return synthesize2d(a, {0, 0, n, n}, {}, ctx).coords.coords;
                                                });
  }
  if (!wants("cut") && !wants("volume") && !wants("job") && !wants("tiles-box") && !wants("tiles-cut") &&
      !wants("tiles-job"))
    return identical ? 0 : 1;
  const SolidAnalysis a = analyzeSolid(exemplar, exemplar, exemplar, {}, analysisCtx);
  const auto triples = [](const SolidSynthesisResult& r) { return r.triples; };
  if (wants("cut")) {
    // Coarse levels cached by the plane below (not timed), as when a cut slides through a model.
    const int n = args.cut;
    std::vector<Voxel> below, plane;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        below.push_back({x, y, 16});
        plane.push_back({x, y, 17});
      }
    SolidLevelCache cache;
    const auto prepare = [&] {  // the cache holds the same values whichever backend fills it
      cache.clear();
      synthesizeSolid(a, below, {}, &cache, analysisCtx);
    };
    identical &= compare<std::vector<Triple>>(args, *device, "cut", std::to_string(n) + "^2 cached", prepare,
                                              [&](const Context& ctx) {
                                                return triples(synthesizeSolid(a, plane, {}, &cache, ctx));
                                              });
  }
  if (wants("volume")) {
    const int n = args.volume;
    identical &= compare<std::vector<Triple>>(args, *device, "volume", std::to_string(n) + "^3", nothing,
                                              [&](const Context& ctx) {
                                                return triples(synthesizeSolidBox(a, {0, 0, 0, n, n, n}, {}, nullptr, ctx));
                                              });
  }
  if (wants("job")) {
    const std::vector<Voxel> voxels = shell(args.shellRadius);
    identical &= compare<std::vector<Triple>>(args, *device, "job",
                                              "shell r" + std::to_string(args.shellRadius) + " " +
                                                  std::to_string(voxels.size()) + "vx",
                                              nothing, [&](const Context& ctx) {
                                                return triples(synthesizeSolid(a, voxels, {}, nullptr, ctx));
                                              });
  }
  if (wants("tiles-box") || wants("tiles-cut") || wants("tiles-job")) identical &= runTiles(args, *device, a, wants);
  return identical ? 0 : 1;
}

} // namespace

int main(int argc, char** argv) {
  const Args args = parseArgs(argc, argv);
  try {
    return runBench(args);
  } catch (const Error& e) {
    std::fprintf(stderr, "vulkan_bench: error: %s\n", e.what());
    return 2;
  }
}
