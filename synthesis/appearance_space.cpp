// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006, §3.
#include "synthesis/appearance_space.h"

#include <algorithm>
#include <cmath>

namespace texfab::synthesis::detail {

int64_t pixelDistance2(int ax, int ay, int bx, int by, int w, int h, ExemplarWrap wrap) {
  int dx = std::abs(ax - bx), dy = std::abs(ay - by);
  if (wrap == ExemplarWrap::Tile) {
    dx = std::min(dx, w - dx);
    dy = std::min(dy, h - dy);
  }
  return int64_t(dx) * dx + int64_t(dy) * dy;
}

std::vector<float> patchWeights() {
  const int side = 2 * kPatchRadius + 1;
  std::vector<float> weights(size_t(side * side));
  for (int j = -kPatchRadius; j <= kPatchRadius; ++j)
    for (int i = -kPatchRadius; i <= kPatchRadius; ++i)
      weights[size_t((j + kPatchRadius) * side + i + kPatchRadius)] =
          std::sqrt(std::exp(-float(i * i + j * j) / (2 * kPatchSigma * kPatchSigma)));
  return weights;
}

void patchOf(const Image& level, int x, int y, int spacing, ExemplarWrap w, const float* weights, float* out) {
  const int side = 2 * kPatchRadius + 1;
  for (int j = -kPatchRadius; j <= kPatchRadius; ++j)
    for (int i = -kPatchRadius; i <= kPatchRadius; ++i) {
      const float wgt = weights[(j + kPatchRadius) * side + i + kPatchRadius];
      const float* p =
          level.pixel(foldIndex(x + i * spacing, level.width, w), foldIndex(y + j * spacing, level.height, w));
      for (int ch = 0; ch < level.channels; ++ch) *out++ = wgt * p[ch];
    }
}

Eigen::MatrixXf principalBasis(Eigen::MatrixXf& raw, Eigen::RowVectorXf& mean) {
  const int n = int(raw.rows()), dims = int(raw.cols());
  mean = raw.colwise().mean();
  raw.rowwise() -= mean;
  const Eigen::MatrixXf covariance = (raw.transpose() * raw) / float(std::max(1, n - 1));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXf> solver(covariance);
  // Eigenvalues come in increasing order: take the last kAppearanceDims columns.
  const int keep = std::min(kAppearanceDims, dims);
  Eigen::MatrixXf basis = Eigen::MatrixXf::Zero(dims, kAppearanceDims);
  for (int k = 0; k < keep; ++k) {
    Eigen::VectorXf v = solver.eigenvectors().col(dims - 1 - k);
    Eigen::Index arg;
    v.cwiseAbs().maxCoeff(&arg);
    if (v(arg) < 0) v = -v;
    basis.col(k) = v;
  }
  return basis;
}

void projectPatch(const float* patch, int dims, const Eigen::RowVectorXf& mean, const float* basis, float scale,
                  int8_t* out) {
  float sum[kAppearanceDims] = {};
  for (int d = 0; d < dims; ++d) {
    const float v = patch[d] - mean(d);
    const float* row = basis + size_t(d) * kAppearanceDims;
    for (int k = 0; k < kAppearanceDims; ++k) sum[k] += row[k] * v;
  }
  for (int k = 0; k < kAppearanceDims; ++k) out[k] = int8_t(std::clamp(std::lrint(sum[k] * scale), -127L, 127L));
}

} // namespace texfab::synthesis::detail
