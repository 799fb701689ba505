// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/fracture/measure_solid.h"

namespace texfab::geometry {

SolidMeasures measureSolid(const Mesh& mesh, uint32_t tag) {
  SolidMeasures m;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero(), areaMoment = Eigen::Vector3d::Zero();
  // Relative to a vertex of the mesh, against cancellation far from the origin.
  const Eigen::Vector3d o = mesh.positions.empty() ? Eigen::Vector3d(0, 0, 0) : Eigen::Vector3d(mesh.positions[0].cast<double>());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3d a = mesh.corner(t, 0).cast<double>() - o, b = mesh.corner(t, 1).cast<double>() - o,
                          c = mesh.corner(t, 2).cast<double>() - o;
    // Signed volume of the tetrahedron (o, a, b, c) and its centroid o + (a + b + c) / 4.
    const double v = a.dot(b.cross(c)) / 6.0;
    m.volume += v;
    moment += v * (a + b + c) / 4.0;
    const double area = 0.5 * (b - a).cross(c - a).norm();
    m.area += area;
    areaMoment += area * (a + b + c) / 3.0;
    if (mesh.tagOf(t) == tag) m.taggedArea += area;
  }
  if (m.volume != 0) m.centroid = o + moment / m.volume;
  else if (m.area > 0) m.centroid = o + areaMoment / m.area;
  return m;
}

} // namespace texfab::geometry
