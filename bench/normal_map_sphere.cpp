// SPDX-License-Identifier: GPL-3.0-or-later
// A measuring program, not a benchmark: normal-map filtering in previews (issue 38). A glossy metal
// sphere whose normal map (256^2, tiled 16 x 8 times) is seen at 4, 16 and 64 texels per pixel at
// the sphere's centre, rendered with each NormalMapFiltering at one sample per pixel and compared
// with the supersampled truth (full-resolution normals, 256-4096 samples per pixel): the RMS
// error of the 8-bit sRGB pixels the sphere covers, for the three test materials; and the glTF
// route (render/material_mips.h: the roughness MIP chain a viewer samples with MIP-mapped
// normals), with its levels as stored and through UASTC as KTX2 carries them. With a path it
// also draws the picture of docs/normal-map-filtering.md (the stone: the truth at 1024 samples per
// pixel, then MIP-mapped normals, Toksvig, the fitted lobes and the glTF route through UASTC at 4;
// the near view's centre, the far views enlarged; --material draws another of the three).
// --microfacet shades with glTF's microfacet BRDF instead of Blinn-Phong (render::SpecularModel).
//   build/bench/normal_map_sphere [--microfacet] [--material NAME] [docs/images/normal_map_filtering.png]
#include "core/image_io.h"
#include "tests/render/test_normal_maps.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace {

using namespace texfab;
using render::NormalMapFiltering;

constexpr int kMapSize = 256, kTilesAround = 16;
constexpr std::array<int, 3> kTexelsPerPixel = {4, 16, 64};
constexpr std::array<NormalMapFiltering, 3> kMethods = {NormalMapFiltering::Mip, NormalMapFiltering::Toksvig,
                                                        NormalMapFiltering::Lobes};

// test::sphereView with the specular model.
render::RenderOptions sphereView(int diameter, int samples, NormalMapFiltering filtering, render::SpecularModel specular) {
  render::RenderOptions o = test::sphereView(diameter, samples, filtering);
  o.specular = specular;
  return o;
}

void printTable(render::SpecularModel specular) {
  std::printf("| material | texels per pixel | sphere, px | MIP-mapped | Toksvig | fitted lobes | glTF route, isotropic | "
              "glTF route | glTF route, UASTC | MIP / lobes | MIP / route |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const test::TestMap& m : test::testMaps(kMapSize)) {
    const geometry::Mesh sphere = test::normalMappedSphere(m.map, kTilesAround);
    const geometry::Mesh isotropicSphere = test::withGltfRoute(sphere, false, {.anisotropy = false});
    const geometry::Mesh routeSphere = test::withGltfRoute(sphere, false), uastcSphere = test::withGltfRoute(sphere, true);
    const render::PreviewRenderer renderer(sphere), isotropic(isotropicSphere), route(routeSphere), routeUastc(uastcSphere);
    for (int texelsPerPixel : kTexelsPerPixel) {
      const int diameter = test::sphereDiameter(kMapSize, kTilesAround, texelsPerPixel);
      const Image truth =
          renderer.render(sphereView(diameter, test::truthSamples(texelsPerPixel), NormalMapFiltering::Mip, specular));
      std::array<double, kMethods.size() + 3> error{};
      for (size_t i = 0; i < kMethods.size(); ++i)
        error[i] = test::coveredRms(renderer.render(sphereView(diameter, 1, kMethods[i], specular)), truth);
      const render::PreviewRenderer* routes[] = {&isotropic, &route, &routeUastc};
      for (size_t i = 0; i < 3; ++i)
        error[3 + i] = test::coveredRms(routes[i]->render(sphereView(diameter, 1, NormalMapFiltering::Mip, specular)), truth);
      std::printf("| %s | %d | %d | %.4f | %.4f | %.4f | %.4f | %.4f | %.4f | %.1fx | %.1fx |\n", m.name.c_str(),
                  texelsPerPixel, diameter, error[0], error[1], error[2], error[3], error[4], error[5], error[0] / error[2],
                  error[0] / error[5]);
      std::fflush(stdout);
    }
  }
}

void drawPicture(const char* path, const test::TestMap& material, render::SpecularModel specular) {
  const geometry::Mesh sphere = test::normalMappedSphere(material.map, kTilesAround);
  const geometry::Mesh routeSphere = test::withGltfRoute(sphere, true);
  const render::PreviewRenderer renderer(sphere), route(routeSphere);
  constexpr int kTile = 160, kColumns = 2 + int(kMethods.size());
  Image sheet(kColumns * kTile, int(kTexelsPerPixel.size()) * kTile, 3, PixelFormat::UInt8);
  for (size_t row = 0; row < kTexelsPerPixel.size(); ++row) {
    const int diameter = test::sphereDiameter(kMapSize, kTilesAround, kTexelsPerPixel[row]);
    for (int column = 0; column < kColumns; ++column) {
      const Image v = column == 0               ? renderer.render(sphereView(diameter, 1024, NormalMapFiltering::Mip, specular))
                      : column == kColumns - 1 ? route.render(sphereView(diameter, 4, NormalMapFiltering::Mip, specular))
                                               : renderer.render(sphereView(diameter, 4, kMethods[size_t(column - 1)], specular));
      // Over white: the view's centre where it is larger than the tile, else the view enlarged
      // (nearest) to the tile.
      const bool crop = v.width >= kTile;
      const int offset = crop ? (v.width - kTile) / 2 : 0;
      for (int y = 0; y < kTile; ++y)
        for (int x = 0; x < kTile; ++x) {
          const int vx = crop ? offset + x : x * v.width / kTile, vy = crop ? offset + y : y * v.height / kTile;
          for (int c = 0; c < 3; ++c)
            sheet.at(column * kTile + x, int(row) * kTile + y, c) = v.at(vx, vy, c) * v.at(vx, vy, 3) + 1 - v.at(vx, vy, 3);
        }
    }
  }
  writeImage(sheet, path);
}

} // namespace

int main(int argc, char** argv) {
  render::SpecularModel specular = render::SpecularModel::BlinnPhong;
  const char* picture = nullptr;
  const std::vector<test::TestMap> materials = test::testMaps(kMapSize);
  const test::TestMap* material = &materials[0];
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--microfacet") == 0) {
      specular = render::SpecularModel::Microfacet;
      continue;
    }
    if (std::strcmp(argv[i], "--material") == 0 && i + 1 < argc) {
      const auto it = std::find_if(materials.begin(), materials.end(), [&](const test::TestMap& m) { return m.name == argv[i + 1]; });
      if (it != materials.end()) {
        material = &*it, ++i;
        continue;
      }
    } else if (!picture && argv[i][0] != '-') {
      picture = argv[i];
      continue;
    }
    std::fprintf(stderr, "usage: normal_map_sphere [--microfacet] [--material stone|'brushed metal'|fabric] [PICTURE.png]\n");
    return 2;
  }
  printTable(specular);
  if (picture) drawPicture(picture, *material, specular);
  return 0;
}
