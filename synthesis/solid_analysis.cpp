// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: Y. Dong, S. Lefebvre, X. Tong, G. Drettakis. Lazy Solid Texture Synthesis. EGSR 2008,
//           §4 (3-D candidate selection) and §6.1-6.2 (shared candidates, PCA, 8-bit storage).
#include "synthesis/solid_analysis.h"

#include "core/error.h"
#include "core/files.h"
#include "core/hash.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/binary_io.h"
#include "synthesis/coord_map.h"
#include "synthesis/cpu/synthesis_kernels.h"
#include "synthesis/exemplar_analysis.h"

#include <Eigen/Dense>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdint>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>

namespace texfab::synthesis {
namespace fs = std::filesystem;

namespace {

constexpr uint32_t kSolidMagic = 0x444c5354;  // "TSLD"
constexpr uint32_t kSolidVersion = 4;         // bump whenever the analysis changes
constexpr int kStripLength = kSolidNeighborhoodSide;
constexpr int kStripDims = kStripLength * 3;
constexpr int kRadius = kSolidNeighborhoodSide / 2;
constexpr int kBasisBits = 12;

int wrap(int a, int m) {
  const int r = a % m;
  return r < 0 ? r + m : r;
}

// Axis unit vectors of each exemplar's (u, v) in the volume (the header's cyclic orientation).
constexpr int kAxisU[3] = {1, 2, 0};
constexpr int kAxisV[3] = {2, 0, 1};

// 8-bit RGB of a stack level (grey is replicated).
std::vector<uint8_t> levelColors(const Image& level) {
  std::vector<uint8_t> out(size_t(level.width) * level.height * 3);
  for (int y = 0; y < level.height; ++y)
    for (int x = 0; x < level.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = level.at(x, y, level.channels >= 3 ? c : 0);
        out[(size_t(y) * level.width + x) * 3 + size_t(c)] = uint8_t(std::lrint(std::clamp(v, 0.0f, 1.0f) * 255.0f));
      }
  return out;
}

struct Exemplar8 {
  int w = 0, h = 0;
  const uint8_t* rgb = nullptr;
  ExemplarWrap border = ExemplarWrap::Tile;  // how positions outside the exemplar are read
  const uint8_t* at(int u, int v) const {
    return rgb + (size_t(foldIndex(v, h, border)) * w + size_t(foldIndex(u, w, border))) * 3;
  }
};

// A pixel index p = v * w + u moved into `valid` (reflectInto per axis); itself when inside.
uint32_t reflectPixel(uint32_t p, int w, const ValidRegion& valid) {
  const int64_t u = cpu::reflectInto(p % uint32_t(w), valid.x0, valid.x1);
  const int64_t v = cpu::reflectInto(p / uint32_t(w), valid.y0, valid.y1);
  return uint32_t(v * w + u);
}

// The indices of the pixels of `valid`, ascending.
std::vector<uint32_t> pixelsIn(const ValidRegion& valid, int w) {
  std::vector<uint32_t> out;
  for (int v = valid.y0; v <= valid.y1; ++v)
    for (int u = valid.x0; u <= valid.x1; ++u) out.push_back(uint32_t(v * w + u));
  return out;
}

// The strip through p along u (row) or v (column), taps `spacing` apart.
void strip(const Exemplar8& e, int u, int v, bool column, int spacing, int32_t* out) {
  for (int t = -kRadius; t <= kRadius; ++t) {
    const uint8_t* c = column ? e.at(u, v + t * spacing) : e.at(u + t * spacing, v);
    for (int ch = 0; ch < 3; ++ch) *out++ = c[ch];
  }
}

int32_t stripDistance(const int32_t* a, const int32_t* b) {
  int32_t s = 0;
  for (int i = 0; i < kStripDims; ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return s;
}

struct Strips {
  std::vector<int32_t> rows, cols;  // n * kStripDims each
};

Strips stripsOf(const Exemplar8& e, int spacing) {
  Strips s;
  const size_t n = size_t(e.w) * e.h;
  s.rows.resize(n * kStripDims);
  s.cols.resize(n * kStripDims);
  for (int v = 0; v < e.h; ++v)
    for (int u = 0; u < e.w; ++u) {
      strip(e, u, v, false, spacing, &s.rows[(size_t(v) * e.w + u) * kStripDims]);
      strip(e, u, v, true, spacing, &s.cols[(size_t(v) * e.w + u) * kStripDims]);
    }
  return s;
}

struct Triple {  // relative to the exemplar it belongs to: the pixel, then next, then previous
  int32_t cb;
  uint32_t q, r;  // pixel indices in the next and previous exemplars
};

// For each query strip, the s nearest strips among the strips of pixels `allowed` (ascending) of
// `points` by exact integer squared distance, as pixel indices, ties to the smaller index (an exact
// search, like the paper's ANN with no approximation). Brute force as blocks of a float matrix
// product: exact, since every term is an integer below 2^24.
std::vector<uint32_t> nearestStrips(const std::vector<int32_t>& queries, const std::vector<int32_t>& points,
                                    const std::vector<uint32_t>& allowed, int s, const Context& ctx) {
  using Rows = Eigen::Matrix<float, Eigen::Dynamic, kStripDims, Eigen::RowMajor>;
  const int n = int(queries.size() / kStripDims), np = int(allowed.size());
  Rows p(np, kStripDims), q(n, kStripDims);
  for (int i = 0; i < np; ++i)
    for (int d = 0; d < kStripDims; ++d) p(i, d) = float(points[size_t(allowed[size_t(i)]) * kStripDims + size_t(d)]);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < kStripDims; ++d) q(i, d) = float(queries[size_t(i) * kStripDims + size_t(d)]);
  const Eigen::VectorXf pn = p.rowwise().squaredNorm();
  std::vector<uint32_t> out(size_t(n) * size_t(s));
  constexpr int kBlock = 32;
  parallelFor(0, (n + kBlock - 1) / kBlock, ctx, [&](int b0, int b1) {
    Eigen::MatrixXf dot;
    std::vector<uint64_t> heap;
    heap.reserve(size_t(s));
    std::vector<int32_t> dist(static_cast<size_t>(np));
    for (int b = b0; b < b1; ++b) {
      const int r0 = b * kBlock, rows = std::min(kBlock, n - r0);
      dot.noalias() = p * q.middleRows(r0, rows).transpose();  // np x rows: one column per query
      for (int j = 0; j < rows; ++j) {
        const float qn = q.row(r0 + j).squaredNorm();
        const float* column = dot.col(j).data();
        const float* norms = pn.data();
        int32_t* d = dist.data();
        for (int i = 0; i < np; ++i) d[i] = int32_t(qn + norms[i] - 2.0f * column[i]);  // < 2^24: exact
        heap.clear();
        int32_t threshold = INT32_MAX;  // the worst distance kept, once the heap is full
        for (int i = 0; i < np; ++i) {
          if (dist[size_t(i)] > threshold) continue;
          const uint64_t key = (uint64_t(uint32_t(dist[size_t(i)])) << 32) | uint32_t(i);
          if (heap.size() < size_t(s)) {
            heap.push_back(key);
            std::push_heap(heap.begin(), heap.end());
            if (heap.size() == size_t(s)) threshold = int32_t(heap.front() >> 32);
          } else if (key < heap.front()) {
            std::pop_heap(heap.begin(), heap.end());
            heap.back() = key;
            std::push_heap(heap.begin(), heap.end());
            threshold = int32_t(heap.front() >> 32);
          }
        }
        std::sort_heap(heap.begin(), heap.end());
        for (int k = 0; k < s; ++k)
          out[size_t(r0 + j) * size_t(s) + size_t(k)] = allowed[size_t(uint32_t(heap[size_t(k)]))];
      }
    }
  }, 1);
  return out;
}

// §4.1: in every pixel of exemplar `self`, the `kept` triples of least crossbar error built from
// the S best strips of the next and previous exemplars centred on pixels `allowed`.
std::vector<std::vector<Triple>> crossbarTriples(const Strips& self, const Strips& next, const Strips& prev, int n,
                                                 const std::vector<uint32_t>& allowed, const SolidAnalysisOptions& o,
                                                 const Context& ctx) {
  const size_t s = std::min<size_t>(size_t(o.strips), allowed.size());
  const std::vector<uint32_t> nearestNext = nearestStrips(self.cols, next.rows, allowed, int(s), ctx);
  const std::vector<uint32_t> nearestPrev = nearestStrips(self.rows, prev.cols, allowed, int(s), ctx);
  std::vector<std::vector<Triple>> out(static_cast<size_t>(n));
  parallelFor(0, n, ctx, [&](int begin, int end) {
    std::vector<int32_t> d1(s), d2(s);
    std::vector<Triple> all;
    all.reserve(s * s);
    for (int p = begin; p < end; ++p) {
      const int32_t* col = &self.cols[size_t(p) * kStripDims];
      const int32_t* row = &self.rows[size_t(p) * kStripDims];
      const uint32_t* qi = &nearestNext[size_t(p) * s];
      const uint32_t* ri = &nearestPrev[size_t(p) * s];
      const size_t nq = s, nr = s;
      // Exact integer strip distances.
      for (size_t i = 0; i < nq; ++i) d1[i] = stripDistance(col, &next.rows[size_t(qi[i]) * kStripDims]);
      for (size_t i = 0; i < nr; ++i) d2[i] = stripDistance(row, &prev.cols[size_t(ri[i]) * kStripDims]);
      // The third crossbar term for all S^2 pairs at once: |a|^2 + |b|^2 - 2 a.b as a small
      // matrix product. Exact in float: every term is an integer below 2^24.
      Eigen::MatrixXf qa(Eigen::Index(nq), kStripDims), rb(Eigen::Index(nr), kStripDims);
      for (size_t a = 0; a < nq; ++a)
        for (int i = 0; i < kStripDims; ++i) qa(Eigen::Index(a), i) = float(next.cols[size_t(qi[a]) * kStripDims + size_t(i)]);
      for (size_t b = 0; b < nr; ++b)
        for (int i = 0; i < kStripDims; ++i) rb(Eigen::Index(b), i) = float(prev.rows[size_t(ri[b]) * kStripDims + size_t(i)]);
      const Eigen::VectorXf qn = qa.rowwise().squaredNorm(), rn = rb.rowwise().squaredNorm();
      const Eigen::MatrixXf dot = qa * rb.transpose();
      // The `kept` least (CB, q, r) among the S^2 pairs, with a max-heap. d1 and d2 ascend (the
      // searches return strips nearest first) and CB >= d1 + d2, so a row stops as soon as
      // d1 + d2 exceeds the worst triple kept: the result is that of the full sort.
      auto less = [](const Triple& x, const Triple& y) {
        return x.cb != y.cb ? x.cb < y.cb : x.q != y.q ? x.q < y.q : x.r < y.r;
      };
      const size_t keep = std::min(nq * nr, size_t(o.kept));
      all.clear();
      for (size_t a = 0; a < nq; ++a) {
        if (all.size() == keep && d1[a] + d2[0] > all.front().cb) break;
        for (size_t b = 0; b < nr; ++b) {
          if (all.size() == keep && d1[a] + d2[b] > all.front().cb) break;
          const auto d3 = int32_t(qn(Eigen::Index(a)) + rn(Eigen::Index(b)) - 2.0f * dot(Eigen::Index(a), Eigen::Index(b)));
          const Triple t{d1[a] + d2[b] + d3, qi[a], ri[b]};
          if (all.size() < keep) {
            all.push_back(t);
            std::push_heap(all.begin(), all.end(), less);
          } else if (less(t, all.front())) {
            std::pop_heap(all.begin(), all.end(), less);
            all.back() = t;
            std::push_heap(all.begin(), all.end(), less);
          }
        }
      }
      std::sort_heap(all.begin(), all.end(), less);
      out[size_t(p)] = all;
    }
  }, 64);
  return out;
}

// §4.2: keep a triple only if, for each foreign coordinate, a candidate of a 4-neighbor pixel has
// that coordinate one tap (h) away. Iterates until no pixel has more than 12 candidates. Steps
// wrap (Tile) or stop at the exemplar's border (Clamp).
void coherenceFilter(std::vector<std::vector<Triple>>& sets, int w, int h, int spacing, ExemplarWrap border,
                     int iterations, const Context& ctx) {
  const int n = w * h;
  constexpr uint32_t kNone = UINT32_MAX;  // a step off a non-toroidal exemplar
  auto stepsOf = [&](uint32_t a, uint32_t* out) {
    const int u = int(a % uint32_t(w)), v = int(a / uint32_t(w));
    const int du[4] = {spacing, -spacing, 0, 0}, dv[4] = {0, 0, spacing, -spacing};
    for (int i = 0; i < 4; ++i) {
      const int su = u + du[i], sv = v + dv[i];
      const bool inside = su >= 0 && su < w && sv >= 0 && sv < h;
      out[i] = border == ExemplarWrap::Tile ? uint32_t(wrap(sv, h) * w + wrap(su, w))
               : inside                     ? uint32_t(sv * w + su)
                                            : kNone;
    }
  };
  for (int it = 0; it < iterations; ++it) {
    bool over = false;
    for (const auto& s : sets) over = over || s.size() > size_t(kSolidMaxCandidates);
    if (!over) break;
    // Each pixel's foreign coordinates, sorted, in flat arrays (offsets[p] .. offsets[p+1]).
    std::vector<size_t> offsets(size_t(n) + 1, 0);
    for (int p = 0; p < n; ++p) offsets[size_t(p) + 1] = offsets[size_t(p)] + sets[size_t(p)].size();
    std::vector<uint32_t> qsFlat(offsets.back()), rsFlat(offsets.back());
    parallelFor(0, n, ctx, [&](int begin, int end) {
      for (int p = begin; p < end; ++p) {
        size_t i = offsets[size_t(p)];
        for (const Triple& t : sets[size_t(p)]) {
          qsFlat[i] = t.q;
          rsFlat[i++] = t.r;
        }
        std::sort(qsFlat.begin() + std::ptrdiff_t(offsets[size_t(p)]), qsFlat.begin() + std::ptrdiff_t(i));
        std::sort(rsFlat.begin() + std::ptrdiff_t(offsets[size_t(p)]), rsFlat.begin() + std::ptrdiff_t(i));
      }
    }, 256);
    std::vector<std::vector<Triple>> next(static_cast<size_t>(n));
    parallelFor(0, n, ctx, [&](int begin, int end) {
      for (int p = begin; p < end; ++p) {
        uint32_t neighbors[4];
        stepsOf(uint32_t(p), neighbors);
        auto found = [&](const std::vector<uint32_t>& flat, uint32_t coord) {
          uint32_t steps[4];
          stepsOf(coord, steps);
          for (uint32_t nb : neighbors)
            for (uint32_t s : steps)
              if (nb != kNone && std::binary_search(flat.begin() + std::ptrdiff_t(offsets[size_t(nb)]),
                                                    flat.begin() + std::ptrdiff_t(offsets[size_t(nb) + 1]), s))
                return true;
          return false;
        };
        std::vector<Triple>& kept = next[size_t(p)];
        for (const Triple& t : sets[size_t(p)])
          if (found(qsFlat, t.q) && found(rsFlat, t.r)) kept.push_back(t);
        if (kept.empty()) kept = sets[size_t(p)];  // never empty a pixel
      }
    }, 256);
    sets.swap(next);
  }
}

// Fits an integer PCA projection to `samples` (rows of `inputs` integers).
SolidProjection fitProjection(const std::vector<int32_t>& samples, int inputs, int dims) {
  const int n = int(samples.size() / size_t(inputs));
  SolidProjection p;
  p.inputs = inputs;
  p.dims = dims;
  Eigen::MatrixXf m(n, inputs);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < inputs; ++j) m(i, j) = float(samples[size_t(i) * inputs + size_t(j)]);
  const Eigen::RowVectorXf mean = m.colwise().mean();
  p.mean.resize(size_t(inputs));
  for (int j = 0; j < inputs; ++j) p.mean[size_t(j)] = int32_t(std::lrint(mean(j)));
  for (int j = 0; j < inputs; ++j) m.col(j).array() -= float(p.mean[size_t(j)]);
  const Eigen::MatrixXd covariance = (m.transpose() * m).cast<double>() / double(std::max(1, n - 1));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
  p.basis.assign(size_t(dims) * inputs, 0);
  for (int d = 0; d < dims && d < inputs; ++d) {
    Eigen::VectorXd v = solver.eigenvectors().col(inputs - 1 - d);
    Eigen::Index arg;
    v.cwiseAbs().maxCoeff(&arg);
    if (v(arg) < 0) v = -v;  // a reproducible sign
    for (int j = 0; j < inputs; ++j)
      p.basis[size_t(d) * inputs + size_t(j)] = int16_t(std::lrint(v(j) * double(1 << kBasisBits)));
  }
  // The divisor maps the largest projected sample to 127.
  int64_t maxAbs = 1;
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < dims; ++d) {
      int64_t acc = 0;
      for (int j = 0; j < inputs; ++j)
        acc += int64_t(p.basis[size_t(d) * inputs + size_t(j)]) * (samples[size_t(i) * inputs + size_t(j)] - p.mean[size_t(j)]);
      maxAbs = std::max(maxAbs, acc < 0 ? -acc : acc);
    }
  // A power of two (a shift at run time), the smallest that maps the largest value into int8.
  p.divisor = int32_t(std::bit_ceil(uint64_t(std::max<int64_t>(1, (maxAbs + 126) / 127))));
  return p;
}

