// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005;
//           S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006;
//           P. Felzenszwalb, D. Huttenlocher. Distance transforms of sampled functions.
//             Theory of Computing 8, 2012 (the exact 1-D squared distance transform).
#include "synthesis/exemplar_analysis.h"

#include "core/error.h"
#include "core/files.h"
#include "core/hash.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/appearance_space.h"
#include "synthesis/coord_map.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>

namespace texfab::synthesis {
namespace fs = std::filesystem;

using namespace detail;

namespace {

constexpr uint32_t kCacheMagic = 0x41584654;  // "TFXA"
constexpr uint32_t kCacheVersion = 3;         // bump whenever the analysis changes
constexpr int kValidMarginSpacings = 1;       // Clamp: valid-region margin, in level spacings

int wrap(int a, int m) {
  const int r = a % m;
  return r < 0 ? r + m : r;
}

// The channels analysis looks at: RGB, or grey for 1- and 2-channel images. Alpha is ignored.
Image colorChannels(const Image& exemplar) {
  const int c = exemplar.channels >= 3 ? 3 : 1;
  Image out(exemplar.width, exemplar.height, c, PixelFormat::Float);
  for (int y = 0; y < exemplar.height; ++y)
    for (int x = 0; x < exemplar.width; ++x)
      for (int i = 0; i < c; ++i) out.at(x, y, i) = exemplar.at(x, y, i);
  return out;
}

// One separable pass of the binomial filter [1 4 6 4 1]/16 with taps `step` apart.
Image binomialPass(const Image& in, int step, bool horizontal, ExemplarWrap w, const Context& ctx) {
  static constexpr float kTaps[5] = {1 / 16.f, 4 / 16.f, 6 / 16.f, 4 / 16.f, 1 / 16.f};
  Image out(in.width, in.height, in.channels, in.format);
  parallelFor(0, in.height, ctx, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < in.width; ++x)
        for (int t = 0; t < 5; ++t) {
          const int o = (t - 2) * step;
          const float* p =
              horizontal ? in.pixel(foldIndex(x + o, in.width, w), y) : in.pixel(x, foldIndex(y + o, in.height, w));
          float* q = out.pixel(x, y);
          for (int c = 0; c < in.channels; ++c) q[c] += kTaps[t] * p[c];
        }
  }, 16);
  return out;
}

// Stack level l-1 from level l (spacing h_l = step): the binomial filter with taps h_l apart.
Image coarserLevel(const Image& level, int step, ExemplarWrap w, const Context& ctx) {
  return binomialPass(binomialPass(level, step, true, w, ctx), step, false, w, ctx);
}

std::vector<Image> gaussianStackOf(const Image& base, ExemplarWrap w) {
  const int levels = stackLevelCount(base.width, base.height);
  std::vector<Image> stack(static_cast<size_t>(levels));
  stack.back() = base;
  for (int l = levels - 2; l >= 0; --l) stack[size_t(l)] = coarserLevel(stack[size_t(l) + 1], 1 << (levels - 2 - l), w, {});
  return stack;
}

// Exact 1-D squared distance transform (Felzenszwalb & Huttenlocher) of f, in place.
void distanceTransform1d(std::vector<float>& f) {
  const int n = int(f.size());
  std::vector<float> d(static_cast<size_t>(n)), z(static_cast<size_t>(n) + 1);
  std::vector<int> v(static_cast<size_t>(n));
  int k = 0;
  v[0] = 0;
  z[0] = -std::numeric_limits<float>::infinity();
  z[1] = std::numeric_limits<float>::infinity();
  for (int q = 1; q < n; ++q) {
    float s;
    for (;;) {
      const int p = v[size_t(k)];
      s = ((f[size_t(q)] + float(q) * float(q)) - (f[size_t(p)] + float(p) * float(p))) / float(2 * (q - p));
      if (s > z[size_t(k)] || k == 0) break;
      --k;
    }
    if (s <= z[size_t(k)]) s = z[size_t(k)];  // k == 0 and parabola below everything
    ++k;
    v[size_t(k)] = q;
    z[size_t(k)] = s;
    z[size_t(k) + 1] = std::numeric_limits<float>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[size_t(k) + 1] < float(q)) ++k;
    const float dq = float(q - v[size_t(k)]);
    d[size_t(q)] = dq * dq + f[size_t(v[size_t(k)])];
  }
  f.swap(d);
}

