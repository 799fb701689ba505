// SPDX-License-Identifier: GPL-3.0-or-later
// texfab solid: lazy solid texture synthesis from 2-D exemplars (Dong, Lefebvre, Tong, Drettakis
// 2008): a whole volume as slices, an arbitrary plane as an image, or colours at listed points.
#include "apps/texfab/analysis.h"
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "apps/texfab/report_json.h"
#include "core/image_io.h"
#include "core/memory.h"
#include "core/text.h"
#include "render/image_stack.h"
#include "render/solid_volume.h"
#include "synthesis/coord_map.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_solid.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <vector>

namespace texfab::cli {
namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;

namespace {

struct SolidJob {
  std::string exemplar, exemplarY, exemplarZ, output, raw, points;
  int volume = 0;
  bool planeGiven = false;
  Vec3 origin{0, 0, 0}, u{0, 0, 0}, v{0, 0, 0};
  int width = 0, height = 0;
  double scale = 1.0;
  synthesis::SolidSynthesisOptions options;
  SolidMethodChoice method;
  WrapChoice wrap = WrapChoice::Auto;
  CommonFlags common;
};

// The smallest slice measured: the fidelity measure's 7x7 neighbourhoods must fit.
constexpr int kMeasuredSide = 8;

// A slice measured for --report against the exemplar of the axis it lies across (0, 1, 2: E_x,
// E_y, E_z), oriented as that exemplar lies in the volume (solid_analysis.h).
struct MeasuredSlice {
  std::string name;
  int axis = 2;
  Image image;
};

// What one mode synthesized, for the report.
struct Synthesized {
  std::vector<synthesis::SolidLevelStats> levels;
  int64_t requested = 0;
  synthesis::SolidLevelCache cache;
  std::vector<MeasuredSlice> slices;
};

// The middle slice of an n^3 volume across each axis, gathered from its z slices as they come.
class MiddleSlices {
public:
  explicit MiddleSlices(int n) : n_(n) {}
  void add(const Image& slice) {
    if (x_.empty()) x_ = y_ = Image(n_, n_, slice.channels);
    const int m = n_ / 2;
    for (int i = 0; i < n_; ++i)
      for (int c = 0; c < slice.channels; ++c) {
        x_.at(i, z_, c) = slice.at(m, i, c);  // E_x: u = y, v = z
        y_.at(z_, i, c) = slice.at(i, m, c);  // E_y: u = z, v = x
      }
    if (z_ == m) middle_ = slice;
    ++z_;
  }
  std::vector<MeasuredSlice> take() {
    return {{"x", 0, std::move(x_)}, {"y", 1, std::move(y_)}, {"z", 2, std::move(middle_)}};
  }

private:
  int n_, z_ = 0;
  Image x_, y_, middle_;
};

// A synthesized voxel of an output position: voxels are `scale` output units wide.
synthesis::Voxel voxelAt(const Vec3& p, double scale) {
  return {int64_t(std::floor(p.x() / scale)), int64_t(std::floor(p.y() / scale)), int64_t(std::floor(p.z() / scale))};
}

void checkPosition(const Vec3& p, double scale, const std::string& where) {
  if (!p.allFinite() || (p / scale).cwiseAbs().maxCoeff() > double(synthesis::kMaxSolidPosition))
    throw Error(where + ": position is not finite or out of range (|p / scale| <= 2^30)");
}

std::vector<Vec3> readPoints(const std::string& path, double scale) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open point file");
  std::vector<Vec3> points;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line.resize(std::min(line.find('#'), line.size()));
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t' || c == '\r') c = ' ';
    std::istringstream fields(line);
    std::vector<std::string> items;
    for (std::string item; fields >> item;) items.push_back(item);
    if (items.empty()) continue;
    const std::string where = path + ":" + std::to_string(number);
    if (items.size() != 3) throw Error(where + ": expected 3 coordinates 'x y z', found " + std::to_string(items.size()));
    Vec3 p;
    for (int i = 0; i < 3; ++i) {
      char* end = nullptr;
      p[i] = std::strtod(items[size_t(i)].c_str(), &end);
      if (end == items[size_t(i)].c_str() || *end != '\0') throw Error(where + ": '" + items[size_t(i)] + "' is not a number");
    }
    checkPosition(p, scale, where);
    points.push_back(p);
  }
  if (points.empty()) throw Error(path + ": no points");
  return points;
}