// Projection inputs of a candidate's 3-neighborhood: 6x the mean exemplar colour of the planes
// through each voxel (so that runtime voxels, 2x the sum of their three colours, match in scale).
void candidateNeighborhood(const std::array<Exemplar8, 3>& ex, const uint32_t* triple, int spacing, int32_t* out) {
  const auto& cross = solidCrossOffsets();
  for (int i = 0; i < kSolidCrossVoxels; ++i) {
    const auto& o = cross[size_t(i)];
    int32_t sum[3] = {0, 0, 0};
    int count = 0;
    for (int e = 0; e < 3; ++e) {
      if (o[size_t(e)] != 0) continue;  // plane e is normal to axis e
      const uint8_t* c = ex[size_t(e)].at(int(coordU(triple[e])) + spacing * o[size_t(kAxisU[e])],
                                          int(coordV(triple[e])) + spacing * o[size_t(kAxisV[e])]);
      for (int ch = 0; ch < 3; ++ch) sum[ch] += c[ch];
      ++count;
    }
    for (int ch = 0; ch < 3; ++ch) out[i * 3 + ch] = sum[ch] * (6 / count);
  }
}

void exemplarNeighborhood2d(const Exemplar8& e, int u, int v, int spacing, int32_t* out) {
  for (int j = -kRadius; j <= kRadius; ++j)
    for (int i = -kRadius; i <= kRadius; ++i) {
      const uint8_t* c = e.at(u + i * spacing, v + j * spacing);
      for (int ch = 0; ch < 3; ++ch) *out++ = 6 * c[ch];
    }
}

