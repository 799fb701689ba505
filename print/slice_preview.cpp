// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/slice_preview.h"

#include "core/mip_pyramid.h"

#include <algorithm>
#include <cmath>

namespace texfab::print {

namespace {

constexpr int kMaxColumns = 2048;       // stored samples per view row
constexpr float kGround[3] = {0.03f, 0.03f, 0.035f};
constexpr int kMargin = 12;
constexpr double kEyeMm = 0.1;          // what the eye resolves at a reading distance (~1 arc minute at 30 cm)

float linear(uint8_t v) { return srgbToLinear(float(v) / 255.0f); }

int ceilDiv(int a, int b) { return (a + b - 1) / b; }

// Gaussian blur of the covered pixels (normalized by coverage, so the ground does not bleed in),
// sigmas in pixels along x and y: colour as the eye sees the dither at a reading distance.
void blurCovered(Image& image, const std::vector<float>& cover, double sigmaX, double sigmaY) {
  if (sigmaX < 0.3 && sigmaY < 0.3) return;
  const auto kernelOf = [](double sigma) {
    const int radius = sigma < 0.3 ? 0 : int(std::ceil(3 * sigma));
    std::vector<float> kernel(size_t(2 * radius + 1), 1.0f);
    for (int i = -radius; i <= radius && radius > 0; ++i)
      kernel[size_t(i + radius)] = float(std::exp(-0.5 * i * i / (sigma * sigma)));
    return kernel;
  };
  const std::vector<float> kernels[2] = {kernelOf(sigmaX), kernelOf(sigmaY)};
  const int w = image.width, h = image.height;
  std::vector<float> planes[4];  // r, g, b weighted by cover, and cover
  for (int c = 0; c < 4; ++c) {
    planes[c].resize(size_t(w) * size_t(h));
    for (size_t i = 0; i < planes[c].size(); ++i) planes[c][i] = c < 3 ? image.pixels[3 * i + size_t(c)] * cover[i] : cover[i];
  }
  for (int pass = 0; pass < 2; ++pass)
    for (std::vector<float>& plane : planes) {
      const std::vector<float>& kernel = kernels[pass];
      const int radius = int(kernel.size() / 2);
      if (radius == 0) continue;
      std::vector<float> out(plane.size(), 0.0f);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          float sum = 0;
          for (int k = -radius; k <= radius; ++k) {
            const int sx = pass == 0 ? std::clamp(x + k, 0, w - 1) : x, sy = pass == 1 ? std::clamp(y + k, 0, h - 1) : y;
            sum += kernel[size_t(k + radius)] * plane[size_t(sy) * size_t(w) + size_t(sx)];
          }
          out[size_t(y) * size_t(w) + size_t(x)] = sum;
        }
      plane = std::move(out);
    }
  for (size_t i = 0; i < cover.size(); ++i)
    if (cover[i] > 0 && planes[3][i] > 0)
      for (int c = 0; c < 3; ++c) image.pixels[3 * i + size_t(c)] = planes[c][i] / planes[3][i];
}

void blit(Image& canvas, const Image& image, int x0, int y0) {
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) canvas.at(x0 + x, y0 + y, c) = image.at(x, y, c);
}

} // namespace

SlicePreview::SlicePreview(const print::PrintGrid& grid, int firstLayer, int layerCount, int width)
    : grid_(grid), first_(firstLayer), count_(layerCount), width_(width) {
  frontStep_ = ceilDiv(grid.width, kMaxColumns);
  sideStep_ = ceilDiv(grid.height, kMaxColumns);
  frontColumns_ = ceilDiv(grid.width, frontStep_);
  sideColumns_ = ceilDiv(grid.height, sideStep_);
  front_.resize(size_t(count_) * size_t(frontColumns_));
  side_.resize(size_t(count_) * size_t(sideColumns_));
  scratch_.resize(size_t(count_));
  for (int k = 0; k < 4; ++k) shown_[size_t(k)] = firstLayer + std::min(layerCount - 1, layerCount * (k + 1) / 5);
  thumbStep_ = std::max(1, ceilDiv(std::max(grid.width, grid.height), 320));
  thumbWidth_ = ceilDiv(grid.width, thumbStep_);
  thumbHeight_ = ceilDiv(grid.height, thumbStep_);
  for (auto& t : thumbs_) t.assign(size_t(thumbWidth_) * size_t(thumbHeight_) * 4, 0.0f);
  for (auto& t : raw_) t.assign(size_t(thumbWidth_) * size_t(thumbHeight_) * 4, 0.0f);
}