// --volume N: slices into a new folder (and the raw file), as an image stack.
std::function<Synthesized(const synthesis::SolidAnalysis&, const render::SolidExemplars&)> prepareVolume(
    const SolidJob& job, Run& run) {
  const int n = job.volume;
  run.checkMemory(render::solidVolumeMemoryBytes(n, job.scale, job.options.refinePasses), "--volume " + std::to_string(n));
  if (!job.raw.empty()) {
    std::error_code ec;
    const auto space = fs::space(fs::absolute(job.raw).parent_path(), ec);
    const double bytes = double(n) * n * n * 3;
    if (!ec && double(space.available) < bytes)
      throw Error(job.raw + ": needs " + figure(bytes / 1073741824.0) + " GiB of disk, only " +
                  figure(double(space.available) / 1073741824.0) + " GiB free");
  }
  auto stack = std::make_shared<render::ImageStackWriter>(run.outputs(), job.output, render::ImageStackOptions{.raw = job.raw});
  return [&job, &run, stack, n](const synthesis::SolidAnalysis& analysis, const render::SolidExemplars& e) {
    Synthesized s;
    std::optional<MiddleSlices> middle;
    if (run.reporting() && n >= kMeasuredSide) middle.emplace(n);
    Stage stage(run.ctx(), "synthesis");
    // The coarse-level cache pays across slabs; within one slab, whole 8^3 bricks at coarse levels
    // cost more than they save (a 64^3 volume: 7.9 instead of 6.1 voxels synthesized per voxel).
    const render::SolidVolumeResult r = render::synthesizeSolidVolume(
        analysis, e, n, job.scale, job.options, n > 128 ? &s.cache : nullptr,
        [&](const Image& slice) {
          stack->write(slice);
          if (middle) middle->add(slice);
        },
        stage.inner());
    stack->finish();
    if (middle) s.slices = middle->take();
    stage.finish(std::to_string(n) + "^3 voxels, " + counted(stack->count(), "slice"));
    s.levels = r.levels;
    s.requested = r.requestedVoxels;
    return s;
  };
}

// --plane ORIGIN,U,V --size WxH: an image of the plane.
std::function<Synthesized(const synthesis::SolidAnalysis&, const render::SolidExemplars&)> preparePlane(
    const SolidJob& job, Run& run) {
  if (job.width == 0) throw UsageError("--plane needs --size WxH");
  for (const Vec3& corner : {job.origin, Vec3(job.origin + job.width * job.u), Vec3(job.origin + job.height * job.v),
                             Vec3(job.origin + job.width * job.u + job.height * job.v)})
    checkPosition(corner, job.scale, "--plane");
  run.checkMemory(synthesis::synthesizeSolidMemoryBytes(int64_t(job.width) * job.height, job.options.refinePasses),
              "a " + std::to_string(job.width) + "x" + std::to_string(job.height) + " plane");
  checkImageWritable(job.output);
  const fs::path out = run.output(job.output);
  return [&job, &run, out](const synthesis::SolidAnalysis& analysis, const render::SolidExemplars& e) {
    Synthesized s;
    Stage stage(run.ctx(), "synthesis");
    std::vector<synthesis::Voxel> voxels;
    for (int j = 0; j < job.height; ++j)
      for (int i = 0; i < job.width; ++i) voxels.push_back(voxelAt(job.origin + (i + 0.5) * job.u + (j + 0.5) * job.v, job.scale));
    const synthesis::SolidSynthesisResult r = synthesizeSolid(analysis, voxels, job.options, nullptr, stage.inner());
    stage.finish(std::to_string(job.width) + "x" + std::to_string(job.height));
    Stage write(run.ctx(), "write");
    Image image = render::solidColorImage(r.triples, e, job.width, job.height);
    writeImage(image, out);
    write.finish(job.output);
    if (run.reporting() && std::min(job.width, job.height) >= kMeasuredSide) {
      // Against the exemplar of the axis nearest the plane's normal.
      Eigen::Index axis = 2;
      job.u.cross(job.v).cwiseAbs().maxCoeff(&axis);
      s.slices.push_back({"plane", int(axis), std::move(image)});
    }
    s.levels = r.levels;
    s.requested = int64_t(voxels.size());
    return s;
  };
}

