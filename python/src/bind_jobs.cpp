// SPDX-License-Identifier: GPL-3.0-or-later
// texfab.texture_mesh (the texture job) and the break jobs (fracture and cut; texfab/__init__.py
// names them over _break_model), with the command line's defaults and policies: the exemplar's
// wrap measured as given, the analysis of a smaller copy where the scale allows.
#include "python/src/bindings.h"
#include "python/src/convert.h"

#include "core/downsample.h"
#include "core/memory.h"
#include "geometry/io/mesh_io.h"
#include "render/break/break_model.h"
#include "render/material_mips.h"
#include "render/texture_mesh.h"
#include "synthesis/graph_file.h"
#include "synthesis/synthesize_surface_graph.h"

#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <optional>

namespace texfab::python {

namespace {

geometry::Mesh toMesh(const py::object& meshLike) {
  if (isPath(meshLike)) {
    const std::filesystem::path path = toPath(meshLike);
    py::gil_scoped_release release;
    return geometry::readMesh(path);
  }
  return meshLike.cast<geometry::Mesh>();
}

struct TextureOutput {
  py::object mesh;
  py::object baseColor, normal, metallicRoughness, height;
  double textureScale = 0;
  size_t charts = 0;
  std::vector<std::string> repairs, warnings;
};

struct TextureInputs {
  Image exemplar;
  std::optional<Image> normal, roughness, height;
  render::TextureExemplar view() const {
    return {&exemplar, nullptr, nullptr, normal ? &*normal : nullptr, roughness ? &*roughness : nullptr,
            height ? &*height : nullptr};
  }
};

TextureInputs textureInputs(const py::object& exemplar, const py::object& maps) {
  TextureInputs in{toImage(exemplar, "exemplar"), {}, {}, {}};
  synthesis::validateExemplarSize(in.exemplar);
  if (!maps.is_none())
    for (const auto& [name, map] : maps.cast<py::dict>()) {
      const std::string kind = py::str(name);
      std::optional<Image>& slot =
          *choose<std::optional<Image>*>(kind, "maps", {{"normal", &in.normal}, {"roughness", &in.roughness}, {"height", &in.height}});
      slot = toImage(map, "maps['" + kind + "']");
    }
  if (in.normal && in.normal->channels < 3) throw Error("maps['normal']: a normal map needs 3 channels");
  return in;
}

// texture_mesh(graph=...): as `texfab texture --graph`, the graph's own maps through its coordinates.
struct GraphInputs {
  synthesis::ExemplarGraph graph;
  std::optional<Image> normal, roughness, height;
  explicit GraphInputs(const py::object& file) : graph(synthesis::readExemplarGraph(toPath(file))) {
    synthesis::checkSurfaceGraphSize(int(graph.exemplars.size()), graph.side());
    normal = synthesis::graphMapAtlas(graph, "normal");
    roughness = synthesis::graphMapAtlas(graph, "roughness");
    height = synthesis::graphMapAtlas(graph, "height");
  }
  render::TextureExemplar view(const synthesis::GraphAnalysis& analysis) const {
    render::TextureExemplar e{&graph.exemplars.front(), nullptr, nullptr, normal ? &*normal : nullptr,
                              roughness ? &*roughness : nullptr, height ? &*height : nullptr};
    e.graph = &analysis;
    return e;
  }
};

// `pixelsAsGiven`: pixels of the exemplar (or graph root) as given per pixel synthesized from.
TextureOutput textureOutput(render::TextureMeshResult&& r, double pixelsAsGiven) {
  return {py::cast(std::move(r.mesh)),
          imageArray(r.baseColor),
          optionalImageArray(r.normal),
          optionalImageArray(r.metallicRoughness),
          optionalImageArray(r.height),
          r.textureScale * pixelsAsGiven,
          r.atlas.report.charts,
          r.preparation.repairs,
          r.warnings};
}

TextureOutput textureMeshFromGraph(const py::object& meshLike, const py::object& graphFile, double featureSize,
                                   render::TextureMeshOptions o, Call& call) {
  const GraphInputs in(graphFile);
  o.textureScale = render::graphScaleAsGiven(in.graph, o.textureScale, featureSize);
  checkMemory(render::textureMeshMemoryBytes(o) +
                  synthesis::graphAnalysisMemoryBytes(int(in.graph.exemplars.size()), in.graph.side()),
              "a " + std::to_string(o.atlas.pack.width) + "x" + std::to_string(o.atlas.pack.height) +
                  " atlas from a graph of " + std::to_string(in.graph.exemplars.size()) + " exemplars");
  const geometry::Mesh mesh = toMesh(meshLike);
  render::TextureMeshResult r = call.run([&] {
    const geometry::PreparedMesh model = geometry::preparedCopy(mesh, geometry::MeshUse::Surface, call.ctx());
    const synthesis::GraphAnalysis analysis = synthesis::analyzeGraph(in.graph, {}, call.analysisCache(), call.ctx());
    return render::textureMesh(model, in.view(analysis), o, call.ctx());
  });
  return textureOutput(std::move(r), 1.0 / in.graph.rootMagnification);
}

TextureOutput textureMesh(const py::object& meshLike, const py::object& exemplarLike, const std::string& mode,
                          const py::object& resolution, int gutter, double textureScale, double featureSize,
                          uint32_t seed, const std::array<float, 3>& direction, const std::string& field,
                          const py::object& maps, const py::object& graph, const std::string& wrap,
                          const std::string& method, int tileSide, float contrastGain, int refine, int threads,
                          const std::string& backend, const py::object& cacheDir, const py::object& progress) {
  if (exemplarLike.is_none() == graph.is_none()) throw Error("give an exemplar or a graph, one of them");
  Call call(threads, backend, cacheDir, progress);
  render::TextureMeshOptions o;
  o.mode = choose<render::TextureMode>(mode, "mode", {{"surface", render::TextureMode::Surface}, {"solid", render::TextureMode::Solid}});
  std::tie(o.atlas.pack.width, o.atlas.pack.height) = toSize(resolution, "resolution");
  o.atlas.pack.gutter = gutter;
  if (textureScale > 0 && featureSize > 0) throw Error("give texture_scale or feature_size, not both");
  o.field.direction = Eigen::Vector3f(direction[0], direction[1], direction[2]);
  o.field.kind = choose<geometry::TangentFieldKind>(field, "field", {{"direction", geometry::TangentFieldKind::Direction},
                                         {"curvature", geometry::TangentFieldKind::Curvature}});
  o.surface.seed = seed;
  o.solid = solidOptions(seed, method, contrastGain, refine);
  o.measure = false;
  if (!graph.is_none()) {
    if (o.mode != render::TextureMode::Surface || !maps.is_none() || wrap != "auto")
      throw Error("graph: synthesized over the surface with the graph's own maps (no solid mode, maps or wrap)");
    o.textureScale = textureScale;
    return textureMeshFromGraph(meshLike, graph, featureSize, o, call);
  }
  checkMemory(render::textureMeshMemoryBytes(o), "a " + std::to_string(o.atlas.pack.width) + "x" +
                                                     std::to_string(o.atlas.pack.height) + " atlas");
  TextureInputs in = textureInputs(exemplarLike, maps);
  render::checkCompanionMaps(in.view(), o.mode);
  const geometry::Mesh mesh = toMesh(meshLike);
  // As `texfab texture`: the wrap measured on the exemplar as given, the analysis of a smaller copy
  // where the scale puts several exemplar pixels in every texel.
  const synthesis::ExemplarWrap exemplarWrap = chooseWrap(wrap, in.exemplar);
  o.textureScale = featureSize > 0 ? std::max(in.exemplar.width, in.exemplar.height) / featureSize : textureScale;
  o.textureScale = render::textureScaleFor(mesh, o);
  const int factor = render::analysisDownsampling(mesh, o, in.exemplar);
  if (factor > 1) {
    for (std::optional<Image>* map : {&in.normal, &in.roughness, &in.height})
      if (*map) **map = downsample(**map, factor);
    in.exemplar = downsample(in.exemplar, factor);
    o.textureScale /= factor;
  }
  render::TextureMeshResult r = call.run([&] {
    const geometry::PreparedMesh model = geometry::preparedCopy(mesh, geometry::MeshUse::Surface, call.ctx());
    std::optional<synthesis::ExemplarAnalysis> analysis;
    std::optional<synthesis::SolidAnalysis> solid;
    render::TextureExemplar ex = in.view();
    if (o.mode == render::TextureMode::Surface) {
      synthesis::AnalysisOptions options;
      options.wrap = exemplarWrap;
      ex.analysis = &analysis.emplace(analyze2d(call, in.exemplar, options));
    } else {
      ex.solidAnalysis = &solid.emplace(analyzeSolid(call, in.exemplar, exemplarWrap, o.solid.method, tileSide));
    }
    return render::textureMesh(model, ex, o, call.ctx());
  });
  return textureOutput(std::move(r), factor);
}

struct PieceOutput {
  std::string name;
  py::object mesh;
  std::array<double, 3> centroid{};
  double volume = 0, cutArea = 0;
};

struct BrokenOutput {
  std::shared_ptr<const render::BrokenModel> model;
  std::vector<PieceOutput> pieces;
  int downsampling = 1;  ///< render::BreakExemplars::downsampling
};

// The break job with the command line's policies: its exemplars analysed as `texfab fracture` and
// `texfab cut` analyse them (render::BreakExemplars).
BrokenOutput breakModel(const py::object& meshLike, const py::object& planes, int pieces, const py::object& impact,
                        double roughness, double minVolume, const py::object& exemplar, const py::object& interior,
                        const std::string& mode, double textureScale, const py::object& resolution,
                        const py::object& interiorResolution, int gutter, uint32_t seed, const std::string& wrap,
                        const std::string& method, int tileSide, float contrastGain, int refine, int threads,
                        const std::string& backend, const py::object& cacheDir, const py::object& progress) {
  Call call(threads, backend, cacheDir, progress);
  render::BreakModelOptions o;
  if (!planes.is_none()) {
    using Vector = std::array<double, 3>;
    for (const auto& [p, n] : planes.cast<std::vector<std::pair<Vector, Vector>>>()) {
      o.planes.push_back({{p[0], p[1], p[2]}, {n[0], n[1], n[2]}});
      geometry::validatePlane(o.planes.back());
    }
    if (o.planes.empty()) throw Error("planes: give at least one (point, normal)");
  } else {
    geometry::FractureOptions& f = o.fracture.emplace();
    f.pieces = pieces;
    f.seed = seed;
    if (!impact.is_none()) {
      const auto p = impact.cast<std::array<double, 3>>();
      f.impact = Eigen::Vector3d(p[0], p[1], p[2]);
    }
    f.roughness = roughness;
    f.minVolume = minVolume;
    f.validate();
  }
  if (exemplar.is_none() && interior.is_none())
    throw Error("the cut faces show a solid texture: give interior= (or exemplar= to texture the outside too)");
  o.outer.mode = choose<render::TextureMode>(mode, "mode", {{"solid", render::TextureMode::Solid}, {"surface", render::TextureMode::Surface}});
  std::tie(o.outer.atlas.pack.width, o.outer.atlas.pack.height) = toSize(resolution, "resolution");
  std::tie(o.interior.atlas.pack.width, o.interior.atlas.pack.height) = toSize(interiorResolution, "interior_resolution");
  o.interior.atlas.pack.gutter = gutter;
  o.interior.textureScale = textureScale;
  o.outer.measure = false;
  o.shareTextureSettings(seed, solidOptions(seed, method, contrastGain, refine));

  checkMemory(render::breakModelMemoryBytes(o, !exemplar.is_none()), "the atlases of the outer and the cut faces");
  render::BreakExemplars ex;
  if (!exemplar.is_none()) ex.outer = toImage(exemplar, "exemplar");
  if (!interior.is_none()) ex.interior = toImage(interior, "interior");
  const geometry::Mesh mesh = toMesh(meshLike);
  auto model = std::make_shared<const render::BrokenModel>(call.run([&] {
    synthesis::SolidTileOptions tiles;
    tiles.tileSide = tileSide;
    const geometry::PreparedMesh solid = render::prepareBreakSolid(mesh, o, call.ctx());  // its repairs before the analyses
    ex.analyze(solid.mesh, o, [&](const Image& image) { return chooseWrap(wrap, image); }, tiles, call.analysisCache(),
               call.ctx());
    return render::breakModel(solid, ex.outerView, ex.interiorView, o, call.ctx());
  }));
  BrokenOutput out{model, {}, ex.downsampling};
  for (const render::Piece& p : model->pieces)
    out.pieces.push_back({p.name, py::cast(p.mesh), {p.centroid.x(), p.centroid.y(), p.centroid.z()}, p.volume, p.cutArea});
  return out;
}

} // namespace

void bindJobs(py::module_& m) {
  py::class_<TextureOutput> texture(m, "TextureResult", "A mesh textured by texture_mesh()");
  texture.def_readonly("mesh", &TextureOutput::mesh, "the input with atlas UVs and one material carrying the maps")
      .def_readonly("base_color", &TextureOutput::baseColor)
      .def_readonly("normal", &TextureOutput::normal)
      .def_readonly("metallic_roughness", &TextureOutput::metallicRoughness)
      .def_readonly("height", &TextureOutput::height)
      .def_readonly("texture_scale", &TextureOutput::textureScale, "exemplar pixels per model unit used")
      .def_readonly("charts", &TextureOutput::charts)
      .def_readonly("repairs", &TextureOutput::repairs, "what made the input a surface to texture, one line each")
      .def_readonly("warnings", &TextureOutput::warnings);
  defSave(texture, [](const TextureOutput& s, const py::object& path, const geometry::MeshWriteOptions& o) {
    const geometry::Mesh& mesh = s.mesh.cast<const geometry::Mesh&>();
    const std::filesystem::path p = toPath(path);
    py::gil_scoped_release release;
    geometry::writeMesh(geometry::meshFormatIsGltf(geometry::meshFormatOf(p)) ? render::withFilteredMips(mesh) : mesh, p, o);
  }, "Writes the textured mesh (.glb .gltf .obj .3mf) as `texfab texture` does (a normal-mapped glTF also "
     "carries a roughness MIP chain widened by the normals' spread, as KTX2, and where they spread one way an "
     "anisotropy chain, KHR_materials_anisotropy)");

  const render::TextureMeshOptions to;
  const synthesis::SolidSynthesisOptions so;
  m.def("texture_mesh", &textureMesh, py::arg("mesh"), py::arg("exemplar") = py::none(), py::kw_only(), py::arg("mode") = "surface",
        py::arg("resolution") = to.atlas.pack.width, py::arg("gutter") = to.atlas.pack.gutter,
        py::arg("texture_scale") = 0.0, py::arg("feature_size") = 0.0, py::arg("seed") = to.surface.seed,
        py::arg("direction") = std::array<float, 3>{to.field.direction.x(), to.field.direction.y(), to.field.direction.z()}, py::arg("field") = "direction", py::arg("maps") = py::none(), py::arg("graph") = py::none(),
        py::arg("wrap") = "auto", py::arg("solid_method") = "lazy", py::arg("tile_size") = 32,
        py::arg("contrast_gain") = so.contrastGain, py::arg("refine") = so.refinePasses, py::arg("threads") = 0,
        py::arg("backend") = "cpu", py::arg("cache_dir") = py::none(), py::arg("progress") = py::none(),
        "Synthesizes a texture over a mesh (surface: anisometric synthesis in the atlas; solid: the material's "
        "interior) and returns the mesh with its atlas and maps; equal to `texfab texture`. graph: an exemplar "
        "graph file instead of the exemplar (`texfab texture --graph`)");

  py::class_<PieceOutput>(m, "Piece", "A piece of a broken model")
      .def_readonly("name", &PieceOutput::name)
      .def_readonly("mesh", &PieceOutput::mesh, "in the model's frame; materials outer..., interior...")
      .def_readonly("centroid", &PieceOutput::centroid)
      .def_readonly("volume", &PieceOutput::volume)
      .def_readonly("cut_area", &PieceOutput::cutArea);
  py::class_<BrokenOutput> broken(m, "BrokenModel", "The pieces of fracture() or cut()");
  broken.def_readonly("pieces", &BrokenOutput::pieces)
      .def_property_readonly("model_volume", [](const BrokenOutput& s) { return s.model->modelVolume; })
      .def_property_readonly("interior_scale",
                             [](const BrokenOutput& s) { return s.model->interiorScale * s.downsampling; })
      .def_property_readonly("notes", [](const BrokenOutput& s) { return s.model->notes; })
      .def_property_readonly("repairs", [](const BrokenOutput& s) { return s.model->preparation.repairs; })
      .def(
          "save",
          [](const BrokenOutput& s, const py::object& path, double explode, const std::string& up, bool draco,
             bool embed, const std::string& textures) {
            const geometry::MeshWriteOptions o = writeOptions(up, draco, embed, textures);
            const std::filesystem::path p = toPath(path);
            py::gil_scoped_release release;
            geometry::writeScene(render::sceneOf(*s.model, explode), p, o);
          },
          py::arg("path"), py::kw_only(), py::arg("explode") = 0.0, py::arg("up") = "y", py::arg("draco") = false,
          py::arg("embed") = false, py::arg("texture_format") = "keep",
          "Writes the pieces as glTF nodes (.glb .gltf), moved apart by `explode`, as `texfab fracture` does");

  const geometry::FractureOptions fo;
  const render::CutFaceTextureOptions co;
  m.def("_break_model", &breakModel, py::arg("mesh"), py::arg("planes") = py::none(), py::kw_only(),
        py::arg("pieces") = fo.pieces, py::arg("impact") = py::none(), py::arg("roughness") = fo.roughness,
        py::arg("min_volume") = fo.minVolume, py::arg("exemplar") = py::none(), py::arg("interior") = py::none(),
        py::arg("mode") = "solid", py::arg("texture_scale") = 0.0, py::arg("resolution") = to.atlas.pack.width,
        py::arg("interior_resolution") = 0, py::arg("gutter") = co.atlas.pack.gutter, py::arg("seed") = so.seed,
        py::arg("wrap") = "auto", py::arg("solid_method") = "lazy", py::arg("tile_size") = 32,
        py::arg("contrast_gain") = so.contrastGain, py::arg("refine") = so.refinePasses, py::arg("threads") = 0,
        py::arg("backend") = "cpu", py::arg("cache_dir") = py::none(), py::arg("progress") = py::none());
}

} // namespace texfab::python
