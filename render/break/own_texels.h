// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A piece of a broken model written on its own carries only its own texels: the atlases its
// materials share with the other pieces are cut down to the part its triangles use, and its UVs
// follow (texfab fracture/cut --separate).

#include "geometry/mesh.h"

namespace texfab::render {

/// `mesh` with each textured material's images cropped to the texels its triangles use: the
/// rectangle around every triangle's texel box grown by `margin` texels (for filtering), texels
/// outside all those grown boxes cleared to zero (they compress to nearly nothing), and the
/// material's UVs mapped into the crop, so that every texel a triangle shows keeps its value. A
/// material whose UVs leave [0, 1] (a tiling texture), whose images differ in size or that has a
/// texture transform is kept as it is.
geometry::Mesh keepOwnTexels(const geometry::Mesh& mesh, int margin = 8);

} // namespace texfab::render
