// SPDX-License-Identifier: GPL-3.0-or-later
// texfab solid: lazy solid texture synthesis from 2-D exemplars (Dong, Lefebvre, Tong, Drettakis
// 2008): a whole volume as slices, an arbitrary plane as an image, or colours at listed points.
#include "apps/texfab/backend_flags.h"
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "render/image/error.h"
#include "render/image/memory.h"
#include "render/image/files.h"
#include "render/image/image_io.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_solid.h"

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct SolidArgs {
  std::string exemplar, exemplarY, exemplarZ;
  std::string output;
  int volume = 0;
  std::string raw;
  std::string plane;
  std::string size;
  std::string points;
  uint32_t seed = 1;
  double scale = 1.0;
  float jitter = synthesis::SolidSynthesisOptions{}.jitter;
  int passes = synthesis::SolidSynthesisOptions{}.passes;
  int finestPasses = synthesis::SolidSynthesisOptions{}.finestPasses;
  int interleave = synthesis::SolidSynthesisOptions{}.interleave;
  int threads = 0;
  BackendFlags backend;
  std::string report;
  std::string cacheDir;
  bool noCache = false;
  bool quiet = false;
};

using Vec3 = std::array<double, 3>;

// A synthesized voxel of an output position: voxels are `scale` output units wide.
synthesis::Voxel voxelAt(const Vec3& p, double scale) {
  return {int64_t(std::floor(p[0] / scale)), int64_t(std::floor(p[1] / scale)), int64_t(std::floor(p[2] / scale))};
}

void checkPosition(const Vec3& p, double scale, const std::string& where) {
  for (double v : p)
    if (!std::isfinite(v) || std::abs(v / scale) > double(synthesis::kMaxSolidPosition))
      throw Error(where + ": position is not finite or out of range (|p / scale| <= 2^30)");
}

std::vector<Vec3> readPoints(const std::string& path, double scale) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open point file");
  std::vector<Vec3> points;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t' || c == '\r') c = ' ';
    std::istringstream fields(line);
    std::vector<std::string> items;
    for (std::string item; fields >> item;) items.push_back(item);
    if (items.empty()) continue;
    const std::string where = path + ":" + std::to_string(number);
    if (items.size() != 3) throw Error(where + ": expected 3 coordinates 'x y z', found " + std::to_string(items.size()));
    Vec3 p{};
    for (int i = 0; i < 3; ++i) {
      char* end = nullptr;
      p[size_t(i)] = std::strtod(items[size_t(i)].c_str(), &end);
      if (end == items[size_t(i)].c_str() || *end != '\0') throw Error(where + ": '" + items[size_t(i)] + "' is not a number");
    }
    checkPosition(p, scale, where);
    points.push_back(p);
  }
  if (points.empty()) throw Error(path + ": no points");
  return points;
}

// Bytes of physical memory, for refusing volumes that cannot fit.
double physicalMemoryBytes() {
  return double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
}

std::string gib(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f GiB", bytes / double(1u << 30));
  return text;
}

Image loadExemplar(const std::string& path) {
  return readImage(path);  // names the file in its errors
}

