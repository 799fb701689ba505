// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: S. Lefebvre, H. Hoppe. Parallel controllable texture synthesis. SIGGRAPH 2005;
//           S. Lefebvre, H. Hoppe. Appearance-space texture synthesis. SIGGRAPH 2006;
//           P. Felzenszwalb, D. Huttenlocher. Distance transforms of sampled functions.
//             Theory of Computing 8, 2012 (the exact 1-D squared distance transform).
#include "synthesis/exemplar_analysis.h"

#include "render/image/error.h"
#include "render/image/files.h"
#include "render/image/image_io.h"
#include "render/image/parallel.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/coord_map.h"
#include "synthesis/hash.h"

#include <Eigen/Dense>
#include <nanoflann.hpp>

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

namespace {

constexpr uint32_t kCacheMagic = 0x41584654;  // "TFXA"
constexpr uint32_t kCacheVersion = 2;         // bump whenever the analysis changes
constexpr int kPatchRadius = 2;               // 5x5 appearance neighborhoods
constexpr float kPatchSigma = 1.5f;           // Gaussian weighting of the 5x5 samples

int wrap(int a, int m) {
  const int r = a % m;
  return r < 0 ? r + m : r;
}

// The channels analysis looks at: RGB, or grey for 1- and 2-channel images. Alpha is ignored.
Image colourChannels(const Image& exemplar) {
  const int c = exemplar.channels >= 3 ? 3 : 1;
  Image out(exemplar.width, exemplar.height, c, PixelFormat::Float);
  for (int y = 0; y < exemplar.height; ++y)
    for (int x = 0; x < exemplar.width; ++x)
      for (int i = 0; i < c; ++i) out.at(x, y, i) = exemplar.at(x, y, i);
  return out;
}

// One separable pass of the binomial filter [1 4 6 4 1]/16 with taps `step` apart, toroidal.
Image binomialPass(const Image& in, int step, bool horizontal) {
  static constexpr float kTaps[5] = {1 / 16.f, 4 / 16.f, 6 / 16.f, 4 / 16.f, 1 / 16.f};
  Image out(in.width, in.height, in.channels, in.format);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x)
      for (int t = 0; t < 5; ++t) {
        const int o = (t - 2) * step;
        const float* p = horizontal ? in.pixel(wrap(x + o, in.width), y) : in.pixel(x, wrap(y + o, in.height));
        float* q = out.pixel(x, y);
        for (int c = 0; c < in.channels; ++c) q[c] += kTaps[t] * p[c];
      }
  return out;
}