// Data set adaptor for nanoflann over quantized appearance vectors.
using RowMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Appearance vectors of one stack level: Gaussian-weighted 5x5 neighborhoods with taps `spacing`
// apart, projected on their 8 principal components, quantized to int8 with one scale.
//
// Up to kExactAnalysisPixels, every neighborhood enters the PCA and the scale is the largest
// projection. Beyond, the PCA and the scale come from a regular grid of about
// kExactAnalysisPixels neighborhoods (values beyond the sample's range saturate at +-127), and
// the pixels are projected row by row, never holding all neighborhoods at once.
std::vector<int8_t> appearanceVectors(const Image& level, int spacing, ExemplarWrap w, const Context& ctx) {
  const int width = level.width, h = level.height, c = level.channels;
  const int side = 2 * kPatchRadius + 1;
  const int dims = side * side * c;
  const int64_t n = int64_t(width) * h;
  const std::vector<float> weights = patchWeights();

  std::vector<int8_t> out(size_t(n) * kAppearanceDims);
  auto quantize = [](float v, float scale) { return int8_t(std::clamp(std::lrint(v * scale), -127L, 127L)); };
  if (n <= kExactAnalysisPixels) {
    RowMatrix rows(n, dims);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < width; ++x) patchOf(level, x, y, spacing, w, weights.data(), &rows(y * width + x, 0));
    Eigen::MatrixXf raw = rows;
    rows.resize(0, 0);
    Eigen::RowVectorXf mean;
    const Eigen::MatrixXf basis = principalBasis(raw, mean);
    const Eigen::MatrixXf projected = raw * basis;
    const float maxAbs = projected.cwiseAbs().maxCoeff();
    const float scale = maxAbs > 0 ? 127.0f / maxAbs : 0.0f;
    for (int64_t p = 0; p < n; ++p)
      for (int k = 0; k < kAppearanceDims; ++k)
        out[size_t(p) * kAppearanceDims + size_t(k)] = quantize(projected(p, k), scale);
    return out;
  }

  const int step = int(std::ceil(std::sqrt(double(n) / double(kExactAnalysisPixels))));
  const int sw = (width + step - 1) / step, sh = (h + step - 1) / step;
  RowMatrix rows(int64_t(sw) * sh, dims);
  for (int j = 0; j < sh; ++j)
    for (int i = 0; i < sw; ++i) patchOf(level, i * step, j * step, spacing, w, weights.data(), &rows(j * sw + i, 0));
  Eigen::MatrixXf raw = rows;
  rows.resize(0, 0);
  Eigen::RowVectorXf mean;
  const Eigen::MatrixXf basis = principalBasis(raw, mean);
  const float maxAbs = (raw * basis).cwiseAbs().maxCoeff();
  const float scale = maxAbs > 0 ? 127.0f / maxAbs : 0.0f;
  raw.resize(0, 0);
  // Each pixel's projection is a fixed-order dot product: independent of the thread count.
  const RowMatrix b = basis;  // dims x kAppearanceDims, row-major
  parallelFor(0, h, ctx, [&](int y0, int y1) {
    std::vector<float> patch(static_cast<size_t>(dims));
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < width; ++x) {
        patchOf(level, x, y, spacing, w, weights.data(), patch.data());
        projectPatch(patch.data(), dims, mean, b.data(), scale, &out[(size_t(y) * width + x) * kAppearanceDims]);
      }
  }, 4);
  return out;
}

