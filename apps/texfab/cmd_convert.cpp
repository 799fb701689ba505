// SPDX-License-Identifier: GPL-3.0-or-later
// texfab convert: between mesh formats, keeping UVs and materials where both formats can.
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "core/error.h"
#include "core/text.h"
#include "geometry/io/mesh_io.h"

#include <memory>

namespace texfab::cli {

namespace {

struct ConvertJob {
  std::string input, output;
  geometry::MeshWriteOptions options;
  bool ascii = false;
  UpChoice up;
  CommonFlags common;
};

void runConvert(ConvertJob& job) {
  using namespace geometry;
  Run run("convert", job.common);
  checkPrintSize(job.options, job.output);
  const MeshFormat out = meshFormatOf(job.output);  // a bad output name fails before reading
  if (job.options.draco && !meshFormatIsGltf(out))
    throw UsageError("--draco needs a .glb or .gltf output, not " + job.output);
  job.options.binary = !job.ascii;
  job.options.up = geometry::upVector(upAxisFor(job.up, job.input));
  const std::filesystem::path staged = run.output(job.output);
  Stage read(run.ctx(), "read");
  const Mesh mesh = readMesh(job.input, run.ctx());
  read.finish(job.input + ": " + counted(int64_t(mesh.vertexCount()), "vertex", "vertices") + ", " +
              counted(int64_t(mesh.triangleCount()), "triangle"));
  Stage write(run.ctx(), "write");
  writeMesh(mesh, staged, job.options);
  write.finish(job.output);
  run.finish();
}

} // namespace

Command addConvertCommand(CLI::App& root) {
  auto job = std::make_shared<ConvertJob>();
  Flags f(root.add_subcommand("convert", "Convert a model between OBJ(+MTL), PLY, OFF, STL, glTF, GLB and 3MF "
                                         "(keeps UVs, normals and materials where both formats can)"));
  f.input("input", job->input, "Input model (.obj, .ply, .off, .stl, .gltf, .glb, .3mf)");
  f.input("output", job->output, "Output model (.obj, .ply, .off, .stl, .gltf, .glb, .3mf); the format follows the extension");
  f.modelOutput(job->options);
  f.printSize(job->options);
  f.up(job->up)->description("The model's up axis, along which --height measures (auto: z for STL, else y)");
  f.option("--draco-level", job->options.dracoLevel, "Draco compression level, 0 fast to 10 small", {0, 10});
  f.flag("--ascii", job->ascii, "Write ASCII PLY/STL instead of binary");
  f.common(job->common, Common::Quiet);
  return {f.app(), [job] { runConvert(*job); }};
}

} // namespace texfab::cli
