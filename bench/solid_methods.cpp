// SPDX-License-Identifier: GPL-3.0-or-later
// The two solid texture methods side by side (issue 33): lazy synthesis (Dong et al. 2008) and the
// tile set (solid_tiles.h). For each exemplar (cropped to SIDE^2, default 128), prints per method
// the slices' 7x7 fidelity and completeness relative to the 2-D synthesis of the same exemplar,
// each measured as a ratio to a shuffled-pixel image's, contrast, histogram distance over the 2-D
// synthesis', the shifted-self correlation at the tile period, the seam ratio and peak step
// (latticeSteps; the largest over the axis-aligned slices), and timings: the tile set's
// precomputation, a 256^2 cut and a 128^3 box (2 threads, best of REPEAT).
//   build/bench/solid_methods /usr/share/gimp/2.0/patterns/Stone/terra.pat ...
// An argument truth:KIND (tests/synthesis/procedural_solids.h: clouds, marble, spots, granite,
// wood, sand) takes a 128^2 slice of that procedural solid as the exemplar and adds a row for the
// solid's own slices: what a perfect solid synthesis from that exemplar could show.
// Environment: SIDE, N (plane side, 256), TILE, VARIANTS, COPIES, ITER, FITER, HIST (SolidTileOptions), LAZY=0
// (tiles only), TILES=0 (lazy only), TRIPLANAR=k (colours weighted by the plane's normal, an
// experiment), SAVE=dir (writes each method's slices as PNG), THREADS, REPEAT, QUICK=1 (the tile
// set's seam ratio and peak step only; with PROFILE=1 also the mean step and the mean colour at
// every offset within the period, in 8-bit units, and the exemplar's).
#include "core/image_io.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/quality_measures.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/solid_tile_measures.h"
#include "synthesis/solid_tiles.h"
#include "synthesis/synthesize_solid.h"
#include "tests/synthesis/procedural_solids.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

using namespace texfab;
using namespace texfab::synthesis;

namespace {

double env(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v ? std::atof(v) : fallback;
}

double seconds(const std::function<void()>& f, int repeat) {
  double best = 1e30;
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

Image crop(const Image& full, int side) {
  const int w = std::min(side, full.width), h = std::min(side, full.height);
  Image out(w, h, full.channels >= 3 ? 3 : 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < out.channels; ++c) out.at(x, y, c) = full.at(x, y, c);
  return out;
}

Image shuffled(const Image& ex, int n) {
  Image out(n, n, ex.channels);
  uint32_t s = 12345;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      s = s * 1664525u + 1013904223u;
      const uint32_t p = (s >> 8) % uint32_t(ex.width * ex.height);
      for (int c = 0; c < ex.channels; ++c) out.at(x, y, c) = ex.pixels[size_t(p) * size_t(ex.channels) + size_t(c)];
    }
  return out;
}

struct Plane {
  std::string name;
  std::vector<Voxel> voxels;
  std::array<double, 3> normal{0, 0, 1};
};

Plane axisPlane(int axis, int64_t k, int n) {
  Plane p{std::string(1, "xyz"[axis]), {}, {}};
  p.name += std::to_string(k);  // (one string built in place: GCC 12 warns falsely on a + of two)
  p.normal[size_t(axis)] = 1;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int64_t a = 1000 + i, b = 2000 + j;
      p.voxels.push_back(axis == 0 ? Voxel{k, a, b} : axis == 1 ? Voxel{b, k, a} : Voxel{a, b, k});
    }
  return p;
}

Plane obliquePlane(int n) {  // normal (1, 2, 3), unit steps
  const double l = std::sqrt(14.0), N[3] = {1 / l, 2 / l, 3 / l};
  const double lu = std::hypot(N[1], N[0]), U[3] = {N[1] / lu, -N[0] / lu, 0};
  const double V[3] = {N[1] * U[2] - N[2] * U[1], N[2] * U[0] - N[0] * U[2], N[0] * U[1] - N[1] * U[0]};
  Plane p{"oblique", {}, {N[0], N[1], N[2]}};
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int64_t q[3];
      for (int a = 0; a < 3; ++a) q[a] = int64_t(std::floor(537 + (i + 0.5) * U[a] + (j + 0.5) * V[a]));
      p.voxels.push_back({q[0], q[1], q[2]});
    }
  return p;
}

