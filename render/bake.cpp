// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/bake.h"

#include "core/error.h"
#include "synthesis/solid_tiles.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <span>
#include <tuple>

namespace texfab::render {

void fillGutters(Image& image, std::vector<uint8_t> filled, int rounds, const Context& ctx) {
  const int w = image.width, h = image.height, c = image.channels;
  std::vector<uint8_t> next = filled;
  for (int round = 0; round < rounds; ++round) {
    std::atomic<bool> grew{false};
    parallelFor(0, h, ctx, [&](int y0, int y1) {
      for (int y = y0; y < y1; ++y)
        for (int x = 0; x < w; ++x) {
          if (filled[size_t(y) * w + x]) continue;
          float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0};
          int n = 0;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int nx = x + dx, ny = y + dy;
              if (nx < 0 || ny < 0 || nx >= w || ny >= h || !filled[size_t(ny) * w + nx]) continue;
              const float* p = image.pixel(nx, ny);
              for (int ch = 0; ch < std::min(c, 8); ++ch) sum[ch] += p[ch];
              ++n;
            }
          if (!n) continue;
          float* out = image.pixel(x, y);  // not read this round: only filled texels are read
          for (int ch = 0; ch < std::min(c, 8); ++ch) out[ch] = sum[ch] / float(n);
          next[size_t(y) * w + x] = 1;
          grew = true;
        }
    }, 16);
    filled = next;
    if (!grew) break;
  }
  std::vector<double> mean(size_t(c), 0.0);
  size_t count = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (filled[size_t(y) * w + x]) {
        for (int ch = 0; ch < c; ++ch) mean[size_t(ch)] += image.at(x, y, ch);
        ++count;
      }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (!filled[size_t(y) * w + x])
        for (int ch = 0; ch < c; ++ch) image.at(x, y, ch) = count ? float(mean[size_t(ch)] / double(count)) : 0.0f;
}

void rotateNormal(const std::array<float, 4>& j, const float* in, float* out) {
  const double nx = 2.0 * in[0] - 1.0, ny = -(2.0 * in[1] - 1.0), nz = 2.0 * in[2] - 1.0;
  const double det = double(j[0]) * j[3] - double(j[1]) * j[2];
  double tx = nx, ty = ny;
  if (det != 0) {
    const double s = std::sqrt(std::fabs(det)) / det;  // J⁻¹ · sqrt|det J|
    tx = s * (j[3] * nx - j[1] * ny);
    ty = s * (-j[2] * nx + j[0] * ny);
  }
  double vx = tx, vy = -ty, vz = nz;
  const double len = std::sqrt(vx * vx + vy * vy + vz * vz);
  if (len > 0) vx /= len, vy /= len, vz /= len;
  else vx = 0, vy = 0, vz = 1;
  out[0] = float(0.5 * vx + 0.5);
  out[1] = float(0.5 * vy + 0.5);
  out[2] = float(0.5 * vz + 0.5);
}

std::string SolidSites::summary(synthesis::SolidMethod method) const {
  const std::string blend = trilinear() ? ", trilinear" : "";
  if (method == synthesis::SolidMethod::Tiles) return std::to_string(voxelsRequested) + " voxels read from the tiles" + blend;
  return std::to_string(voxelsRequested) + " voxels requested, " + std::to_string(voxelsSynthesized) + " synthesized" + blend;
}

namespace {

using synthesis::Voxel;

bool voxelLess(const Voxel& a, const Voxel& b) { return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x); }

