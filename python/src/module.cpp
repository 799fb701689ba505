// SPDX-License-Identifier: GPL-3.0-or-later
// texfab._texfab: the library's entries for Python (re-exported by the texfab package).
#include "python/src/bindings.h"

#include "core/error.h"

namespace texfab::python {

PYBIND11_MODULE(_texfab, m) {
  m.doc() = "texfab: mesh texturing by example and fabrication (synthesis, solid textures, fracture, slices)";
  m.attr("__version__") = TEXFAB_VERSION;
  const py::exception<Error>& error = py::register_exception<Error>(m, "Error");
  py::register_exception<Cancelled>(m, "Cancelled", error);
  bindMesh(m);
  bindSynthesis(m);
  bindJobs(m);
  bindSlice(m);
}

} // namespace texfab::python