void SlicePreview::addRow(int layer, int r, std::span<const print::VoxelSpan> spans, const uint8_t* rgba) {
  const size_t i = size_t(layer - first_);
  std::vector<Sample>& row = scratch_[i];
  if (r == 0) row.assign(size_t(grid_.width), Sample{});
  const int y = grid_.height - 1 - r;
  const float depth = float((y + 0.5) * grid_.pitchMm.y());
  for (const print::VoxelSpan& s : spans)
    for (int x = s.begin; x < s.end; ++x) {
      Sample& v = row[size_t(x)];  // rows come back to front: the nearest voxel is written last
      for (int c = 0; c < 3; ++c) v.rgb[c] = linear(rgba[4 * x + c]);
      v.depth = depth;
    }
  if (!spans.empty()) {  // the side view: the row's first voxel along +x
    Sample& v = side_[i * size_t(sideColumns_) + size_t(y / sideStep_)];
    const int x = spans.front().begin;
    const float w = 1.0f / float(sideStep_);
    for (int c = 0; c < 3; ++c) v.rgb[c] += w * linear(rgba[4 * x + c]);
    v.depth = std::max(v.depth, 0.0f) + w * float((x + 0.5) * grid_.pitchMm.x());
  }
  for (int k = 0; k < 4; ++k)
    if (shown_[size_t(k)] == layer)
      for (const print::VoxelSpan& s : spans)
        for (int x = s.begin; x < s.end; ++x) {
          const size_t at = 4 * (size_t(r / thumbStep_) * size_t(thumbWidth_) + size_t(x / thumbStep_));
          float* t = &thumbs_[size_t(k)][at];
          for (int c = 0; c < 3; ++c) t[c] += linear(rgba[4 * x + c]);
          t[3] += 1;
          if (r % thumbStep_ == 0 && x % thumbStep_ == 0) {  // the raw panel: one voxel per pixel
            float* p = &raw_[size_t(k)][at];
            for (int c = 0; c < 3; ++c) p[c] = linear(rgba[4 * x + c]);
            p[3] = 1;
          }
        }
  if (r == grid_.height - 1) {  // the front row, reduced to stored columns
    for (int col = 0; col < frontColumns_; ++col) {
      Sample& out = front_[i * size_t(frontColumns_) + size_t(col)];
      int n = 0;
      for (int x = col * frontStep_; x < std::min(grid_.width, (col + 1) * frontStep_); ++x)
        if (const Sample& v = row[size_t(x)]; v.depth >= 0) {
          for (int c = 0; c < 3; ++c) out.rgb[c] += v.rgb[c];
          out.depth = std::max(out.depth, 0.0f) + v.depth;
          ++n;
        }
      if (n)
        for (float* p : {&out.rgb[0], &out.rgb[1], &out.rgb[2], &out.depth}) *p /= float(n);
    }
    row = {};
  }
}

// A view: stored samples (count_ rows of `columns`, each column columnMm wide, each row a layer)
// resampled to square pixels of the front view's scale, top layer at the top, shaded by the
// slope of the depth.
Image SlicePreview::view(const std::vector<Sample>& samples, int columns, double columnMm) const {
  const double mmPerPixel = grid_.width * grid_.pitchMm.x() / width_;
  const int w = std::max(1, int(std::lround(columns * columnMm / mmPerPixel)));
  const int h = std::max(1, int(std::lround(count_ * grid_.pitchMm.z() / mmPerPixel)));
  std::vector<float> depth(size_t(w) * size_t(h), -1.0f), covered(size_t(w) * size_t(h), 0.0f);
  Image out(w, h, 3, PixelFormat::Float);
  for (int py = 0; py < h; ++py)
    for (int px = 0; px < w; ++px) {
      const int c0 = px * columns / w, c1 = std::max(c0 + 1, (px + 1) * columns / w);
      const int r0 = (h - 1 - py) * count_ / h, r1 = std::max(r0 + 1, (h - py) * count_ / h);
      float rgb[3] = {0, 0, 0}, d = 0;
      int n = 0, all = 0;
      for (int r = r0; r < r1; ++r)
        for (int c = c0; c < c1; ++c, ++all)
          if (const Sample& s = samples[size_t(r) * size_t(columns) + size_t(c)]; s.depth >= 0) {
            for (int k = 0; k < 3; ++k) rgb[k] += s.rgb[k];
            d += s.depth;
            ++n;
          }
      covered[size_t(py) * size_t(w) + size_t(px)] = float(n) / float(all);
      for (int k = 0; k < 3; ++k) out.at(px, py, k) = n ? rgb[k] / float(n) : kGround[k];
      if (n) depth[size_t(py) * size_t(w) + size_t(px)] = d / float(n);
    }
  blurCovered(out, covered, kEyeMm / mmPerPixel, kEyeMm / mmPerPixel);
  for (size_t i = 0; i < covered.size(); ++i)
    for (int k = 0; k < 3; ++k) out.pixels[3 * i + size_t(k)] = out.pixels[3 * i + size_t(k)] * covered[i] + kGround[k] * (1 - covered[i]);
  // Shade by the slope: normal (dd/dx, -1, dd/dz) lit from the upper left, in front.
  const Eigen::Vector3f light = Eigen::Vector3f(-0.4f, -1.0f, 0.5f).normalized();
  for (int py = 0; py < h; ++py)
    for (int px = 0; px < w; ++px) {
      const float d = depth[size_t(py) * size_t(w) + size_t(px)];
      if (d < 0) continue;
      auto at = [&](int x, int y) {
        x = std::clamp(x, 0, w - 1), y = std::clamp(y, 0, h - 1);
        const float v = depth[size_t(y) * size_t(w) + size_t(x)];
        return v < 0 ? d : v;
      };
      const float dx = (at(px + 1, py) - at(px - 1, py)) / float(2 * mmPerPixel);
      const float dz = (at(px, py - 1) - at(px, py + 1)) / float(2 * mmPerPixel);
      const float shade = 0.35f + 0.65f * std::max(0.0f, Eigen::Vector3f(dx, -1.0f, dz).normalized().dot(light));
      for (int k = 0; k < 3; ++k) out.at(px, py, k) *= shade;
    }
  return out;
}

