// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/voxel_colors.h"

#include "core/error.h"
#include "render/bake.h"

#include <algorithm>
#include <cassert>
#include <array>
#include <cmath>

namespace texfab::print {

// ---- the solid texture ---------------------------------------------------------------------------

// The distinct solid voxels that the prepared layers' shell voxels sample, and their colours,
// sorted with the model axis along the print's rows fastest (the grid's modelAxisOfX: a run of a
// row's voxels is then a run of the list).
struct SolidVoxelColors::Samples {
  std::array<int, 3> order{2, 1, 0};  // slowest to fastest (the constructor's)
  std::vector<synthesis::Voxel> voxels;
  std::vector<float> rgb;  // linear, 3 per voxel

  bool less(const synthesis::Voxel& a, const synthesis::Voxel& b) const {
    for (int axis : order)
      if (a[axis] != b[axis]) return a[axis] < b[axis];
    return false;
  }
};

SolidVoxelColors::SolidVoxelColors(const synthesis::SolidAnalysis& analysis, const Image& ex, const Image& ey,
                                   const Image& ez, const synthesis::SolidSynthesisOptions& options, double scale,
                                   const print::PrintGrid& grid)
    : analysis_(analysis), ex_(ex), ey_(ey), ez_(ez), options_(options), scale_(scale), grid_(grid),
      modelPitch_((grid.rotation.transpose() * grid.pitch).cwiseAbs()),
      cache_(std::make_unique<synthesis::SolidLevelCache>(size_t(128) << 20)), samples_(std::make_unique<Samples>()) {
  options.validate();
  if (grid.rotation(0, grid.modelAxisOfX) != 1) throw Error("internal: the print's x must be a model axis, unflipped");
  if (!(scale > 0) || !std::isfinite(scale)) throw Error("solid texture scale must be a positive number of voxels per model unit");
  const double voxelsPerPitch = grid.pitch.minCoeff() * scale;
  sampling_ = voxelsPerPitch < render::kSolidTrilinearBelow ? SolidSampling::Trilinear
              : voxelsPerPitch >= kSolidBoxFrom                 ? SolidSampling::Box
                                                                : SolidSampling::Nearest;
  samples_->order = grid.modelAxisOfX == 0 ? std::array<int, 3>{2, 1, 0} : std::array<int, 3>{2, 0, 1};
  const Eigen::Vector3d far = grid.origin + Eigen::Vector3d(grid.width, grid.height, grid.layers).cwiseProduct(grid.pitch);
  const double reach = (std::max(grid.origin.cwiseAbs().maxCoeff(), far.cwiseAbs().maxCoeff()) + grid.pitch.maxCoeff()) *
                           scale + 1;  // any rotation; a footprint reaches a pitch and a voxel further
  if (!(reach < double(synthesis::kMaxSolidPosition)))
    throw Error("the texture scale puts the print outside the solid texture's range (|position x scale| <= 2^30)");
}

SolidVoxelColors::~SolidVoxelColors() = default;

const char* toString(SolidSampling sampling) {
  return sampling == SolidSampling::Trilinear ? "trilinear" : sampling == SolidSampling::Box ? "box" : "nearest";
}

SolidVoxelColors::Taps SolidVoxelColors::taps(double coordinate, int axis) const {
  Taps t;
  if (sampling_ == SolidSampling::Nearest) {
    t.first = int64_t(std::floor(coordinate * scale_));
    return t;
  }
  if (sampling_ == SolidSampling::Trilinear) {  // the two voxel centres around it
    const double q = coordinate * scale_ - 0.5, below = std::floor(q);
    t.first = int64_t(below), t.count = 2;
    t.weight[1] = float(q - below), t.weight[0] = 1.0f - t.weight[1];
    return t;
  }
  // Box: the voxels the print voxel [a, b) overlaps, each weighted by its share of the overlap;
  // wider than kMaxTaps voxels, kMaxTaps of them evenly spread.
  const double half = 0.5 * modelPitch_[axis];
  const double a = (coordinate - half) * scale_, b = (coordinate + half) * scale_;
  t.first = int64_t(std::floor(a));
  const int64_t last = int64_t(std::ceil(b)) - 1;
  if (last - t.first < kMaxTaps) {
    t.count = int(last - t.first + 1);
    for (int k = 0; k < t.count; ++k) {
      const double lo = std::max(a, double(t.first + k)), hi = std::min(b, double(t.first + k + 1));
      t.weight[size_t(k)] = float((hi - lo) / (b - a));
    }
  } else {
    t.count = kMaxTaps, t.stride = (last - t.first) / (kMaxTaps - 1);
    t.weight.fill(1.0f / float(kMaxTaps));
  }
  return t;
}

std::array<SolidVoxelColors::Taps, 2> SolidVoxelColors::rowTaps(int y, int layer) const {
  const Eigen::Vector3d c = grid_.center(0, y, layer);
  const std::array<int, 3>& order = samples_->order;
  return {taps(c[order[0]], order[0]), taps(c[order[1]], order[1])};
}

SolidVoxelColors::Taps SolidVoxelColors::fastTaps(int x) const {
  // The rotation takes the print's x to model axis modelAxisOfX with factor +1, so that
  // coordinate of center(x, y, layer) is centerX(x), bit for bit.
  return taps(grid_.centerX(x), grid_.modelAxisOfX);
}

void SolidVoxelColors::prepare(std::span<const print::LayerSpans> layers, const Context& ctx) {
  Samples prepared;
  const int fast = grid_.modelAxisOfX;
  prepared.order = samples_->order;
  // The solid voxels of each shell span: the runs of its print voxels' taps along the fast axis,
  // in each row of solid voxels the print row's footprint covers.
  struct Run {
    int64_t slow[2], lo, hi;
    bool operator<(const Run& o) const {
      return slow[0] != o.slow[0] ? slow[0] < o.slow[0] : slow[1] != o.slow[1] ? slow[1] < o.slow[1] : lo < o.lo;
    }
  };
  std::vector<Run> runs;
  std::vector<std::pair<int64_t, int64_t>> along;  // a span's runs along the fast axis
  for (const print::LayerSpans& layer : layers)
    for (int r = 0; r < layer.rows(); ++r) {
      const std::array<Taps, 2> row = rowTaps(grid_.height - 1 - r, layer.layer);
      for (const print::VoxelSpan& s : layer.row(r)) {
        if (!s.shell) continue;
        along.clear();
        for (int x = s.begin; x < s.end; ++x) {
          const Taps t = fastTaps(x);
          for (int k = 0; k < t.count; ++k)
            if (const int64_t f = t.voxel(k); along.empty() || f > along.back().second + 1)
              along.emplace_back(f, f);
            else
              along.back().second = std::max(along.back().second, f);
        }
        for (int i = 0; i < row[0].count; ++i)
          for (int j = 0; j < row[1].count; ++j)
            for (const auto& [lo, hi] : along) runs.push_back({{row[0].voxel(i), row[1].voxel(j)}, lo, hi});
      }
    }
  std::sort(runs.begin(), runs.end());
  for (size_t i = 0; i < runs.size();) {
    Run merged = runs[i];
    for (++i; i < runs.size() && runs[i].slow[0] == merged.slow[0] && runs[i].slow[1] == merged.slow[1] &&
              runs[i].lo <= merged.hi + 1;
         ++i)
      merged.hi = std::max(merged.hi, runs[i].hi);
    synthesis::Voxel v;
    v[prepared.order[0]] = merged.slow[0];
    v[prepared.order[1]] = merged.slow[1];
    for (int64_t f = merged.lo; f <= merged.hi; ++f) {
      v[fast] = f;
      prepared.voxels.push_back(v);
    }
  }
  const synthesis::SolidSynthesisResult result =
      synthesis::synthesizeSolid(analysis_, prepared.voxels, options_, cache_.get(), ctx);
  requested_ += int64_t(prepared.voxels.size());
  synthesized_ += result.voxelsSynthesized();
  std::vector<float> colors;
  synthesis::solidColors(result.triples, ex_, ey_, ez_, colors);
  const bool grey = synthesis::solidColorChannels(ex_, ey_, ez_) == 1;
  prepared.rgb.resize(3 * prepared.voxels.size());
  for (size_t i = 0; i < prepared.voxels.size(); ++i)
    for (size_t c = 0; c < 3; ++c) prepared.rgb[3 * i + c] = srgbToLinear(colors[grey ? i : 3 * i + c]);
  *samples_ = std::move(prepared);
}

void SolidVoxelColors::colors(int layer, int y, int begin, int end, float* rgba) const {
  const Samples& s = *samples_;
  const int fast = grid_.modelAxisOfX;
  const std::array<Taps, 2> row = rowTaps(y, layer);
  // One cursor per row of solid voxels the print row's footprint covers, each moving forward with x.
  const int rows = row[0].count * row[1].count;
  const int64_t firstAlong = fastTaps(begin).first;
  std::array<std::vector<synthesis::Voxel>::const_iterator, kMaxTaps * kMaxTaps> at;
  std::array<float, kMaxTaps * kMaxTaps> rowWeight;
  for (int d = 0; d < rows; ++d) {
    const int i = d % row[0].count, j = d / row[0].count;
    synthesis::Voxel first;
    first[s.order[0]] = row[0].voxel(i);
    first[s.order[1]] = row[1].voxel(j);
    first[fast] = firstAlong;
    at[size_t(d)] = std::lower_bound(s.voxels.begin(), s.voxels.end(), first,
                                     [&](const auto& a, const auto& b) { return s.less(a, b); });
    rowWeight[size_t(d)] = row[0].weight[size_t(i)] * row[1].weight[size_t(j)];
  }
  for (int x = begin; x < end; ++x, rgba += 4) {
    const Taps along = fastTaps(x);
    float sum[3] = {0, 0, 0};
    for (int d = 0; d < rows; ++d) {
      auto& it = at[size_t(d)];
      while (it + 1 < s.voxels.end() && (*it)[fast] < along.first) ++it;
      for (int k = 0; k < along.count; ++k) {
        auto tap = it;  // the row's voxels are sorted along the fast axis
        while (tap + 1 < s.voxels.end() && (*tap)[fast] < along.voxel(k)) ++tap;
        assert((*tap)[fast] == along.voxel(k) && "a voxel outside the prepared shell");
        const float* c = &s.rgb[3 * size_t(tap - s.voxels.begin())];
        const float w = rowWeight[size_t(d)] * along.weight[size_t(k)];
        for (int ch = 0; ch < 3; ++ch) sum[ch] += w * c[ch];
      }
    }
    std::copy(sum, sum + 3, rgba);
    rgba[3] = 1.0f;
  }
}

// ---- the model's own texture ----------------------------------------------------------------------

SurfaceVoxelColors::SurfaceVoxelColors(const geometry::Mesh& mesh, const print::PrintGrid& grid, double maxDistanceMm)
    : mesh_(mesh), grid_(grid), maxDistance_(float(maxDistanceMm / grid.mmPerUnit + grid.pitch.norm())), scene_(mesh) {
  pyramids_.resize(mesh.materials.size());
  for (size_t m = 0; m < mesh.materials.size(); ++m)
    if (const geometry::Texture& t = mesh.materials[m].baseColorTexture; t && mesh.hasUvs())
      pyramids_[m] = buildMipPyramid(*t.image, true);
  // Mip level per triangle: log2 of texels per voxel, texels per model unit from the triangle's
  // UV area over its area.
  const double voxel = std::cbrt(grid.pitch.prod());
  lod_.assign(mesh.triangleCount(), 0.0f);
  for (size_t t = 0; t < mesh.triangleCount() && mesh.hasUvs(); ++t) {
    const uint32_t m = mesh.materialOf(t);
    if (m >= pyramids_.size() || pyramids_[m].empty()) continue;
    const Image& image = pyramids_[m].levels[0];
    const geometry::Texture& tex = mesh.materials[m].baseColorTexture;
    const Eigen::Vector2f a = mesh.uvs[3 * t], b = mesh.uvs[3 * t + 1], c = mesh.uvs[3 * t + 2];
    const double uvArea = 0.5 * std::abs(double((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x())) *
                          std::abs(double(tex.scale.x() * tex.scale.y())) * image.width * image.height;
    const double area = 0.5 * double((mesh.corner(t, 1) - mesh.corner(t, 0)).cross(mesh.corner(t, 2) - mesh.corner(t, 0)).norm());
    if (area > 0 && uvArea > 0) lod_[t] = float(std::max(0.0, std::log2(std::sqrt(uvArea / area) * voxel)));
  }
}

SurfaceVoxelColors::~SurfaceVoxelColors() = default;

void SurfaceVoxelColors::colors(int layer, int y, int begin, int end, float* rgba) const {
  for (int x = begin; x < end; ++x, rgba += 4) {
    const geometry::SurfacePoint near = scene_.closestPoint(grid_.center(x, y, layer).cast<float>(), maxDistance_);
    Eigen::Vector4f c(1, 1, 1, 1);
    if (near.found && near.triangle < mesh_.triangleCount() && !mesh_.materials.empty()) {
      const uint32_t m = mesh_.materialOf(near.triangle);
      const geometry::Material& material = mesh_.materials[m];
      c = material.baseColorFactor;
      if (!pyramids_[m].empty()) {
        const size_t t = near.triangle;
        const Eigen::Vector2f& bary = near.barycentric;
        const Eigen::Vector2f uv = material.baseColorTexture.apply(
            (1 - bary.x() - bary.y()) * mesh_.uvs[3 * t] + bary.x() * mesh_.uvs[3 * t + 1] + bary.y() * mesh_.uvs[3 * t + 2]);
        c = c.cwiseProduct(sampleTrilinear(pyramids_[m], uv.x(), uv.y(), lod_[t]));
      }
      if (!material.blend) c[3] = 1.0f;
    }
    for (int k = 0; k < 4; ++k) rgba[k] = c[k];
  }
}

} // namespace texfab::print
