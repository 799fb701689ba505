// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/quality_measures.h"

#include "core/crop.h"
#include "core/error.h"
#include "core/parallel.h"
#include "synthesis/synthesize_2d.h"

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <vector>

namespace texfab::synthesis {

namespace {

int colorChannelCount(const Image& image) { return image.channels >= 3 ? 3 : 1; }

uint8_t quantize(float v) { return uint8_t(std::lrint(std::clamp(v, 0.0f, 1.0f) * 255.0f)); }

std::vector<float> luminance(const Image& image) {
  std::vector<float> out(size_t(image.width) * size_t(image.height));
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float* p = image.pixel(x, y);
      out[size_t(y) * image.width + x] = image.channels >= 3 ? 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2] : p[0];
    }
  return out;
}

double pearson(const std::vector<float>& lum, int w, int h, int dx, int dy) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const double n = double(w - dx) * double(h - dy);
  for (int y = 0; y + dy < h; ++y)
    for (int x = 0; x + dx < w; ++x) {
      const double a = lum[size_t(y) * w + x], b = lum[size_t(y + dy) * w + x + dx];
      sa += a; sb += b; saa += a * a; sbb += b * b; sab += a * b;
    }
  const double cov = sab / n - (sa / n) * (sb / n);
  const double va = saa / n - (sa / n) * (sa / n), vb = sbb / n - (sb / n) * (sb / n);
  if (va <= 1e-12 || vb <= 1e-12) return 1.0;  // a constant image repeats with any period
  return cov / std::sqrt(va * vb);
}

// A neighbourhood of n samples as 8-bit values, with removeMean less their channel's rounded mean.
void quantizePatch(const float* patch, int n, int channels, bool removeMean, int16_t* out) {
  for (int d = 0; d < n * channels; ++d) out[d] = quantize(patch[d]);
  if (!removeMean) return;
  for (int ch = 0; ch < channels; ++ch) {
    int32_t sum = 0;
    for (int i = 0; i < n; ++i) sum += out[i * channels + ch];
    const int32_t mean = (sum + n / 2) / n;
    for (int i = 0; i < n; ++i) out[i * channels + ch] = int16_t(out[i * channels + ch] - mean);
  }
}

double fidelityOf(std::span<const float> patches, const Image& exemplar, int radius, bool toroidal, bool removeMean,
                  const Context& ctx) {
  const int r = radius, side = 2 * r + 1;
  if (r < 0 || r > 8) throw Error("fidelity radius must be in [0, 8]");
  const int c = colorChannelCount(exemplar);
  const int dims = side * side * c;
  if (patches.empty() || patches.size() % size_t(dims) != 0)
    throw Error("fidelity: patches must hold a whole number of " + std::to_string(dims) + "-value neighborhoods");

  // All exemplar neighborhoods (toroidal, or those wholly inside), quantized, one contiguous vector each.
  const int ew = exemplar.width, eh = exemplar.height;
  const int m = toroidal ? 0 : r;  // margin of the centres
  if (ew <= 2 * m || eh <= 2 * m) throw Error("fidelity: the exemplar is smaller than its neighborhoods");
  const size_t exemplarCount = size_t(ew - 2 * m) * size_t(eh - 2 * m);
  std::vector<int16_t> ex(exemplarCount * size_t(dims));
  std::vector<float> gathered(static_cast<size_t>(dims));
  for (int y = m; y < eh - m; ++y)
    for (int x = m; x < ew - m; ++x) {
      float* v = gathered.data();
      for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
          const float* p = exemplar.pixel(((x + i) % ew + ew) % ew, ((y + j) % eh + eh) % eh);
          for (int ch = 0; ch < c; ++ch) *v++ = p[ch];
        }
      quantizePatch(gathered.data(), side * side, c, removeMean,
                    &ex[(size_t(y - m) * size_t(ew - 2 * m) + size_t(x - m)) * size_t(dims)]);
    }

  const size_t count = patches.size() / size_t(dims);
  std::vector<double> nearest(count);
  parallelFor(0, int(count), ctx, [&](int begin, int end) {
    std::vector<int16_t> q(size_t(dims), 0);
    for (int s = begin; s < end; ++s) {
      quantizePatch(&patches[size_t(s) * size_t(dims)], side * side, c, removeMean, q.data());
      // Exact search with partial-distance elimination, one neighborhood row at a time.
      const int rowDims = side * c;
      int64_t best = std::numeric_limits<int64_t>::max();
      for (size_t e = 0; e < exemplarCount; ++e) {
        const int16_t* a = &ex[e * size_t(dims)];
        int64_t sum = 0;
        for (int row = 0; row < side && sum < best; ++row) {
          int32_t rowSum = 0;
          for (int d = row * rowDims; d < (row + 1) * rowDims; ++d) {
            const int32_t diff = int32_t(a[d]) - int32_t(q[size_t(d)]);
            rowSum += diff * diff;
          }
          sum += rowSum;
        }
        best = std::min(best, sum);
      }
      nearest[size_t(s)] = std::sqrt(double(best) / dims) / 255.0;
    }
  }, 16);
  return std::accumulate(nearest.begin(), nearest.end(), 0.0) / double(nearest.size());
}

