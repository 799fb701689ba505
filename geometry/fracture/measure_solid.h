// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Volume, centroid and area of a closed mesh (divergence theorem, in double precision).

#include "geometry/mesh.h"

#include <Eigen/Core>

#include <cstdint>

namespace texfab::geometry {

struct SolidMeasures {
  double volume = 0;                                 ///< model units³; negative when inside out
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero(); ///< of the volume (the area centroid when the volume is 0)
  double area = 0;                                   ///< model units²
  double taggedArea = 0;                             ///< of the triangles tagged `tag`
};

/// Exact for a closed, consistently oriented mesh; meaningless for an open one.
SolidMeasures measureSolid(const Mesh& mesh, uint32_t tag = 1);

} // namespace texfab::geometry
