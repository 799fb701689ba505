// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/filter_normal_map.h"

#include "core/error.h"
#include "core/files.h"
#include "core/hash.h"
#include "core/parallel.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/binary_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cmath>
#include <fstream>
#include <optional>
#include <string>

namespace texfab::render {

namespace {

constexpr double kPi = 3.14159265358979323846;
/// A texel's normals are summed in chunks of rows holding about this many normals, the chunks'
/// sums then added in order: the same sums whether a texel's EM runs on one thread or on many.
constexpr int kChunkNormals = 4096;
constexpr int kMaxLobes = 8;

// e^x for x <= 0 (0 below -700): x = k ln 2 + r with |r| <= ln 2 / 2, e^r by its Taylor series to
// degree 9 (relative error below 1e-11), times 2^k made from its bits. Fixed operations only,
// unlike libm's exp, whose code path follows the CPU: the same bits on every machine.
double expNonPositive(double x) {
  if (!(x >= -700.0)) return 0.0;
  const double k = std::floor(x * 1.4426950408889634 + 0.5);
  const double r = (x - k * 0.6931471803691238) - k * 1.9082149292705877e-10;
  constexpr double inverse[] = {1.0, 1.0, 1.0 / 2, 1.0 / 3, 1.0 / 4, 1.0 / 5, 1.0 / 6, 1.0 / 7, 1.0 / 8, 1.0 / 9};
  double p = 1;
  for (int n = 9; n >= 1; --n) p = 1 + p * r * inverse[n];
  return p * std::bit_cast<double>(uint64_t(int64_t(k) + 1023) << 52);
}

double sharpnessOf(double meanLength) {
  const double r = std::min(meanLength, 1.0 - 1e-9);
  if (r <= 0) return 0;
  return std::min((3 * r - r * r * r) / (1 - r * r), double(kMaxVmfSharpness));
}

// The vMF normalization κ / (4π sinh κ) without the e^κ the density's exponent carries:
// γ(n) = norm(κ) e^{κ (μ·n - 1)}.
double vmfNorm(double kappa) {
  if (kappa < 1e-6) return 1.0 / (4 * kPi);
  return kappa / (2 * kPi * (1 - expNonPositive(-2 * kappa)));
}

// A lobe during EM: its mean r (what is stored), axis μ, sharpness κ, weight α, and α·norm(κ) for
// the E-step.
struct Lobe {
  Eigen::Vector3d mean = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double kappa = 0, weight = 0, scale = 0;
  void setScale() { scale = weight * vmfNorm(kappa); }
};

// Σ z and Σ z n per lobe over some normals.
struct Sums {
  std::array<double, kMaxLobes> z{};
  std::array<Eigen::Vector3d, kMaxLobes> zn;
  Sums() { zn.fill(Eigen::Vector3d::Zero()); }
  void add(const Sums& o, int lobes) {
    for (int j = 0; j < lobes; ++j) z[size_t(j)] += o.z[size_t(j)], zn[size_t(j)] += o.zn[size_t(j)];
  }
};

// The level-0 normals as doubles, row-major.
struct NormalField {
  int width = 0, height = 0;
  std::vector<Eigen::Vector3d> normals;
  const Eigen::Vector3d& at(int x, int y) const { return normals[size_t(y) * size_t(width) + size_t(x)]; }
};

// The rectangle of level-0 normals a texel covers, cut into chunks of rows.
struct Footprint {
  int x0, y0, x1, y1, rowsPerChunk;
  int chunks() const { return (y1 - y0 + rowsPerChunk - 1) / rowsPerChunk; }
  int count() const { return (x1 - x0) * (y1 - y0); }
};

Footprint footprint(const NormalField& f, int level, int x, int y) {
  Footprint p{x << level, y << level, std::min((x + 1) << level, f.width), std::min((y + 1) << level, f.height), 1};
  p.rowsPerChunk = std::max(1, kChunkNormals / std::max(1, p.x1 - p.x0));
  return p;
}

// The E-step's sums over chunk `c` of a footprint: each normal's responsibilities
// z_j ∝ α_j γ_j(n) (the largest exponent factored out so that sharp lobes do not underflow).
Sums chunkSums(const NormalField& f, const Footprint& p, int c, std::span<const Lobe> lobes) {
  Sums s;
  const int lobeCount = int(lobes.size());
  const int yEnd = std::min(p.y1, p.y0 + (c + 1) * p.rowsPerChunk);
  std::array<double, kMaxLobes> exponent{}, z{};
  for (int y = p.y0 + c * p.rowsPerChunk; y < yEnd; ++y)
    for (int x = p.x0; x < p.x1; ++x) {
      const Eigen::Vector3d& n = f.at(x, y);
      double top = -1e300;
      for (int j = 0; j < lobeCount; ++j) {
        const Lobe& l = lobes[size_t(j)];
        exponent[size_t(j)] = l.scale > 0 ? l.kappa * (l.axis.dot(n) - 1) : -1e300;
        top = std::max(top, exponent[size_t(j)]);
      }
      double total = 0;
      for (int j = 0; j < lobeCount; ++j) {
        const Lobe& l = lobes[size_t(j)];
        const double below = exponent[size_t(j)] - top;  // a lobe e^-40 below the nearest one takes nothing
        z[size_t(j)] = l.scale > 0 && below > -40 ? l.scale * expNonPositive(below) : 0;
        total += z[size_t(j)];
      }
      for (int j = 0; j < lobeCount; ++j) {
        const double w = z[size_t(j)] / total;
        s.z[size_t(j)] += w;
        s.zn[size_t(j)] += w * n;
      }
    }
  return s;
}

// The M-step: means, weights, axes and sharpness from the E-step's sums over `count` normals.
void maximize(std::span<Lobe> lobes, const Sums& s, int count) {
  for (size_t j = 0; j < lobes.size(); ++j) {
    Lobe& l = lobes[j];
    l.weight = s.z[j] / double(count);
    if (!(s.z[j] > 0)) {
      l.weight = 0, l.scale = 0;
      continue;
    }
    l.mean = s.zn[j] / s.z[j];
    const double length = l.mean.norm();
    if (length > 0) l.axis = l.mean / length;
    l.kappa = sharpnessOf(length);
    l.setScale();
  }
}

// The lobes that start a texel's EM: the J furthest apart of its children's lobes (greedy
// k-centre [Hochbaum and Shmoys 1985], the heaviest first), with equal weights.
std::vector<Lobe> initialLobes(const NdfMipChain& chain, int level, int x, int y, int lobeCount) {
  const NdfLevel& child = chain.levels[size_t(level - 1)];
  std::vector<Lobe> candidates;
  std::vector<double> weights;
  for (int cy = 2 * y; cy < std::min(2 * y + 2, child.height); ++cy)
    for (int cx = 2 * x; cx < std::min(2 * x + 2, child.width); ++cx)
      for (const VmfLobe& v : chain.texel(level - 1, cx, cy)) {
        if (!(v.weight > 0)) continue;
        Lobe l;
        l.axis = v.axis().cast<double>();
        l.kappa = v.sharpness();
        candidates.push_back(l);
        weights.push_back(v.weight);
      }
  std::vector<Lobe> chosen;
  std::vector<double> distance(candidates.size(), 1e300);  // to the nearest chosen axis
  size_t next = size_t(std::max_element(weights.begin(), weights.end()) - weights.begin());
  while (int(chosen.size()) < lobeCount) {
    chosen.push_back(candidates[next]);
    double far = 0;
    for (size_t i = 0; i < candidates.size(); ++i) {
      distance[i] = std::min(distance[i], 1 - candidates[i].axis.dot(chosen.back().axis));
      if (distance[i] > far) far = distance[i], next = i;
    }
    if (far <= 1e-9) break;  // the rest repeat chosen axes
  }
  for (Lobe& l : chosen) l.weight = 1.0 / double(chosen.size()), l.setScale();
  return chosen;
}

// The lobes of one level's texels during EM (flat: lobeCount per texel, `active` of them used).
struct LevelFit {
  int lobeCount = 0;
  std::vector<Lobe> lobes;
  std::vector<int> active;
  std::span<Lobe> of(int t) { return {lobes.data() + size_t(t) * size_t(lobeCount), size_t(active[size_t(t)])}; }
};

// Fits every texel of `level` by `iterations` of EM over the level-0 normals it covers. A texel
// whose footprint is one chunk runs its EM on one thread; larger footprints (the top levels, few
// texels each covering many normals) spread each iteration's chunks over the threads and add them
// in order. Either way the sums are the same.
void fitLevel(const NormalField& f, NdfMipChain& chain, int level, int iterations, const Context& ctx) {
  NdfLevel& out = chain.levels[size_t(level)];
  const int texels = out.width * out.height, lobeCount = out.lobesPerTexel;
  const auto footprintOf = [&](int t) { return footprint(f, level, t % out.width, t / out.width); };
  LevelFit fit{lobeCount, std::vector<Lobe>(size_t(texels) * size_t(lobeCount)), std::vector<int>(size_t(texels))};
  std::vector<int> firstChunk(size_t(texels) + 1, 0);
  parallelFor(0, texels, ctx, [&](int b, int e) {
    for (int t = b; t < e; ++t) {
      const std::vector<Lobe> start = initialLobes(chain, level, t % out.width, t / out.width, lobeCount);
      fit.active[size_t(t)] = int(start.size());
      std::copy(start.begin(), start.end(), fit.lobes.begin() + std::ptrdiff_t(t) * lobeCount);
    }
  });
  for (int t = 0; t < texels; ++t) firstChunk[size_t(t) + 1] = firstChunk[size_t(t)] + footprintOf(t).chunks();
  const int chunks = firstChunk.back();
  const auto step = [&](int t, std::span<const Sums> chunkSums) {
    Sums total;
    for (const Sums& s : chunkSums) total.add(s, lobeCount);
    maximize(fit.of(t), total, footprintOf(t).count());
  };
  if (chunks == texels) {
    parallelFor(0, texels, ctx, [&](int b, int e) {
      for (int t = b; t < e; ++t)
        for (int iteration = 0; iteration < iterations; ++iteration) {
          const Sums s = chunkSums(f, footprintOf(t), 0, fit.of(t));
          step(t, std::span(&s, 1));
        }
    });
  } else {
    std::vector<int> owner(static_cast<size_t>(chunks));
    for (int t = 0; t < texels; ++t)
      std::fill(owner.begin() + firstChunk[size_t(t)], owner.begin() + firstChunk[size_t(t) + 1], t);
    std::vector<Sums> sums(static_cast<size_t>(chunks));
    for (int iteration = 0; iteration < iterations; ++iteration) {
      parallelFor(0, chunks, ctx, [&](int b, int e) {
        for (int c = b; c < e; ++c) {
          const int t = owner[size_t(c)];
          sums[size_t(c)] = chunkSums(f, footprintOf(t), c - firstChunk[size_t(t)], fit.of(t));
        }
      });
      for (int t = 0; t < texels; ++t)
        step(t, std::span(sums).subspan(size_t(firstChunk[size_t(t)]), size_t(firstChunk[size_t(t) + 1] - firstChunk[size_t(t)])));
    }
  }
  for (int t = 0; t < texels; ++t) {
    const std::span<Lobe> lobes = fit.of(t);
    for (size_t j = 0; j < lobes.size(); ++j)
      out.lobes[size_t(t) * size_t(lobeCount) + j] = {float(lobes[j].weight), lobes[j].mean.cast<float>()};
  }
}

} // namespace

Eigen::Vector3f VmfLobe::axis() const {
  const float length = mean.norm();
  return length > 0 ? Eigen::Vector3f(mean / length) : Eigen::Vector3f::UnitZ();
}

float VmfLobe::sharpness() const { return float(sharpnessOf(double(mean.norm()))); }

std::span<const VmfLobe> NdfLevel::texel(int x, int y) const {
  return {lobes.data() + (size_t(y) * size_t(width) + size_t(x)) * size_t(lobesPerTexel), size_t(lobesPerTexel)};
}

Eigen::Vector3f decodeNormal(const Image& map, int x, int y) {
  const Eigen::Vector3f n(2 * map.at(x, y, 0) - 1, 2 * map.at(x, y, 1) - 1, 2 * map.at(x, y, 2) - 1);
  const float length = n.norm();
  return length > 0 ? Eigen::Vector3f(n / length) : Eigen::Vector3f::UnitZ();
}

NdfMipChain filterNormalMap(const Image& map, const FilterNormalMapOptions& o, const Context& ctx) {
  if (map.channels < 3 || map.width < 1 || map.height < 1)
    throw Error("normal-map filtering: a normal map has three channels (got " + std::to_string(map.channels) + ")");
  if (o.lobes < 1 || o.lobes > kMaxLobes) throw Error("normal-map filtering: lobes must be in [1, 8]");
  if (o.iterations < 1 || o.iterations > 100) throw Error("normal-map filtering: iterations must be in [1, 100]");
  Stage stage(ctx, "NDF");
  NormalField f{map.width, map.height, std::vector<Eigen::Vector3d>(size_t(map.width) * size_t(map.height))};
  NdfMipChain chain;
  NdfLevel& base = chain.levels.emplace_back(NdfLevel{map.width, map.height, 1, {}});
  base.lobes.resize(f.normals.size());
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      const Eigen::Vector3f n = decodeNormal(map, x, y);
      f.normals[size_t(y) * size_t(map.width) + size_t(x)] = n.cast<double>();
      base.lobes[size_t(y) * size_t(map.width) + size_t(x)] = {1.0f, n};
    }
  int levels = 1;
  for (int w = map.width, h = map.height; w > 1 || h > 1; w = (w + 1) / 2, h = (h + 1) / 2) ++levels;
  for (int level = 1; level < levels; ++level) {
    const NdfLevel& finer = chain.levels.back();
    NdfLevel next{(finer.width + 1) / 2, (finer.height + 1) / 2, o.lobes, {}};
    next.lobes.resize(size_t(next.width) * size_t(next.height) * size_t(o.lobes));
    chain.levels.push_back(std::move(next));
    fitLevel(f, chain, level, o.iterations, stage.inner());
    stage.advance(level, levels - 1);
  }
  stage.finish(std::to_string(levels) + " levels");
  return chain;
}