std::vector<Image> gaussianStackOf(const Image& base) {
  const int levels = stackLevelCount(base.width, base.height);
  std::vector<Image> stack(static_cast<size_t>(levels));
  stack.back() = base;
  for (int l = levels - 2; l >= 0; --l) {
    const int step = 1 << (levels - 2 - l);  // h_{l+1}
    stack[size_t(l)] = binomialPass(binomialPass(stack[size_t(l) + 1], step, true), step, false);
  }
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
struct AppearanceCloud {
  std::vector<float> points;  // n * kAppearanceDims
  size_t kdtree_get_point_count() const { return points.size() / kAppearanceDims; }
  float kdtree_get_pt(size_t i, size_t d) const { return points[i * kAppearanceDims + d]; }
  template <class Box> bool kdtree_get_bbox(Box&) const { return false; }
};
using AppearanceTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, AppearanceCloud>, AppearanceCloud, kAppearanceDims, uint32_t>;

// Toroidal squared distance between two exemplar pixels.
int64_t toroidalDistance2(int ax, int ay, int bx, int by, int w, int h) {
  int dx = std::abs(ax - bx), dy = std::abs(ay - by);
  dx = std::min(dx, w - dx);
  dy = std::min(dy, h - dy);
  return int64_t(dx) * dx + int64_t(dy) * dy;
}

// Appearance vectors of one stack level: Gaussian-weighted 5x5 neighborhoods with taps `spacing`
// apart, projected on their 8 principal components, quantized to int8 with one scale.
std::vector<int8_t> appearanceVectors(const Image& level, int spacing) {
  const int w = level.width, h = level.height, c = level.channels;
  const int side = 2 * kPatchRadius + 1;
  const int dims = side * side * c;
  const int n = w * h;
  std::vector<float> weights(size_t(side * side));
  for (int j = -kPatchRadius; j <= kPatchRadius; ++j)
    for (int i = -kPatchRadius; i <= kPatchRadius; ++i)
      weights[size_t((j + kPatchRadius) * side + i + kPatchRadius)] =
          std::sqrt(std::exp(-float(i * i + j * j) / (2 * kPatchSigma * kPatchSigma)));

  Eigen::MatrixXf raw(n, dims);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int col = 0;
      for (int j = -kPatchRadius; j <= kPatchRadius; ++j)
        for (int i = -kPatchRadius; i <= kPatchRadius; ++i) {
          const float wgt = weights[size_t((j + kPatchRadius) * side + i + kPatchRadius)];
          const float* p = level.pixel(wrap(x + i * spacing, w), wrap(y + j * spacing, h));
          for (int ch = 0; ch < c; ++ch) raw(y * w + x, col++) = wgt * p[ch];
        }
    }
  const Eigen::RowVectorXf mean = raw.colwise().mean();
  raw.rowwise() -= mean;
  const Eigen::MatrixXf covariance = (raw.transpose() * raw) / float(std::max(1, n - 1));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXf> solver(covariance);
  // Eigenvalues come in increasing order: take the last kAppearanceDims columns, largest first,
  // each with a fixed sign (largest-magnitude component positive) so the basis is reproducible.
  const int keep = std::min(kAppearanceDims, dims);
  Eigen::MatrixXf basis = Eigen::MatrixXf::Zero(dims, kAppearanceDims);
  for (int k = 0; k < keep; ++k) {
    Eigen::VectorXf v = solver.eigenvectors().col(dims - 1 - k);
    Eigen::Index arg;
    v.cwiseAbs().maxCoeff(&arg);
    if (v(arg) < 0) v = -v;
    basis.col(k) = v;
  }
  const Eigen::MatrixXf projected = raw * basis;
  const float maxAbs = projected.cwiseAbs().maxCoeff();
  const float scale = maxAbs > 0 ? 127.0f / maxAbs : 0.0f;
  std::vector<int8_t> out(size_t(n) * kAppearanceDims);
  for (int p = 0; p < n; ++p)
    for (int k = 0; k < kAppearanceDims; ++k)
      out[size_t(p) * kAppearanceDims + size_t(k)] = int8_t(std::lrint(projected(p, k) * scale));
  return out;
}

