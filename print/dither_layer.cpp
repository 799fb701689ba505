// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: R. Floyd, L. Steinberg. An adaptive algorithm for spatial greyscale. Proc. SID 17(2),
//   1976; R. Ulichney. The void-and-cluster method for dither array generation. SPIE 1913, 1993.
#include "print/dither_layer.h"

#include "core/error.h"

#include <algorithm>
#include <cstring>

namespace texfab::print {

LayerDitherer::LayerDitherer(const MaterialMixer& mixer, DitherMode mode, const BlueNoiseVolume* noise, int layer, int width)
    : mixer_(mixer), mode_(mode), noise_(noise), layer_(layer), width_(width) {
  if (mode == DitherMode::None) throw Error("internal: no ditherer without dithering");
  if (mode == DitherMode::BlueNoise && !noise) throw Error("internal: blue-noise dithering needs its threshold array");
  if (mode == DitherMode::FloydSteinberg) {
    error_.assign(3 * size_t(width), 0.0f);
    nextError_.assign(3 * size_t(width), 0.0f);
    target_.assign(4 * size_t(width), 0.0f);
    shell_.assign(size_t(width), 0);
  }
}

void LayerDitherer::ditherRow(int y, std::span<const print::VoxelSpan> row, const float* rgba, uint8_t* out) {
  if (mode_ == DitherMode::BlueNoise) blueNoiseRow(y, row, rgba, out);
  else diffuseRow(row, rgba, out);
  ++rowsDone_;
}

// Neighbouring voxels mostly share a colour (a solid texture's voxel spans several print voxels),
// so a colour's mix is computed once per run of equal colours; the thresholds of the row come from
// one row of the array.
void LayerDitherer::blueNoiseRow(int y, std::span<const print::VoxelSpan> row, const float* rgba, uint8_t* out) {
  const int64_t size = noise_->size;
  const auto wrap = [size](int64_t v) { return (v % size + size) % size; };
  const uint32_t* ranks = noise_->rank.data() + size_t(size * (wrap(y) + size * wrap(layer_)));
  const float cells = float(noise_->rank.size());
  thresholds_.resize(size_t(size));
  for (int64_t i = 0; i < size; ++i) thresholds_[size_t(i)] = (float(ranks[i]) + 0.5f) / cells;  // as threshold()
  MaterialMixer::Mix mix;
  const float* mixed = nullptr;  // the colour `mix` is of
  for (const print::VoxelSpan& s : row) {
    if (!s.shell) continue;
    int64_t cell = wrap(s.begin);
    for (int x = s.begin; x < s.end; ++x, rgba += 4) {
      if (!mixed || std::memcmp(mixed, rgba, 4 * sizeof(float)) != 0) {
        mix = mixer_.mix(rgba);
        mixed = rgba;
      }
      out[x] = uint8_t(mixer_.pick(mix, thresholds_[size_t(cell)]) + 1);
      if (++cell == size) cell = 0;
    }
  }
}

void LayerDitherer::diffuseRow(std::span<const print::VoxelSpan> row, const float* rgba, uint8_t* out) {
  // Targets: the colours the materials can reproduce (out-of-gamut error would grow unbounded).
  for (const print::VoxelSpan& s : row) {
    if (!s.shell) continue;
    for (int x = s.begin; x < s.end; ++x, rgba += 4) {
      const std::array<float, 3> c = mixer_.reproduced(rgba);
      std::copy(c.begin(), c.end(), &target_[4 * size_t(x)]);
      shell_[size_t(x)] = 1;
    }
  }
  const bool forward = rowsDone_ % 2 == 0;
  const int step = forward ? 1 : -1;
  auto visit = [&](int x) {
    float value[3];
    for (int c = 0; c < 3; ++c) value[c] = std::clamp(target_[4 * size_t(x) + size_t(c)] + error_[3 * size_t(x) + size_t(c)], -0.5f, 1.5f);
    const int m = mixer_.nearest(value);
    out[x] = uint8_t(m + 1);
    const std::array<float, 3>& got = mixer_.linearColor(m);
    for (int c = 0; c < 3; ++c) {
      const float e = value[c] - got[size_t(c)];
      const int ahead = x + step, behind = x - step;
      if (ahead >= 0 && ahead < width_) {
        if (shell_[size_t(ahead)]) error_[3 * size_t(ahead) + size_t(c)] += e * 7.0f / 16.0f;
        nextError_[3 * size_t(ahead) + size_t(c)] += e * 1.0f / 16.0f;
      }
      if (behind >= 0 && behind < width_) nextError_[3 * size_t(behind) + size_t(c)] += e * 3.0f / 16.0f;
      nextError_[3 * size_t(x) + size_t(c)] += e * 5.0f / 16.0f;
    }
  };
  for (size_t i = 0; i < row.size(); ++i) {
    const print::VoxelSpan& s = row[forward ? i : row.size() - 1 - i];
    if (!s.shell) continue;
    if (forward)
      for (int x = s.begin; x < s.end; ++x) visit(x);
    else
      for (int x = s.end - 1; x >= s.begin; --x) visit(x);
  }
  for (const print::VoxelSpan& s : row) std::fill(shell_.begin() + s.begin, shell_.begin() + s.end, 0);
  std::swap(error_, nextError_);
  std::fill(nextError_.begin(), nextError_.end(), 0.0f);
}

} // namespace texfab::print