/// Neighborhoods of `image` centred on a regular grid of about `samples` texels (all if 0),
/// wrapping around its borders or only wholly inside it.
std::vector<float> sampledNeighborhoods(const Image& image, int r, int samples, bool toroidal) {
  const int side = 2 * r + 1, c = colorChannelCount(image);
  if (r < 0 || r > 8) throw Error("fidelity radius must be in [0, 8]");
  if (image.width < side || image.height < side)
    throw Error("image is smaller than the " + std::to_string(side) + "x" + std::to_string(side) + " fidelity neighborhood");
  const int m = toroidal ? 0 : r;  // margin of the centres
  const int iw = image.width - 2 * m, ih = image.height - 2 * m;
  int step = 1;
  if (samples > 0 && int64_t(iw) * ih > samples) step = std::max(1, int(std::lround(std::sqrt(double(iw) * ih / samples))));
  std::vector<float> patches;
  for (int y = m; y < image.height - m; y += step)
    for (int x = m; x < image.width - m; x += step)
      for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
          const float* p = image.pixel(((x + i) % image.width + image.width) % image.width,
                                       ((y + j) % image.height + image.height) % image.height);
          patches.insert(patches.end(), p, p + c);
        }
  return patches;
}

} // namespace

double patchFidelity(std::span<const float> patches, const Image& exemplar, const FidelityOptions& options,
                     const Context& ctx) {
  return fidelityOf(patches, exemplar, options.radius, options.toroidal, options.removeMean, ctx);
}

double neighborhoodFidelity(const Image& image, const Image& exemplar, const FidelityOptions& options, const Context& ctx) {
  if (colorChannelCount(image) != colorChannelCount(exemplar))
    throw Error("image and exemplar differ in colour channels (grey versus RGB)");
  return fidelityOf(sampledNeighborhoods(image, options.radius, options.samples, false), exemplar, options.radius,
                    options.toroidal, options.removeMean, ctx);
}

double neighborhoodCompleteness(const Image& image, const Image& exemplar, const FidelityOptions& options,
                                const Context& ctx) {
  if (colorChannelCount(image) != colorChannelCount(exemplar))
    throw Error("image and exemplar differ in colour channels (grey versus RGB)");
  return fidelityOf(sampledNeighborhoods(exemplar, options.radius, options.samples, options.toroidal), image,
                    options.radius, false, options.removeMean, ctx);
}

double histogramDistance(const Image& image, const Image& exemplar) {
  const int c = colorChannelCount(image);
  if (c != colorChannelCount(exemplar)) throw Error("image and exemplar differ in colour channels (grey versus RGB)");
  auto histogram = [](const Image& img, int ch) {
    std::vector<double> h(256, 0.0);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) h[quantize(img.at(x, y, ch))] += 1.0;
    for (double& v : h) v /= double(img.width) * img.height;
    return h;
  };
  double worst = 0;
  for (int ch = 0; ch < c; ++ch) {
    const std::vector<double> a = histogram(image, ch), b = histogram(exemplar, ch);
    double cdfA = 0, cdfB = 0, emd = 0;
    for (int i = 0; i < 256; ++i) {
      cdfA += a[size_t(i)];
      cdfB += b[size_t(i)];
      emd += std::abs(cdfA - cdfB);
    }
    worst = std::max(worst, emd / 255.0);
  }
  return worst;
}

