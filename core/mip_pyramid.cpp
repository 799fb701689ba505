// SPDX-License-Identifier: GPL-3.0-or-later
#include "core/mip_pyramid.h"

#include <algorithm>
#include <cmath>

namespace texfab {

float srgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

namespace {

// A level as the pyramid holds it: 4 float channels, linear when `srgb`.
Image expanded(const Image& image, bool srgb) {
  Image level(image.width, image.height, 4, PixelFormat::Float);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float* s = image.pixel(x, y);
      float* d = level.pixel(x, y);
      const int c = image.channels;
      const float r = s[0], g = c >= 3 ? s[1] : s[0], b = c >= 3 ? s[2] : s[0];
      const float a = c == 2 ? s[1] : c >= 4 ? s[3] : 1.0f;
      d[0] = srgb ? srgbToLinear(r) : r;
      d[1] = srgb ? srgbToLinear(g) : g;
      d[2] = srgb ? srgbToLinear(b) : b;
      d[3] = a;
    }
  return level;
}

} // namespace

MipPyramid mipPyramidOf(std::span<const Image> levels, bool srgb) {
  MipPyramid pyramid;
  for (const Image& level : levels) pyramid.levels.push_back(expanded(level, srgb));
  return pyramid;
}

MipPyramid buildMipPyramid(const Image& image, bool srgb) {
  MipPyramid pyramid;
  if (image.empty()) return pyramid;
  pyramid.levels.push_back(expanded(image, srgb));
  while (pyramid.levels.back().width > 1 || pyramid.levels.back().height > 1) {
    const Image& src = pyramid.levels.back();
    Image dst((src.width + 1) / 2, (src.height + 1) / 2, 4, PixelFormat::Float);
    for (int y = 0; y < dst.height; ++y)
      for (int x = 0; x < dst.width; ++x) {
        float* d = dst.pixel(x, y);
        const int x0 = std::min(2 * x, src.width - 1), x1 = std::min(2 * x + 1, src.width - 1);
        const int y0 = std::min(2 * y, src.height - 1), y1 = std::min(2 * y + 1, src.height - 1);
        for (int c = 0; c < 4; ++c)
          d[c] = 0.25f * (src.at(x0, y0, c) + src.at(x1, y0, c) + src.at(x0, y1, c) + src.at(x1, y1, c));
      }
    pyramid.levels.push_back(std::move(dst));
  }
  return pyramid;
}

Eigen::Vector4f sampleBilinear(const Image& level, float u, float v) {
  const float fx = u * float(level.width) - 0.5f;
  const float fy = (1.0f - v) * float(level.height) - 0.5f;
  if (!std::isfinite(fx) || !std::isfinite(fy)) return Eigen::Vector4f::Zero();
  const float x0f = std::floor(fx), y0f = std::floor(fy);
  const float tx = fx - x0f, ty = fy - y0f;
  auto wrap = [](long long i, int n) { return int(((i % n) + n) % n); };
  const int x0 = wrap((long long)x0f, level.width), x1 = wrap((long long)x0f + 1, level.width);
  const int y0 = wrap((long long)y0f, level.height), y1 = wrap((long long)y0f + 1, level.height);
  const Eigen::Map<const Eigen::Vector4f> a(level.pixel(x0, y0)), b(level.pixel(x1, y0)), c(level.pixel(x0, y1)),
      d(level.pixel(x1, y1));
  return (1 - ty) * ((1 - tx) * a + tx * b) + ty * ((1 - tx) * c + tx * d);
}

Eigen::Vector4f sampleTrilinear(const MipPyramid& pyramid, float u, float v, float lod) {
  if (pyramid.empty()) return Eigen::Vector4f::Ones();
  const float maxLevel = float(pyramid.levels.size() - 1);
  lod = std::isfinite(lod) ? std::clamp(lod, 0.0f, maxLevel) : 0.0f;
  const int l0 = int(std::floor(lod));
  const int l1 = std::min(l0 + 1, int(maxLevel));
  const float t = lod - float(l0);
  const Eigen::Vector4f a = sampleBilinear(pyramid.levels[size_t(l0)], u, v);
  if (t == 0.0f || l1 == l0) return a;
  return (1 - t) * a + t * sampleBilinear(pyramid.levels[size_t(l1)], u, v);
}

} // namespace texfab
