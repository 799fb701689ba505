// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/dither_measures.h"

#include <algorithm>
#include <cmath>

namespace texfab::print {

std::vector<float> ditherBox(const DitherBox& box, std::span<const float> target, const MaterialMixer& mixer,
                             DitherMode mode, const BlueNoiseVolume* noise) {
  std::vector<float> out(target.size());
  const print::VoxelSpan span{0, box.width, true};
  std::vector<float> rgba(4 * size_t(box.width));
  std::vector<uint8_t> row(size_t(box.width));
  for (int z = 0; z < box.layers; ++z) {
    LayerDitherer ditherer(mixer, mode, noise, z, box.width);
    for (int y = box.height - 1; y >= 0; --y) {
      const size_t first = (size_t(z) * size_t(box.height) + size_t(y)) * size_t(box.width);
      for (int x = 0; x < box.width; ++x) {
        std::copy_n(&target[3 * (first + size_t(x))], 3, &rgba[4 * size_t(x)]);
        rgba[4 * size_t(x) + 3] = 1;
      }
      ditherer.ditherRow(y, {&span, 1}, rgba.data(), row.data());
      for (int x = 0; x < box.width; ++x) {
        const std::array<float, 3>& c = mixer.linearColor(row[size_t(x)] - 1);
        std::copy(c.begin(), c.end(), &out[3 * (first + size_t(x))]);
      }
    }
  }
  return out;
}

std::vector<float> reproducedColors(std::span<const float> target, const MaterialMixer& mixer) {
  std::vector<float> out(target.size());
  for (size_t i = 0; i + 2 < target.size(); i += 3) {
    const std::array<float, 3> c = mixer.reproduced(&target[i]);
    std::copy(c.begin(), c.end(), &out[i]);
  }
  return out;
}

BlockColorError blockColorError(const DitherBox& box, std::span<const float> dithered, std::span<const float> reference,
                                int block) {
  BlockColorError e;
  int blocks = 0;
  for (int bz = 0; bz + block <= box.layers; bz += block)
    for (int by = 0; by + block <= box.height; by += block)
      for (int bx = 0; bx + block <= box.width; bx += block, ++blocks) {
        double d[3] = {0, 0, 0};
        for (int z = bz; z < bz + block; ++z)
          for (int y = by; y < by + block; ++y)
            for (int x = bx; x < bx + block; ++x) {
              const size_t v = 3 * ((size_t(z) * size_t(box.height) + size_t(y)) * size_t(box.width) + size_t(x));
              for (size_t k = 0; k < 3; ++k) d[k] += double(dithered[v + k]) - reference[v + k];
            }
        const double error = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / std::pow(double(block), 3);
        e.mean += error;
        e.worst = std::max(e.worst, error);
      }
  if (blocks > 0) e.mean /= blocks;
  return e;
}

double visibleError(const DitherBox& box, std::span<const float> dithered, std::span<const float> reference,
                    bool vertical, int index, double sigmaMm) {
  const int w = box.width, h = vertical ? box.layers : box.height;
  auto cell = [&](int i, int j) {  // plane cell (i, j) -> voxel
    return vertical ? (size_t(j) * size_t(box.height) + size_t(index)) * size_t(box.width) + size_t(i)
                    : (size_t(index) * size_t(box.height) + size_t(j)) * size_t(box.width) + size_t(i);
  };
  std::vector<double> diff(3 * size_t(w) * size_t(h));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      for (size_t k = 0; k < 3; ++k)
        diff[3 * (size_t(j) * size_t(w) + size_t(i)) + k] = double(dithered[3 * cell(i, j) + k]) - reference[3 * cell(i, j) + k];
  // Separable Gaussian, normalized over the taps inside the plane.
  auto blur = [&](double sigma, bool alongX) {
    const int r = int(std::ceil(3 * sigma));
    std::vector<double> out(diff.size(), 0.0);
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        double sum = 0;
        const size_t o = 3 * (size_t(j) * size_t(w) + size_t(i));
        for (int t = -r; t <= r; ++t) {
          const int ii = alongX ? i + t : i, jj = alongX ? j : j + t;
          if (ii < 0 || ii >= w || jj < 0 || jj >= h) continue;
          const double g = std::exp(-0.5 * t * t / (sigma * sigma));
          sum += g;
          for (size_t k = 0; k < 3; ++k) out[o + k] += g * diff[3 * (size_t(jj) * size_t(w) + size_t(ii)) + k];
        }
        for (size_t k = 0; k < 3; ++k) out[o + k] /= sum;
      }
    diff = std::move(out);
  };
  blur(sigmaMm / box.pitchMm.x(), true);
  blur(sigmaMm / (vertical ? box.pitchMm.z() : box.pitchMm.y()), false);
  double sum = 0;
  for (double d : diff) sum += d * d;
  return std::sqrt(sum / double(diff.size()));
}

} // namespace texfab::print
