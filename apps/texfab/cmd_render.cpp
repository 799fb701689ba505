// SPDX-License-Identifier: GPL-3.0-or-later
// texfab render: a ray-traced preview picture of a model (Embree), or a turntable of them.
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/text.h"
#include "geometry/io/mesh_io.h"
#include "render/preview_renderer.h"

#include <cstdio>
#include <memory>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct RenderJob {
  std::string model, output;
  render::RenderOptions options;
  int turntable = 0;
  float zoom = 1;
  UpChoice up;
  CommonFlags common;
};

// "transparent", a name, "#rrggbb", or "r,g,b" in 0..1 (sRGB).
bool parseBackground(const std::string& text, Eigen::Vector3f& color) {
  if (text == "transparent") return false;
  if (text == "white") color = {1, 1, 1};
  else if (text == "black") color = {0, 0, 0};
  else if (text == "grey" || text == "gray") color = {0.5f, 0.5f, 0.5f};
  else if (text.size() == 7 && text[0] == '#') {
    for (int k = 0; k < 3; ++k) {
      const std::string hex = text.substr(size_t(1 + 2 * k), 2);
      if (hex.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos)
        throw CLI::ValidationError("--background", "'" + text + "' is not a colour");
      color[k] = float(std::stoi(hex, nullptr, 16)) / 255.0f;
    }
  } else {
    if (text.find(',') == std::string::npos)
      throw CLI::ValidationError("--background", "expected transparent, white, black, grey, #rrggbb or R,G,B");
    const std::vector<double> v = parseNumbers("--background", text, 3, {0, 1});
    color = Eigen::Vector3f(float(v[0]), float(v[1]), float(v[2]));
  }
  return true;
}

fs::path turntableName(const fs::path& output, int index) {
  char suffix[16];
  std::snprintf(suffix, sizeof suffix, "_%03d", index);
  return output.parent_path() / (output.stem().string() + suffix + output.extension().string());
}

void runRender(RenderJob& job) {
  Run run("render", job.common);
  const int views = std::max(job.turntable, 1);
  checkImageWritable(job.output);
  std::vector<fs::path> outputs;
  for (int i = 0; i < views; ++i) outputs.push_back(run.output(job.turntable ? turntableName(job.output, i) : fs::path(job.output)));

  Stage load(run.ctx(), "load");
  const geometry::Mesh mesh = geometry::readMesh(job.model, run.ctx());
  load.finish(job.model + ": " + counted(int64_t(mesh.triangleCount()), "triangle"));
  render::RenderOptions options = job.options;
  options.up = geometry::upVector(upAxisFor(job.up, job.model));
  options.normalMapCache = run.analysisCache();
  options.margin = job.options.margin / job.zoom;
  run.checkMemory(render::renderMemoryBytes(mesh, options),
                  "a " + std::to_string(options.width) + "x" + std::to_string(options.height) + " render");
  Stage bvh(run.ctx(), "bvh");
  const render::PreviewRenderer renderer(mesh);
  bvh.finish();
  for (int i = 0; i < views; ++i) {
    Stage stage(run.ctx(), "render");
    if (job.turntable) options.azimuthDegrees = job.options.azimuthDegrees + 360.0f * float(i) / float(views);
    writeImage(renderer.render(options, stage.inner()), outputs[size_t(i)]);
    stage.finish(std::to_string(options.width) + "x" + std::to_string(options.height) + ", " +
                 std::to_string(options.samplesPerPixel) + " spp, azimuth " + figure(options.azimuthDegrees));
  }
  run.finish();
}

} // namespace

Command addRenderCommand(CLI::App& root) {
  auto job = std::make_shared<RenderJob>();
  render::RenderOptions& o = job->options;
  Flags f(root.add_subcommand("render", "Ray-traced preview picture of a model (textures, normal maps, key light, "
                                        "ambient occlusion; framed tightly)"));
  f.input("model", job->model, "Model (.obj, .ply, .off, .stl, .gltf, .glb)");
  f.text("-o,--output", job->output, "Output image (.png); with --turntable, NAME_000.png, NAME_001.png, ...")
      ->required();
  f.size("--size", o.width, o.height, "Image size", {1, 16384});
  f.up(job->up);
  f.camera(o);
  f.option("--turntable", job->turntable, "Render N views evenly around the model instead of one", {0, 3600})
      ->default_str("");
  f.option("--spp", o.samplesPerPixel, "Samples per pixel (antialiasing; rounded down to a square)", {1, 4096});
  f.option("--ao", o.aoSamples, "Ambient-occlusion rays per sample (0 = plain sky light)", {0, 64});
  f.option("--zoom", job->zoom, "Magnification of the tight framing (2: the model appears twice as large, cropped)", {0.05, 50});
  f.option("--fov", o.fovYDegrees, "Vertical field of view, degrees", {1, 170});
  CLI::Option* background = f.app()->add_option_function<std::string>(
      "--background",
      [&o](const std::string& text) { o.transparentBackground = !parseBackground(text, o.background); },
      "transparent, white, black, grey, #rrggbb or R,G,B (each 0 to 1)");
  background->type_name("COLOUR");
  background->default_str("white");
  f.common(job->common, Common::Threads | Common::Memory | Common::Quiet);
  return {f.app(), [job] { runRender(*job); }};
}

} // namespace texfab::cli