std::vector<int8_t> runtimeNeighborhoods(const std::vector<int8_t>& appearance, int w, int h, int spacing,
                                         ExemplarWrap wrapMode) {
  std::vector<int8_t> out(size_t(w) * size_t(h) * kNeighborhoodDims);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int i = 0; i < kNeighborhoodSamples; ++i) {
        const int sx = foldIndex(x + kDiagonalX[i] * spacing, w, wrapMode);
        const int sy = foldIndex(y + kDiagonalY[i] * spacing, h, wrapMode);
        std::memcpy(&out[(size_t(y) * w + x) * kNeighborhoodDims + size_t(i) * kAppearanceDims],
                    &appearance[(size_t(sy) * w + sx) * kAppearanceDims], kAppearanceDims);
      }
  return out;
}

// k-coherence candidates: the pixel itself, then its most similar pixels (exact k-nearest
// neighbors in appearance space) that lie at least a minimum distance from it and from each other
// (LH05 §3.3: candidates spread apart in the exemplar). Missing slots repeat the pixel itself.
//
// Level l sees the exemplar through samples `spacing` apart, so pixels closer than that are the
// same feature there: the search runs over a grid of that stride (capped at an eighth of the
// exemplar, so that a few dozen places remain to choose from) and the spread distance grows to
// match. Without this, coarse levels found no candidate outside the pixel's own blur footprint.
//
// Only pixels of the level's valid region are searched and found (pixels outside it are never a
// coordinate: their sets are the pixel alone). Beyond kExactAnalysisPixels, the grid's stride is
// at least sqrt(pixels / kExactAnalysisPixels), and only the pixels of a grid of the same stride
// (at least 2) are queried; every other pixel p takes the set of the grid
// pixel q at or before it, shifted by p - q (the candidates of a coherent patch move with it).
std::vector<uint32_t> coherenceCandidates(const std::vector<int8_t>& appearance, int w, int h, int spacing,
                                          const ValidRegion& valid, const AnalysisOptions& options,
                                          const Context& ctx) {
  const int64_t n = int64_t(w) * h;
  const bool spread = n > kExactAnalysisPixels;
  // Large exemplars: the grid never holds more than about kExactAnalysisPixels sites.
  const int sampleStride = spread ? int(std::ceil(std::sqrt(double(n) / double(kExactAnalysisPixels)))) : 1;
  const int stride = std::max({1, std::min(spacing, std::min(w, h) / 8), sampleStride});
  const int queryStride = spread ? std::max(2, stride) : 1;
  AppearanceCloud cloud;
  std::vector<uint32_t> sites;  // exemplar index of each point of the search grid
  for (int y = valid.y0; y <= valid.y1; y += stride)
    for (int x = valid.x0; x <= valid.x1; x += stride) {
      sites.push_back(uint32_t(y * w + x));
      for (int d = 0; d < kAppearanceDims; ++d)
        cloud.points.push_back(appearance[size_t(y * w + x) * kAppearanceDims + size_t(d)]);
    }
  AppearanceTree tree(kAppearanceDims, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  const int64_t minDistance = std::max<int64_t>(
      {2, std::lrint(options.minSpread * float(std::min(w, h))), int64_t(stride)});
  const int64_t minDistance2 = minDistance * minDistance;
  const auto query = std::min(sites.size(), size_t(options.searchNeighbors) + 1);
  const int k = options.k;

  std::vector<uint32_t> out(size_t(n) * size_t(k));
  for (int64_t p = 0; p < n; ++p)
    std::fill_n(&out[size_t(p) * size_t(k)], k, packCoord(uint32_t(p % w), uint32_t(p / w)));
  // The queried pixels: every pixel of the valid region, or its grid.
  const int qw = (valid.x1 - valid.x0) / queryStride + 1, qh = (valid.y1 - valid.y0) / queryStride + 1;
  parallelFor(0, qh, ctx, [&](int r0, int r1) {
    std::vector<uint32_t> index(query);
    std::vector<float> dist(query), point(kAppearanceDims);
    std::vector<std::pair<float, uint32_t>> ranked;
    for (int r = r0; r < r1; ++r)
      for (int i = 0; i < qw; ++i) {
        const int px = valid.x0 + i * queryStride, py = valid.y0 + r * queryStride;
        const size_t p = size_t(py) * w + size_t(px);
        for (int d = 0; d < kAppearanceDims; ++d) point[size_t(d)] = appearance[p * kAppearanceDims + size_t(d)];
        const size_t found = tree.knnSearch(point.data(), query, index.data(), dist.data());
        ranked.clear();
        for (size_t f = 0; f < found; ++f) ranked.emplace_back(dist[f], sites[index[f]]);
        std::sort(ranked.begin(), ranked.end());  // distance, then index: a fixed order for ties
        uint32_t* slot = &out[p * size_t(k)];
        int taken = 1;
        for (const auto& [d, q] : ranked) {
          if (taken == k) break;
          const int qx = int(q) % w, qy = int(q) / w;
          bool apart = true;
          for (int t = 0; t < taken && apart; ++t)
            apart = pixelDistance2(qx, qy, int(coordU(slot[t])), int(coordV(slot[t])), w, h, options.wrap) >= minDistance2;
          if (apart) slot[taken++] = packCoord(uint32_t(qx), uint32_t(qy));
        }
      }
  }, spread ? 1 : 256 / std::max(1, qw) + 1);
  if (queryStride == 1) return out;

  // Spread each grid pixel's set to the pixels after it, shifted (toroidally, or clamped to the
  // valid region).
  parallelFor(valid.y0, valid.y1 + 1, ctx, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = valid.x0; x <= valid.x1; ++x) {
        const int gx = valid.x0 + (x - valid.x0) / queryStride * queryStride;
        const int gy = valid.y0 + (y - valid.y0) / queryStride * queryStride;
        if (gx == x && gy == y) continue;
        const uint32_t* from = &out[(size_t(gy) * w + size_t(gx)) * size_t(k)];
        uint32_t* to = &out[(size_t(y) * w + size_t(x)) * size_t(k)];
        for (int t = 1; t < k; ++t) {
          int u = int(coordU(from[t])) + x - gx, v = int(coordV(from[t])) + y - gy;
          if (from[t] == from[0]) {  // an empty slot stays the pixel itself
            u = x;
            v = y;
          } else if (options.wrap == ExemplarWrap::Tile) {
            u = wrap(u, w);
            v = wrap(v, h);
          } else {
            u = std::clamp(u, valid.x0, valid.x1);
            v = std::clamp(v, valid.y0, valid.y1);
          }
          to[t] = packCoord(uint32_t(u), uint32_t(v));
        }
      }
  }, 4);
  return out;
}

} // namespace