void runSolid(const SolidArgs& args) {
  using namespace synthesis;
  Progress progress("texfab solid", args.quiet);
  Context ctx{.threads = args.threads};
  if (const std::string line = applyBackend(args.backend, ctx); !line.empty()) progress.note("backend: " + line);

  // Validate everything before any work: one mode, its parameters, the outputs.
  const int modes = (args.volume != 0) + !args.plane.empty() + !args.points.empty();
  if (modes != 1) throw Error("choose exactly one of --volume N, --plane ORIGIN,U,V or --points FILE");
  if (!(std::isfinite(args.scale) && args.scale > 0 && args.scale <= 1e6))
    throw Error("--scale: must be a positive number of output units per voxel, got " + std::to_string(args.scale));
  SolidSynthesisOptions options;
  options.seed = args.seed;
  options.jitter = args.jitter;
  options.passes = args.passes;
  options.finestPasses = args.finestPasses;
  options.interleave = args.interleave;
  options.validate();
  if (!args.raw.empty() && args.volume == 0) throw Error("--raw: only with --volume");
  if (!args.size.empty() && args.plane.empty()) throw Error("--size: only with --plane");

  Vec3 origin{}, u{}, v{};
  int width = 0, height = 0;
  std::vector<Vec3> points;
  if (args.volume != 0) {
    if (args.volume < 1 || args.volume > kMaxImageSide)
      throw Error("--volume: size must be in [1, " + std::to_string(kMaxImageSide) + "], got " + std::to_string(args.volume));
    const double n = args.volume;
    // Working set: one 128-slice slab of triples and colours (voxels are `scale` slices wide),
    // plus the synthesis of one 128^3 tile.
    const double side = std::ceil(n / args.scale) + 1, slab = std::ceil(std::min(n, 128.0) / args.scale) + 1;
    const double need = side * side * slab * 12 + n * n * std::min(n, 128.0) * 12 + 512.0 * (1 << 20);
    if (need > 0.8 * physicalMemoryBytes())
      throw Error("--volume " + std::to_string(args.volume) + ": needs about " + gib(need) + " of memory, more than " +
                  "this machine can give (" + gib(physicalMemoryBytes()) + ")");
    if (fs::exists(args.output) && !(fs::is_directory(args.output) && fs::is_empty(args.output)))
      throw Error(args.output + ": output folder exists and is not empty");
    if (!args.output.empty() && fs::path(args.output).has_parent_path() && !fs::is_directory(fs::path(args.output).parent_path()))
      throw Error(args.output + ": parent folder does not exist");
    if (!args.raw.empty()) {
      const fs::path parent = fs::path(args.raw).parent_path();
      if (!parent.empty() && !fs::is_directory(parent)) throw Error(args.raw + ": folder does not exist");
      std::error_code ec;
      const auto space = fs::space(parent.empty() ? fs::path(".") : parent, ec);
      const double bytes = n * n * n * 3;
      if (!ec && double(space.available) < bytes)
        throw Error(args.raw + ": needs " + gib(bytes) + " of disk, only " + gib(double(space.available)) + " free");
    }
  } else if (!args.plane.empty()) {
    const std::vector<double> p = parseNumberList(args.plane, "--plane");
    if (p.size() != 9) throw Error("--plane: expected ORIGIN,U,V as 9 numbers ox,oy,oz,ux,uy,uz,vx,vy,vz, got '" + args.plane + "'");
    for (double x : p)
      if (!std::isfinite(x)) throw Error("--plane: '" + args.plane + "' has a value that is not finite");
    origin = {p[0], p[1], p[2]};
    u = {p[3], p[4], p[5]};
    v = {p[6], p[7], p[8]};
    const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    const double lv = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (lu == 0 || lv == 0) throw Error("--plane: the axis " + std::string(lu == 0 ? "U" : "V") + " is zero");
    const Vec3 c{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    if (std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) <= 1e-9 * lu * lv)
      throw Error("--plane: the axes U and V are parallel");
    if (args.size.empty()) throw Error("--plane needs --size WxH");
    std::tie(width, height) = parseSize(args.size, "--size");
    for (const Vec3& corner : {origin, Vec3{origin[0] + width * u[0], origin[1] + width * u[1], origin[2] + width * u[2]},
                               Vec3{origin[0] + height * v[0], origin[1] + height * v[1], origin[2] + height * v[2]},
                               Vec3{origin[0] + width * u[0] + height * v[0], origin[1] + width * u[1] + height * v[1],
                                    origin[2] + width * u[2] + height * v[2]}})
      checkPosition(corner, args.scale, "--plane");
    if (double(width) * height * 40 > 0.8 * physicalMemoryBytes())
      throw Error("--size " + args.size + ": the plane needs more memory than this machine has");
    checkImageWritable(args.output);
  } else {
    points = readPoints(args.points, args.scale);
    const fs::path parent = fs::path(args.output).parent_path();
    if (!parent.empty() && !fs::is_directory(parent)) throw Error(args.output + ": folder does not exist");
  }

  progress.start("load");
  const Image ex = loadExemplar(args.exemplar);
  const Image ey = args.exemplarY.empty() ? ex : loadExemplar(args.exemplarY);
  const Image ez = args.exemplarZ.empty() ? ex : loadExemplar(args.exemplarZ);
  validateSolidExemplars(ex, ey, ez,
                         {args.exemplar, args.exemplarY.empty() ? args.exemplar : args.exemplarY,
                          args.exemplarZ.empty() ? args.exemplar : args.exemplarZ});
  progress.finish(args.exemplar + " " + std::to_string(ex.width) + "x" + std::to_string(ex.height));

  progress.start("analysis");
  bool cached = false;
  const SolidAnalysisOptions analysisOptions;
  const SolidAnalysis analysis =
      args.noCache ? analyzeSolid(ex, ey, ez, analysisOptions, ctx)
                   : analyzeSolidCached(ex, ey, ez, analysisOptions,
                                        args.cacheDir.empty() ? defaultCacheDir() : fs::path(args.cacheDir),
                                        ctx, &cached);
  progress.finish(cached ? "(cached)" : std::to_string(analysis.levels.size()) + " levels" +
                                            (analysis.shared ? ", candidates shared" : ""));

  const int channels = solidColorChannels(ex, ey, ez);
  SolidLevelCache cache;
  std::vector<SolidLevelStats> levelStats;
  int64_t requested = 0;
  auto accumulate = [&](const SolidSynthesisResult& r) {
    if (levelStats.empty()) levelStats = r.levels;
    else
      for (size_t i = 0; i < r.levels.size(); ++i) {
        levelStats[i].voxels += r.levels[i].voxels;
        levelStats[i].corrections += r.levels[i].corrections;
        levelStats[i].seconds += r.levels[i].seconds;
      }
  };
  auto pixelFormat = [&] {
    return ex.format == PixelFormat::UInt8 && ey.format == PixelFormat::UInt8 && ez.format == PixelFormat::UInt8
               ? PixelFormat::UInt8
               : PixelFormat::UInt16;
  };

  if (args.volume != 0) {
    const int n = args.volume;
    progress.start("synthesis");
    // Write everything into a temporary folder next to the output, then rename it: a failure
    // never leaves a partial volume under the output name.
    const fs::path out = args.output;
    const fs::path tmp = temporaryPathFor(out);
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    fs::path rawTmp;
    std::ofstream raw;
    try {
      if (!args.raw.empty()) {
        rawTmp = temporaryPathFor(args.raw);
        raw.open(rawTmp, std::ios::binary);
        if (!raw) throw Error(args.raw + ": cannot create file");
      }
      auto voxelOf = [&](int i) { return int64_t(std::floor((i + 0.5) / args.scale)); };
      for (int z0 = 0; z0 < n; z0 += 128) {
        const int z1 = std::min(n, z0 + 128);
        const VoxelBox box{voxelOf(0), voxelOf(0), voxelOf(z0), int(voxelOf(n - 1) - voxelOf(0) + 1),
                           int(voxelOf(n - 1) - voxelOf(0) + 1), int(voxelOf(z1 - 1) - voxelOf(z0) + 1)};
        // The coarse-level cache pays across slabs; within one request, whole 8^3 bricks at coarse
        // levels cost more than they save (measured: a 64^3 volume synthesizes 7.9 instead of
        // 6.1 voxels per voxel through it).
        const SolidSynthesisResult r =
            synthesizeSolidBox(analysis, box, options, n > 128 ? &cache : nullptr, ctx);
        accumulate(r);
        std::vector<float> colours;
        solidColors(r.triples, ex, ey, ez, colours);
        for (int z = z0; z < z1; ++z) {
          Image slice(n, n, channels, pixelFormat());
          for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
              const size_t i = (size_t(voxelOf(z) - box.z) * size_t(box.ny) + size_t(voxelOf(y) - box.y)) * size_t(box.nx) +
                               size_t(voxelOf(x) - box.x);
              for (int c = 0; c < channels; ++c) slice.at(x, y, c) = colours[i * size_t(channels) + size_t(c)];
            }
          char name[32];
          std::snprintf(name, sizeof name, "slice_%05d.png", z);
          writeImage(slice, tmp / name);
          if (raw) {
            std::vector<uint8_t> bytes(size_t(n) * n * 3);
            for (size_t i = 0; i < size_t(n) * n; ++i)
              for (int c = 0; c < 3; ++c)
                bytes[i * 3 + size_t(c)] =
                    uint8_t(std::lrint(std::clamp(slice.pixels[i * size_t(channels) + size_t(channels == 3 ? c : 0)], 0.0f, 1.0f) * 255.0f));
            raw.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
          }
        }
      }
      requested = int64_t(n) * n * n;
      if (raw) {
        raw.flush();
        if (!raw) throw Error(args.raw + ": cannot write file");
        raw.close();
      }
      progress.finish(std::to_string(n) + "^3 voxels");
      progress.start("write");
      if (fs::exists(out)) fs::remove(out);  // an empty folder, checked above
      fs::rename(tmp, out);
      if (!rawTmp.empty()) commitFile(rawTmp, args.raw);
      progress.finish(args.output);
    } catch (...) {
      std::error_code ec;
      fs::remove_all(tmp, ec);
      if (!rawTmp.empty()) fs::remove(rawTmp, ec);
      throw;
    }
  } else if (!args.plane.empty()) {
    progress.start("synthesis");
    std::vector<Voxel> voxels(size_t(width) * height);
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i) {
        Vec3 p;
        for (int a = 0; a < 3; ++a) p[size_t(a)] = origin[size_t(a)] + (i + 0.5) * u[size_t(a)] + (j + 0.5) * v[size_t(a)];
        voxels[size_t(j) * width + size_t(i)] = voxelAt(p, args.scale);
      }
    const SolidSynthesisResult r = synthesizeSolid(analysis, voxels, options, nullptr, ctx);
    accumulate(r);
    requested = int64_t(voxels.size());
    std::vector<float> colours;
    solidColors(r.triples, ex, ey, ez, colours);
    Image image(width, height, channels, pixelFormat());
    image.pixels = std::move(colours);
    progress.finish(std::to_string(width) + "x" + std::to_string(height));
    progress.start("write");
    writeImage(image, args.output);
    progress.finish(args.output);
  } else {
    progress.start("synthesis");
    std::vector<Voxel> voxels;
    for (const Vec3& p : points) voxels.push_back(voxelAt(p, args.scale));
    const SolidSynthesisResult r = synthesizeSolid(analysis, voxels, options, nullptr, ctx);
    accumulate(r);
    requested = int64_t(voxels.size());
    std::vector<float> colours;
    solidColors(r.triples, ex, ey, ez, colours);
    progress.finish(std::to_string(points.size()) + " points");
    progress.start("write");
    const fs::path tmp = temporaryPathFor(args.output);
    {
      std::ofstream out(tmp);
      if (!out) throw Error(args.output + ": cannot create file");
      out << "# x y z  colour (" << channels << " channels, 0..1)  exemplar coordinates: Ex u v, Ey u v, Ez u v\n";
      char line[256];
      for (size_t i = 0; i < points.size(); ++i) {
        int k = std::snprintf(line, sizeof line, "%.9g %.9g %.9g", points[i][0], points[i][1], points[i][2]);
        for (int c = 0; c < channels; ++c)
          k += std::snprintf(line + k, sizeof line - size_t(k), " %.6f", colours[i * size_t(channels) + size_t(c)]);
        for (int e = 0; e < 3; ++e)
          k += std::snprintf(line + k, sizeof line - size_t(k), " %u %u", coordU(r.triples[i][size_t(e)]),
                             coordV(r.triples[i][size_t(e)]));
        out << line << '\n';
      }
      out.flush();
      if (!out) {
        out.close();
        std::error_code ec;
        fs::remove(tmp, ec);
        throw Error(args.output + ": cannot write file");
      }
    }
    commitFile(tmp, args.output);
    progress.finish(args.output);
  }

  if (!args.report.empty()) {
    nlohmann::json report;
    report["command"] = "solid";
    report["exemplars"] = {{"x", args.exemplar},
                           {"y", args.exemplarY.empty() ? args.exemplar : args.exemplarY},
                           {"z", args.exemplarZ.empty() ? args.exemplar : args.exemplarZ},
                           {"width", ex.width}, {"height", ex.height}, {"shared_candidates", analysis.shared},
                           {"analysis_cached", cached}, {"analysis_seconds", analysis.stats.seconds},
                           {"mean_candidates_kept", analysis.stats.meanCandidatesBeforeFilter},
                           {"mean_candidates_coherent", analysis.stats.meanCandidatesAfterFilter}};
    report["parameters"] = {{"seed", options.seed}, {"jitter", options.jitter}, {"passes", options.passes},
                            {"finest_passes", options.finestPasses},
                            {"subpasses", options.subpasses()}, {"scale", args.scale}};
    nlohmann::json levels = nlohmann::json::array();
    int64_t synthesized = 0;
    for (const SolidLevelStats& l : levelStats) {
      levels.push_back({{"stack_level", l.stackLevel}, {"voxels", l.voxels}, {"corrections", l.corrections},
                        {"seconds", l.seconds}});
      synthesized += l.voxels;
    }
    report["levels"] = levels;
    report["requested_voxels"] = requested;
    report["synthesized_voxels"] = synthesized;
    report["synthesized_per_requested"] = requested > 0 ? double(synthesized) / double(requested) : 0.0;
    report["coarse_cache"] = {{"bytes", cache.bytes()}, {"hits", cache.hits()}, {"misses", cache.misses()}};
    report["timings"] = progress.timings();
    report["peak_memory_mib"] = peakMemoryMiB();
    writeReport(report, args.report);
  }
}

} // namespace