double coherence(const CoordMap& m) {
  int64_t pairs = 0, coherent = 0;
  const auto ew = uint32_t(m.exemplarWidth), eh = uint32_t(m.exemplarHeight);
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      const uint32_t c = m.at(x, y);
      if (x + 1 < m.width) {
        const uint32_t n = m.at(x + 1, y);
        ++pairs;
        coherent += coordU(n) == (coordU(c) + 1) % ew && coordV(n) == coordV(c);
      }
      if (y + 1 < m.height) {
        const uint32_t n = m.at(x, y + 1);
        ++pairs;
        coherent += coordU(n) == coordU(c) && coordV(n) == (coordV(c) + 1) % eh;
      }
    }
  return pairs ? double(coherent) / double(pairs) : 0.0;
}

int64_t wrapCrossings(const CoordMap& m) {
  const auto crosses = [](uint32_t a, uint32_t b, int size) {
    const int d = std::abs(int(a) - int(b));
    return d > 2 && size - d <= 2;
  };
  int64_t count = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      const uint32_t c = m.at(x, y);
      for (const uint32_t n : {x + 1 < m.width ? m.at(x + 1, y) : c, y + 1 < m.height ? m.at(x, y + 1) : c})
        count += crosses(coordU(c), coordU(n), m.exemplarWidth) || crosses(coordV(c), coordV(n), m.exemplarHeight);
    }
  return count;
}

double seamVisibility(const CoordMap& m, const Image& exemplar) {
  if (exemplar.width != m.exemplarWidth || exemplar.height != m.exemplarHeight)
    throw Error("seam visibility: the coordinates index a " + std::to_string(m.exemplarWidth) + "x" +
                std::to_string(m.exemplarHeight) + " exemplar, got " + std::to_string(exemplar.width) + "x" +
                std::to_string(exemplar.height));
  const std::vector<float> lum = luminance(exemplar);
  const int ew = exemplar.width, eh = exemplar.height;
  const auto at = [&](uint32_t c) { return double(lum[size_t(coordV(c)) * ew + coordU(c)]); };
  double inside = 0;
  for (int y = 0; y < eh; ++y)
    for (int x = 0; x < ew; ++x) {
      if (x + 1 < ew) inside += std::abs(lum[size_t(y) * ew + x + 1] - lum[size_t(y) * ew + x]);
      if (y + 1 < eh) inside += std::abs(lum[size_t(y + 1) * ew + x] - lum[size_t(y) * ew + x]);
    }
  inside /= double(ew - 1) * eh + double(eh - 1) * ew;
  double seams = 0;
  int64_t count = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      const uint32_t c = m.at(x, y);
      if (x + 1 < m.width) {
        const uint32_t n = m.at(x + 1, y);
        if (coordU(n) != coordU(c) + 1 || coordV(n) != coordV(c)) seams += std::abs(at(n) - at(c)), ++count;
      }
      if (y + 1 < m.height) {
        const uint32_t n = m.at(x, y + 1);
        if (coordU(n) != coordU(c) || coordV(n) != coordV(c) + 1) seams += std::abs(at(n) - at(c)), ++count;
      }
    }
  if (count == 0) return 0.0;
  return inside > 1e-12 ? seams / double(count) / inside : 1.0;
}

double coverage(const CoordMap& m) {
  std::vector<bool> used(size_t(m.exemplarWidth) * size_t(m.exemplarHeight), false);
  for (uint32_t c : m.coords) used[size_t(coordV(c)) * m.exemplarWidth + coordU(c)] = true;
  return double(std::count(used.begin(), used.end(), true)) / double(used.size());
}

double shiftedSelfCorrelation(const Image& image, int dx, int dy) {
  if (dx <= 0 || dy <= 0 || image.width <= dx || image.height <= dy)
    throw Error("shifted correlation needs an image larger than the shift (" + std::to_string(dx) + ", " +
                std::to_string(dy) + "), got " + std::to_string(image.width) + "x" + std::to_string(image.height));
  const std::vector<float> lum = luminance(image);
  return std::max(pearson(lum, image.width, image.height, dx, 0), pearson(lum, image.width, image.height, 0, dy));
}

double latticeCorrelation(const Image& image, int period) {
  double c = 0;
  for (int k = period; period > 0 && 2 * k < std::min(image.width, image.height); k += period)
    c = std::max(c, shiftedSelfCorrelation(image, k, k));
  return c;
}