namespace {

constexpr uint32_t kNdfMagic = 0x3046444e;  // "NDF0"
constexpr uint32_t kNdfVersion = 1;

uint64_t ndfKey(const Image& map, const FilterNormalMapOptions& o) {
  Fnv1a h;
  h.add(kNdfVersion);
  h.add(map.width), h.add(map.height), h.add(map.channels);
  h.add(map.pixels.data(), map.pixels.size() * sizeof(float));
  h.add(o.lobes), h.add(o.iterations);
  return h.h;
}

void writeNdf(const std::pair<uint64_t, const NdfMipChain*>& value, const std::filesystem::path& path) {
  writeFileAtomically(path, [&](std::ostream& out) {
    synthesis::BinaryWriter w{out};
    w.value(kNdfMagic), w.value(kNdfVersion), w.value(value.first);
    w.value(uint64_t(value.second->levels.size()));
    for (const NdfLevel& l : value.second->levels) {
      w.value(l.width), w.value(l.height), w.value(l.lobesPerTexel);
      w.vec(l.lobes);
    }
  });
}

// The chain in a cache file, when it is one of `key` whose levels halve as filterNormalMap's do.
std::optional<NdfMipChain> readNdf(const std::filesystem::path& path, uint64_t key, const Image& map, int lobes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  synthesis::BinaryReader r{in};
  uint32_t magic = 0, version = 0;
  uint64_t storedKey = 0, levels = 0;
  r.value(magic), r.value(version), r.value(storedKey), r.value(levels);
  if (!r.ok || magic != kNdfMagic || version != kNdfVersion || storedKey != key || levels > 64) return std::nullopt;
  NdfMipChain chain;
  int w = map.width, h = map.height;
  for (uint64_t i = 0; i < levels; ++i, w = (w + 1) / 2, h = (h + 1) / 2) {
    NdfLevel l;
    r.value(l.width), r.value(l.height), r.value(l.lobesPerTexel);
    if (!r.ok || l.width != w || l.height != h || l.lobesPerTexel != (i == 0 ? 1 : lobes)) return std::nullopt;
    r.vec(l.lobes, size_t(w) * size_t(h) * size_t(l.lobesPerTexel));
    if (!r.ok) return std::nullopt;
    chain.levels.push_back(std::move(l));
  }
  // A complete chain ends at 1x1, and so does the file.
  if (chain.levels.empty() || chain.levels.back().width != 1 || chain.levels.back().height != 1 ||
      in.peek() != std::ifstream::traits_type::eof())
    return std::nullopt;
  return chain;
}

} // namespace

