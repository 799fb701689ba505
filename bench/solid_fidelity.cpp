// SPDX-License-Identifier: GPL-3.0-or-later
// Solid texture fidelity, measured on slices (not a benchmark: no timing). For each exemplar given
// (a 64^2 crop by default), synthesizes axis-aligned and oblique planes of a lazy solid texture and
// colours their triples by several rules, then prints per rule: luminance contrast ratio (standard
// deviation of luminance, slice / exemplar), 7x7 neighbourhood fidelity relative to the 2-D
// synthesis of the same exemplar, the same on both halved (5x5 neighbourhoods: structure at twice
// the scale, "coarse"), 7x7 completeness relative to the 2-D synthesis', histogram distance, and
// the shifted-self correlation of 256^2 planes at the exemplar's period. The 2-D synthesis and a
// random-pixel image are the baselines; a flat and a blurred image ("~flat", "~blurred") give scale.
//   build/bench/solid_fidelity models/exemplars/marble.png /usr/share/gimp/2.0/patterns/Stone/rock.pat
// Environment: SIDE (crop), N (plane side), BIG (repetition plane side), JITTER, OFFSET, PASSES, FINEST,
// INTERLEAVE, MATCH (matchColors 0/1), GAIN (contrastGain), REFINE (refinePasses), STRIPS, KEPT, COHIT, LEVELS, K2D (analysis and
// synthesis options), FK3D, FK2D, CK3D (candidates kept at the finest / coarser levels), CALBOX (calibration box side), DUMP=dir
// (writes the exemplars as PNG and stops),
// WRAP=clamp (non-toroidal analyses, 2-D and solid, and fidelity measured without wrap),
// RULES=mean,cal (only these rules), SAVE=1 (writes the images to /tmp/solidfid-*.png),
// HISTPEN=lambda with HPITERS, HPBINS, HPBOX, HPALPHA, HPALL (see applyHistogramPenalty).
#include "core/downsample.h"
#include "core/hash.h"
#include "core/image_io.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/quality_measures.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/synthesize_2d.h"
#include "synthesis/synthesize_solid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>
#include <vector>

using namespace texfab;
using namespace texfab::synthesis;

namespace {

const Context kCtx{.threads = 2};

Image crop(const Image& full, int side) {
  Image out(side, side, full.channels >= 3 ? 3 : 1);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      for (int c = 0; c < out.channels; ++c) out.at(x, y, c) = full.at(x, y, c);
  return out;
}

double lumStd(const Image& im) {
  double s = 0, ss = 0;
  const double n = double(im.width) * im.height;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const float* p = im.pixel(x, y);
      const double l = im.channels >= 3 ? 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2] : p[0];
      s += l;
      ss += l * l;
    }
  return std::sqrt(std::max(0.0, ss / n - (s / n) * (s / n)));
}

double env(const char* name, double def) {
  const char* v = std::getenv(name);
  return v ? std::atof(v) : def;
}

using Rule = std::function<void(const Triple&, float*)>;

struct Plane {
  std::string name;
  std::vector<Voxel> voxels;
  int w, h;
};

Plane axisPlane(int axis, int64_t k, int n, int64_t off) {
  Plane p{std::string(1, "xyz"[axis]), {}, n, n};
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int64_t x = axis == 0 ? k : i + off, y = axis == 1 ? k : axis == 0 ? i + off : j + off, z = axis == 2 ? k : j + off;
      p.voxels.push_back({x, y, z});
    }
  return p;
}

