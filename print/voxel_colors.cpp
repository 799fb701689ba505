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
      trilinear_(grid.pitch.minCoeff() * scale < render::kSolidTrilinearBelow),
      cache_(std::make_unique<synthesis::SolidLevelCache>(size_t(128) << 20)), samples_(std::make_unique<Samples>()) {
  options.validate();
  if (grid.rotation(0, grid.modelAxisOfX) != 1) throw Error("internal: the print's x must be a model axis, unflipped");
  if (!(scale > 0) || !std::isfinite(scale)) throw Error("solid texture scale must be a positive number of voxels per model unit");
  samples_->order = grid.modelAxisOfX == 0 ? std::array<int, 3>{2, 1, 0} : std::array<int, 3>{2, 0, 1};
  const Eigen::Vector3d far = grid.origin + Eigen::Vector3d(grid.width, grid.height, grid.layers).cwiseProduct(grid.pitch);
  const double reach = std::max(grid.origin.cwiseAbs().maxCoeff(), far.cwiseAbs().maxCoeff()) * scale + 1;  // any rotation
  if (!(reach < double(synthesis::kMaxSolidPosition)))
    throw Error("the texture scale puts the print outside the solid texture's range (|position x scale| <= 2^30)");
}

SolidVoxelColors::~SolidVoxelColors() = default;

SolidVoxelColors::Position SolidVoxelColors::solidPosition(double coordinate) const {
  const double q = coordinate * scale_ - (trilinear_ ? 0.5 : 0.0);  // trilinear: on the voxel centres' lattice
  const double below = std::floor(q);
  return {int64_t(below), float(q - below)};
}

std::array<SolidVoxelColors::Position, 2> SolidVoxelColors::rowPosition(int y, int layer) const {
  const Eigen::Vector3d c = grid_.center(0, y, layer);
  const std::array<int, 3>& order = samples_->order;
  return {solidPosition(c[order[0]]), solidPosition(c[order[1]])};
}

SolidVoxelColors::Position SolidVoxelColors::fastPosition(int x) const {
  // The rotation takes the print's x to model axis modelAxisOfX with factor +1, so that
  // coordinate of center(x, y, layer) is centerX(x), bit for bit.
  return solidPosition(grid_.centerX(x));
}

void SolidVoxelColors::prepare(std::span<const print::LayerSpans> layers, const Context& ctx) {
  Samples prepared;
  const int fast = grid_.modelAxisOfX;
  prepared.order = samples_->order;
  // The solid voxels of each shell span: a run along the fast axis (every one between the ends
  // when a print voxel is narrower than a solid voxel, else listed one by one); trilinear, the
  // next voxel along every axis too.
  struct Run {
    int64_t slow[2], lo, hi;
    bool operator<(const Run& o) const {
      return slow[0] != o.slow[0] ? slow[0] < o.slow[0] : slow[1] != o.slow[1] ? slow[1] < o.slow[1] : lo < o.lo;
    }
  };
  const int rows = trilinear_ ? 4 : 1;     // rows of solid voxels per print row (trilinear: 2 x 2)
  const int64_t next = trilinear_ ? 1 : 0;  // and the next voxel along the row
  const bool contiguous = grid_.pitch.x() * scale_ <= 0.5;
  std::vector<Run> runs;
  for (const print::LayerSpans& layer : layers)
    for (int r = 0; r < layer.rows(); ++r) {
      const std::array<Position, 2> row = rowPosition(grid_.height - 1 - r, layer.layer);
      for (const print::VoxelSpan& s : layer.row(r)) {
        if (!s.shell) continue;
        for (int d = 0; d < rows; ++d) {
          const int64_t slow[2] = {row[0].voxel + (d & 1), row[1].voxel + (d >> 1)};
          if (contiguous) {
            runs.push_back({{slow[0], slow[1]}, fastPosition(s.begin).voxel, fastPosition(s.end - 1).voxel + next});
            continue;
          }
          for (int x = s.begin; x < s.end; ++x)
            if (const int64_t f = fastPosition(x).voxel; x == s.begin || f > runs.back().hi)
              runs.push_back({{slow[0], slow[1]}, f, f + next});
            else
              runs.back().hi = std::max(runs.back().hi, f + next);
        }
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
  const std::array<Position, 2> row = rowPosition(y, layer);
  // One cursor per row of solid voxels read (trilinear: the 4 rows around the print row), each
  // moving forward with x.
  const int rows = trilinear_ ? 4 : 1;
  std::array<std::vector<synthesis::Voxel>::const_iterator, 4> at;
  for (int d = 0; d < rows; ++d) {
    synthesis::Voxel first;
    first[s.order[0]] = row[0].voxel + (d & 1);
    first[s.order[1]] = row[1].voxel + (d >> 1);
    first[fast] = fastPosition(begin).voxel;
    at[size_t(d)] = std::lower_bound(s.voxels.begin(), s.voxels.end(), first,
                                     [&](const auto& a, const auto& b) { return s.less(a, b); });
  }
  for (int x = begin; x < end; ++x, rgba += 4) {
    const Position along = fastPosition(x);
    float sum[3] = {0, 0, 0};
    for (int d = 0; d < rows; ++d) {
      auto& i = at[size_t(d)];
      while (i + 1 < s.voxels.end() && (*i)[fast] < along.voxel) ++i;
      assert(i + (rows > 1) < s.voxels.end() && (*i)[fast] == along.voxel && "a voxel outside the prepared shell");
      const float* c = &s.rgb[3 * size_t(i - s.voxels.begin())];
      if (rows == 1) {
        std::copy(c, c + 3, sum);
        break;
      }
      // Trilinear: this row's two voxels along x, weighted by the row's share of the 4.
      const float w = ((d & 1) ? row[0].fraction : 1.0f - row[0].fraction) *
                      ((d >> 1) ? row[1].fraction : 1.0f - row[1].fraction);
      for (int k = 0; k < 3; ++k) sum[k] += w * ((1.0f - along.fraction) * c[k] + along.fraction * c[3 + k]);
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