LatticeSteps latticeSteps(const Image& image, int period, int64_t originX, int64_t originY) {
  if (period < 3) throw Error("lattice steps need a period of 3 or more, got " + std::to_string(period));
  const int channels = std::min(image.channels, 3);
  std::vector<double> sum(size_t(period), 0.0), count(size_t(period), 0.0);
  auto step = [&](const float* a, const float* b, int64_t position) {
    double d = 0;
    for (int c = 0; c < channels; ++c) d += std::fabs(double(b[c]) - double(a[c]));
    const size_t k = size_t((position % period + period) % period);
    sum[k] += d;
    count[k] += 1;
  };
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      if (x + 1 < image.width) step(image.pixel(x, y), image.pixel(x + 1, y), originX + x);
      if (y + 1 < image.height) step(image.pixel(x, y), image.pixel(x, y + 1), originY + y);
    }
  LatticeSteps s;
  s.meanStep.resize(size_t(period));
  for (size_t k = 0; k < sum.size(); ++k) s.meanStep[k] = count[k] > 0 ? sum[k] / count[k] : 0.0;
  return s;
}

double LatticeSteps::seamRatio() const {
  const size_t last = meanStep.size() - 1;
  double inside = 0;
  for (size_t k = 1; k < last; ++k) inside += meanStep[k];
  inside /= double(last - 1);
  return inside > 0 ? (meanStep[0] + meanStep[last]) / 2 / inside : 1.0;
}

double LatticeSteps::peak() const {
  std::vector<double> sorted = meanStep;
  std::sort(sorted.begin(), sorted.end());
  return sorted[sorted.size() / 2] > 0 ? sorted.back() / sorted[sorted.size() / 2] : 1.0;
}

double contrastRatio(const Image& image, const Image& exemplar) {
  auto deviation = [](const Image& im) {
    const std::vector<float> lum = luminance(im);
    double s = 0, ss = 0;
    for (float l : lum) s += l, ss += double(l) * l;
    const double n = double(lum.size()), mean = s / n;
    return std::sqrt(std::max(0.0, ss / n - mean * mean));
  };
  const double e = deviation(exemplar);
  return e > 0 ? deviation(image) / e : std::numeric_limits<double>::quiet_NaN();
}

double measureQualityMemoryBytes(const Image& image, const Image& exemplar, const FidelityOptions& fidelity) {
  const double dims = double((2 * fidelity.radius + 1) * (2 * fidelity.radius + 1) * colorChannelCount(exemplar));
  auto sampled = [&](double pixels) { return fidelity.samples > 0 ? std::min(pixels, 2.0 * fidelity.samples) : pixels; };
  auto phase = [&](double searched, double measured) {  // 8-bit set searched, float patches and distances measured
    return searched * dims + sampled(measured) * (dims * sizeof(float) + sizeof(double));
  };
  const double imagePixels = double(image.width) * image.height;
  const double exemplarPixels = double(exemplar.width) * exemplar.height;
  const double cropPixels = std::min(imagePixels, 4 * exemplarPixels);
  return std::max(phase(exemplarPixels, imagePixels),
                  cropPixels * image.channels * sizeof(float) + phase(cropPixels, exemplarPixels)) +
         imagePixels * sizeof(float);  // the luminance of the image (shifted correlation)
}

QualityReport measureQuality(const Image& image, const Image& exemplar, const CoordMap* coords,
                             const FidelityOptions& fidelity, const Context& ctx) {
  QualityReport report;
  report.fidelity = neighborhoodFidelity(image, exemplar, fidelity, ctx);
  const int cw = std::min(image.width, 2 * exemplar.width), ch = std::min(image.height, 2 * exemplar.height);
  report.completeness =
      neighborhoodCompleteness(crop(image, (image.width - cw) / 2, (image.height - ch) / 2, cw, ch), exemplar, fidelity, ctx);
  report.histogramDistance = histogramDistance(image, exemplar);
  report.contrast = contrastRatio(image, exemplar);
  if (image.width > exemplar.width && image.height > exemplar.height)
    report.shiftedCorrelation = shiftedSelfCorrelation(image, exemplar.width, exemplar.height);
  else
    report.shiftedCorrelation = std::numeric_limits<double>::quiet_NaN();
  if (coords) {
    report.coherence = coherence(*coords);
    report.coverage = coverage(*coords);
  }
  return report;
}

QualityReport measureSynthesisBaseline(const ExemplarAnalysis& analysis, const Image& exemplar, int width, int height,
                                       const FidelityOptions& fidelity, const Context& ctx) {
  const SynthesisResult r = synthesize2d(analysis, {0, 0, width, height}, {}, ctx);
  return measureQuality(applyCoords(r.coords, exemplar, ctx), exemplar, nullptr, fidelity, ctx);
}

} // namespace texfab::synthesis
