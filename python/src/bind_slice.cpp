// SPDX-License-Identifier: GPL-3.0-or-later
// texfab.slice: the print job (render/print_job.h) into a folder of layer PNGs and its manifest,
// with `texfab slice`'s defaults.
#include "python/src/bindings.h"
#include "python/src/convert.h"

#include "core/downsample.h"
#include "core/memory.h"
#include "geometry/io/mesh_io.h"
#include "print/print_job.h"
#include "print/print_materials.h"

#include <pybind11/stl.h>

#include <optional>

namespace texfab::python {

namespace {

py::object slice(const py::object& meshLike, const py::object& output, const py::object& exemplarLike,
                 const std::string& mode, const std::string& up, double heightMm, double unitMm,
                 const std::pair<double, double>& dpi, double layerMm, double shellMm, const py::object& layers,
                 const std::string& dither, const std::string& format, const std::string& core,
                 const py::object& materials, const py::object& iccProfile, double textureScale, double featureSize,
                 uint32_t seed, const std::string& wrap, const std::string& method, int tileSide, float contrastGain,
                 int refine, int resolution, bool force, int threads, const std::string& backend, const py::object& cacheDir,
                 const py::object& progress) {
  Call call(threads, backend, cacheDir, progress);
  print::PrintJobOptions o;
  o.grid.up = geometry::parseUpAxis(up);
  o.grid.heightMm = heightMm;
  o.grid.mmPerUnit = unitMm;
  o.grid.dpiX = dpi.first;
  o.grid.dpiY = dpi.second;
  o.grid.layerMm = layerMm;
  o.voxelize.shellMm = shellMm;
  o.slice.dither = choose<print::DitherMode>(dither, "dither", {{"blue-noise", print::DitherMode::BlueNoise},
                                             {"floyd-steinberg", print::DitherMode::FloydSteinberg},
                                             {"none", print::DitherMode::None}});
  o.slice.format = choose<print::SliceFormat>(format, "format", {{"png", print::SliceFormat::Indexed},
                                             {"voxelprint", print::SliceFormat::VoxelPrint}});
  o.slice.coreMaterial = core;
  if (!materials.is_none()) o.slice.materials = print::readPrintMaterials(toPath(materials));
  if (!iccProfile.is_none()) o.slice.iccProfile = toPath(iccProfile);
  const bool textured = !exemplarLike.is_none();
  o.colors = !textured ? print::PrintColors::Model
             : choose<print::PrintColors>(mode, "mode", {{"solid", print::PrintColors::Solid}, {"surface", print::PrintColors::Surface}});
  o.textureScale = textureScale;
  o.featureSize = featureSize;
  o.seed = seed;
  o.solid = solidOptions(seed, method, contrastGain, refine);
  o.resolution = resolution;
  o.validate();
  const std::filesystem::path folder = toPath(output);
  std::optional<Image> exemplar;
  if (textured) exemplar = toImage(exemplarLike, "exemplar");
  const std::string exemplarName = textured && isPath(exemplarLike) ? toPath(exemplarLike).filename().string() : "exemplar";
  const std::filesystem::path meshPath = isPath(meshLike) ? toPath(meshLike) : std::filesystem::path();
  const geometry::Mesh mesh = meshPath.empty() ? meshLike.cast<geometry::Mesh>() : geometry::Mesh();
  const std::string modelName = meshPath.empty() ? "mesh" : meshPath.filename().string();
  int first = 0, count = -1;  // layers (A, B): A, B - A; checked against the grid below
  if (!layers.is_none()) {
    const auto [a, b] = layers.cast<std::pair<int, int>>();
    first = a, count = b - a;
  }

  const nlohmann::ordered_json manifest = call.run([&] {
    print::SliceWriter writer(folder, force);
    const print::PrintJob job(meshPath.empty() ? mesh : geometry::readMesh(meshPath, call.ctx()), o, call.ctx());
    if (!layers.is_none() && (first < 0 || count < 1 || first + count > job.grid().layers))
      throw Error("layers: expected (A, B) with 0 <= A < B <= " + std::to_string(job.grid().layers) +
                  " (the print's layers)");
    checkMemory(job.memoryBytes(call.ctx()), "one layer of " + std::to_string(job.grid().width) + " x " +
                                              std::to_string(job.grid().height) + " voxels with its batch");
    std::optional<synthesis::SolidAnalysis> solid;
    std::optional<synthesis::ExemplarAnalysis> surface;
    print::PrintExemplar ex;
    if (exemplar) {
      ex = {&*exemplar, nullptr, nullptr, exemplarName};
      const synthesis::ExemplarWrap w = chooseWrap(wrap, *exemplar);  // on the exemplar given
      if (o.colors == print::PrintColors::Solid) {
        ex.downsampling = job.analysisDownsampling(*exemplar);  // as texfab slice
        if (ex.downsampling > 1) *exemplar = downsample(*exemplar, ex.downsampling);
        ex.solid = &solid.emplace(analyzeSolid(call, *exemplar, w, o.solid.method, tileSide));
      } else {
        synthesis::AnalysisOptions options;
        options.wrap = w;
        ex.surface = &surface.emplace(analyze2d(call, *exemplar, options));
      }
    }
    job.slice(ex, first, count, writer, modelName, call.ctx());
    writer.publish();
    return print::readSliceManifest(folder);
  });
  return py::module_::import("json").attr("loads")(manifest.dump());
}

// The print's grid (width, height, layers) as slice() lays it out.
py::dict printGrid(const py::object& meshLike, const std::string& up, double heightMm, double unitMm,
                   const std::pair<double, double>& dpi, double layerMm) {
  print::PrintGridOptions o;
  o.up = geometry::parseUpAxis(up);
  o.heightMm = heightMm;
  o.mmPerUnit = unitMm;
  o.dpiX = dpi.first;
  o.dpiY = dpi.second;
  o.layerMm = layerMm;
  o.validate();
  const geometry::BoundingBox box =
      geometry::boundingBox(isPath(meshLike) ? geometry::readMesh(toPath(meshLike)) : meshLike.cast<geometry::Mesh>());
  const print::PrintGrid grid = print::printGrid(box, o);
  using namespace pybind11::literals;
  return py::dict("width"_a = grid.width, "height"_a = grid.height, "layers"_a = grid.layers);
}

} // namespace

void bindSlice(py::module_& m) {
  const print::PrintJobOptions o;
  const synthesis::SolidSynthesisOptions so;
  m.def("slice", &slice, py::arg("mesh"), py::arg("output"), py::kw_only(), py::arg("exemplar") = py::none(),
        py::arg("mode") = "solid", py::arg("up") = "y", py::arg("height_mm") = o.grid.heightMm,
        py::arg("unit_mm") = o.grid.mmPerUnit, py::arg("dpi") = std::pair(o.grid.dpiX, o.grid.dpiY),
        py::arg("layer_mm") = o.grid.layerMm, py::arg("shell_mm") = o.voxelize.shellMm,
        py::arg("layers") = py::none(), py::arg("dither") = "blue-noise", py::arg("format") = "png",
        py::arg("core") = o.slice.coreMaterial, py::arg("materials") = py::none(),
        py::arg("icc_profile") = py::none(), py::arg("texture_scale") = 0.0,
        py::arg("feature_size") = 0.0, py::arg("seed") = o.seed, py::arg("wrap") = "auto",
        py::arg("solid_method") = "lazy", py::arg("tile_size") = 32, py::arg("contrast_gain") = so.contrastGain,
        py::arg("refine") = so.refinePasses, py::arg("resolution") = o.resolution, py::arg("force") = false,
        py::arg("threads") = 0, py::arg("backend") = "cpu", py::arg("cache_dir") = py::none(),
        py::arg("progress") = py::none(),
        "Slices a closed model into one PNG per print layer and the manifest slices.json in `output` (a new or "
        "empty folder, or force=True), coloured from its own materials or the exemplar's texture and dithered to "
        "the printer's materials (aiming at the colours icc_profile, the printer's ICC output profile, says it "
        "reproduces, when given); layers=(A, B) writes layers A..B-1 only, byte for byte as in a full run. Returns "
        "the manifest. Equal to `texfab slice`");
  m.def("_print_grid", &printGrid, py::arg("mesh"), py::kw_only(), py::arg("up") = "y",
        py::arg("height_mm") = o.grid.heightMm, py::arg("unit_mm") = o.grid.mmPerUnit,
        py::arg("dpi") = std::pair(o.grid.dpiX, o.grid.dpiY), py::arg("layer_mm") = o.grid.layerMm);
}

} // namespace texfab::python