void AnalysisOptions::validate() const {
  if (k < 1 || k > 8) throw Error("k must be in [1, 8], got " + std::to_string(k));
  if (!(featureWeight >= 0.0f) || featureWeight > 100.0f)
    throw Error("feature weight must be in [0, 100], got " + std::to_string(featureWeight));
  if (searchNeighbors < k || searchNeighbors > 256)
    throw Error("search neighbors must be in [k, 256], got " + std::to_string(searchNeighbors));
  if (!(minSpread >= 0.0f) || minSpread > 0.5f)
    throw Error("candidate spread must be in [0, 0.5], got " + std::to_string(minSpread));
}

int stackLevelCount(int width, int height) {
  const auto side = uint32_t(std::max(width, height));
  return int(std::bit_width(std::bit_ceil(side)));  // ceil(log2(side)) + 1
}

int foldIndex(int a, int side, ExemplarWrap wrapMode) {
  if (wrapMode == ExemplarWrap::Tile) return wrap(a, side);
  const int r = wrap(a, 2 * side);  // mirrored: period 2 side
  return r < side ? r : 2 * side - 1 - r;
}

const char* toString(ExemplarWrap wrapMode) { return wrapMode == ExemplarWrap::Tile ? "tile" : "clamp"; }

ValidRegion validRegion(int width, int height, int spacing, ExemplarWrap wrapMode) {
  if (wrapMode == ExemplarWrap::Tile) return {0, 0, width - 1, height - 1};
  const int mx = std::min(kValidMarginSpacings * spacing, (width - 1) / 4);
  const int my = std::min(kValidMarginSpacings * spacing, (height - 1) / 4);
  return {mx, my, width - 1 - mx, height - 1 - my};
}