// The slice's colours: the mean of the three exemplar colours (solidColors), or with TRIPLANAR=k
// (an experiment) E_e's colour weighted by |n_e|^k for the plane's normal n.
Image image(const std::vector<Triple>& triples, const Image& ex, int n, const std::array<double, 3>& normal) {
  const int ch = solidColorChannels(ex, ex, ex);
  Image out(n, n, ch);
  const double k = env("TRIPLANAR", 0);
  if (k <= 0) {
    std::vector<float> colors;
    solidColors(triples, ex, ex, ex, colors);
    out.pixels = std::move(colors);
    return out;
  }
  double w[3], sum = 0;
  for (int e = 0; e < 3; ++e) sum += w[e] = std::pow(std::fabs(normal[size_t(e)]), k);
  const Image view = solidColorView(ex, ch);
  for (size_t i = 0; i < triples.size(); ++i)
    for (int c = 0; c < ch; ++c) {
      double v = 0;
      for (int e = 0; e < 3; ++e)
        v += w[e] / sum * view.at(int(coordU(triples[i][size_t(e)])), int(coordV(triples[i][size_t(e)])), c);
      out.pixels[i * size_t(ch) + size_t(c)] = float(v);
    }
  return out;
}

// KIND of an argument truth:KIND.
std::optional<std::string> truthKind(const std::string& arg) {
  if (arg.rfind("truth:", 0) != 0) return std::nullopt;
  return arg.substr(6);
}

Image truthSlice(const test::ProceduralSolid& solid, const std::vector<Voxel>& voxels, int n) {
  Image out(n, n, 3);
  for (size_t i = 0; i < voxels.size(); ++i) {
    const auto c = solid.color(voxels[i][0], voxels[i][1], voxels[i][2]);
    for (size_t k = 0; k < 3; ++k) out.pixels[i * 3 + k] = c[k];
  }
  return out;
}

// The steps across the lattice (latticeSteps) on an axis-aligned plane whose in-plane voxel
// coordinates are 1000 + i and 2000 + j (axisPlane).
LatticeSteps planeSteps(const Image& im, int period) { return latticeSteps(im, period, 1000, 2000); }

// The mean colour at each offset within the period along such a plane's first axis, in 8-bit units.
std::vector<double> colorProfile(const Image& im, int period) {
  std::vector<double> sum(size_t(period), 0.0), count(size_t(period), 0.0);
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      for (int c = 0; c < im.channels; ++c) {
        const size_t k = size_t((1000 + x) % period);
        sum[k] += im.at(x, y, c);
        count[k] += 1;
      }
  for (size_t k = 0; k < sum.size(); ++k) sum[k] = 255.0 * sum[k] / count[k];
  return sum;
}

struct Measures {
  double fidelity = 0, completeness = 0, contrast = 0, histogram = 0, lattice = 0, seam = 0, peak = 0;
  // Seam ratio and peak step: the largest over the axis-aligned planes.
  void addSteps(const LatticeSteps& p) {
    seam = std::max(seam, p.seamRatio());
    peak = std::max(peak, p.peak());
  }
};

// SAVE=dir: one PNG per exemplar, method and plane.
void saveImage(const char* dir, const Image& im, const std::string& name, const std::string& method, const Plane& p) {
  if (dir)
    writeImage(im, std::filesystem::path(dir) /
                       (name.substr(name.find(':') + 1) + "-" + method + "-" + p.name + ".png"));
}

// BLEND=2: the tile set's mean colour at each position in the cell (side^3 positions, channels
// interleaved), over a box of 4^3 cells read with seed 1.
std::vector<double> cellMeans(const SolidTileSet& tiles, const Image& ex, const Context& ctx) {
  const int side = tiles.layout.side, b = 4 * side, ch = solidColorChannels(ex, ex, ex);
  std::vector<Triple> box(size_t(b) * b * b);
  evaluateSolidTilesBox(tiles, 1, VoxelBox{0, 0, 0, b, b, b}, box, ctx);
  std::vector<float> colors;
  solidColors(box, ex, ex, ex, colors);
  std::vector<double> means(size_t(side) * side * side * size_t(ch), 0.0);
  for (size_t v = 0; v < box.size(); ++v) {
    const size_t x = v % size_t(b), y = v / size_t(b) % size_t(b), z = v / size_t(b * b);
    const size_t cell = ((z % size_t(side)) * size_t(side) + y % size_t(side)) * size_t(side) + x % size_t(side);
    for (int c = 0; c < ch; ++c) means[cell * size_t(ch) + size_t(c)] += colors[v * size_t(ch) + size_t(c)] / 64.0;
  }
  return means;
}

