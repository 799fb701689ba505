// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Voxelization of a closed mesh one print layer at a time: which voxels of a layer lie inside the
// model, and which of those lie within a given distance of its surface (the coloured shell; the
// rest is the core, printed in one material). A layer is computed alone, in O(rows x crossings)
// for the inside and O(triangles near the layer x rows they span) for the shell, from the mesh,
// so any set of layers can be computed in any order, on any thread, with the same result.
//
// Inside: the plane of the layer cuts the triangles into segments; a scanline through each row of
// voxel centres counts the segments it crosses with their orientation (the non-zero winding rule,
// so overlapping or self-intersecting parts are a union). The rule is exact and consistent: a
// vertex on the plane counts as above it and a segment end on a row as above it (half-open
// rules, i.e. symbolic perturbation), and both triangles of an edge compute its cut point from
// the edge's two positions in one canonical order, so the cut contours are closed, bit for bit,
// whenever the mesh is.
//
// Shell: a voxel is in the shell when its centre lies within `shellMm` (Euclidean, in mm) of a
// triangle. For each triangle near the layer and each row it reaches, the part of the row within
// that distance of the triangle is one interval (the triangle swept by a ball is convex): the
// union of the row's intersections with the triangle's slab and with the capsules around its
// edges.

#include "geometry/mesh.h"
#include "print/print_grid.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace texfab::print {

struct VoxelizeOptions {
  /// Voxels whose centres lie within this distance of the surface form the shell, in mm;
  /// (0, 1e4]. A value larger than the model colours every voxel.
  double shellMm = 1.0;

  void validate() const;
};

/// A run [begin, end) of voxels of one row, all inside the model, all shell or all core.
struct VoxelSpan {
  int32_t begin = 0;
  int32_t end = 0;
  bool shell = false;
};

/// The inside of one layer as runs per image row (row 0 is the top row, y = height - 1).
struct LayerSpans {
  int layer = 0;
  std::vector<uint32_t> rowStart;  ///< height + 1 offsets into `spans`
  std::vector<VoxelSpan> spans;    ///< per row: sorted, disjoint; neighbours that touch differ in `shell`

  std::span<const VoxelSpan> row(int r) const {
    return {spans.data() + rowStart[size_t(r)], spans.data() + rowStart[size_t(r) + 1]};
  }
  int rows() const { return rowStart.empty() ? 0 : int(rowStart.size()) - 1; }
  int64_t insideVoxels() const;
  int64_t shellVoxels() const;
};

/// What the voxelizer found and did to the mesh before slicing.
struct VoxelizerReport {
  size_t weldedVertices = 0;   ///< vertices merged with another at the same position
  size_t triangles = 0;        ///< triangles sliced (degenerate ones included: they cut nothing)
  std::vector<std::string> repairs;  ///< one line per repair made
};

/// Slices `mesh` on `grid`. The mesh must be closed: after merging vertices at equal positions,
/// every edge must be matched by an edge running the other way (a triangle soup that bounds a
/// volume; several parts, cavities and self-intersections are fine). Construction throws
/// texfab::Error for an open or inconsistently oriented mesh (naming how many edges are
/// unmatched) and for invalid options. Queries are const and thread-safe.
class LayerVoxelizer {
public:
  LayerVoxelizer(const geometry::Mesh& mesh, const PrintGrid& grid, const VoxelizeOptions& options = {});
  ~LayerVoxelizer();
  LayerVoxelizer(LayerVoxelizer&&) noexcept;
  LayerVoxelizer& operator=(LayerVoxelizer&&) noexcept;

  /// The inside and shell voxels of `layer` in [0, grid.layers).
  LayerSpans voxelize(int layer) const;

  const PrintGrid& grid() const;
  const VoxelizeOptions& options() const;
  const VoxelizerReport& report() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace texfab::print