std::vector<Image> gaussianStack(const Image& exemplar, ExemplarWrap wrapMode) {
  return gaussianStackOf(colorChannels(exemplar), wrapMode);
}

Image featureDistance(const Image& exemplar, ExemplarWrap wrapMode) {
  const int w = exemplar.width, h = exemplar.height;
  const Image color = colorChannels(exemplar);
  std::vector<float> luminance(size_t(w) * size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* p = color.pixel(x, y);
      luminance[size_t(y) * w + x] = color.channels == 3 ? 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2] : p[0];
    }
  auto lum = [&](int x, int y) {
    return luminance[size_t(foldIndex(y, h, wrapMode)) * w + size_t(foldIndex(x, w, wrapMode))];
  };
  std::vector<float> gradient(luminance.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {  // Sobel
      const float gx = (lum(x + 1, y - 1) + 2 * lum(x + 1, y) + lum(x + 1, y + 1)) -
                       (lum(x - 1, y - 1) + 2 * lum(x - 1, y) + lum(x - 1, y + 1));
      const float gy = (lum(x - 1, y + 1) + 2 * lum(x, y + 1) + lum(x + 1, y + 1)) -
                       (lum(x - 1, y - 1) + 2 * lum(x, y - 1) + lum(x + 1, y - 1));
      gradient[size_t(y) * w + x] = std::sqrt(gx * gx + gy * gy);
    }
  std::vector<float> sorted = gradient;
  const size_t decile = sorted.size() * 9 / 10;
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(decile), sorted.end());
  // Features: the top decile of gradient magnitude, and never flat pixels.
  const float threshold = std::max(sorted[decile], 1e-6f);

  // Squared distance to the nearest feature pixel: rows then columns, each over three periods so
  // the transform is toroidal (the outer two featureless when the exemplar does not tile).
  const float far = float(w * w + h * h);
  const bool tiles = wrapMode == ExemplarWrap::Tile;
  std::vector<float> dist2(gradient.size());
  for (size_t i = 0; i < gradient.size(); ++i) dist2[i] = gradient[i] > threshold ? 0.0f : far;
  std::vector<float> line;
  for (int y = 0; y < h; ++y) {
    line.resize(size_t(3 * w));
    for (int i = 0; i < 3 * w; ++i) line[size_t(i)] = tiles || i / w == 1 ? dist2[size_t(y) * w + size_t(i % w)] : far;
    distanceTransform1d(line);
    for (int x = 0; x < w; ++x) dist2[size_t(y) * w + x] = line[size_t(w + x)];
  }
  for (int x = 0; x < w; ++x) {
    line.resize(size_t(3 * h));
    for (int i = 0; i < 3 * h; ++i) line[size_t(i)] = tiles || i / h == 1 ? dist2[size_t(i % h) * w + x] : far;
    distanceTransform1d(line);
    for (int y = 0; y < h; ++y) dist2[size_t(y) * w + x] = line[size_t(h + y)];
  }
  Image out(w, h, 1, PixelFormat::Float);
  for (size_t i = 0; i < dist2.size(); ++i) out.pixels[i] = std::sqrt(std::min(dist2[i], far));
  return out;
}

uint64_t analysisKey(const Image& exemplar, const AnalysisOptions& options) {
  Fnv1a hash;
  hash.add(kCacheVersion);
  hash.add(exemplar.width);
  hash.add(exemplar.height);
  hash.add(exemplar.channels);
  hash.add(exemplar.pixels.data(), exemplar.pixels.size() * sizeof(float));
  hash.add(options.k);
  hash.add(options.featureWeight);
  hash.add(options.searchNeighbors);
  hash.add(options.minSpread);
  hash.add(options.wrap);
  return hash.h;
}

