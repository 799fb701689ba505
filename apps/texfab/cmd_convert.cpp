// SPDX-License-Identifier: GPL-3.0-or-later
// texfab convert: between mesh formats, keeping UVs and materials where both formats can.
#include "apps/texfab/cli_util.h"
#include "apps/texfab/command.h"
#include "geometry/mesh_io.h"
#include "render/image/error.h"

#include <memory>

namespace texfab::cli {

namespace {

struct ConvertArgs {
  std::string input;
  std::string output;
  bool draco = false;
  int dracoLevel = 7;
  bool ascii = false;
  bool quiet = false;
};

void runConvert(const ConvertArgs& args) {
  using namespace geometry;
  Progress progress("texfab convert", args.quiet);
  const MeshFormat out = meshFormatOf(args.output);  // a bad output name fails before reading
  MeshWriteOptions options;
  options.draco = args.draco;
  options.dracoLevel = args.dracoLevel;
  options.binary = !args.ascii;
  if (args.draco && out != MeshFormat::Glb && out != MeshFormat::Gltf)
    throw Error("--draco needs a .glb or .gltf output, not " + args.output);
  if (args.dracoLevel < 0 || args.dracoLevel > 10) throw Error("--draco-level must be 0..10");
  progress.start("read");
  const Mesh mesh = readMesh(args.input);
  progress.finish(args.input + ": " + std::to_string(mesh.vertexCount()) + " vertices, " +
                  std::to_string(mesh.triangleCount()) + " triangles");
  progress.start("write");
  writeMesh(mesh, args.output, options);
  progress.finish(args.output);
}

} // namespace

Command addConvertCommand(CLI::App& root) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* app = root.add_subcommand("convert", "Convert a model between OBJ(+MTL), PLY, OFF, STL, glTF and GLB "
                                                 "(keeps UVs, normals and materials where both formats can)");
  app->add_option("input", args->input, "Input model (.obj, .ply, .off, .stl, .gltf, .glb)")->required();
  app->add_option("output", args->output, "Output model; the format follows the extension")->required();
  app->add_flag("--draco", args->draco, "Compress the geometry with Draco (KHR_draco_mesh_compression; .glb/.gltf)");
  app->add_option("--draco-level", args->dracoLevel, "Draco compression level 0 (fast) .. 10 (small)")->capture_default_str();
  app->add_flag("--ascii", args->ascii, "Write ASCII PLY/STL instead of binary");
  app->add_flag("-q,--quiet", args->quiet, "No progress output");
  return {app, [args] { runConvert(*args); }};
}

} // namespace texfab::cli
