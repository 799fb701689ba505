// SPDX-License-Identifier: GPL-3.0-or-later
// texfab.synthesize (2-D synthesis, Lefebvre & Hoppe 2005/2006) and texfab.solid (the solid
// texture at points, in a box or on a plane; lazy synthesis, Dong et al. 2008, or solid tiles).
#include "python/src/bindings.h"
#include "python/src/convert.h"

#include "core/memory.h"
#include "render/solid_volume.h"
#include "synthesis/coord_map.h"
#include "synthesis/graph_file.h"
#include "synthesis/synthesize_2d.h"
#include "synthesis/synthesize_graph.h"
#include "synthesis/synthesize_solid.h"

#include <pybind11/stl.h>

#include <cmath>
#include <map>

namespace texfab::python {

namespace {

struct SynthesisOutput {
  py::array image, coords;
  py::dict maps;
  std::string wrap;
};

py::array coordsArray(const synthesis::CoordMap& map) {
  py::array_t<int32_t> coords({py::ssize_t(map.height), py::ssize_t(map.width), py::ssize_t(2)});
  int32_t* out = coords.mutable_data();
  for (uint32_t c : map.coords) *out++ = int32_t(synthesis::coordU(c)), *out++ = int32_t(synthesis::coordV(c));
  return coords;
}

// What a synthesis call computes (without the GIL), and its Python form.
struct Synthesized {
  synthesis::CoordMap coords;
  Image image;
  std::map<std::string, Image> maps;  ///< companion maps through the same coordinates
};

SynthesisOutput outputOf(Synthesized&& r, synthesis::ExemplarWrap wrap) {
  SynthesisOutput output{imageArray(std::move(r.image)), coordsArray(r.coords), {}, toString(wrap)};
  for (auto& [name, map] : r.maps) output.maps[py::str(name)] = imageArray(std::move(map));
  return output;
}

// The window a call asks for: `window` (x, y, width, height), else (0, 0) and `size`.
synthesis::Window windowOf(const py::object& size, const py::object& window) {
  synthesis::Window w;
  if (!window.is_none()) {
    const auto v = window.cast<std::vector<int64_t>>();
    if (v.size() != 4) throw Error("window: expected (x, y, width, height)");
    w = {v[0], v[1], int(v[2]), int(v[3])};
  } else {
    const auto [width, height] = toSize(size, "size");
    w = {0, 0, width, height};
  }
  if (w.width < 1 || w.height < 1 || w.width > kMaxImageSide || w.height > kMaxImageSide)
    throw Error("size: width and height must be 1 to " + std::to_string(kMaxImageSide));
  return w;
}

SynthesisOutput synthesize(const py::object& exemplarLike, const py::object& size, const py::object& window,
                           uint32_t seed, std::vector<float> jitter, int passes, int interleave, int k,
                           float featureWeight, bool tileable, const std::string& wrap, const py::object& mapsLike,
                           int threads, const std::string& backend, const py::object& cacheDir,
                           const py::object& progress) {
  using namespace synthesis;
  Call call(threads, backend, cacheDir, progress);
  const Image exemplar = toImage(exemplarLike, "exemplar");
  std::map<std::string, Image> maps;
  if (!mapsLike.is_none())
    for (const auto& [name, map] : mapsLike.cast<py::dict>()) {
      const std::string key = py::str(name);
      maps[key] = toImage(map, "maps['" + key + "']");
    }
  if (!window.is_none() && tileable) throw Error("tileable and window cannot be combined (the tile is the output size)");
  const Window w = windowOf(size, window);
  SynthesisOptions options;
  options.seed = seed;
  options.jitter = std::move(jitter);
  options.passes = passes;
  options.interleave = interleave;
  if (tileable) options.periodX = w.width, options.periodY = w.height;
  options.validate();
  AnalysisOptions analysis;
  analysis.k = k;
  analysis.featureWeight = featureWeight;
  analysis.wrap = chooseWrap(wrap, exemplar);
  analysis.validate();
  for (const auto& [name, map] : maps)
    if (map.width != exemplar.width || map.height != exemplar.height)
      throw Error("maps['" + name + "']: a companion map must have the exemplar's size");

  int channels = exemplar.channels;  // resolved through the coordinates: the colours, then each map
  for (const auto& [name, map] : maps) channels += map.channels;
  checkMemory(synthesize2dMemoryBytes(w, channels) +
                  analysisMemoryBytes(exemplar.width, exemplar.height, analysis),
              "a " + std::to_string(w.width) + "x" + std::to_string(w.height) + " output from a " +
                  std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) + " exemplar");
  Synthesized r = call.run([&] {
    Synthesized out;
    const ExemplarAnalysis a = analyze2d(call, exemplar, analysis);
    Stage stage(call.ctx(), "synthesis");
    out.coords = synthesize2d(a, w, options, stage.inner()).coords;
    stage.finish();
    out.image = applyCoords(out.coords, exemplar, call.ctx());
    for (const auto& [name, map] : maps) out.maps[name] = applyCoords(out.coords, map, call.ctx());
    return out;
  });
  return outputOf(std::move(r), analysis.wrap);
}

SynthesisOutput synthesizeGraph(const py::handle& graphFile, const py::object& size, const py::object& window,
                                double zoom, uint32_t seed, std::vector<float> jitter, int passes, int interleave,
                                bool tileable, int threads, const py::object& cacheDir, const py::object& progress) {
  using namespace synthesis;
  Call call(threads, "cpu", cacheDir, progress);
  if (!window.is_none() && tileable) throw Error("tileable and window cannot be combined (the tile is the output size)");
  const Window w = windowOf(size, window);
  GraphSynthesisOptions options;
  options.zoomOctaves = graphZoomOctaves(zoom);
  options.seed = seed;
  options.jitter = std::move(jitter);
  options.passes = passes;
  options.interleave = interleave;
  if (tileable) options.periodX = w.width, options.periodY = w.height;
  const ExemplarGraph graph = readExemplarGraph(toPath(graphFile));
  options.zoomOctaves -= graph.rootOctaves();  // zoom counts pixels of the root as given
  checkMemory(graphAnalysisMemoryBytes(int(graph.exemplars.size()), graph.side()) + synthesizeGraphMemoryBytes(w),
              "a " + std::to_string(w.width) + "x" + std::to_string(w.height) + " output from a graph of " +
                  std::to_string(graph.exemplars.size()) + " exemplars");
  Synthesized r = call.run([&] {
    Synthesized out;
    const GraphAnalysis a = analyzeGraph(graph, {}, call.analysisCache(), call.ctx());
    options.validate(a);
    Stage stage(call.ctx(), "synthesis");
    const SynthesisResult result = synthesizeGraph(a, w, options, stage.inner());
    stage.finish();
    out.coords = result.coords;
    out.image = graphColors(result, a, call.ctx());
    for (const GraphMap& map : graph.maps) out.maps[map.name] = applyCoords(out.coords, graphMapAtlas(map), call.ctx());
    return out;
  });
  return outputOf(std::move(r), ExemplarWrap::Tile);
}

synthesis::Voxel voxelAt(const Eigen::Vector3d& p, double voxelSize) {
  const Eigen::Vector3d v = p / voxelSize;
  if (!v.allFinite() || v.cwiseAbs().maxCoeff() > double(synthesis::kMaxSolidPosition))
    throw Error("solid: a position is not finite or out of range (|p / voxel_size| <= 2^30)");
  return {int64_t(std::floor(v.x())), int64_t(std::floor(v.y())), int64_t(std::floor(v.z()))};
}

// The voxels a call asks for, and the shape of its answer before the channels.
struct Request {
  std::vector<synthesis::Voxel> voxels;
  std::vector<py::ssize_t> shape;
  std::optional<synthesis::VoxelBox> box;
};

Request request(const py::object& points, const py::object& box, const py::object& plane, const py::object& size,
                double voxelSize) {
  if (!(voxelSize > 0) || !std::isfinite(voxelSize)) throw Error("voxel_size: expected a positive number");
  if (int(!points.is_none()) + int(!box.is_none()) + int(!plane.is_none()) != 1)
    throw Error("solid: give exactly one of points, box and plane");
  Request r;
  if (!points.is_none()) {
    const auto p = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(points);
    if (!p || p.ndim() != 2 || p.shape(1) != 3) throw Error("points: expected an array of shape (N, 3)");
    for (py::ssize_t i = 0; i < p.shape(0); ++i) r.voxels.push_back(voxelAt({p.at(i, 0), p.at(i, 1), p.at(i, 2)}, voxelSize));
    r.shape = {p.shape(0)};
  } else if (!box.is_none()) {
    const auto b = box.cast<std::vector<int64_t>>();
    if (b.size() != 6 || b[3] < 1 || b[4] < 1 || b[5] < 1 || b[3] > kMaxImageSide || b[4] > kMaxImageSide ||
        b[5] > kMaxImageSide)
      throw Error("box: expected (x, y, z, nx, ny, nz), each size 1 to " + std::to_string(kMaxImageSide));
    for (int i = 0; i < 3; ++i)
      if (std::llabs(b[size_t(i)]) + b[size_t(i) + 3] > synthesis::kMaxSolidPosition)
        throw Error("box: out of range (|x| + nx <= 2^30)");
    r.box = synthesis::VoxelBox{b[0], b[1], b[2], int(b[3]), int(b[4]), int(b[5])};
    r.shape = {py::ssize_t(b[5]), py::ssize_t(b[4]), py::ssize_t(b[3])};
  } else {
    // (origin, u, v) and size (w, h): pixel (i, j) shows origin + (i + 0.5) u + (j + 0.5) v.
    const auto axes = plane.cast<std::vector<std::vector<double>>>();
    if (axes.size() != 3 || axes[0].size() != 3 || axes[1].size() != 3 || axes[2].size() != 3)
      throw Error("plane: expected (origin, u, v), three 3-vectors");
    if (size.is_none()) throw Error("plane: give size=(width, height)");
    const auto [w, h] = toSize(size, "size");
    if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide)
      throw Error("size: width and height must be 1 to " + std::to_string(kMaxImageSide));
    const Eigen::Vector3d o(axes[0].data()), u(axes[1].data()), v(axes[2].data());
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) r.voxels.push_back(voxelAt(o + (i + 0.5) * u + (j + 0.5) * v, voxelSize));
    r.shape = {h, w};
  }
  return r;
}