void validateExemplarSize(const Image& exemplar) {
  if (exemplar.width < kMinExemplarSide || exemplar.height < kMinExemplarSide)
    throw Error("exemplar is " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) +
                ", smaller than the " + std::to_string(kMinExemplarSide) + "x" +
                std::to_string(kMinExemplarSide) + " appearance neighborhood");
  if (exemplar.width > kMaxExemplarSide || exemplar.height > kMaxExemplarSide)
    throw Error("exemplar is " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) +
                ", larger than the supported " + std::to_string(kMaxExemplarSide) + "x" +
                std::to_string(kMaxExemplarSide) + " (exemplars are small pictures: 64 to 512 pixels)");
}

double analysisMemoryBytes(int width, int height, const AnalysisOptions& options) {
  const double n = double(width) * height;
  const int levels = stackLevelCount(width, height);
  const int channels = 3 + (options.featureWeight > 0);
  // Per level: appearance, runtime neighborhoods and candidates (kept); ten float images' worth
  // (the caller's exemplar and its decoding, the colour copy, a stack level, the next one and its
  // filter pass, allocator slack), the search grid and its tree (transient); plus the PCA sample
  // and the program. Fitted to measured peaks (512^2 to 2048^2) with a margin.
  const double kept = levels * (kAppearanceDims + kNeighborhoodDims + 4.0 * options.k);
  const double transient = 10 * 4.0 * channels + 4.0 * (kAppearanceDims + 3);
  return n * (kept + transient) + 160.0 * (1 << 20);
}

double analysisCpuSeconds(int width, int height) {
  // Wall seconds on 2 threads: 3.6 at 256^2, 7.1 at 1024^2, 129 at 4096^2.
  return 2 * (3.0 + 7.5e-6 * double(width) * double(height));
}

ExemplarAnalysis analyzeExemplar(const Image& exemplar, const AnalysisOptions& options, const Context& ctx) {
  options.validate();
  validateExemplarSize(exemplar);
  const int w = exemplar.width, h = exemplar.height;
  reportEstimate(ctx, analysisCpuSeconds(w, h),
                 "the analysis of a " + std::to_string(w) + "x" + std::to_string(h) + " exemplar");

  // Colour plus (optionally) the feature-distance channel, scaled so that its standard deviation
  // is featureWeight times the mean colour standard deviation (LH06 §3.2).
  Image base = colorChannels(exemplar);
  if (options.featureWeight > 0) {
    const Image feature = featureDistance(exemplar, options.wrap);
    auto stddev = [&](const Image& img, int c) {
      double s = 0, s2 = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          s += img.at(x, y, c);
          s2 += double(img.at(x, y, c)) * img.at(x, y, c);
        }
      const double n = double(w) * h;
      return std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
    };
    double colorStd = 0;
    for (int c = 0; c < base.channels; ++c) colorStd += stddev(base, c) / base.channels;
    const double featureStd = stddev(feature, 0);
    const float scale = featureStd > 0 ? float(options.featureWeight * colorStd / featureStd) : 0.0f;
    Image augmented(w, h, base.channels + 1, PixelFormat::Float);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        for (int c = 0; c < base.channels; ++c) augmented.at(x, y, c) = base.at(x, y, c);
        augmented.at(x, y, base.channels) = scale * feature.at(x, y, 0);
      }
    base = std::move(augmented);
  }

  ExemplarAnalysis analysis;
  analysis.width = w;
  analysis.height = h;
  analysis.k = options.k;
  analysis.wrap = options.wrap;
  analysis.key = analysisKey(exemplar, options);
  const int levels = stackLevelCount(w, h);
  analysis.levels.resize(size_t(levels));
  const int finest = levels - 1;
  // Finest level first: each stack level is filtered from the one below it, analysed, and
  // dropped, so that at most two levels of floats are held at once. Each level's work is spread
  // over the threads (rows, grid cells): no value depends on the thread count.
  Image level = std::move(base);
  for (int l = finest; l >= 0; --l) {
    Stage stage(ctx, "level " + std::to_string(finest - l + 1) + "/" + std::to_string(levels));
    const Context inner = stage.inner();
    AnalysisLevel& out = analysis.levels[size_t(l)];
    out.spacing = 1 << (finest - l);
    out.valid = validRegion(w, h, out.spacing, options.wrap);
    if (l < finest) level = coarserLevel(level, out.spacing / 2, options.wrap, inner);  // taps h_{l+1} apart
    stage.advance(0.1);
    out.appearance = appearanceVectors(level, out.spacing, options.wrap, inner);
    stage.advance(0.4);
    out.neighborhood = runtimeNeighborhoods(out.appearance, w, h, out.spacing, options.wrap);
    out.candidates = coherenceCandidates(out.appearance, w, h, out.spacing, out.valid, options, inner);
    stage.finish();
  }
  return analysis;
}