// --points FILE: one line per point, "x y z  colour  exemplar coordinates".
std::function<Synthesized(const synthesis::SolidAnalysis&, const render::SolidExemplars&)> preparePoints(
    const SolidJob& job, Run& run) {
  auto points = std::make_shared<std::vector<Vec3>>(readPoints(job.points, job.scale));
  const fs::path out = run.output(job.output);
  return [&job, &run, out, points](const synthesis::SolidAnalysis& analysis, const render::SolidExemplars& e) {
    Synthesized s;
    Stage stage(run.ctx(), "synthesis");
    std::vector<synthesis::Voxel> voxels;
    for (const Vec3& p : *points) voxels.push_back(voxelAt(p, job.scale));
    const synthesis::SolidSynthesisResult r = synthesizeSolid(analysis, voxels, job.options, nullptr, stage.inner());
    const Image colors = render::solidColorImage(r.triples, e, int(points->size()), 1);
    stage.finish(counted(int64_t(points->size()), "point"));
    Stage write(run.ctx(), "write");
    writeFileAtomically(out, [&](std::ostream& file) {
      file << "# x y z  colour (" << colors.channels << " channels, 0..1)  exemplar coordinates: Ex u v, Ey u v, Ez u v\n";
      char line[256];
      for (size_t i = 0; i < points->size(); ++i) {
        const Vec3& p = (*points)[i];
        int k = std::snprintf(line, sizeof line, "%.9g %.9g %.9g", p.x(), p.y(), p.z());
        for (int c = 0; c < colors.channels; ++c)
          k += std::snprintf(line + k, sizeof line - size_t(k), " %.6f", colors.pixels[i * size_t(colors.channels) + size_t(c)]);
        for (uint32_t coord : r.triples[i])
          k += std::snprintf(line + k, sizeof line - size_t(k), " %u %u", synthesis::coordU(coord), synthesis::coordV(coord));
        file << line << '\n';
      }
    });
    write.finish(job.output);
    s.levels = r.levels;
    s.requested = int64_t(voxels.size());
    return s;
  };
}

// --report: each slice's quality measures against its exemplar, and its fidelity and completeness
// against those of a 2-D synthesis of the same size from that exemplar (the ratios).
nlohmann::json measureSlices(Run& run, std::span<const MeasuredSlice> slices, const render::SolidExemplars& e) {
  const Image* exemplars[3] = {&e.x, &e.y, &e.z};
  // One baseline per distinct exemplar: the slices of a request all have one size.
  std::vector<std::pair<const Image*, synthesis::QualityReport>> baselines;
  auto baselineOf = [&](const Image& ex, const Image& slice) -> const synthesis::QualityReport& {
    for (const auto& [image, b] : baselines)
      if (image->width == ex.width && image->height == ex.height && image->pixels == ex.pixels) return b;
    bool cached = false;
    const synthesis::ExemplarAnalysis analysis = analyzeExemplar(run, ex, {}, cached);
    Stage stage(run.ctx(), "2-D baseline");
    auto b = synthesis::measureSynthesisBaseline(analysis, ex, slice.width, slice.height, {}, stage.inner());
    stage.finish("contrast " + figure(b.contrast) + ", fidelity " + figure(b.fidelity));
    return baselines.emplace_back(&ex, b).second;
  };
  nlohmann::json j = nlohmann::json::object();
  double contrast = 0, ratio = 0, completeness = 0;
  for (const MeasuredSlice& slice : slices) {
    const Image& ex = *exemplars[slice.axis];
    const synthesis::QualityReport& b = baselineOf(ex, slice.image);
    Stage stage(run.ctx(), "measures " + slice.name);
    const synthesis::QualityReport q =
        synthesis::measureQuality(slice.image, synthesis::solidColorView(ex, slice.image.channels), nullptr, {},
                                  stage.inner());
    stage.finish("contrast " + figure(q.contrast) + ", fidelity " + figure(q.fidelity / b.fidelity) +
                 "x and completeness " + figure(q.completeness / b.completeness) + "x 2-D synthesis'");
    j[slice.name] = toJson(q, b);
    contrast += q.contrast / double(slices.size());
    ratio += q.fidelity / b.fidelity / double(slices.size());
    completeness += q.completeness / b.completeness / double(slices.size());
  }
  run.note("slices keep " + figure(100 * contrast) + " % of the exemplar's contrast; their fidelity is " +
           figure(ratio) + "x and their completeness " + figure(completeness) +
           "x a 2-D synthesis' (1 = as faithful, as complete)");
  return {{"slices", j}, {"contrast_ratio", contrast}, {"fidelity_ratio", ratio}, {"completeness_ratio", completeness}};
}