bool samePixels(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.channels == b.channels && a.pixels == b.pixels;
}

// SolidLevel::searchColors of one channel: `sums` counts the sums of three colours (source),
// `values` the exemplar colours (target). Exact integer arithmetic: the source quantile at the
// middle of sum s's share, q = (below + count/2) / total, is looked up in the target's
// distribution with linear interpolation inside the 8-bit bin it falls in (bin b spans
// [b - 1/2, b + 1/2]).
void matchHistogram(const std::array<int64_t, kSolidColorSums>& sums, const std::array<int64_t, 256>& values,
                    std::array<int16_t, kSolidColorSums>& out) {
  int64_t sourceTotal = 0, targetTotal = 0;
  for (int64_t c : sums) sourceTotal += c;
  for (int64_t c : values) targetTotal += c;
  int64_t below = 0;
  for (int s = 0; s < kSolidColorSums; ++s) {
    // The quantile in target units, as the fraction position / den.
    const int64_t den = 2 * sourceTotal, position = (2 * below + sums[size_t(s)]) * targetTotal;
    below += sums[size_t(s)];
    int64_t before = 0;
    int b = 0;
    while (b < 255 && (before + values[size_t(b)]) * den < position) before += values[size_t(b++)];
    const int64_t inBin = values[size_t(b)] * den;
    const int64_t sixths = inBin > 0 ? (6 * (position - before * den) + inBin / 2) / inBin : 3;
    out[size_t(s)] = int16_t(std::clamp<int64_t>(6 * b - 3 + std::clamp<int64_t>(sixths, 0, 6), 0, 6 * 255));
  }
}

