// SPDX-License-Identifier: GPL-3.0-or-later
// texfab render: a ray-traced preview picture of a model (Embree), or a turntable of them.
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "geometry/mesh_io.h"
#include "render/image/error.h"
#include "render/image/image_io.h"
#include "render/preview_renderer.h"

#include <cstdio>
#include <memory>

namespace texfab::cli {
namespace fs = std::filesystem;

namespace {

struct RenderArgs {
  std::string model;
  std::string output;
  std::string size = "800";
  float azimuth = 30.0f;
  float elevation = 20.0f;
  int turntable = 0;
  int spp = 16;
  int ao = 1;
  float fov = 35.0f;
  std::string background = "white";
  int threads = 0;
  bool quiet = false;
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
        throw Error("--background: '" + text + "' is not a colour");
      color[k] = float(std::stoi(hex, nullptr, 16)) / 255.0f;
    }
  } else {
    const std::vector<double> v = parseNumberList(text, "--background");
    if (v.size() != 3) throw Error("--background: expected transparent, white, black, grey, #rrggbb or R,G,B");
    for (int k = 0; k < 3; ++k) {
      if (!(v[size_t(k)] >= 0 && v[size_t(k)] <= 1)) throw Error("--background: components must be in 0..1");
      color[k] = float(v[size_t(k)]);
    }
  }
  return true;
}

fs::path turntableName(const fs::path& output, int index) {
  char suffix[16];
  std::snprintf(suffix, sizeof suffix, "_%03d", index);
  return output.parent_path() / (output.stem().string() + suffix + output.extension().string());
}

void runRender(const RenderArgs& args) {
  Progress progress("texfab render", args.quiet);
  Context ctx{.threads = args.threads};
  render::RenderOptions options;
  const auto [w, h] = parseSize(args.size, "--size");
  options.width = w;
  options.height = h;
  options.samplesPerPixel = args.spp;
  options.azimuthDegrees = args.azimuth;
  options.elevationDegrees = args.elevation;
  options.fovYDegrees = args.fov;
  options.aoSamples = args.ao;
  options.transparentBackground = !parseBackground(args.background, options.background);
  if (args.spp < 1 || args.spp > 4096) throw Error("--spp must be 1..4096");
  if (args.ao < 0 || args.ao > 64) throw Error("--ao must be 0..64");
  if (args.turntable < 0 || args.turntable > 3600) throw Error("--turntable must be 0..3600");
  if (!(args.elevation > -90 && args.elevation < 90)) throw Error("--elevation must be in (-90, 90)");
  checkImageWritable(args.output);
  progress.start("load");
  const geometry::Mesh mesh = geometry::readMesh(args.model);
  progress.finish(args.model + ": " + std::to_string(mesh.triangleCount()) + " triangles");
  progress.start("bvh");
  const render::PreviewRenderer renderer(mesh);
  progress.finish();
  const int views = args.turntable > 0 ? args.turntable : 1;
  // Render everything first, then write: a failure leaves no partial set of images.
  std::vector<Image> images;
  for (int i = 0; i < views; ++i) {
    progress.start("render");
    if (args.turntable > 0) options.azimuthDegrees = args.azimuth + 360.0f * float(i) / float(views);
    images.push_back(renderer.render(options, ctx));
    progress.finish(std::to_string(w) + "x" + std::to_string(h) + ", " + std::to_string(args.spp) + " spp, azimuth " +
                    std::to_string(int(std::lround(options.azimuthDegrees))));
  }
  progress.start("write");
  for (int i = 0; i < views; ++i)
    writeImage(images[size_t(i)], args.turntable > 0 ? turntableName(args.output, i) : fs::path(args.output));
  progress.finish(args.turntable > 0 ? turntableName(args.output, 0).string() + " .. " : args.output);
}

} // namespace

Command addRenderCommand(CLI::App& root) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* app = root.add_subcommand("render", "Ray-traced preview picture of a model (textures, normal maps, key light, "
                                                "ambient occlusion; auto-framed)");
  app->add_option("model", args->model, "Model (.obj, .ply, .off, .stl, .gltf, .glb)")->required();
  app->add_option("-o,--output", args->output, "Output image (.png); with --turntable, NAME_000.png, NAME_001.png, ...")
      ->required();
  app->add_option("--size", args->size, "Image size WxH (or N for NxN)")->capture_default_str();
  app->add_option("--azimuth", args->azimuth, "Camera angle around the vertical axis, degrees (0 = from +Z)")
      ->capture_default_str();
  app->add_option("--elevation", args->elevation, "Camera angle above the horizon, degrees")->capture_default_str();
  app->add_option("--turntable", args->turntable, "Render N views evenly around the model instead of one");
  app->add_option("--spp", args->spp, "Samples per pixel (antialiasing; rounded down to a square)")->capture_default_str();
  app->add_option("--ao", args->ao, "Ambient-occlusion rays per sample (0 = plain sky light)")->capture_default_str();
  app->add_option("--fov", args->fov, "Vertical field of view, degrees")->capture_default_str();
  app->add_option("--background", args->background, "transparent, white, black, grey, #rrggbb or R,G,B (0..1)")
      ->capture_default_str();
  app->add_option("--threads", args->threads, "Worker threads (0 = all cores)")->capture_default_str();
  app->add_flag("-q,--quiet", args->quiet, "No progress output");
  return {app, [args] { runRender(*args); }};
}

} // namespace texfab::cli
