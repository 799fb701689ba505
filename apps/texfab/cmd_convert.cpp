// SPDX-License-Identifier: GPL-3.0-or-later
// texfab convert: between mesh formats, keeping UVs and materials where both formats can.
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "geometry/mesh_io.h"
#include "render/image/error.h"
#include "render/image/text.h"

#include <memory>

namespace texfab::cli {

namespace {

struct ConvertJob {
  std::string input, output;
  geometry::MeshWriteOptions options;
  bool ascii = false;
  CommonFlags common;
};

void runConvert(ConvertJob& job) {
  using namespace geometry;
  Run run("convert", job.common);
  const MeshFormat out = meshFormatOf(job.output);  // a bad output name fails before reading
  if (job.options.draco && out != MeshFormat::Glb && out != MeshFormat::Gltf)
    throw UsageError("--draco needs a .glb or .gltf output, not " + job.output);
  job.options.binary = !job.ascii;
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
  Flags f(root.add_subcommand("convert", "Convert a model between OBJ(+MTL), PLY, OFF, STL, glTF and GLB "
                                         "(keeps UVs, normals and materials where both formats can)"));
  f.input("input", job->input, "Input model (.obj, .ply, .off, .stl, .gltf, .glb)");
  f.input("output", job->output, "Output model; the format follows the extension");
  f.modelOutput(job->options);
  f.option("--draco-level", job->options.dracoLevel, "Draco compression level, 0 fast to 10 small", {0, 10});
  f.flag("--ascii", job->ascii, "Write ASCII PLY/STL instead of binary");
  f.common(job->common, Common::Quiet);
  return {f.app(), [job] { runConvert(*job); }};
}

} // namespace texfab::cli
