// SPDX-License-Identifier: GPL-3.0-or-later
// A measuring program, not a benchmark: the pictures of docs/normal-map-filtering.md. A glossy
// metal sphere with a bumpy normal map (tiled 16 x 8 times) at three distances, each shown as the
// supersampled truth (1024 samples per pixel, full-resolution normals), MIP-mapped normals and
// filtered normal distributions (4 samples per pixel each), the far views enlarged.
//   build/bench/normal_map_pictures docs/images/normal_map_filtering.png
#include "core/image_io.h"
#include "render/preview_renderer.h"
#include "tests/render/test_normal_maps.h"

#include <cmath>
#include <cstdio>

namespace {

using namespace texfab;

// A latitude-longitude sphere of radius 1 with UVs, the normal map tiled 16 x 8 times.
geometry::Mesh uvSphere(int segments, int rings) {
  geometry::Mesh m;
  const double pi = 3.14159265358979323846;
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i <= segments; ++i) {
      const double theta = pi * j / rings, phi = 2 * pi * i / segments;
      m.positions.emplace_back(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)), float(std::sin(theta) * std::sin(phi)));
    }
  const auto index = [&](int i, int j) { return uint32_t(j * (segments + 1) + i); };
  const auto uv = [&](int i, int j) { return Eigen::Vector2f(16.0f * float(i) / float(segments), 8.0f * (1 - float(j) / float(rings))); };
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < segments; ++i) {
      const std::array<std::pair<int, int>, 6> corners = {{{i, j}, {i, j + 1}, {i + 1, j + 1}, {i, j}, {i + 1, j + 1}, {i + 1, j}}};
      for (int t = 0; t < 2; ++t) {
        m.triangles.push_back({index(corners[size_t(3 * t)].first, corners[size_t(3 * t)].second),
                               index(corners[size_t(3 * t + 1)].first, corners[size_t(3 * t + 1)].second),
                               index(corners[size_t(3 * t + 2)].first, corners[size_t(3 * t + 2)].second)});
        for (int k = 0; k < 3; ++k) m.uvs.push_back(uv(corners[size_t(3 * t + k)].first, corners[size_t(3 * t + k)].second));
      }
    }
  geometry::computeSmoothNormals(m);
  return m;
}

} // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: normal_map_pictures OUTPUT.png\n");
    return 2;
  }
  geometry::Mesh sphere = uvSphere(128, 64);
  geometry::Material metal;
  metal.baseColorFactor = Eigen::Vector4f(0.95f, 0.9f, 0.8f, 1.0f);
  metal.metallicFactor = 1.0f;
  metal.roughnessFactor = 0.3f;
  metal.normalTexture.image = std::make_shared<Image>(test::testMaps(256)[0].map);
  sphere.materials = {metal};
  const render::PreviewRenderer renderer(sphere);
  constexpr int kTile = 160;
  const float margins[] = {1.1f, 4.0f, 12.0f};
  Image sheet(3 * kTile, 3 * kTile, 3, PixelFormat::UInt8);
  for (int row = 0; row < 3; ++row) {
    // Render at the distance, then enlarge the centre so that the sphere fills the tile.
    const int side = std::max(8, int(std::lround(kTile / margins[row] * 1.1f)));
    for (int column = 0; column < 3; ++column) {
      render::RenderOptions o;
      o.width = o.height = kTile;
      o.margin = margins[row];
      o.aoSamples = 0;
      o.samplesPerPixel = column == 0 ? 1024 : 4;
      o.filterNormalMaps = column == 2;
      const Image view = renderer.render(o);
      const int x0 = (kTile - side) / 2;
      for (int y = 0; y < kTile; ++y)
        for (int x = 0; x < kTile; ++x)
          for (int c = 0; c < 3; ++c)
            sheet.at(column * kTile + x, row * kTile + y, c) = view.at(x0 + x * side / kTile, x0 + y * side / kTile, c);
    }
    std::printf("row %d: sphere about %d px across\n", row, int(kTile / margins[row]));
  }
  writeImage(sheet, argv[1]);
  return 0;
}