WrapDiscontinuity wrapDiscontinuity(const Image& exemplar) {
  const Image color = colorChannels(exemplar);
  const int c = color.channels;
  // The measure along x on `img` (transposed for y): for block size s, the mean over rows of
  // blocks of |block left of a boundary - block right of it| (colour L1), at the wrap against the
  // mean at every boundary inside.
  auto alongX = [c](const Image& img) {
    const int w = img.width, h = img.height;
    double worst = 0;
    for (int s = 1; s <= 8 && 16 * s <= std::min(w, h); s *= 2) {
      // Column sums of s-row blocks: blockSum[(by * w + x) * c + ch].
      const int rows = h / s;
      std::vector<double> col(size_t(rows) * w * c, 0.0);
      for (int by = 0; by < rows; ++by)
        for (int y = by * s; y < by * s + s; ++y)
          for (int x = 0; x < w; ++x)
            for (int ch = 0; ch < c; ++ch) col[(size_t(by) * w + x) * c + ch] += img.at(x, y, ch);
      auto boundary = [&](int b) {  // blocks [b - s, b) and [b, b + s), columns toroidal
        double sum = 0;
        for (int by = 0; by < rows; ++by)
          for (int ch = 0; ch < c; ++ch) {
            double left = 0, right = 0;
            for (int i = 0; i < s; ++i) {
              left += col[(size_t(by) * w + size_t(wrap(b - s + i, w))) * c + ch];
              right += col[(size_t(by) * w + size_t(wrap(b + i, w))) * c + ch];
            }
            sum += std::abs(left - right);
          }
        return sum / (double(rows) * c * s * s);
      };
      // The 90th percentile of the boundaries inside (linear between order statistics).
      std::vector<double> inner;
      for (int b = s; b <= w - s; ++b) inner.push_back(boundary(b));
      std::sort(inner.begin(), inner.end());
      const double rank = 0.9 * double(inner.size() - 1);
      const size_t k = size_t(rank);
      const double inside =
          k + 1 < inner.size() ? inner[k] + (rank - double(k)) * (inner[k + 1] - inner[k]) : inner[k];
      const double across = boundary(0);
      worst = std::max(worst, inside > 1e-9 ? across / inside : (across > 1e-9 ? 1e9 : 1.0));
    }
    return worst;
  };
  Image transposed(color.height, color.width, c, PixelFormat::Float);
  for (int y = 0; y < color.height; ++y)
    for (int x = 0; x < color.width; ++x)
      for (int ch = 0; ch < c; ++ch) transposed.at(y, x, ch) = color.at(x, y, ch);
  return {alongX(color), alongX(transposed)};
}

ExemplarWrap detectExemplarWrap(const Image& exemplar) {
  if (std::min(exemplar.width, exemplar.height) < kWrapDetectionMinSide) return ExemplarWrap::Tile;
  return wrapDiscontinuity(exemplar).worst() > kWrapDiscontinuityThreshold ? ExemplarWrap::Clamp : ExemplarWrap::Tile;
}

