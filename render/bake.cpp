// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/bake.h"

#include "core/error.h"
#include "synthesis/solid_tiles.h"

#include <atomic>
#include <cmath>
#include <cstdlib>

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
  if (method == synthesis::SolidMethod::Tiles) return std::to_string(voxelsRequested) + " voxels read from the tiles";
  return std::to_string(voxelsRequested) + " voxels requested, " + std::to_string(voxelsSynthesized) + " synthesized";
}

SolidSites solidTriplesAtSites(const synthesis::SurfaceLevel& sites, const atlas::AtlasFields& fields,
                               const synthesis::SolidAnalysis& analysis, const synthesis::SolidSynthesisOptions& options,
                               double scale, const Context& ctx, synthesis::SolidLevelCache* cache) {
  auto voxelAt = [&](size_t s) {
    const atlas::Float3& p = fields.position.at(sites.x[s], sites.y[s]);
    const synthesis::Voxel v{int64_t(std::floor(double(p.x) * scale)), int64_t(std::floor(double(p.y) * scale)),
                             int64_t(std::floor(double(p.z) * scale))};
    for (int64_t c : {v.x, v.y, v.z})
      if (std::abs(c) > synthesis::kMaxSolidPosition)
        throw Error("the scale puts the model outside the solid texture's range (|position × scale| <= 2^30)");
    return v;
  };
  if (options.method == synthesis::SolidMethod::Tiles) {  // one read per site, no request to build
    const synthesis::SolidTileSet& tiles = synthesis::requireTiles(analysis);
    SolidSites out{std::vector<synthesis::Triple>(sites.size()), int64_t(sites.size()), 0};
    parallelFor(0, int(sites.size()), ctx, [&](int begin, int end) {
      synthesis::SolidTileReader read(tiles, options.seed);
      for (int s = begin; s < end; ++s) {
        const synthesis::Voxel v = voxelAt(size_t(s));
        out.triples[size_t(s)] = read(v.x, v.y, v.z);
      }
    }, 4096);
    return out;
  }
  std::vector<synthesis::Voxel> voxels(sites.size());
  for (size_t s = 0; s < sites.size(); ++s) voxels[s] = voxelAt(s);
  synthesis::SolidSynthesisResult result = synthesizeSolid(analysis, voxels, options, cache, ctx);
  return {std::move(result.triples), result.distinctVoxels, result.voxelsSynthesized()};
}

} // namespace texfab::render