void matchSearchColors(SolidLevel& level, int w) {
  auto colors = [&](int e) { return level.colors[level.colors[size_t(e)].empty() ? 0 : size_t(e)].data(); };
  auto at = [&](int e, uint32_t c) { return colors(e) + (size_t(coordV(c)) * size_t(w) + coordU(c)) * 3; };
  const size_t pixels = level.colors[0].size() / 3;
  for (int ch = 0; ch < 3; ++ch) {
    std::array<int64_t, kSolidColorSums> sums{};
    std::array<int64_t, 256> values{};
    for (int e = 0; e < 3; ++e)
      for (size_t p = 0; p < pixels; ++p) {
        ++values[colors(e)[p * 3 + size_t(ch)]];
        for (int k = 0; k < kSolidTransferCandidates; ++k) {
          const uint32_t* t = &level.triples[size_t(e)][(p * kSolidMaxCandidates + size_t(k)) * 3];
          ++sums[size_t(at(0, t[0])[ch] + at(1, t[1])[ch] + at(2, t[2])[ch])];
        }
      }
    matchHistogram(sums, values, level.searchColors[size_t(ch)]);
  }
}

// Fills the derived tables of a level (see SolidLevel::candidateDescriptors2d, searchColors).
void deriveTables(SolidLevel& level, int w) {
  matchSearchColors(level, w);
  for (int e = 0; e < 3; ++e) {
    const auto& cands = level.candidates2d[size_t(e)];
    const auto& desc = level.descriptors2d[size_t(e)];
    auto& out = level.candidateDescriptors2d[size_t(e)];
    out.resize(cands.size() * kSolid2dDims);
    for (size_t i = 0; i < cands.size(); ++i) {
      const size_t p = size_t(coordV(cands[i])) * size_t(w) + coordU(cands[i]);
      std::copy_n(desc.begin() + std::ptrdiff_t(p * kSolid2dDims), kSolid2dDims,
                  out.begin() + std::ptrdiff_t(i * kSolid2dDims));
    }
  }
}

} // namespace