fs::path defaultCacheDir() {
  if (const char* dir = std::getenv("TEXFAB_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return fs::path(xdg) / "texfab";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "texfab";
  return fs::temp_directory_path() / "texfab-cache";
}

void writeAnalysis(const ExemplarAnalysis& a, const fs::path& path) {
  writeFileAtomically(path, [&](std::ostream& out) {
    auto put = [&](const void* data, size_t size) { out.write(static_cast<const char*>(data), std::streamsize(size)); };
    const int32_t header[6] = {a.width, a.height, int32_t(a.levels.size()), a.k, kAppearanceDims, int32_t(a.wrap)};
    put(&kCacheMagic, 4);
    put(&kCacheVersion, 4);
    put(&a.key, 8);
    put(header, sizeof header);
    for (const AnalysisLevel& level : a.levels) {
      put(&level.spacing, 4);
      put(level.appearance.data(), level.appearance.size());
      put(level.candidates.data(), level.candidates.size() * sizeof(uint32_t));
    }
  });
}

std::optional<ExemplarAnalysis> readAnalysis(const fs::path& path, uint64_t expectedKey) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  auto get = [&](void* data, size_t size) { return bool(in.read(static_cast<char*>(data), std::streamsize(size))); };
  uint32_t magic = 0, version = 0;
  ExemplarAnalysis a;
  int32_t header[6];
  if (!get(&magic, 4) || !get(&version, 4) || !get(&a.key, 8) || !get(header, sizeof header)) return std::nullopt;
  if (magic != kCacheMagic || version != kCacheVersion || a.key != expectedKey) return std::nullopt;
  a.width = header[0];
  a.height = header[1];
  a.k = header[3];
  if (a.width < kMinExemplarSide || a.height < kMinExemplarSide || a.width > kMaxExemplarSide ||
      a.height > kMaxExemplarSide || header[2] != stackLevelCount(a.width, a.height) || a.k < 1 || a.k > 8 ||
      header[4] != kAppearanceDims || (header[5] != int32_t(ExemplarWrap::Tile) && header[5] != int32_t(ExemplarWrap::Clamp)))
    return std::nullopt;
  a.wrap = ExemplarWrap(header[5]);
  const size_t n = size_t(a.width) * size_t(a.height);
  a.levels.resize(size_t(header[2]));
  for (size_t l = 0; l < a.levels.size(); ++l) {
    AnalysisLevel& level = a.levels[l];
    level.appearance.resize(n * kAppearanceDims);
    level.candidates.resize(n * size_t(a.k));
    if (!get(&level.spacing, 4) || level.spacing != (1 << (a.levels.size() - 1 - l)) ||
        !get(level.appearance.data(), level.appearance.size()) ||
        !get(level.candidates.data(), level.candidates.size() * sizeof(uint32_t)))
      return std::nullopt;
    for (uint32_t c : level.candidates)
      if (coordU(c) >= uint32_t(a.width) || coordV(c) >= uint32_t(a.height)) return std::nullopt;
    level.valid = validRegion(a.width, a.height, level.spacing, a.wrap);
    level.neighborhood = runtimeNeighborhoods(level.appearance, a.width, a.height, level.spacing, a.wrap);
  }
  if (in.peek() != std::char_traits<char>::eof()) return std::nullopt;
  return a;
}

ExemplarAnalysis analyzeExemplarCached(const Image& exemplar, const AnalysisOptions& options,
                                       const fs::path& cacheDir, const Context& ctx, bool* fromCache) {
  options.validate();
  return loadOrCompute(
      cacheDir, analysisKey(exemplar, options), ".analysis", readAnalysis,
      [&] { return analyzeExemplar(exemplar, options, ctx); }, writeAnalysis, fromCache, ctx);
}

} // namespace texfab::synthesis