Plane obliquePlane(int n, int64_t off) {
  // Orthonormal basis of a plane with normal (1, 2, 3)/|..|, unit steps.
  const double nx = 1, ny = 2, nz = 3, l = std::sqrt(nx * nx + ny * ny + nz * nz);
  const double N[3] = {nx / l, ny / l, nz / l};
  double U[3] = {N[1], -N[0], 0};
  const double lu = std::sqrt(U[0] * U[0] + U[1] * U[1]);
  for (double& v : U) v /= lu;
  const double V[3] = {N[1] * U[2] - N[2] * U[1], N[2] * U[0] - N[0] * U[2], N[0] * U[1] - N[1] * U[0]};
  Plane p{"oblique", {}, n, n};
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double q[3];
      for (int a = 0; a < 3; ++a) q[a] = off + 37 + (i + 0.5) * U[a] + (j + 0.5) * V[a];
      p.voxels.push_back({int64_t(std::floor(q[0])), int64_t(std::floor(q[1])), int64_t(std::floor(q[2]))});
    }
  return p;
}

// Experiment (HISTPEN=lambda): Kopf et al. 2007's histogram weights frozen at precomputation. A
// calibration box is synthesized HPITERS times (HPBOX^3 voxels); after each, per channel and
// HPBINS bins, log w(bin) += HPALPHA * log(used / exemplar frequency), and each 3-D candidate's
// descriptor gains one dimension sqrt(lambda * sum over its 3 colours and channels of
// (log w - min log w)), against which targets project to 0 (a zero projection row): the search
// then adds that penalty to the SSD. The finest level only, or every level (HPALL=1), with the
// finest colours. Figures: docs/measurements.md#slice-contrast-and-a-histogram-penalty.
void applyHistogramPenalty(SolidAnalysis& a, const Image& e, const SolidSynthesisOptions& so, double lambda) {
  const int bins = int(env("HPBINS", 16)), iters = int(env("HPITERS", 2)), side = int(env("HPBOX", 32));
  const double alpha = env("HPALPHA", 1.0);
  const bool allLevels = env("HPALL", 0) > 0;
  auto bin = [&](uint32_t c, int ch) {
    const float v = e.at(int(coordU(c)), int(coordV(c)), std::min(ch, e.channels - 1));
    return size_t(ch * bins + int(std::lrint(v * 255)) * bins / 256);
  };
  std::vector<double> exemplar(size_t(3 * bins), 0), logw(size_t(3 * bins), 0);
  for (int y = 0; y < e.height; ++y)
    for (int x = 0; x < e.width; ++x)
      for (int ch = 0; ch < 3; ++ch) exemplar[bin(packCoord(uint32_t(x), uint32_t(y)), ch)] += 1;
  const std::vector<SolidLevel> original = a.levels;
  for (int it = 0; it < iters; ++it) {
    const SolidSynthesisResult cal =
        synthesizeSolidBox(a, {-5000 - it * 999, 7000, 3000, side, side, side}, so, nullptr, kCtx);
    std::vector<double> used(size_t(3 * bins), 0);
    for (const Triple& t : cal.triples)
      for (int q = 0; q < 3; ++q)
        for (int ch = 0; ch < 3; ++ch) used[bin(t[size_t(q)], ch)] += 1;
    const double nu = double(cal.triples.size()) * 3, ne = double(e.width) * e.height;
    double difference = 0;
    for (size_t b = 0; b < used.size(); ++b) {
      const double pu = used[b] / nu, pe = exemplar[b] / ne;
      difference += std::abs(pu - pe) / 6;
      if (pe > 0) logw[b] += alpha * std::log(std::max(pu, 1e-4) / pe);
    }
    std::printf("  histogram penalty, calibration %d: L1 histogram difference %.3f\n", it, difference);
    const double lowest = *std::min_element(logw.begin(), logw.end());
    for (size_t li = 0; li < a.levels.size(); ++li) {
      if (!allLevels && li + 1 != a.levels.size()) continue;
      SolidLevel& level = a.levels[li];
      const SolidLevel& o = original[li];
      const int d0 = o.dims, d1 = d0 + 1;
      level.dims = d1;
      level.projection3d = o.projection3d;
      level.projection3d.dims = d1;
      level.projection3d.basis.resize(size_t(d1 * o.projection3d.inputs), 0);
      for (size_t ex = 0; ex < 3; ++ex) {
        const size_t n = o.triples[ex].size() / 3;
        auto& out = level.descriptors3d[ex];
        out.assign(n * size_t(d1), 0);
        for (size_t i = 0; i < n; ++i) {
          std::copy_n(&o.descriptors3d[ex][i * size_t(d0)], d0, &out[i * size_t(d1)]);
          double penalty = 0;
          for (int q = 0; q < 3; ++q)
            for (int ch = 0; ch < 3; ++ch) penalty += logw[bin(o.triples[ex][i * 3 + size_t(q)], ch)] - lowest;
          out[i * size_t(d1) + size_t(d0)] = int8_t(std::min(127.0, std::round(std::sqrt(lambda * penalty))));
        }
      }
    }
  }
}

} // namespace

