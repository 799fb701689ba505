// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: R. Ulichney. The void-and-cluster method for dither array generation. SPIE 1913, 1993.
#include "print/blue_noise.h"

#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace texfab::print {

namespace {

constexpr double kSigma = 1.5;    // filter width in mean voxel spacings (Ulichney's 1.5 pixels)
constexpr double kRadius = 4.5;   // filter support, in mean voxel spacings

uint64_t splitMix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

struct Tap {
  int dx, dy, dz;
  int64_t weight;
};

// The binary pattern on the torus, its energies (the filter summed over the pattern's 1s), and per
// block of cells the tightest cluster (1 with the highest energy) and largest void (0 with the
// lowest), ties to the lowest index.
class VoidsAndClusters {
public:
  VoidsAndClusters(int size, const Eigen::Vector3d& pitch) : s_(size), b_(size >= 16 ? 8 : size) {
    // Three energies: within the layer (2-D distances in the layer's mean spacing), within the
    // column (distances in layers), and a quarter of the 3-D one (distances in the mean voxel
    // spacing) between different layers. Each layer alone and each column alone is then blue, and
    // the volume stays even across layers.
    auto weight = [](double d2) {
      const double f = 1.0 + d2 / (2 * kSigma * kSigma);
      return int64_t(16777216.0 / (f * f));
    };
    const Eigen::Vector3d layerUnit(pitch.x() / std::sqrt(pitch.x() * pitch.y()), pitch.y() / std::sqrt(pitch.x() * pitch.y()), 1);
    const Eigen::Vector3d volumeUnit = pitch / std::cbrt(pitch.x() * pitch.y() * pitch.z());
    int reach[3];
    for (int a = 0; a < 3; ++a)
      reach[a] = std::min((size - 1) / 2, int(std::floor(kRadius / std::min(layerUnit[a], volumeUnit[a]))));
    for (int dz = -reach[2]; dz <= reach[2]; ++dz)
      for (int dy = -reach[1]; dy <= reach[1]; ++dy)
        for (int dx = -reach[0]; dx <= reach[0]; ++dx) {
          int64_t w = 0;
          const Eigen::Vector3d d(dx, dy, dz);
          if (const double d2 = d.cwiseProduct(layerUnit).squaredNorm(); (dz == 0 || (dx == 0 && dy == 0)) && d2 <= kRadius * kRadius)
            w += weight(d2);
          if (const double d2 = d.cwiseProduct(volumeUnit).squaredNorm(); dz != 0 && d2 <= kRadius * kRadius)
            w += weight(d2) / 4;
          if (w > 0) taps_.push_back({dx, dy, dz, w});
        }
    const size_t n = size_t(size) * size_t(size) * size_t(size);
    ones_.assign(n, 0);
    energy_.assign(n, 0);
    const int blocks = s_ / b_;
    blockCluster_.assign(size_t(blocks) * blocks * blocks, -1);
    blockVoid_.assign(blockCluster_.size(), -1);
    dirty_.assign(blockCluster_.size(), 1);
  }

  size_t cells() const { return ones_.size(); }
  bool one(size_t i) const { return ones_[i] != 0; }

  void set(size_t i, bool value) {
    ones_[i] = value;
    const int x = int(i % size_t(s_)), y = int(i / size_t(s_) % size_t(s_)), z = int(i / size_t(s_) / size_t(s_));
    for (const Tap& t : taps_) {
      const size_t j = index((x + t.dx + s_) % s_, (y + t.dy + s_) % s_, (z + t.dz + s_) % s_);
      energy_[j] += value ? t.weight : -t.weight;
      dirty_[blockOf(j)] = 1;
    }
  }