void runSolid(SolidJob& job) {
  Run run("solid", job.common);
  job.options.method = job.method.method;
  // One mode, checked with its outputs before any work.
  if ((job.volume != 0) + job.planeGiven + !job.points.empty() != 1)
    throw UsageError("choose exactly one of --volume N, --plane ORIGIN,U,V or --points FILE");
  if (!job.raw.empty() && job.volume == 0) throw UsageError("--raw: only with --volume");
  if (job.width != 0 && !job.planeGiven) throw UsageError("--size: only with --plane");
  const auto synthesize = job.volume ? prepareVolume(job, run) : job.planeGiven ? preparePlane(job, run) : preparePoints(job, run);

  Stage load(run.ctx(), "load");
  const std::string pathY = job.exemplarY.empty() ? job.exemplar : job.exemplarY;
  const std::string pathZ = job.exemplarZ.empty() ? job.exemplar : job.exemplarZ;
  const Image ex = readImage(job.exemplar);
  const Image ey = job.exemplarY.empty() ? ex : readImage(job.exemplarY);
  const Image ez = job.exemplarZ.empty() ? ex : readImage(job.exemplarZ);
  synthesis::validateSolidExemplars(ex, ey, ez, {job.exemplar, pathY, pathZ});
  load.finish(job.exemplar + " " + std::to_string(ex.width) + "x" + std::to_string(ex.height));
  bool cached = false;
  const synthesis::SolidAnalysis analysis = analyzeSolid(run, ex, ey, ez, {}, job.wrap, cached, job.method);
  const Synthesized s = synthesize(analysis, {ex, ey, ez});
  if (!s.slices.empty()) run.report()["measures"] = measureSlices(run, s.slices, {ex, ey, ez});

  nlohmann::json& r = run.report();
  r["exemplars"] = {{"x", job.exemplar}, {"y", pathY}, {"z", pathZ}, {"width", ex.width}, {"height", ex.height},
                    {"shared_candidates", analysis.shared}, {"analysis_cached", cached},
                    {"analysis_seconds", analysis.stats.seconds},
                    {"mean_candidates_kept", analysis.stats.meanCandidatesBeforeFilter},
                    {"mean_candidates_coherent", analysis.stats.meanCandidatesAfterFilter}};
  const synthesis::SolidSynthesisOptions& o = job.options;
  r["parameters"] = {{"seed", o.seed}, {"jitter", o.jitter}, {"offset_cells", o.offsetCells},
                     {"passes", o.passes}, {"finest_passes", o.finestPasses}, {"subpasses", o.subpasses()},
                     {"method", synthesis::toString(o.method)}, {"contrast_gain", o.contrastGain},
                     {"refine_passes", o.refinePasses},
                     {"scale", job.scale}, {"exemplar_wrap", toString(analysis.wrap)}};
  int64_t synthesized = 0;
  for (const synthesis::SolidLevelStats& l : s.levels) synthesized += l.voxels;
  r["levels"] = toJson(s.levels);
  r["requested_voxels"] = s.requested;
  r["synthesized_voxels"] = synthesized;
  r["synthesized_per_requested"] = s.requested > 0 ? double(synthesized) / double(s.requested) : 0.0;
  r["coarse_cache"] = {{"bytes", s.cache.bytes()}, {"hits", s.cache.hits()}, {"misses", s.cache.misses()}};
  run.finish();
}

} // namespace