void sortUnique(std::vector<Voxel>& v) {
  std::sort(v.begin(), v.end(), voxelLess);
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

// Corner k of the cell whose lowest corner is b (x fastest, then y, then z: SolidSites::cells).
Voxel corner(const Voxel& b, int k) { return {b.x + (k & 1), b.y + ((k >> 1) & 1), b.z + ((k >> 2) & 1)}; }

uint32_t indexIn(const std::vector<Voxel>& sorted, const Voxel& v) {
  return uint32_t(std::lower_bound(sorted.begin(), sorted.end(), v, voxelLess) - sorted.begin());
}

// The voxel coordinate below q, with room for the trilinear cell's c + 1.
int64_t voxelBelow(double q) {
  const double f = std::floor(q);
  if (!(std::fabs(f) < double(synthesis::kMaxSolidPosition)))  // also NaN
    throw Error("the scale puts the model outside the solid texture's range (|position × scale| < 2^30)");
  return int64_t(f);
}

// The triples of `voxels`, one request: the tiles read in parallel, or the lazy engine.
SolidSites readVoxels(std::span<const Voxel> voxels, const synthesis::SolidAnalysis& analysis,
                      const synthesis::SolidSynthesisOptions& options, const Context& ctx,
                      synthesis::SolidLevelCache* cache) {
  SolidSites out;
  if (options.method == synthesis::SolidMethod::Tiles) {
    out.triples.resize(voxels.size());
    synthesis::evaluateSolidTiles(synthesis::requireTiles(analysis), options.seed, voxels, out.triples, ctx);
    out.voxelsRequested = int64_t(voxels.size());
    return out;
  }
  synthesis::SolidSynthesisResult r = synthesizeSolid(analysis, voxels, options, cache, ctx);
  out.triples = std::move(r.triples);
  out.voxelsRequested = r.distinctVoxels;
  out.voxelsSynthesized = r.voxelsSynthesized();
  return out;
}

} // namespace

SolidSites solidAtSites(const synthesis::SurfaceLevel& sites, const atlas::AtlasFields& fields,
                        const synthesis::SolidAnalysis& analysis, const synthesis::SolidSynthesisOptions& options,
                        double scale, double voxelsPerTexel, const Context& ctx, synthesis::SolidLevelCache* cache) {
  const size_t n = sites.size();
  const bool trilinear = voxelsPerTexel < kSolidTrilinearBelow;
  // The site's position in voxels; trilinear reads the cell of voxel centres around it.
  std::vector<Voxel> voxel(n);
  std::vector<std::array<float, 3>> fraction(trilinear ? n : 0);
  parallelFor(0, int(n), ctx, [&](int begin, int end) {
    for (int s = begin; s < end; ++s) {
      const atlas::Float3& p = fields.position.at(sites.x[size_t(s)], sites.y[size_t(s)]);
      const double shift = trilinear ? 0.5 : 0.0;  // to the voxel centres' lattice
      const double q[3] = {double(p.x) * scale - shift, double(p.y) * scale - shift, double(p.z) * scale - shift};
      Voxel& v = voxel[size_t(s)];
      v = {voxelBelow(q[0]), voxelBelow(q[1]), voxelBelow(q[2])};
      if (trilinear) fraction[size_t(s)] = {float(q[0] - double(v.x)), float(q[1] - double(v.y)), float(q[2] - double(v.z))};
    }
  }, 4096);
  if (!trilinear) return readVoxels(voxel, analysis, options, ctx, cache);  // one voxel per site

  std::vector<Voxel> base = voxel;  // the cells' lowest corners
  sortUnique(base);
  std::vector<Voxel> corners;
  corners.reserve(base.size() * 8);
  for (const Voxel& b : base)
    for (int k = 0; k < 8; ++k) corners.push_back(corner(b, k));
  sortUnique(corners);
  SolidSites out = readVoxels(corners, analysis, options, ctx, cache);
  out.cells.resize(base.size());
  out.cellOfSite.resize(n);
  out.fractionOfSite = std::move(fraction);
  parallelFor(0, int(base.size()), ctx, [&](int begin, int end) {
    for (int c = begin; c < end; ++c)
      for (int k = 0; k < 8; ++k) out.cells[size_t(c)][size_t(k)] = indexIn(corners, corner(base[size_t(c)], k));
  }, 1024);
  parallelFor(0, int(n), ctx, [&](int begin, int end) {
    for (int s = begin; s < end; ++s) out.cellOfSite[size_t(s)] = indexIn(base, voxel[size_t(s)]);
  }, 4096);
  return out;
}

} // namespace texfab::render