std::vector<int8_t> runtimeNeighborhoods(const std::vector<int8_t>& appearance, int w, int h, int spacing) {
  std::vector<int8_t> out(size_t(w) * size_t(h) * kNeighborhoodDims);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int i = 0; i < kNeighborhoodSamples; ++i) {
        const int sx = wrap(x + kDiagonalX[i] * spacing, w), sy = wrap(y + kDiagonalY[i] * spacing, h);
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
std::vector<uint32_t> coherenceCandidates(const std::vector<int8_t>& appearance, int w, int h, int spacing,
                                          const AnalysisOptions& options, const Context& ctx) {
  const int n = w * h;
  const int stride = std::max(1, std::min(spacing, std::min(w, h) / 8));
  AppearanceCloud cloud;
  std::vector<uint32_t> sites;  // exemplar index of each point of the search grid
  for (int y = 0; y < h; y += stride)
    for (int x = 0; x < w; x += stride) {
      sites.push_back(uint32_t(y * w + x));
      for (int d = 0; d < kAppearanceDims; ++d)
        cloud.points.push_back(appearance[size_t(y * w + x) * kAppearanceDims + size_t(d)]);
    }
  AppearanceTree tree(kAppearanceDims, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  const int64_t minDistance = std::max<int64_t>(
      {2, std::lrint(options.minSpread * float(std::min(w, h))), int64_t(stride)});
  const int64_t minDistance2 = minDistance * minDistance;
  const auto query = std::min(sites.size(), size_t(options.searchNeighbors) + 1);

  std::vector<uint32_t> out(size_t(n) * size_t(options.k));
  parallelFor(0, n, ctx, [&](int begin, int end) {
    std::vector<uint32_t> index(query);
    std::vector<float> dist(query), point(kAppearanceDims);
    std::vector<std::pair<float, uint32_t>> ranked;
    for (int p = begin; p < end; ++p) {
      const int px = p % w, py = p / w;
      for (int d = 0; d < kAppearanceDims; ++d) point[size_t(d)] = appearance[size_t(p) * kAppearanceDims + size_t(d)];
      const size_t found = tree.knnSearch(point.data(), query, index.data(), dist.data());
      ranked.clear();
      for (size_t i = 0; i < found; ++i) ranked.emplace_back(dist[i], sites[index[i]]);
      std::sort(ranked.begin(), ranked.end());  // distance, then index: a fixed order for ties
      uint32_t* slot = &out[size_t(p) * size_t(options.k)];
      int taken = 0;
      slot[taken++] = packCoord(uint32_t(px), uint32_t(py));
      for (const auto& [d, q] : ranked) {
        if (taken == options.k) break;
        const int qx = int(q) % w, qy = int(q) / w;
        bool spread = true;
        for (int t = 0; t < taken && spread; ++t)
          spread = toroidalDistance2(qx, qy, int(coordU(slot[t])), int(coordV(slot[t])), w, h) >= minDistance2;
        if (spread) slot[taken++] = packCoord(uint32_t(qx), uint32_t(qy));
      }
      while (taken < options.k) slot[taken++] = slot[0];
    }
  }, 256);
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

std::vector<Image> gaussianStack(const Image& exemplar) { return gaussianStackOf(colourChannels(exemplar)); }

Image featureDistance(const Image& exemplar) {
  const int w = exemplar.width, h = exemplar.height;
  const Image colour = colourChannels(exemplar);
  std::vector<float> luminance(size_t(w) * size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* p = colour.pixel(x, y);
      luminance[size_t(y) * w + x] = colour.channels == 3 ? 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2] : p[0];
    }
  auto lum = [&](int x, int y) { return luminance[size_t(wrap(y, h)) * w + size_t(wrap(x, w))]; };
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
  // the transform is toroidal.
  const float far = float(w * w + h * h);
  std::vector<float> dist2(gradient.size());
  for (size_t i = 0; i < gradient.size(); ++i) dist2[i] = gradient[i] > threshold ? 0.0f : far;
  std::vector<float> line;
  for (int y = 0; y < h; ++y) {
    line.resize(size_t(3 * w));
    for (int i = 0; i < 3 * w; ++i) line[size_t(i)] = dist2[size_t(y) * w + size_t(i % w)];
    distanceTransform1d(line);
    for (int x = 0; x < w; ++x) dist2[size_t(y) * w + x] = line[size_t(w + x)];
  }
  for (int x = 0; x < w; ++x) {
    line.resize(size_t(3 * h));
    for (int i = 0; i < 3 * h; ++i) line[size_t(i)] = dist2[size_t(i % h) * w + x];
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
  return hash.h;
}

void validateExemplarSize(const Image& exemplar) {
  if (exemplar.width < kMinExemplarSide || exemplar.height < kMinExemplarSide)
    throw Error("exemplar is " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) +
                ", smaller than the " + std::to_string(kMinExemplarSide) + "x" +
                std::to_string(kMinExemplarSide) + " appearance neighborhood");
  if (exemplar.width > 4096 || exemplar.height > 4096)
    throw Error("exemplar is " + std::to_string(exemplar.width) + "x" + std::to_string(exemplar.height) +
                ", larger than the supported 4096x4096 (exemplars are small pictures: 64 to 512 pixels)");
}

ExemplarAnalysis analyzeExemplar(const Image& exemplar, const AnalysisOptions& options, const Context& ctx) {
  options.validate();
  validateExemplarSize(exemplar);
  const int w = exemplar.width, h = exemplar.height;

  // Colour plus (optionally) the feature-distance channel, scaled so that its standard deviation
  // is featureWeight times the mean colour standard deviation (LH06 §3.2).
  Image base = colourChannels(exemplar);
  if (options.featureWeight > 0) {
    const Image feature = featureDistance(exemplar);
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
    double colourStd = 0;
    for (int c = 0; c < base.channels; ++c) colourStd += stddev(base, c) / base.channels;
    const double featureStd = stddev(feature, 0);
    const float scale = featureStd > 0 ? float(options.featureWeight * colourStd / featureStd) : 0.0f;
    Image augmented(w, h, base.channels + 1, PixelFormat::Float);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        for (int c = 0; c < base.channels; ++c) augmented.at(x, y, c) = base.at(x, y, c);
        augmented.at(x, y, base.channels) = scale * feature.at(x, y, 0);
      }
    base = std::move(augmented);
  }

  const std::vector<Image> stack = gaussianStackOf(base);
  ExemplarAnalysis analysis;
  analysis.width = w;
  analysis.height = h;
  analysis.k = options.k;
  analysis.key = analysisKey(exemplar, options);
  analysis.levels.resize(stack.size());
  const int finest = int(stack.size()) - 1;
  // Levels are independent: analyse them in parallel, each writing its own slot.
  parallelFor(0, int(stack.size()), ctx, [&](int begin, int end) {
    for (int l = begin; l < end; ++l) {
      AnalysisLevel& level = analysis.levels[size_t(l)];
      level.spacing = 1 << (finest - l);
      level.appearance = appearanceVectors(stack[size_t(l)], level.spacing);
      level.neighborhood = runtimeNeighborhoods(level.appearance, w, h, level.spacing);
      level.candidates = coherenceCandidates(level.appearance, w, h, level.spacing, options, ctx);
    }
  });
  return analysis;
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
    const int32_t header[5] = {a.width, a.height, int32_t(a.levels.size()), a.k, kAppearanceDims};
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
  int32_t header[5];
  if (!get(&magic, 4) || !get(&version, 4) || !get(&a.key, 8) || !get(header, sizeof header)) return std::nullopt;
  if (magic != kCacheMagic || version != kCacheVersion || a.key != expectedKey) return std::nullopt;
  a.width = header[0];
  a.height = header[1];
  a.k = header[3];
  if (a.width < kMinExemplarSide || a.height < kMinExemplarSide || a.width > 4096 || a.height > 4096 ||
      header[2] != stackLevelCount(a.width, a.height) || a.k < 1 || a.k > 8 || header[4] != kAppearanceDims)
    return std::nullopt;
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
    level.neighborhood = runtimeNeighborhoods(level.appearance, a.width, a.height, level.spacing);
  }
  if (in.peek() != std::char_traits<char>::eof()) return std::nullopt;
  return a;
}

ExemplarAnalysis analyzeExemplarCached(const Image& exemplar, const AnalysisOptions& options,
                                       const fs::path& cacheDir, const Context& ctx, bool* fromCache) {
  options.validate();
  return loadOrCompute(
      cacheDir, analysisKey(exemplar, options), ".analysis", readAnalysis,
      [&] { return analyzeExemplar(exemplar, options, ctx); }, writeAnalysis, fromCache);
}

} // namespace texfab::synthesis