Command addSolidCommand(CLI::App& root) {
  auto job = std::make_shared<SolidJob>();
  synthesis::SolidSynthesisOptions& o = job->options;
  Flags f(root.add_subcommand(
      "solid", "Solid texture from 2-D exemplars, voxels on demand (lazy solid synthesis, Dong et al. 2008, or "
               "a set of matching solid tiles with --solid-method tiles): a volume as slices, any plane as an "
               "image, or colours at listed points. The volume is infinite and deterministic: the same voxel "
               "always gets the same colour."));
  f.input("exemplar", job->exemplar,
          "Exemplar image, used for all three axes unless --exemplar-y/--exemplar-z are given "
          "(E_x lies in the y-z plane, E_y in z-x, E_z in x-y); 8x8 to 512x512. The precomputation, cached, "
          "takes about 8 s at 128x128, 1 min at 256x256, 15 min at 512x512 on 2 cores");
  f.text("--exemplar-y", job->exemplarY, "Exemplar for the z-x planes (same size as EXEMPLAR)");
  f.text("--exemplar-z", job->exemplarZ, "Exemplar for the x-y planes (same size as EXEMPLAR)");
  f.text("-o,--output", job->output,
         "Output: a new folder for --volume (slice_00000.png, ...), an image for --plane, a text file for "
         "--points (x y z colour exemplar-coordinates per line)")
      ->required();
  f.option("--volume", job->volume, "Synthesize the N^3 volume at the origin, one PNG per z slice", {1, kMaxImageSide})
      ->default_str("");
  f.text("--raw", job->raw, "With --volume: also write the volume as raw 8-bit RGB, x fastest, then y, z");
  f.numbers("--plane", 9, "OX,OY,OZ,UX,UY,UZ,VX,VY,VZ",
            "An image of the plane through ORIGIN; pixel (i, j) shows ORIGIN + (i+0.5) U + (j+0.5) V "
            "(oblique planes welcome)",
            {}, false, [job](const std::vector<double>& p) {
              job->origin = {p[0], p[1], p[2]};
              job->u = {p[3], p[4], p[5]};
              job->v = {p[6], p[7], p[8]};
              if (job->u.norm() == 0 || job->v.norm() == 0)
                throw CLI::ValidationError("--plane", std::string("the axis ") + (job->u.norm() == 0 ? "U" : "V") + " is zero");
              if (job->u.cross(job->v).norm() <= 1e-9 * job->u.norm() * job->v.norm())
                throw CLI::ValidationError("--plane", "the axes U and V are parallel");
              job->planeGiven = true;
            });
  f.size("--size", job->width, job->height, "With --plane: image size", {1, kMaxImageSide})->default_str("");
  f.text("--points", job->points, "Text file of positions, 'x y z' per line (# comments)");
  f.option("--seed", o.seed, "Random seed: the only source of variation");
  f.option("--voxel-size", job->scale, "Output units per synthesized voxel (2 = texture twice as large)", positive(1e6));
  f.option("--jitter", o.jitter, "Strength of the random warp applied once after initialization", {0, 4});
  f.option("--offset-cells", o.offsetCells,
           "Side, in voxels of the coarsest level, of the cells that each start from the exemplar at their own random "
           "offset (0 = one tiling, as in the paper, which repeats with the exemplar's period)",
           {0, 1024});
  wrapFlag(f, job->wrap);
  solidFidelityFlags(f, job->method, o.contrastGain, o.refinePasses, "");
  f.option("--passes", o.passes, "Correction passes per level above the finest", {0, 4});
  f.option("--finest-passes", o.finestPasses,
           "Correction passes at the finest level (the paper: 2, about 3x the finest level's work)", {0, 4});
  f.option("--interleave", o.interleave,
           "2: 8 sub-passes per pass, as in the paper; 1: one (a far shorter dependency chain)", {1, 2});
  f.common(job->common, Common::Threads | Common::Memory | Common::Report | Common::Cache | Common::Backend | Common::Quiet);
  return {f.app(), [job] { runSolid(*job); }};
}

} // namespace texfab::cli