// BLEND=1 or 2 (an experiment; docs/measurements.md): the plane read from 8 arrangements of the tile
// set (seeds 1-8), each shifted by half a tile along some of the axes, and blended as Heitz and
// Neyret 2018 blend their tiles: each weighted by the product over the axes of a hat that is 0 on
// its faces and 1 in its cells' middles (the weights sum to 1), variance-preserving around the mean
// colour of the 8 readings (1: `means` empty) or each reading's expected colour at its position in
// the cell (2: `means` from cellMeans). Colours, not triples: what evaluation would have to return.
Image blendedSlice(const SolidTileSet& tiles, const Image& ex, const Plane& plane, int n,
                   const std::vector<double>& means, const Context& ctx) {
  const int side = tiles.layout.side;
  const size_t count = plane.voxels.size();
  std::vector<Image> parts;
  std::vector<std::vector<double>> weights;
  std::vector<std::vector<size_t>> cells;  // each reading's position in its cell
  for (int bits = 0; bits < 8; ++bits) {
    std::vector<Voxel> shifted = plane.voxels;
    std::vector<double> w(count, 1.0);
    std::vector<size_t> cell(count, 0);
    for (size_t i = 0; i < count; ++i)
      for (int a = 2; a >= 0; --a) {
        int64_t& q = shifted[i][size_t(a)];
        q += ((bits >> a) & 1) * (side / 2);
        const int64_t offset = (q % side + side) % side;
        w[i] *= 1 - std::fabs(2 * (double(offset) + 0.5) / side - 1);
        cell[i] = cell[i] * size_t(side) + size_t(offset);
      }
    std::vector<Triple> triples(count);
    evaluateSolidTiles(tiles, uint32_t(1 + bits), shifted, triples, ctx);
    parts.push_back(image(triples, ex, n, plane.normal));
    weights.push_back(std::move(w));
    cells.push_back(std::move(cell));
  }
  const int ch = parts[0].channels;
  std::vector<double> mean(size_t(ch), 0.0);
  for (const Image& p : parts)
    for (size_t i = 0; i < p.pixels.size(); ++i) mean[i % size_t(ch)] += p.pixels[i] / double(8 * count);
  Image out = parts[0];
  for (size_t i = 0; i < count; ++i) {
    double norm = 0;
    for (const auto& w : weights) norm += w[i] * w[i];
    for (int c = 0; c < ch; ++c) {
      double v = 0;
      for (size_t p = 0; p < parts.size(); ++p) {
        const double expected = means.empty() ? mean[size_t(c)] : means[cells[p][i] * size_t(ch) + size_t(c)];
        v += weights[p][i] * (parts[p].pixels[i * size_t(ch) + size_t(c)] - expected);
      }
      out.pixels[i * size_t(ch) + size_t(c)] = float(std::clamp(mean[size_t(c)] + v / std::sqrt(norm), 0.0, 1.0));
    }
  }
  return out;
}