void SolidProjection::project(const int32_t* values, int8_t* out) const {
  // |basis| <= 2^12 and |x - mean| <= 6 * 255: 183 products fit in int32 (as in the kernels).
  int16_t centred[kSolidCrossVoxels * 3];
  for (int j = 0; j < inputs; ++j) centred[j] = int16_t(values[j] - mean[size_t(j)]);
  for (int d = 0; d < dims; ++d) {
    const int16_t* b = basis.data() + size_t(d) * inputs;
    int32_t acc = 0;
    for (int j = 0; j < inputs; ++j) acc += int32_t(b[j]) * int32_t(centred[j]);
    const int32_t q = (acc + (divisor >> 1)) >> std::countr_zero(uint32_t(divisor));  // round half up
    out[d] = int8_t(std::clamp(q, -127, 127));
  }
}

const std::array<std::array<int, 3>, kSolidCrossVoxels>& solidCrossOffsets() {
  static const auto offsets = [] {
    std::array<std::array<int, 3>, kSolidCrossVoxels> o{};
    int k = 0;
    for (int y = -kRadius; y <= kRadius; ++y)  // (x, y) plane
      for (int x = -kRadius; x <= kRadius; ++x) o[size_t(k++)] = {x, y, 0};
    for (int x = -kRadius; x <= kRadius; ++x)  // (z, x) plane, off the x axis
      for (int z = -kRadius; z <= kRadius; ++z)
        if (z != 0) o[size_t(k++)] = {x, 0, z};
    for (int z = -kRadius; z <= kRadius; ++z)  // (y, z) plane, off both axes
      for (int y = -kRadius; y <= kRadius; ++y)
        if (y != 0 && z != 0) o[size_t(k++)] = {0, y, z};
    return o;
  }();
  return offsets;
}

void SolidAnalysisOptions::validate() const {
  if (strips < 4 || strips > 256) throw Error("strips (S) must be in [4, 256], got " + std::to_string(strips));
  if (kept < kSolidMaxCandidates || kept > strips * strips)
    throw Error("kept triples must be in [12, S^2], got " + std::to_string(kept));
  if (coherenceIterations < 0 || coherenceIterations > 8)
    throw Error("coherence iterations must be in [0, 8], got " + std::to_string(coherenceIterations));
  if (levels < 1 || levels > 8) throw Error("synthesized levels must be in [1, 8], got " + std::to_string(levels));
  if (candidates2d < 1 || candidates2d > 8)
    throw Error("2-D candidates must be in [1, 8], got " + std::to_string(candidates2d));
}

void validateSolidExemplars(const Image& ex, const Image& ey, const Image& ez, const std::array<std::string, 3>& names) {
  const Image* images[3] = {&ex, &ey, &ez};
  for (int e = 0; e < 3; ++e) {
    const Image& i = *images[e];
    const std::string size = std::to_string(i.width) + "x" + std::to_string(i.height);
    if (i.width < 8 || i.height < 8)
      throw Error(names[size_t(e)] + ": exemplar is " + size + ", smaller than the 8x8 solid synthesis needs");
    if (i.width > kMaxSolidExemplarSide || i.height > kMaxSolidExemplarSide)
      throw Error(names[size_t(e)] + ": exemplar is " + size + ", larger than the " +
                  std::to_string(kMaxSolidExemplarSide) + "x" + std::to_string(kMaxSolidExemplarSide) +
                  " solid synthesis accepts (its precomputation grows with the square of the pixels: about 15 min at "
                  "512x512); downsample it, e.g. oiiotool IN --resize 50% -o OUT");
  }
  for (int e = 1; e < 3; ++e)
    if (images[e]->width != ex.width || images[e]->height != ex.height)
      throw Error(names[size_t(e)] + ": exemplar is " + std::to_string(images[e]->width) + "x" +
                  std::to_string(images[e]->height) + " but " + names[0] + " is " + std::to_string(ex.width) + "x" +
                  std::to_string(ex.height) + " (the three exemplars must have the same size)");
}

double solidAnalysisCpuSeconds(int width, int height) {
  // 14.4 s of CPU at 128^2, 124 s at 256^2, 1590 s at 512^2: the strip searches, about n^1.7.
  const double n = double(width) * double(height) / (128.0 * 128.0);
  return 14.4 * std::pow(n, 1.7);
}

uint64_t solidAnalysisKey(const Image& ex, const Image& ey, const Image& ez, const SolidAnalysisOptions& o) {
  Fnv1a hash;
  hash.add(kSolidMagic);
  hash.add(kSolidVersion);
  for (const Image* i : {&ex, &ey, &ez}) {
    hash.add(i->width);
    hash.add(i->height);
    hash.add(i->channels);
    hash.add(i->pixels.data(), i->pixels.size() * sizeof(float));
  }
  hash.add(o.strips);
  hash.add(o.kept);
  hash.add(o.coherenceIterations);
  hash.add(o.levels);
  hash.add(o.candidates2d);
  hash.add(o.wrap);
  return hash.h;
}