int main(int argc, char** argv) {
  const int side = int(env("SIDE", 64));
  const int n = int(env("N", 128));
  const int big = int(env("BIG", 256));
  SolidSynthesisOptions so;
  so.jitter = float(env("JITTER", so.jitter));
  so.offsetCells = int(env("OFFSET", so.offsetCells));
  so.finestPasses = int(env("FINEST", so.finestPasses));
  so.passes = int(env("PASSES", so.passes));
  so.interleave = int(env("INTERLEAVE", so.interleave));
  so.matchColors = env("MATCH", so.matchColors) > 0;
  so.contrastGain = float(env("GAIN", so.contrastGain));
  so.refinePasses = int(env("REFINE", so.refinePasses));
  SolidAnalysisOptions ao;
  ao.strips = int(env("STRIPS", ao.strips));
  ao.kept = int(env("KEPT", ao.kept));
  ao.coherenceIterations = int(env("COHIT", ao.coherenceIterations));
  ao.levels = int(env("LEVELS", ao.levels));
  ao.candidates2d = int(env("K2D", ao.candidates2d));
  const bool clamp = std::getenv("WRAP") && std::string(std::getenv("WRAP")) == "clamp";
  AnalysisOptions ao2;
  FidelityOptions fo;
  if (clamp) ao.wrap = ao2.wrap = ExemplarWrap::Clamp, fo.toroidal = false;
  const std::string cache = "/tmp/solidfid-cache";
  std::map<std::string, std::vector<double>> sums;
  for (int i = 1; i < argc; ++i) {
    const Image full = readImage(argv[i]);
    if (std::getenv("DUMP")) {
      std::string base = argv[i];
      base = base.substr(base.rfind('/') + 1);
      writeImage(full, std::string(std::getenv("DUMP")) + "/" + base.substr(0, base.find('.')) + ".png");
      continue;
    }
    const Image e = crop(full, std::min({side, full.width, full.height}));
    SolidAnalysis a = analyzeSolidCached(e, e, e, ao, cache, kCtx);
    if (env("FK3D", 0) > 0) a.levels.back().k3d = int(env("FK3D", 4));
    if (env("FK2D", 0) > 0) a.levels.back().k2d = int(env("FK2D", 2));
    if (env("CK3D", 0) > 0) for (auto& l : a.levels) if (&l != &a.levels.back()) l.k3d = int(env("CK3D", 12));
    if (const double lambda = env("HISTPEN", 0); lambda > 0) applyHistogramPenalty(a, e, so, lambda);
    const ExemplarAnalysis a2 = analyzeExemplarCached(e, ao2, cache, kCtx);
    const int ch = e.channels;
    const double exStd = lumStd(e);
    // 2-D synthesis baseline.
    const SynthesisResult s2 = synthesize2d(a2, {0, 0, n, n}, {}, kCtx);
    const Image im2 = applyCoords(s2.coords, e);
    const double f2 = neighborhoodFidelity(im2, e, fo), h2 = histogramDistance(im2, e);
    const double k2 = neighborhoodCompleteness(im2, e, fo);
    const Image eh = downsample(e, 2);
    FidelityOptions coarse = fo;
    coarse.radius = 2;
    const double g2 = neighborhoodFidelity(downsample(im2, 2), eh, coarse);
    if (std::getenv("SAVE")) writeImage(im2, "/tmp/solidfid-2d.png"), writeImage(e, "/tmp/solidfid-ex.png");
    const SynthesisResult s2b = synthesize2d(a2, {0, 0, big, big}, {}, kCtx);
    const double sc2 = shiftedSelfCorrelation(applyCoords(s2b.coords, e), e.width, e.height);
    Image rnd(n, n, ch);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const uint32_t hh = voxelHash(3, 0, x, y, 0, 0);
        for (int c = 0; c < ch; ++c) rnd.at(x, y, c) = e.at(int(hh % uint32_t(e.width)), int((hh >> 12) % uint32_t(e.height)), c);
      }
    const double fr = neighborhoodFidelity(rnd, e, fo);
    std::printf("\n%s %dx%d: 2D contrast %.3f fidelity %.4f (random %.4f) hist %.4f shifted %.3f\n", argv[i], e.width,
                e.height, lumStd(im2) / exStd, f2, fr, h2, sc2);
    // Two images that lose the exemplar's contrast, for scale: a flat one of its mean colour, and
    // its 2-D synthesis box-blurred (3x3). Listed with the rules as "~flat" and "~blurred".
    {
      Image flat(n, n, ch), blurred(n, n, ch);
      for (int c = 0; c < ch; ++c) {
        double mean = 0;
        for (int y = 0; y < e.height; ++y)
          for (int x = 0; x < e.width; ++x) mean += e.at(x, y, c) / (double(e.width) * e.height);
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            double box = 0;
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) box += im2.at((x + dx + n) % n, (y + dy + n) % n, c) / 9;
            flat.at(x, y, c) = float(mean), blurred.at(x, y, c) = float(box);
          }
      }
      for (const auto& [name, im] : {std::pair<std::string, const Image&>{"~flat", flat}, {"~blurred", blurred}}) {
        const double c = lumStd(im) / exStd, f = neighborhoodFidelity(im, e, fo) / f2;
        const double k = neighborhoodCompleteness(im, e, fo) / k2, h = histogramDistance(im, e) / h2;
        std::printf("  %-8s contrast %.3f fidratio %.3f compratio %.3f\n", name.c_str(), c, f, k);
        auto& sum = sums[name];
        sum.resize(6);
        sum[0] += c, sum[1] += f, sum[2] += h, sum[4] += neighborhoodFidelity(downsample(im, 2), eh, coarse) / g2, sum[5] += k;
      }
    }

    // Colour rules.
    const SolidLevel& fin = a.levels.back();
    auto px = [&](int, uint32_t c, int ch_) { return e.at(int(coordU(c)), int(coordV(c)), ch_); };
    auto sum8 = [&](const Triple& t, int c) {
      int s = 0;
      for (int q = 0; q < 3; ++q) s += int(std::lrint(px(q, t[size_t(q)], c) * 255));
      return s;
    };
    // Histogram-matching LUTs (sum of the three 8-bit colours -> exemplar quantile), per channel,
    // learned from a set of triples.
    auto learnLut = [&](const std::vector<Triple>& source) {
      std::vector<std::array<float, 766>> lut(static_cast<size_t>(ch));
      for (int c = 0; c < ch; ++c) {
        std::vector<double> hs(766, 0), he(256, 0);
        for (const Triple& t : source) hs[size_t(sum8(t, c))] += 1;
        for (int y = 0; y < e.height; ++y)
          for (int x = 0; x < e.width; ++x) he[size_t(std::lrint(e.at(x, y, c) * 255))] += 1;
        const double ts = double(source.size()), te = double(e.width) * e.height;
        // Map the middle of each source bin's CDF interval to the exemplar's quantile.
        double cs = 0;
        for (int s = 0; s < 766; ++s) {
          const double q = (cs + hs[size_t(s)] / 2) / ts;
          cs += hs[size_t(s)];
          double ce = 0;
          int b = 0;
          for (; b < 255; ++b) {
            if ((ce + he[size_t(b)]) / te >= q) break;
            ce += he[size_t(b)];
          }
          const double frac = he[size_t(b)] > 0 ? (q * te - ce) / he[size_t(b)] : 0.5;
          lut[size_t(c)][size_t(s)] = float((b - 0.5 + std::clamp(frac, 0.0, 1.0)) / 255.0);
        }
      }
      return lut;
    };
    // Source 1: the first k 3-D candidates of every exemplar pixel at the finest level.
    auto candidates = [&](int k) {
      std::vector<Triple> out;
      for (int ex = 0; ex < 3; ++ex)
        for (int p = 0; p < e.width * e.height; ++p)
          for (int kk = 0; kk < k; ++kk) {
            const uint32_t* t = &fin.triples[size_t(ex)][(size_t(p) * kSolidMaxCandidates + size_t(kk)) * 3];
            out.push_back({t[0], t[1], t[2]});
          }
      return out;
    };
    const auto lut4 = learnLut(candidates(4));
    // Source 2: a synthesized calibration box far from the measured planes.
    const int cb = int(env("CALBOX", 32));
    const auto cal = learnLut(synthesizeSolidBox(a, {-5000, 7000, 3000, cb, cb, cb}, so, nullptr, kCtx).triples);
    std::vector<std::pair<std::string, Rule>> rules = {
        {"mean", [&](const Triple& t, float* o) { for (int c = 0; c < ch; ++c) { float s = 0; for (int q = 0; q < 3; ++q) s += px(q, t[size_t(q)], c); o[c] = s / 3; } }},
        {"median", [&](const Triple& t, float* o) { for (int c = 0; c < ch; ++c) { float v[3]; for (int q = 0; q < 3; ++q) v[q] = px(q, t[size_t(q)], c); std::sort(v, v + 3); o[c] = v[1]; } }},
        {"medoid", [&](const Triple& t, float* o) {
           float v[3][3];
           for (int q = 0; q < 3; ++q) for (int c = 0; c < ch; ++c) v[q][c] = px(q, t[size_t(q)], c);
           int best = 0; double bd = 1e9;
           for (int q = 0; q < 3; ++q) { double d = 0; for (int r = 0; r < 3; ++r) for (int c = 0; c < ch; ++c) d += std::abs(v[q][c] - v[r][c]); if (d < bd - 1e-9) { bd = d; best = q; } }
           for (int c = 0; c < ch; ++c) o[c] = v[best][c]; }},
        {"ez", [&](const Triple& t, float* o) { for (int c = 0; c < ch; ++c) o[c] = px(2, t[2], c); }},
        {"cal", [&](const Triple& t, float* o) { for (int c = 0; c < ch; ++c) o[c] = cal[size_t(c)][size_t(sum8(t, c))]; }},
        {"lut4", [&](const Triple& t, float* o) { for (int c = 0; c < ch; ++c) o[c] = lut4[size_t(c)][size_t(sum8(t, c))]; }},
    };

    std::vector<Plane> planes;
    for (int axis = 0; axis < 3; ++axis) planes.push_back(axisPlane(axis, 21, n, 0));
    planes.push_back(obliquePlane(n, 0));
    std::vector<Plane> bigPlanes{axisPlane(2, 40, big, 0), obliquePlane(big, 0)};
    std::vector<Voxel> all;
    for (auto* ps : {&planes, &bigPlanes})
      for (const Plane& p : *ps) all.insert(all.end(), p.voxels.begin(), p.voxels.end());
    const SolidSynthesisResult r = synthesizeSolid(a, all, so, nullptr, kCtx);
    {
      // Coherence of the in-plane exemplar's coordinates on the three axis planes.
      size_t at = 0;
      std::string line;
      for (int axis = 0; axis < 3; ++axis) {
        const Plane& p = planes[size_t(axis)];
        // The y plane's image is (x, z) where E_y's (u, v) is (z, x): measured transposed.
        const bool transposed = axis == 1;
        CoordMap m{transposed ? p.h : p.w, transposed ? p.w : p.h, e.width, e.height, {}};
        m.coords.resize(p.voxels.size());
        for (size_t v = 0; v < p.voxels.size(); ++v) {
          const size_t i = v % size_t(p.w), j = v / size_t(p.w);
          m.coords[transposed ? i * size_t(p.h) + j : v] = r.triples[at + v][size_t(axis)];
        }
        at += p.voxels.size();
        char buf[64];
        std::snprintf(buf, sizeof buf, " %c:%.3f", "xyz"[axis], coherence(m));
        line += buf;
      }
      std::printf("  coherence of the plane's own exemplar:%s\n", line.c_str());
    }
    for (const auto& [name, rule] : rules) {
      if (const char* only = std::getenv("RULES"); only && std::string(",") .append(only).append(",").find("," + name + ",") == std::string::npos) continue;
      size_t at = 0;
      double cr = 0, fid = 0, hist = 0, shifted = 0, coarseFid = 0, comp = 0;
      std::string line;
      auto image = [&](const Plane& p) {
        Image im(p.w, p.h, ch);
        for (size_t v = 0; v < p.voxels.size(); ++v) rule(r.triples[at + v], &im.pixels[v * size_t(ch)]);
        at += p.voxels.size();
        return im;
      };
      char buf[256];
      for (const Plane& p : planes) {
        const Image im = image(p);
        const double c = lumStd(im) / exStd, f = neighborhoodFidelity(im, e, fo), hd = histogramDistance(im, e);
        cr += c / 4, fid += f / 4, hist += hd / 4, coarseFid += neighborhoodFidelity(downsample(im, 2), eh, coarse) / 4;
        comp += neighborhoodCompleteness(im, e, fo) / 4;
        std::snprintf(buf, sizeof buf, " %s:%.2f/%.2f/%.3f", p.name.c_str(), c, f / f2, hd);
        line += buf;
        if (std::getenv("SAVE")) writeImage(im, std::string("/tmp/solidfid-") + name + "-" + p.name + ".png");
      }
      for (const Plane& p : bigPlanes) {
        const Image im = image(p);
        const double s = shiftedSelfCorrelation(im, e.width, e.height);
        shifted = std::max(shifted, s);
        std::snprintf(buf, sizeof buf, " sc_%s:%.2f", p.name.c_str(), s);
        line += buf;
      }
      std::printf("  %-8s contrast %.3f fidratio %.3f compratio %.3f coarseratio %.3f hist %.4f (2D %.4f) shifted %.3f |%s\n",
                  name.c_str(), cr, fid / f2, comp / k2, coarseFid / g2, hist, h2, shifted, line.c_str());
      auto& s = sums[name];
      s.resize(6);
      s[0] += cr, s[1] += fid / f2, s[2] += hist / h2, s[3] += shifted, s[4] += coarseFid / g2, s[5] += comp / k2;
    }
  }
  std::printf("\nmeans over %d exemplars (contrast, fidelity ratio, histogram ratio vs 2D, shifted):\n", argc - 1);
  for (const auto& [name, s] : sums)
    std::printf("  %-8s %.3f %.3f %.3f %.3f coarse fidelity ratio %.3f completeness ratio %.3f\n", name.c_str(),
                s[0] / (argc - 1), s[1] / (argc - 1), s[2] / (argc - 1), s[3] / (argc - 1), s[4] / (argc - 1),
                s[5] / (argc - 1));
}