// QUICK=1: the tile set's seam ratio and peak step on the axis-aligned planes (the first three);
// PROFILE=1 adds the mean step and colour by offset, and the exemplar colour that the tile set's
// shared elements (faces, edges, corners) and its interiors point at.
void printTileSeams(const std::string& name, const Image& ex, const SolidAnalysis& a, const SolidTileOptions& to,
                    const std::vector<Plane>& planes, int n, const char* save, const Context& ctx) {
  const bool printProfile = env("PROFILE", 0) != 0;
  const int blend = int(env("BLEND", 0));
  const SolidTileSet tiles = buildSolidTiles(a, to, ctx);
  const std::vector<double> means = blend == 2 ? cellMeans(tiles, ex, ctx) : std::vector<double>{};
  Measures m;
  for (size_t k = 0; k < 3; ++k) {
    Image im;
    if (blend != 0) {
      im = blendedSlice(tiles, ex, planes[k], n, means, ctx);
    } else {
      std::vector<Triple> out(planes[k].voxels.size());
      evaluateSolidTiles(tiles, 1, planes[k].voxels, out, ctx);
      im = image(out, ex, n, planes[k].normal);
    }
    saveImage(save, im, name, blend != 0 ? "blend" : "tiles", planes[k]);
    const LatticeSteps steps = planeSteps(im, to.tileSide);
    m.addSteps(steps);
    if (!printProfile) continue;
    std::printf("plane %zu step by offset:", k);
    for (double step : steps.meanStep) std::printf(" %.1f", 255.0 * step);
    std::printf("\nplane %zu mean colour by offset:", k);
    for (double color : colorProfile(im, to.tileSide)) std::printf(" %.0f", color);
    std::printf("\n");
  }
  if (printProfile) {
    double sums[2] = {0, 0}, counts[2] = {0, 0};  // shared elements, interiors
    for (size_t el = 0; el < tiles.elements.size(); ++el) {
      const int k = el < tiles.layout.interiors ? 0 : 1;
      for (uint32_t c : tiles.elements[el])
        for (int ch = 0; ch < 3; ++ch) sums[k] += ex.at(int(coordU(c)), int(coordV(c)), ch), counts[k] += 1;
    }
    std::printf("mean exemplar colour at shared elements %.0f, at interiors %.0f\n", 255.0 * sums[0] / counts[0],
                255.0 * sums[1] / counts[1]);
    const LatticeSteps own = latticeSteps(ex, 3, 0, 0);
    std::printf("exemplar mean step %.1f, mean colour %.0f\n",
                255.0 * (own.meanStep[0] + own.meanStep[1] + own.meanStep[2]) / 3, colorProfile(ex, 1)[0]);
  }
  const SolidTileLattice jobs = measureSolidTileLattice(tiles, ex, ex, ex, ctx);  // what the jobs report
  std::printf("%-14s %-6s seam %.3f, peak step %.3f, precomputation %.1f s; the jobs' measure: seam %.3f, peak "
              "step %.3f, lattice %.3f\n",
              name.c_str(), blend != 0 ? "blend" : "tiles", m.seam, m.peak, tiles.seconds, jobs.seamRatio,
              jobs.peakStep, jobs.correlation);
  std::fflush(stdout);
}

} // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: solid_methods EXEMPLAR...\n");
    return 2;
  }
  const int side = int(env("SIDE", 128)), n = int(env("N", 256)), repeat = int(env("REPEAT", 3));
  const Context ctx{.threads = int(env("THREADS", 2))};
  SolidTileOptions to;
  to.tileSide = int(env("TILE", to.tileSide));
  to.faceVariants = int(env("VARIANTS", to.faceVariants));
  to.arrangementCopies = int(env("COPIES", to.arrangementCopies));
  to.iterations = int(env("ITER", to.iterations));
  to.finestIterations = int(env("FITER", to.finestIterations));
  to.histogramWeight = float(env("HIST", to.histogramWeight));
  const bool lazy = env("LAZY", 1) != 0, tilesToo = env("TILES", 1) != 0;
  const char* save = std::getenv("SAVE");
  const FidelityOptions fo{};

  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (truthKind(arg) && !test::ProceduralSolid(*truthKind(arg)).valid()) {
      std::fprintf(stderr, "solid_methods: unknown procedural solid '%s'\n", arg.c_str());
      return 2;
    }
  }
  std::printf("%-14s %-6s %8s %8s %8s %8s %8s %8s %8s %8s %9s %9s %9s\n", "exemplar", "method", "fid/2d", "comp/2d",
              "contrast", "hist/2d", "lattice", "seam", "peak", "faceLat", "precomp_s", "cut256_ms", "box128_ms");
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const test::ProceduralSolid truth(truthKind(arg).value_or(""));
    const std::string name = truth.valid() ? arg : std::filesystem::path(arg).stem().string();
    const Image ex = truth.valid() ? truth.exemplar(side) : crop(readImage(arg), side);
    SolidAnalysisOptions ao;
    ao.wrap = detectExemplarWrap(ex);
    const SolidAnalysis a = analyzeSolid(ex, ex, ex, ao, ctx);
    const std::vector<Plane> planes{axisPlane(2, 45, n), axisPlane(0, 77, n), axisPlane(1, 301, n),
                                    obliquePlane(n)};
    if (env("QUICK", 0) != 0) {
      printTileSeams(name, ex, a, to, planes, n, save, ctx);
      continue;
    }
    AnalysisOptions o2;
    o2.wrap = ao.wrap;
    const ExemplarAnalysis a2 = analyzeExemplar(ex, o2, ctx);
    const QualityReport base = measureSynthesisBaseline(a2, ex, n, n, fo, ctx);
    const Image shuf = shuffled(ex, n);
    const double shufFid = neighborhoodFidelity(shuf, ex, fo, ctx);
    const double shufComp = neighborhoodCompleteness(shuf, ex, fo, ctx);
    const double baseFid = base.fidelity / shufFid, baseComp = base.completeness / shufComp;
    std::printf("%-14s %-6s %8.3f %8.3f %8.3f %8.4f\n", name.c_str(), "2d", baseFid, baseComp, base.contrast,
                base.histogramDistance);

    auto measureImages = [&](const std::function<Image(const Plane&)>& view, const std::string& method, int period) {
      Measures m;
      for (const Plane& p : planes) {
        const Image im = view(p);
        saveImage(save, im, name, method, p);
        m.fidelity += neighborhoodFidelity(im, ex, fo, ctx) / shufFid / baseFid / double(planes.size());
        m.completeness += neighborhoodCompleteness(im, ex, fo, ctx) / shufComp / baseComp / double(planes.size());
        m.contrast += contrastRatio(im, ex) / double(planes.size());
        m.histogram += histogramDistance(im, ex) / base.histogramDistance / double(planes.size());
        m.lattice = std::max(m.lattice, latticeCorrelation(im, period));
        if (p.name == "oblique") continue;
        m.addSteps(planeSteps(im, period));
      }
      return m;
    };
    auto measure = [&](const std::function<std::vector<Triple>(const Plane&)>& slice, const std::string& method,
                       int period) {
      return measureImages([&](const Plane& p) { return image(slice(p), ex, n, p.normal); }, method, period);
    };
    auto row = [&](const char* method, const Measures& m, double face, double pre, double cut, double box) {
      std::printf("%-14s %-6s %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %9.2f %9.3f %9.2f\n", name.c_str(),
                  method, m.fidelity, m.completeness, m.contrast, m.histogram, m.lattice, m.seam, m.peak, face, pre,
                  cut * 1e3, box * 1e3);
      std::fflush(stdout);
    };

    const int period = to.tileSide;
    if (truth.valid())
      row("truth", measureImages([&](const Plane& p) { return truthSlice(truth, p.voxels, n); }, "truth", period), 0,
          0, 0, 0);
    const Plane cut = axisPlane(2, 40, n);
    const VoxelBox box{0, 0, 0, 128, 128, 128};
    if (lazy) {
      const SolidSynthesisOptions so;
      auto slice = [&](const Plane& p) { return synthesizeSolid(a, p.voxels, so, nullptr, ctx).triples; };
      const Measures m = measure(slice, "lazy", period);
      const double tCut = seconds([&] { synthesizeSolid(a, cut.voxels, so, nullptr, ctx); }, repeat);
      const double tBox = seconds([&] { synthesizeSolidBox(a, box, so, nullptr, ctx); }, 1);
      row("lazy", m, 0, a.stats.seconds, tCut, tBox);
    }
    if (!tilesToo) continue;
    SolidTileSet tiles;
    const double pre = seconds([&] { tiles = buildSolidTiles(a, to, ctx); }, 1);
    auto slice = [&](const Plane& p) {
      std::vector<Triple> out(p.voxels.size());
      evaluateSolidTiles(tiles, 1, p.voxels, out, ctx);
      return out;
    };
    const Measures m = measure(slice, "tiles", period);
    const Plane facePlane = axisPlane(2, 4 * period, n);  // a slice on a face plane of the lattice
    const double face = latticeCorrelation(image(slice(facePlane), ex, n, facePlane.normal), period);
    std::vector<Triple> out(size_t(box.count()));
    const double tCut = seconds([&] { slice(cut); }, repeat * 10);
    const double tBox = seconds([&] { evaluateSolidTilesBox(tiles, 1, box, out, ctx); }, repeat);
    row("tiles", m, face, pre, tCut, tBox);
    if (const int blend = int(env("BLEND", 0)); blend != 0) {
      const std::vector<double> means = blend == 2 ? cellMeans(tiles, ex, ctx) : std::vector<double>{};
      const auto view = [&](const Plane& p) { return blendedSlice(tiles, ex, p, n, means, ctx); };
      row("blend", measureImages(view, "blend", period), 0, pre, 0, 0);
    }
  }
  return 0;
}