namespace {

// Stack levels solid synthesis may use: all, or (Clamp) those whose valid region is one tap
// spacing inside the exemplar (spacing <= (side - 1) / 4, validRegion's bound).
int solidLevelLimit(int w, int h, ExemplarWrap wrap) {
  const int stackLevels = stackLevelCount(w, h);
  if (wrap == ExemplarWrap::Tile) return stackLevels;
  return std::min(stackLevels, int(std::bit_width(unsigned((std::min(w, h) - 1) / 4))));
}

// A level's 2-D k-coherence candidates, each moved into `valid` (reflectInto per axis), in place of
// pixel p's own when p lies outside it.
std::vector<uint32_t> candidatesIn(const AnalysisLevel& level2d, const ValidRegion& valid) {
  std::vector<uint32_t> out = level2d.candidates;
  for (uint32_t& c : out)
    c = packCoord(uint32_t(cpu::reflectInto(coordU(c), valid.x0, valid.x1)),
                  uint32_t(cpu::reflectInto(coordV(c), valid.y0, valid.y1)));
  return out;
}

// The level's 3-D candidates (crossbar triples, §4.1, through the coherence filter, §4.2), found
// per distinct exemplar relative to itself and stored with absolute axes for every exemplar that
// shares them (all three when shared); the finest level's figures go to `stats`. Foreign
// coordinates come from the level's valid region; a pixel outside it takes the set of its
// reflection into it.
void candidateTriples(SolidLevel& level, const std::array<Exemplar8, 3>& ex, bool shared,
                      const SolidAnalysisOptions& options, bool finest, SolidAnalysisStats& stats, const Context& ctx) {
  const int w = ex[0].w, h = ex[0].h, n = w * h, distinct = shared ? 1 : 3;
  auto src = [&](int e) { return shared ? 0 : e; };
  const std::vector<uint32_t> allowed = pixelsIn(level.valid, w);  // foreign coordinates
  std::vector<Strips> strips(static_cast<size_t>(distinct));
  for (int e = 0; e < distinct; ++e) strips[size_t(e)] = stripsOf(ex[size_t(e)], level.spacing);
  for (int e = 0; e < distinct; ++e) {
    const Strips& next = strips[size_t(src((e + 1) % 3))];
    const Strips& prev = strips[size_t(src((e + 2) % 3))];
    std::vector<std::vector<Triple>> sets = crossbarTriples(strips[size_t(e)], next, prev, n, allowed, options, ctx);
    if (finest) {
      double kept = 0, best = 0;
      for (const auto& s : sets) {
        kept += double(s.size());
        best += s.empty() ? 0.0 : double(s[0].cb);
      }
      stats.meanCandidatesBeforeFilter += kept / n / distinct;
      stats.meanBestCrossbarError += best / n / distinct;
    }
    coherenceFilter(sets, w, h, level.spacing, options.wrap, options.coherenceIterations, ctx);
    if (finest) {
      double kept = 0;
      for (const auto& s : sets) kept += double(s.size());
      stats.meanCandidatesAfterFilter += kept / n / distinct;
    }
    for (int target = 0; target < 3; ++target) {
      if (src(target) != e) continue;
      std::vector<uint32_t>& out = level.triples[size_t(target)];
      out.resize(size_t(n) * kSolidMaxCandidates * 3);
      auto pack = [&](uint32_t index) { return packCoord(index % uint32_t(w), index / uint32_t(w)); };
      for (int p = 0; p < n; ++p) {
        const uint32_t self = reflectPixel(uint32_t(p), w, level.valid);  // p, unless in the margin
        const auto& s = sets[self];
        for (int k = 0; k < kSolidMaxCandidates; ++k) {
          const Triple& t = s[size_t(k) < s.size() ? size_t(k) : 0];
          uint32_t* slot = &out[(size_t(p) * kSolidMaxCandidates + size_t(k)) * 3];
          slot[target] = pack(self);
          slot[(target + 1) % 3] = pack(t.q);
          slot[(target + 2) % 3] = pack(t.r);
        }
      }
    }
  }
}

// PCA of 2-D neighborhoods (all pixels of the distinct exemplars) and of 3-neighborhoods (the two
// best candidates of every pixel of every exemplar, at most 8192 samples), §6.2.
void fitProjections(SolidLevel& level, const std::array<Exemplar8, 3>& ex, bool shared) {
  const int w = ex[0].w, n = w * ex[0].h, distinct = shared ? 1 : 3;
  std::vector<int32_t> samples;
  for (int e = 0; e < distinct; ++e)
    for (int p = 0; p < n; ++p) {
      samples.resize(samples.size() + 75);
      exemplarNeighborhood2d(ex[size_t(e)], p % w, p / w, level.spacing, &samples[samples.size() - 75]);
    }
  level.projection2d = fitProjection(samples, 75, kSolid2dDims);
  samples.clear();
  const int64_t total = int64_t(n) * 3 * 2;
  const int64_t stride = std::max<int64_t>(1, total / 8192);
  for (int64_t i = 0; i < total; i += stride) {
    const int e = int(i / (int64_t(n) * 2)), p = int((i / 2) % n), k = int(i % 2);
    samples.resize(samples.size() + kSolidCrossVoxels * 3);
    candidateNeighborhood(ex, &level.triples[size_t(e)][(size_t(p) * kSolidMaxCandidates + size_t(k)) * 3], level.spacing,
                          &samples[samples.size() - kSolidCrossVoxels * 3]);
  }
  level.projection3d = fitProjection(samples, kSolidCrossVoxels * 3, level.dims);
}

// Every pixel's projected 2-D neighborhood and its candidates' projected 3-neighborhoods.
void projectNeighborhoods(SolidLevel& level, const std::array<Exemplar8, 3>& ex, const Context& ctx) {
  const int w = ex[0].w, n = w * ex[0].h;
  for (int e = 0; e < 3; ++e) {
    level.descriptors2d[size_t(e)].resize(size_t(n) * kSolid2dDims);
    level.descriptors3d[size_t(e)].resize(size_t(n) * kSolidMaxCandidates * size_t(level.dims));
  }
  parallelFor(0, n, ctx, [&](int begin, int end) {
    int32_t values[kSolidCrossVoxels * 3];
    for (int p = begin; p < end; ++p)
      for (int e = 0; e < 3; ++e) {
        exemplarNeighborhood2d(ex[size_t(e)], p % w, p / w, level.spacing, values);
        level.projection2d.project(values, &level.descriptors2d[size_t(e)][size_t(p) * kSolid2dDims]);
        for (int k = 0; k < kSolidMaxCandidates; ++k) {
          const size_t slot = size_t(p) * kSolidMaxCandidates + size_t(k);
          candidateNeighborhood(ex, &level.triples[size_t(e)][slot * 3], level.spacing, values);
          level.projection3d.project(values, &level.descriptors3d[size_t(e)][slot * size_t(level.dims)]);
        }
      }
  }, 64);
}

} // namespace