py::array solid(const py::object& exemplarLike, const py::object& points, const py::object& box,
                const py::object& plane, const py::object& size, double voxelSize, uint32_t seed,
                const std::string& method, int tileSide, float contrastGain, int refine, const std::string& wrap,
                int threads, const std::string& backend, const py::object& cacheDir, const py::object& progress) {
  Call call(threads, backend, cacheDir, progress);
  const Image exemplar = toImage(exemplarLike, "exemplar");
  Request req = request(points, box, plane, size, voxelSize);
  const synthesis::SolidSynthesisOptions options = solidOptions(seed, method, contrastGain, refine);
  const synthesis::ExemplarWrap exemplarWrap = chooseWrap(wrap, exemplar);
  const int64_t count = req.box ? req.box->count() : int64_t(req.voxels.size());
  checkMemory(synthesis::synthesizeSolidMemoryBytes(count, refine), "a request of " + std::to_string(count) + " voxels");
  Image colors = call.run([&] {
    const synthesis::SolidAnalysis a = analyzeSolid(call, exemplar, exemplarWrap, options.method, tileSide);
    Stage stage(call.ctx(), "synthesis");
    const synthesis::SolidSynthesisResult r =
        req.box ? synthesis::synthesizeSolidBox(a, *req.box, options, nullptr, stage.inner())
                : synthesis::synthesizeSolid(a, req.voxels, options, nullptr, stage.inner());
    stage.finish();
    return render::solidColorImage(r.triples, {exemplar, exemplar, exemplar}, int(r.triples.size()), 1);
  });
  py::array flat = imageArray(std::move(colors));
  std::vector<py::ssize_t> shape = req.shape;
  shape.push_back(flat.shape(2));
  return flat.reshape(shape);
}

} // namespace

