// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The parts of the module, one per file: images and meshes; 2-D and solid synthesis; the jobs
// (texture, fracture and cut, slice).

#include "geometry/io/mesh_io.h"

#include <pybind11/pybind11.h>

#include <string>

namespace texfab::python {
namespace py = pybind11;

void bindMesh(py::module_& m);
void bindSynthesis(py::module_& m);
void bindJobs(py::module_& m);
void bindSlice(py::module_& m);

/// The up axis by name: "x", "-x", "y", "-y", "z", "-z".
/// The writer's options as Mesh.save takes them.
geometry::MeshWriteOptions writeOptions(const std::string& up, bool draco, bool embed, const std::string& textureFormat);
/// Adds save(path, *, up, draco, embed, texture_format) to a class whose objects `write`s.
template <class Class, class Write>
void defSave(Class& c, Write write, const char* doc) {
  c.def(
      "save",
      [write](typename Class::type& self, const py::object& path, const std::string& up, bool draco, bool embed,
              const std::string& textures) { write(self, path, writeOptions(up, draco, embed, textures)); },
      py::arg("path"), py::kw_only(), py::arg("up") = "y", py::arg("draco") = false, py::arg("embed") = false,
      py::arg("texture_format") = "keep", doc);
}

} // namespace texfab::python