Command addSolidCommand(CLI::App& root) {
  auto args = std::make_shared<SolidArgs>();
  CLI::App* app = root.add_subcommand(
      "solid", "Solid texture from 2-D exemplars, voxels on demand (lazy solid synthesis, Dong et al. 2008): "
               "a volume as slices, any plane as an image, or colours at listed points. The volume is "
               "infinite and deterministic: the same voxel always gets the same colour.");
  app->add_option("exemplar", args->exemplar,
                  "Exemplar image, used for all three axes unless --exemplar-y/--exemplar-z are given "
                  "(E_x lies in the y-z plane, E_y in z-x, E_z in x-y)")
      ->required();
  app->add_option("--exemplar-y", args->exemplarY, "Exemplar for the z-x planes (same size as EXEMPLAR)");
  app->add_option("--exemplar-z", args->exemplarZ, "Exemplar for the x-y planes (same size as EXEMPLAR)");
  app->add_option("-o,--output", args->output,
                  "Output: a new folder for --volume (slice_00000.png, ...), an image for --plane, a text file for "
                  "--points (x y z colour exemplar-coordinates per line)")
      ->required();
  app->add_option("--volume", args->volume, "Synthesize the N^3 volume at the origin, one PNG per z slice");
  app->add_option("--raw", args->raw, "With --volume: also write the volume as raw 8-bit RGB, x fastest, then y, z");
  app->add_option("--plane", args->plane,
                  "ox,oy,oz,ux,uy,uz,vx,vy,vz: an image of the plane through ORIGIN; pixel (i, j) shows "
                  "ORIGIN + (i+0.5) U + (j+0.5) V (oblique planes welcome)");
  app->add_option("--size", args->size, "With --plane: image size WxH");
  app->add_option("--points", args->points, "Text file of positions, 'x y z' per line (# comments)");
  app->add_option("--seed", args->seed, "Random seed: the only source of variation")->capture_default_str();
  app->add_option("--scale", args->scale, "Output units per synthesized voxel (2 = texture twice as large)")
      ->capture_default_str();
  app->add_option("--jitter", args->jitter, "Strength of the random warp applied once after initialization (0-4)")
      ->capture_default_str();
  app->add_option("--passes", args->passes, "Correction passes per level above the finest (0-4)")->capture_default_str();
  app->add_option("--finest-passes", args->finestPasses,
                  "Correction passes at the finest level (0-4; the paper: 2, about 3x the finest level's work)")
      ->capture_default_str();
  app->add_option("--interleave", args->interleave,
                  "2: 8 sub-passes per pass, as in the paper; 1: one (a far shorter dependency chain)")
      ->capture_default_str();
  app->add_option("--threads", args->threads, "Worker threads (0 = all cores)")->capture_default_str();
  addBackendFlags(*app, args->backend);
  app->add_option("--report", args->report, "Write timings, voxel counts and memory to this JSON file");
  app->add_option("--cache-dir", args->cacheDir, "Analysis cache folder (default: ~/.cache/texfab)");
  app->add_flag("--no-cache", args->noCache, "Neither read nor write the analysis cache");
  app->add_flag("-q,--quiet", args->quiet, "No progress output");
  return {app, [args] { runSolid(*args); }};
}

} // namespace texfab::cli
