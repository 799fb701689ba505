// SPDX-License-Identifier: GPL-3.0-or-later
// texfab.Mesh, texfab.Material, load_mesh, read_image, write_image.
#include "python/src/bindings.h"
#include "python/src/convert.h"

#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/mesh.h"
#include "geometry/up_axis.h"

#include <pybind11/stl.h>

#include <cstring>

namespace texfab::python {

namespace {

// A read-only view of `count` rows of `shape` values, owned by `self`.
template <class T>
py::array view(const py::object& self, const T* data, std::vector<py::ssize_t> shape) {
  py::array array(py::dtype::of<T>(), shape, data, self);
  py::detail::array_proxy(array.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return array;
}

template <class T, class Element>
void copyRows(const py::handle& values, std::vector<Element>& out, std::vector<py::ssize_t> shape, const char* what) {
  const auto array = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!array || array.ndim() != py::ssize_t(shape.size()))
    throw Error(std::string(what) + ": expected an array of " + std::to_string(shape.size()) + " dimensions");
  size_t count = 1;
  for (size_t d = 0; d < shape.size(); ++d) {
    if (shape[d] >= 0 && array.shape(py::ssize_t(d)) != shape[d])
      throw Error(std::string(what) + ": dimension " + std::to_string(d) + " must be " + std::to_string(shape[d]));
    count *= size_t(array.shape(py::ssize_t(d)));
  }
  static_assert(sizeof(Element) % sizeof(T) == 0);
  out.resize(count * sizeof(T) / sizeof(Element));
  std::memcpy(static_cast<void*>(out.data()), array.data(), count * sizeof(T));
}

geometry::Mesh makeMesh(const py::object& vertices, const py::object& triangles, const py::object& uvs) {
  geometry::Mesh mesh;
  copyRows<float>(vertices, mesh.positions, {-1, 3}, "vertices");
  const auto signedIndices = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(triangles);
  if (!signedIndices || signedIndices.ndim() != 2 || signedIndices.shape(1) != 3)
    throw Error("triangles: expected an array of shape (M, 3)");
  mesh.triangles.resize(size_t(signedIndices.shape(0)));
  const int64_t* index = signedIndices.data();
  for (auto& t : mesh.triangles)
    for (uint32_t& v : t) {
      if (*index < 0 || *index >= int64_t(mesh.positions.size()))
        throw Error("triangles: index " + std::to_string(*index) + " is out of range (" +
                    std::to_string(mesh.positions.size()) + " vertices)");
      v = uint32_t(*index++);
    }
  if (!uvs.is_none()) copyRows<float>(uvs, mesh.uvs, {py::ssize_t(mesh.triangles.size()), 3, 2}, "uvs");
  geometry::validateMesh(mesh, "mesh");
  return mesh;
}

void bindMaterial(py::module_& m) {
  using geometry::Material;
  py::class_<Material>(m, "Material", "A glTF PBR metallic-roughness material")
      .def_readonly("name", &Material::name)
      .def_property_readonly("base_color_factor",
                             [](const Material& s) { return py::array_t<float>(4, s.baseColorFactor.data()); })
      .def_readonly("metallic_factor", &Material::metallicFactor)
      .def_readonly("roughness_factor", &Material::roughnessFactor)
      .def_property_readonly("base_color", [](const Material& s) { return optionalImageArray(s.baseColorTexture.image); })
      .def_property_readonly("normal", [](const Material& s) { return optionalImageArray(s.normalTexture.image); })
      .def_property_readonly("metallic_roughness",
                             [](const Material& s) { return optionalImageArray(s.metallicRoughnessTexture.image); })
      .def("__repr__", [](const Material& s) { return "<texfab.Material '" + s.name + "'>"; });
}

} // namespace

geometry::MeshWriteOptions writeOptions(const std::string& up, bool draco, bool embed, const std::string& textureFormat) {
  using geometry::TextureEncoding;
  geometry::MeshWriteOptions o;
  o.up = geometry::upVector(geometry::parseUpAxis(up));
  o.draco = draco;
  o.embed = embed;
  o.textures = choose<TextureEncoding>(textureFormat, "texture_format",
                      {{"keep", TextureEncoding::Keep}, {"png", TextureEncoding::Png}, {"jpeg", TextureEncoding::Jpeg},
                       {"webp", TextureEncoding::Webp}});
  return o;
}

void bindMesh(py::module_& m) {
  using geometry::Mesh;
  bindMaterial(m);
  py::class_<Mesh> mesh(m, "Mesh", "An indexed triangle mesh; attributes per corner (3 per triangle)");
  mesh.def(py::init(&makeMesh), py::arg("vertices"), py::arg("triangles"), py::arg("uvs") = py::none(),
           "vertices (N, 3), triangles (M, 3) counter-clockwise seen from outside, uvs (M, 3, 2) per corner")
      .def_property_readonly("vertices", [](const py::object& self) {
        const Mesh& s = self.cast<const Mesh&>();
        return view(self, s.positions.data()->data(), {py::ssize_t(s.positions.size()), 3});
      })
      .def_property_readonly("triangles", [](const py::object& self) {
        const Mesh& s = self.cast<const Mesh&>();
        return view(self, s.triangles.data()->data(), {py::ssize_t(s.triangles.size()), 3});
      })
      .def_property_readonly("uvs", [](const py::object& self) -> py::object {
        const Mesh& s = self.cast<const Mesh&>();
        if (!s.hasUvs()) return py::none();
        return view(self, s.uvs.data()->data(), {py::ssize_t(s.triangles.size()), 3, 2});
      })
      .def_property_readonly("face_materials", [](const Mesh& s) {
        py::array_t<uint32_t> ids(py::ssize_t(s.triangleCount()));
        for (size_t t = 0; t < s.triangleCount(); ++t) ids.mutable_at(py::ssize_t(t)) = s.materialOf(t);
        return ids;
      })
      .def_property_readonly("face_tags", [](const Mesh& s) {
        py::array_t<uint32_t> tags(py::ssize_t(s.triangleCount()));
        for (size_t t = 0; t < s.triangleCount(); ++t) tags.mutable_at(py::ssize_t(t)) = s.tagOf(t);
        return tags;
      })
      .def_readonly("materials", &Mesh::materials)
      .def("__repr__", [](const Mesh& s) {
        return "<texfab.Mesh " + std::to_string(s.vertexCount()) + " vertices, " + std::to_string(s.triangleCount()) +
               " triangles>";
      });
  defSave(mesh, [](const Mesh& s, const py::object& path, const geometry::MeshWriteOptions& o) {
    const std::filesystem::path p = toPath(path);
    py::gil_scoped_release release;
    geometry::writeMesh(s, p, o);
  }, "Writes the mesh (.glb .gltf .obj .ply .off .stl .3mf) as the command line does");

  m.def("load_mesh", [](const py::object& path) {
    const std::filesystem::path p = toPath(path);
    py::gil_scoped_release release;
    return geometry::readMesh(p);
  }, py::arg("path"), "Reads a mesh (.obj .ply .off .stl .gltf .glb .3mf)");
  m.def("read_image", [](const py::object& path) {
    const std::filesystem::path p = toPath(path);
    Image image;
    {
      py::gil_scoped_release release;
      image = readImage(p);
    }
    return imageArray(std::move(image));
  }, py::arg("path"), "Reads an image as float32 (H, W, C), values normalized as the file stores them");
  m.def("write_image", [](const py::object& image, const py::object& path, int bits) {
    Image out = toImage(image, "image");
    out.format = choose<PixelFormat>(std::to_string(bits), "bits",
                        {{"8", PixelFormat::UInt8}, {"16", PixelFormat::UInt16}, {"32", PixelFormat::Float}});
    const std::filesystem::path p = toPath(path);
    py::gil_scoped_release release;
    writeImage(out, p);
  }, py::arg("image"), py::arg("path"), py::kw_only(), py::arg("bits") = 8,
        "Writes an image as texfab does (8 or 16 bits: round(v * max), clamped; 32: float where the format allows)");
}

} // namespace texfab::python