SolidAnalysis analyzeSolid(const Image& exIn, const Image& eyIn, const Image& ezIn, const SolidAnalysisOptions& options,
                           const Context& ctx) {
  const auto started = std::chrono::steady_clock::now();
  options.validate();
  validateSolidExemplars(exIn, eyIn, ezIn);
  const Image* inputs[3] = {&exIn, &eyIn, &ezIn};
  const bool shared = samePixels(exIn, eyIn) && samePixels(exIn, ezIn);
  const int w = exIn.width, h = exIn.height;
  reportEstimate(ctx, solidAnalysisCpuSeconds(w, h),
                 "the solid precomputation of a " + std::to_string(w) + "x" + std::to_string(h) + " exemplar");

  SolidAnalysis a;
  a.width = w;
  a.height = h;
  a.shared = shared;
  a.key = solidAnalysisKey(exIn, eyIn, ezIn, options);
  a.wrap = options.wrap;
  const int stackLevels = stackLevelCount(w, h);
  a.finestStackLevel = stackLevels - 1;
  const int levelCount = std::min(options.levels, solidLevelLimit(w, h, options.wrap));

  // Stacks and 2-D k-coherence candidates, once per distinct exemplar.
  const int distinct = shared ? 1 : 3;
  std::vector<std::vector<Image>> stacks(static_cast<size_t>(distinct));
  std::vector<ExemplarAnalysis> analyses2d(static_cast<size_t>(distinct));
  AnalysisOptions options2d;
  options2d.k = options.candidates2d;
  options2d.searchNeighbors = std::max(options2d.searchNeighbors, options.candidates2d);
  options2d.wrap = options.wrap;
  for (int e = 0; e < distinct; ++e) {
    Stage stage(ctx, distinct == 1 ? std::string("2-D analysis") : std::string("2-D analysis of E_") + "xyz"[e]);
    stacks[size_t(e)] = gaussianStack(*inputs[e], options.wrap);
    analyses2d[size_t(e)] = analyzeExemplar(*inputs[e], options2d, stage.inner());
    stage.finish();
  }
  auto src = [&](int e) { return shared ? 0 : e; };

  a.levels.resize(size_t(levelCount));
  for (int li = 0; li < levelCount; ++li) {
    Stage stage(ctx, "3-D candidates, level " + std::to_string(li + 1) + "/" + std::to_string(levelCount));
    SolidLevel& level = a.levels[size_t(li)];
    const int sl = a.finestStackLevel - (levelCount - 1 - li);
    const bool finest = li == levelCount - 1;
    level.stackLevel = sl;
    level.spacing = 1 << (a.finestStackLevel - sl);
    level.valid = validRegion(w, h, level.spacing, options.wrap);
    level.dims = finest ? 8 : kSolidMaxDims;
    level.k2d = finest ? std::min(2, options.candidates2d) : options.candidates2d;
    level.k3d = finest ? 4 : kSolidMaxCandidates;
    std::vector<std::vector<uint8_t>> colors(static_cast<size_t>(distinct));
    for (int e = 0; e < distinct; ++e) colors[size_t(e)] = levelColors(stacks[size_t(e)][size_t(sl)]);
    std::array<Exemplar8, 3> ex;
    for (int e = 0; e < 3; ++e) {
      ex[size_t(e)] = {w, h, colors[size_t(src(e))].data(), options.wrap};
      level.colors[size_t(e)] = colors[size_t(src(e))];
      level.candidates2d[size_t(e)] = candidatesIn(analyses2d[size_t(src(e))].levels[size_t(sl)], level.valid);
    }

    candidateTriples(level, ex, shared, options, finest, a.stats, stage.inner());
    stage.advance(0.8);
    fitProjections(level, ex, shared);
    projectNeighborhoods(level, ex, stage.inner());
    deriveTables(level, w);
    stage.finish();
  }
  a.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return a;
}

// ---- the on-disk cache ----

namespace {

using Writer = BinaryWriter;
using Reader = BinaryReader;

void writeProjection(Writer& w, const SolidProjection& p) {
  w.value(p.inputs);
  w.value(p.dims);
  w.value(p.divisor);
  w.vec(p.mean);
  w.vec(p.basis);
}

void readProjection(Reader& r, SolidProjection& p, int inputs, int dims) {
  r.value(p.inputs);
  r.value(p.dims);
  r.value(p.divisor);
  if (p.inputs != inputs || p.dims != dims || p.divisor < 1 || !std::has_single_bit(uint32_t(p.divisor))) r.ok = false;
  r.vec(p.mean, size_t(inputs));
  r.vec(p.basis, size_t(inputs) * size_t(dims));
}

} // namespace