void bindSynthesis(py::module_& m) {
  py::class_<SynthesisOutput>(m, "SynthesisResult", "An image synthesized from an exemplar, and its coordinates")
      .def_readonly("image", &SynthesisOutput::image, "(H, W, C) float32: the exemplar through the coordinates")
      .def_readonly("coords", &SynthesisOutput::coords, "(H, W, 2) int32: the exemplar pixel (x, y) of each texel")
      .def_readonly("maps", &SynthesisOutput::maps, "companion maps through the same coordinates, by name")
      .def_readonly("wrap", &SynthesisOutput::wrap, "how the exemplar's borders were treated: tile or clamp");
  const synthesis::SynthesisOptions so;
  const synthesis::AnalysisOptions ao;
  m.def("synthesize", &synthesize, py::arg("exemplar"), py::arg("size") = py::make_tuple(512, 512), py::kw_only(),
        py::arg("window") = py::none(), py::arg("seed") = so.seed, py::arg("jitter") = so.jitter,
        py::arg("passes") = so.passes, py::arg("interleave") = so.interleave, py::arg("k") = ao.k,
        py::arg("feature_weight") = ao.featureWeight, py::arg("tileable") = false, py::arg("wrap") = "auto",
        py::arg("maps") = py::none(), py::arg("threads") = 0, py::arg("backend") = "cpu",
        py::arg("cache_dir") = py::none(), py::arg("progress") = py::none(),
        "Synthesizes `size` (W, H), or the window (X, Y, W, H) of the infinite texture plane, from an exemplar "
        "(parallel appearance-space synthesis, Lefebvre & Hoppe 2005/2006); equal to `texfab synth`");
  const synthesis::GraphSynthesisOptions gso;
  m.def("synthesize_graph", &synthesizeGraph, py::arg("graph"), py::arg("size") = py::make_tuple(512, 512),
        py::kw_only(), py::arg("window") = py::none(), py::arg("zoom") = 1.0, py::arg("seed") = gso.seed,
        py::arg("jitter") = gso.jitter, py::arg("passes") = gso.passes, py::arg("interleave") = gso.interleave,
        py::arg("tileable") = false, py::arg("threads") = 0, py::arg("cache_dir") = py::none(),
        py::arg("progress") = py::none(),
        "Synthesizes `size` (W, H), or the window (X, Y, W, H), at `zoom` (a power of two: output texels are 1/zoom of "
        "a root pixel) from an exemplar graph file (multiscale synthesis, Han et al. 2008); coords are positions in "
        "the graph's packed exemplars; maps: the companion maps the graph's exemplars give; tileable: the output "
        "wraps at its size. Equal to `texfab synth --graph`");
  const synthesis::SolidSynthesisOptions sso;
  m.def("solid", &solid, py::arg("exemplar"), py::kw_only(), py::arg("points") = py::none(),
        py::arg("box") = py::none(), py::arg("plane") = py::none(), py::arg("size") = py::none(),
        py::arg("voxel_size") = 1.0, py::arg("seed") = sso.seed, py::arg("method") = "lazy",
        py::arg("tile_size") = 32, py::arg("contrast_gain") = sso.contrastGain,
        py::arg("refine") = sso.refinePasses, py::arg("wrap") = "auto", py::arg("threads") = 0,
        py::arg("backend") = "cpu", py::arg("cache_dir") = py::none(), py::arg("progress") = py::none(),
        "Colours of the solid texture: at points (N, 3) -> (N, C); in box (x, y, z, nx, ny, nz) -> (nz, ny, nx, C); "
        "on plane (origin, u, v) with size (W, H) -> (H, W, C), pixel (i, j) at origin + (i + .5) u + (j + .5) v. "
        "Positions in output units, voxel_size units per voxel; equal to `texfab solid`");
}

} // namespace texfab::python