NdfMipChain filterNormalMap(const Image& map, const FilterNormalMapOptions& o, const synthesis::AnalysisCacheSettings& cache,
                            const Context& ctx, bool* cached) {
  if (cached) *cached = false;
  if (!cache.dir) return filterNormalMap(map, o, ctx);
  const uint64_t key = ndfKey(map, o);
  NdfMipChain chain = synthesis::loadOrCompute(
      *cache.dir, key, ".ndf", [&](const std::filesystem::path& path, uint64_t k) { return readNdf(path, k, map, o.lobes); },
      [&] { return filterNormalMap(map, o, ctx); },
      [&](const NdfMipChain& c, const std::filesystem::path& path) { writeNdf({key, &c}, path); }, cached, ctx);
  synthesis::pruneCache(cache);
  return chain;
}

double blinnPhong(const Eigen::Vector3f& n, const Eigen::Vector3f& light, const Eigen::Vector3f& half, double s) {
  const double cosine = std::max(0.0f, n.dot(light)), specular = std::max(0.0f, n.dot(half));
  return (s + 1) / (2 * kPi) * std::pow(specular, s) * cosine;
}

double shadeBlinnPhong(std::span<const VmfLobe> lobes, const Eigen::Vector3f& light, const Eigen::Vector3f& half,
                       double s) {
  double sum = 0;
  for (const VmfLobe& l : lobes) {
    if (!(l.weight > 0)) continue;
    sum += l.weight * blinnPhong(l.axis(), light, half, convolvedExponent(double(l.sharpness()), s));
  }
  return sum;
}

Eigen::Vector3f meanReflection(const Eigen::Vector3f& dir, const Eigen::Vector3f& axis, float sharpness, float length) {
  const float ratio = sharpness > 1e-3f ? length / sharpness : 1.0f / 3.0f;
  return dir - 2 * (ratio * dir + (1 - 3 * ratio) * axis.dot(dir) * axis);
}

double shadeToksvig(const Eigen::Vector3f& mean, const Eigen::Vector3f& light, const Eigen::Vector3f& half, double s) {
  const double f = std::min(1.0, double(mean.norm()));
  if (!(f > 0)) return 0;
  const double exponent = f * s / (f + s * (1 - f));
  return blinnPhong(Eigen::Vector3f(mean.normalized()), light, half, exponent);
}

} // namespace texfab::render
