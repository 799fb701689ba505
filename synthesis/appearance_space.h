// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The pieces of appearance-space analysis (Lefebvre & Hoppe 2006, §3) that every analysis shares:
// Gaussian-weighted 5x5 neighborhoods of a stack level and their principal basis. Internal to the
// analyses (exemplar_analysis.cpp, exemplar_graph.cpp), which are compiled for the baseline
// instruction set (synthesis/CMakeLists.txt): Eigen's sums follow the vector width.

#include "core/image.h"
#include "synthesis/exemplar_analysis.h"

#include <Eigen/Dense>
#include <nanoflann.hpp>

#include <cstdint>
#include <vector>

namespace texfab::synthesis::detail {

inline constexpr int kPatchRadius = 2;      ///< 5x5 appearance neighborhoods
inline constexpr float kPatchSigma = 1.5f;  ///< Gaussian weighting of the 5x5 samples

/// Appearance vectors as a point cloud for nanoflann's exact k-nearest search.
struct AppearanceCloud {
  std::vector<float> points;  ///< n * kAppearanceDims
  size_t kdtree_get_point_count() const { return points.size() / kAppearanceDims; }
  float kdtree_get_pt(size_t i, size_t d) const { return points[i * kAppearanceDims + d]; }
  template <class Box> bool kdtree_get_bbox(Box&) const { return false; }
};
using AppearanceTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, AppearanceCloud>, AppearanceCloud, kAppearanceDims, uint32_t>;

/// Squared distance between two pixels of a w x h exemplar, toroidal (Tile) or not.
int64_t pixelDistance2(int ax, int ay, int bx, int by, int w, int h, ExemplarWrap wrap);

/// The square roots of the Gaussian weights of the 5x5 samples, row by row (so that distances
/// between weighted patches are Gaussian-weighted).
std::vector<float> patchWeights();

/// The weighted 5x5 neighborhood of (x, y) with taps `spacing` apart: 25 * channels values.
void patchOf(const Image& level, int x, int y, int spacing, ExemplarWrap w, const float* weights, float* out);

/// The PCA basis (dims x kAppearanceDims, largest variance first) of the rows of `raw`, which are
/// centred in place; each column's sign is fixed (largest-magnitude component positive) so the
/// basis is reproducible.
Eigen::MatrixXf principalBasis(Eigen::MatrixXf& raw, Eigen::RowVectorXf& mean);

/// The appearance vector of a weighted patch of `dims` values: (patch - mean) projected on `basis`
/// (dims x kAppearanceDims, row-major), each coefficient summed over d in order (the same bits
/// however the loop is vectorized: each lane is its own sum), times `scale`, rounded and clamped
/// to +-127.
void projectPatch(const float* patch, int dims, const Eigen::RowVectorXf& mean, const float* basis, float scale,
                  int8_t* out);

} // namespace texfab::synthesis::detail