void writeSolidAnalysis(const SolidAnalysis& a, const fs::path& path) {
  writeFileAtomically(path, [&](std::ostream& out) {
    Writer w{out};
    w.value(kSolidMagic);
    w.value(kSolidVersion);
    w.value(a.key);
    w.value(a.width);
    w.value(a.height);
    w.value(uint8_t(a.shared));
    w.value(a.wrap);
    w.value(a.finestStackLevel);
    w.value(int32_t(a.levels.size()));
    w.value(a.stats);
    for (const SolidLevel& l : a.levels) {
      w.value(l.stackLevel);
      w.value(l.spacing);
      w.value(l.dims);
      w.value(l.k2d);
      w.value(l.k3d);
      for (int e = 0; e < 3; ++e) {
        w.vec(l.colors[size_t(e)]);
        w.vec(l.candidates2d[size_t(e)]);
        w.vec(l.descriptors2d[size_t(e)]);
        w.vec(l.triples[size_t(e)]);
        w.vec(l.descriptors3d[size_t(e)]);
      }
      writeProjection(w, l.projection2d);
      writeProjection(w, l.projection3d);
    }
  });
}

std::optional<SolidAnalysis> readSolidAnalysis(const fs::path& path, uint64_t expectedKey) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  Reader r{in};
  uint32_t magic = 0, version = 0;
  SolidAnalysis a;
  uint8_t shared = 0;
  int32_t count = 0;
  r.value(magic);
  r.value(version);
  r.value(a.key);
  r.value(a.width);
  r.value(a.height);
  r.value(shared);
  r.value(a.wrap);
  r.value(a.finestStackLevel);
  r.value(count);
  r.value(a.stats);
  if (!r.ok || magic != kSolidMagic || version != kSolidVersion || a.key != expectedKey) return std::nullopt;
  if (a.width < 8 || a.height < 8 || a.width > kMaxSolidExemplarSide || a.height > kMaxSolidExemplarSide ||
      (a.wrap != ExemplarWrap::Tile && a.wrap != ExemplarWrap::Clamp) ||
      a.finestStackLevel != stackLevelCount(a.width, a.height) - 1 || count < 1 ||
      count > solidLevelLimit(a.width, a.height, a.wrap))
    return std::nullopt;
  a.shared = shared != 0;
  const size_t n = size_t(a.width) * size_t(a.height);
  a.levels.resize(size_t(count));
  for (int li = 0; li < count && r.ok; ++li) {
    SolidLevel& l = a.levels[size_t(li)];
    r.value(l.stackLevel);
    r.value(l.spacing);
    r.value(l.dims);
    r.value(l.k2d);
    r.value(l.k3d);
    if (l.stackLevel != a.finestStackLevel - (count - 1 - li) || l.spacing != 1 << (a.finestStackLevel - l.stackLevel) ||
        l.dims < 1 || l.dims > kSolidMaxDims || l.k2d < 1 || l.k2d > 8 || l.k3d < 1 || l.k3d > kSolidMaxCandidates)
      return std::nullopt;
    l.valid = validRegion(a.width, a.height, l.spacing, a.wrap);
    for (int e = 0; e < 3; ++e) {
      r.vec(l.colors[size_t(e)], n * 3);
      uint64_t k2 = 0;
      {
        // the 2-D candidate count is options.candidates2d; read its length first
        const auto pos = in.tellg();
        r.value(k2);
        in.seekg(pos);
      }
      if (k2 == 0 || k2 % n != 0 || k2 / n < size_t(l.k2d) || k2 / n > 8) return std::nullopt;
      r.vec(l.candidates2d[size_t(e)], size_t(k2));
      r.vec(l.descriptors2d[size_t(e)], n * kSolid2dDims);
      r.vec(l.triples[size_t(e)], n * kSolidMaxCandidates * 3);
      r.vec(l.descriptors3d[size_t(e)], n * kSolidMaxCandidates * size_t(l.dims));
      if (!r.ok) return std::nullopt;
      for (uint32_t c : l.candidates2d[size_t(e)])
        if (coordU(c) >= uint32_t(a.width) || coordV(c) >= uint32_t(a.height)) return std::nullopt;
      for (uint32_t c : l.triples[size_t(e)])
        if (coordU(c) >= uint32_t(a.width) || coordV(c) >= uint32_t(a.height)) return std::nullopt;
    }
    readProjection(r, l.projection2d, 75, kSolid2dDims);
    readProjection(r, l.projection3d, kSolidCrossVoxels * 3, l.dims);
    if (r.ok) deriveTables(l, a.width);
  }
  if (!r.ok || in.peek() != std::char_traits<char>::eof()) return std::nullopt;
  return a;
}

SolidAnalysis analyzeSolidCached(const Image& ex, const Image& ey, const Image& ez, const SolidAnalysisOptions& options,
                                 const fs::path& cacheDir, const Context& ctx, bool* fromCache) {
  options.validate();
  validateSolidExemplars(ex, ey, ez);
  return loadOrCompute(
      cacheDir, solidAnalysisKey(ex, ey, ez, options), ".solid", readSolidAnalysis,
      [&] { return analyzeSolid(ex, ey, ez, options, ctx); }, writeSolidAnalysis, fromCache, ctx);
}

} // namespace texfab::synthesis