Image SlicePreview::shownLayer(int k, bool seen) const {
  const float full = float(thumbStep_) * float(thumbStep_);
  const size_t pixels = size_t(thumbWidth_) * size_t(thumbHeight_);
  Image out(thumbWidth_, thumbHeight_, 3, PixelFormat::Float);
  std::vector<float> cover(pixels);
  for (size_t i = 0; i < pixels; ++i) {
    const float* p = &(seen ? thumbs_ : raw_)[size_t(k)][4 * i];
    cover[i] = seen ? std::min(1.0f, p[3] / full) : p[3];
    for (size_t c = 0; c < 3; ++c) out.pixels[3 * i + c] = p[3] > 0 ? (seen ? p[c] / p[3] : p[c]) : 0.0f;
  }
  // As seen: the materials' linear colours low-passed by the eye's Gaussian at the print's pitch.
  if (seen) blurCovered(out, cover, kEyeMm / (thumbStep_ * grid_.pitchMm.x()), kEyeMm / (thumbStep_ * grid_.pitchMm.y()));
  for (size_t i = 0; i < pixels; ++i)
    for (size_t c = 0; c < 3; ++c) out.pixels[3 * i + c] = out.pixels[3 * i + c] * cover[i] + kGround[c] * (1 - cover[i]);
  return out;
}

Image SlicePreview::compose() const {
  const Image front = view(front_, frontColumns_, frontStep_ * grid_.pitchMm.x());
  const Image side = view(side_, sideColumns_, sideStep_ * grid_.pitchMm.y());
  // Thumbnails: four layers at one scale, side by side under the views: as dithered, and below
  // them as seen.
  const int total = std::max(front.width + side.width + kMargin, 4 * thumbWidth_ + 3 * kMargin);
  const double thumbScale = double(total - 3 * kMargin) / 4.0 / (thumbWidth_ * thumbStep_ * grid_.pitchMm.x());
  const int tw = std::max(1, int(thumbWidth_ * thumbStep_ * grid_.pitchMm.x() * thumbScale));
  const int th = std::max(1, int(thumbHeight_ * thumbStep_ * grid_.pitchMm.y() * thumbScale));
  const int thumbTop = 2 * kMargin + std::max(front.height, side.height);
  Image canvas(total + 2 * kMargin, thumbTop + 2 * th + 2 * kMargin, 3, PixelFormat::Float);
  for (size_t i = 0; i < canvas.pixels.size(); ++i) canvas.pixels[i] = 0.18f;
  blit(canvas, front, kMargin, kMargin);
  blit(canvas, side, 2 * kMargin + front.width, kMargin);
  for (int k = 0; k < 4; ++k) {
    const int x0 = kMargin + k * (tw + kMargin);
    for (int seen = 0; seen < 2; ++seen) {
      const Image panel = shownLayer(k, seen == 1);
      Image thumb(tw, th, 3, PixelFormat::Float);
      for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x) {
          const int sx = std::min(thumbWidth_ - 1, x * thumbWidth_ / tw), sy = std::min(thumbHeight_ - 1, y * thumbHeight_ / th);
          for (int c = 0; c < 3; ++c) thumb.at(x, y, c) = panel.at(sx, sy, c);
        }
      blit(canvas, thumb, x0, thumbTop + seen * (th + kMargin));
    }
  }
  for (float& v : canvas.pixels) v = linearToSrgb(std::clamp(v, 0.0f, 1.0f));  // written as an 8-bit sRGB image
  canvas.format = PixelFormat::UInt8;
  return canvas;
}

} // namespace texfab::print
