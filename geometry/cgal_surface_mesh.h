// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// CGAL's Surface_mesh on the kernel of the solid-geometry code (exact predicates, inexact
// constructions), with short names for its handles. Private to geometry/'s .cpp files: public
// headers never include CGAL.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

namespace texfab::geometry::cgal {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using VI = SurfaceMesh::Vertex_index;
using FI = SurfaceMesh::Face_index;
using HI = SurfaceMesh::Halfedge_index;
using EI = SurfaceMesh::Edge_index;

} // namespace texfab::geometry::cgal