  // Indices of the tightest cluster and the largest void; the pattern must have a 1, resp. a 0.
  size_t tightestCluster() { return found(best(true)); }
  size_t largestVoid() { return found(best(false)); }

private:
  static size_t found(int64_t i) {
    if (i < 0) throw Error("internal: blue-noise volume without a cell to move");
    return size_t(i);
  }
  size_t index(int x, int y, int z) const { return size_t(x) + size_t(s_) * (size_t(y) + size_t(s_) * size_t(z)); }
  size_t blockOf(size_t i) const {
    const int blocks = s_ / b_;
    const int x = int(i % size_t(s_)) / b_, y = int(i / size_t(s_) % size_t(s_)) / b_, z = int(i / size_t(s_) / size_t(s_)) / b_;
    return size_t(x + blocks * (y + blocks * z));
  }
  // Whether cell i (of the kind searched) beats cell j: higher energy for clusters, lower for voids.
  bool better(int64_t i, int64_t j, bool cluster) const {
    if (j < 0) return true;
    const int64_t ei = energy_[size_t(i)], ej = energy_[size_t(j)];
    return cluster ? (ei > ej || (ei == ej && i < j)) : (ei < ej || (ei == ej && i < j));
  }
  void refresh(size_t block) {
    const int blocks = s_ / b_;
    const int bx = int(block % size_t(blocks)) * b_, by = int(block / size_t(blocks) % size_t(blocks)) * b_,
              bz = int(block / size_t(blocks) / size_t(blocks)) * b_;
    int64_t cluster = -1, hole = -1;
    for (int z = bz; z < bz + b_; ++z)
      for (int y = by; y < by + b_; ++y)
        for (int x = bx; x < bx + b_; ++x) {
          const int64_t i = int64_t(index(x, y, z));
          if (ones_[size_t(i)]) {
            if (better(i, cluster, true)) cluster = i;
          } else if (better(i, hole, false)) {
            hole = i;
          }
        }
    blockCluster_[block] = cluster;
    blockVoid_[block] = hole;
    dirty_[block] = 0;
  }
  int64_t best(bool cluster) {
    int64_t found = -1;
    for (size_t b = 0; b < dirty_.size(); ++b) {
      if (dirty_[b]) refresh(b);
      const int64_t candidate = cluster ? blockCluster_[b] : blockVoid_[b];
      if (candidate >= 0 && better(candidate, found, cluster)) found = candidate;
    }
    return found;
  }

  int s_, b_;
  std::vector<Tap> taps_;
  std::vector<uint8_t> ones_;
  std::vector<int64_t> energy_;
  std::vector<int64_t> blockCluster_, blockVoid_;
  std::vector<uint8_t> dirty_;
};

} // namespace

BlueNoiseVolume blueNoiseVolume(int size, const Eigen::Vector3d& pitch) {
  if (size < 4 || size > 64 || (size >= 16 && size % 8 != 0))
    throw Error("blue-noise volume: size must be 4-15, or a multiple of 8 up to 64, got " + std::to_string(size));
  if (!(pitch.minCoeff() > 0) || !pitch.allFinite()) throw Error("blue-noise volume: voxel pitch must be positive");
  VoidsAndClusters initial(size, pitch);
  const size_t n = initial.cells();
  // Initial pattern: a tenth of the cells, hashed; then relaxed until the tightest cluster is the
  // largest void.
  size_t ones = 0;
  for (uint64_t k = 0; ones < std::max<size_t>(1, n / 10); ++k)
    if (const size_t i = size_t(splitMix(k) % n); !initial.one(i)) initial.set(i, true), ++ones;
  for (size_t step = 0; step < n; ++step) {
    const size_t cluster = initial.tightestCluster();
    initial.set(cluster, false);
    const size_t hole = initial.largestVoid();
    initial.set(hole, true);
    if (hole == cluster) break;
  }
  BlueNoiseVolume out;
  out.size = size;
  out.rank.assign(n, 0);
  VoidsAndClusters shrinking = initial;  // phase 1: remove clusters, ranks descending
  for (size_t count = ones; count > 0; --count) {
    const size_t cluster = shrinking.tightestCluster();
    out.rank[cluster] = uint32_t(count - 1);
    shrinking.set(cluster, false);
  }
  for (size_t count = ones; count < n; ++count) {  // phases 2 and 3: fill voids, ranks ascending
    const size_t hole = initial.largestVoid();
    out.rank[hole] = uint32_t(count);
    initial.set(hole, true);
  }
  return out;
}

} // namespace texfab::print
