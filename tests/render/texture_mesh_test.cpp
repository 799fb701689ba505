// SPDX-License-Identifier: GPL-3.0-or-later
// texfab texture's job (atlas/texture_mesh.h) on analytic surfaces: seams, scale, fidelity in
// exemplar space, orientation by the tangent field, solid mode against the solid synthesizer,
// determinism, and bad input.
#include "core/error.h"
#include "core/image_io.h"
#include "render/texture_mesh.h"
#include "synthesis/quality_measures.h"
#include "synthesis/synthesize_2d.h"
#include "tests/atlas/test_meshes.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <iostream>
#include <map>

using namespace texfab;
using namespace texfab::atlas;
using namespace texfab::render;

namespace {

Image bundledExemplar(const std::string& name) {
  return readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models" / "exemplars" / name);
}

// Grey stripes of period 16 along x (constant along y), with a little texture so that pixels differ.
Image stripes(int size = 64) {
  Image img(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 3; ++c)
        img.at(x, y, c) = ((x / 8) % 2 ? 0.8f : 0.2f) + 0.05f * float((x * 7 + y * 13 + c) % 5) / 5.0f;
  return img;
}

Image transposed(const Image& in) {
  Image out(in.height, in.width, in.channels);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x)
      for (int c = 0; c < in.channels; ++c) out.at(y, x, c) = in.at(x, y, c);
  return out;
}

Image checker(int size = 64, int square = 16) {
  Image img(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const bool odd = ((x / square) + (y / square)) % 2 != 0;
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = (odd ? 0.85f : 0.15f) + 0.04f * float((x * 5 + y * 3 + c) % 7) / 7.0f;
    }
  return img;
}

// A closed cube [-1, 1]^3 with n x n quads per face, vertices shared along the edges.
geometry::Mesh makeCube(int n) {
  geometry::Mesh m;
  std::map<std::array<int, 3>, uint32_t> index;
  auto vertex = [&](std::array<int, 3> p) {
    auto [it, inserted] = index.try_emplace(p, uint32_t(m.positions.size()));
    if (inserted) m.positions.push_back(Eigen::Vector3f(float(p[0]), float(p[1]), float(p[2])) * (2.0f / float(n)) -
                                        Eigen::Vector3f::Ones());
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          std::array<uint32_t, 4> q;
          const int corner[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> p{};
            p[size_t(axis)] = side * n;
            p[size_t(u)] = corner[k][0];
            p[size_t(v)] = corner[k][1];
            q[size_t(k)] = vertex(p);
          }
          if (side) {
            m.triangles.push_back({q[0], q[1], q[2]});
            m.triangles.push_back({q[0], q[2], q[3]});
          } else {
            m.triangles.push_back({q[0], q[2], q[1]});
            m.triangles.push_back({q[0], q[3], q[2]});
          }
        }
    }
  return m;
}

struct Exemplar {
  Image image;
  synthesis::ExemplarAnalysis analysis;
  explicit Exemplar(Image img, synthesis::ExemplarWrap wrap = synthesis::ExemplarWrap::Tile)
      : image(std::move(img)), analysis(synthesis::analyzeExemplar(image, {.wrap = wrap})) {}
  TextureExemplar view() const {
    TextureExemplar e;
    e.color = &image;
    e.analysis = &analysis;
    return e;
  }
};

TextureMeshOptions surfaceOptions(int resolution, Eigen::Vector3f direction = {0, 0, 1}) {
  TextureMeshOptions o;
  o.atlas.pack.width = o.atlas.pack.height = resolution;
  o.field.direction = direction;
  return o;
}

// Luminance-gradient energy along `axis` over all of it: Σ (g·a)² / Σ |g|², with g the 3-D
// gradient of the baked texture's luminance inside charts. 0: the texture only varies across
// `axis` (stripes parallel to it); 1: only along it.
double gradientAlong(const TextureMeshResult& r, const Eigen::Vector3d& axis) {
  const Image& img = *r.baseColor;
  const AtlasFields& f = r.atlas.fields;
  auto lum = [&](int x, int y) { return 0.299 * img.at(x, y, 0) + 0.587 * img.at(x, y, 1) + 0.114 * img.at(x, y, 2); };
  auto pos = [&](int x, int y) {
    const Float3& p = f.position.at(x, y);
    return Eigen::Vector3d(p.x, p.y, p.z);
  };
  double along = 0, total = 0;
  for (size_t s = 0; s < r.sites.size(); ++s) {
    const int x = r.sites.x[s], y = r.sites.y[s];
    if (!f.samples.contains(x + 1, y + 1) || f.samples.at(x + 1, y).chart != r.sites.chart[s] ||
        f.samples.at(x, y + 1).chart != r.sites.chart[s])
      continue;
    const Eigen::Vector3d ex = pos(x + 1, y) - pos(x, y), ey = pos(x, y + 1) - pos(x, y);
    const double lx = lum(x + 1, y) - lum(x, y), ly = lum(x, y + 1) - lum(x, y);
    // g = a ex + b ey with g·ex = lx, g·ey = ly.
    Eigen::Matrix2d gram;
    gram << ex.dot(ex), ex.dot(ey), ey.dot(ex), ey.dot(ey);
    if (std::fabs(gram.determinant()) < 1e-20) continue;
    const Eigen::Vector2d ab = gram.inverse() * Eigen::Vector2d(lx, ly);
    const Eigen::Vector3d g = ab(0) * ex + ab(1) * ey;
    along += std::pow(g.dot(axis), 2);
    total += g.squaredNorm();
  }
  return total > 0 ? along / total : 0;
}

// Fidelity of `count` 7x7 neighborhoods of a 2-D image, each sampled bilinearly on a grid turned by
// a pseudo-random angle, as measureSurfaceFidelity samples the atlas.
double rotatedFidelity(const Image& image, const Image& exemplar, int count) {
  std::vector<float> patches;
  for (int k = 0; k < count; ++k) {
    const double angle = 2 * M_PI * std::fmod(k * 0.618033988749895, 1.0);
    const double cx = 8 + std::fmod(k * 37.77, image.width - 16.0), cy = 8 + std::fmod(k * 53.31, image.height - 16.0);
    for (int v = -3; v <= 3; ++v)
      for (int u = -3; u <= 3; ++u) {
        const double px = cx + std::cos(angle) * u - std::sin(angle) * v, py = cy + std::sin(angle) * u + std::cos(angle) * v;
        const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
        const double fx = px - x0, fy = py - y0;
        for (int c = 0; c < 3; ++c)
          patches.push_back(float((1 - fy) * ((1 - fx) * image.at(x0, y0, c) + fx * image.at(x0 + 1, y0, c)) +
                                  fy * ((1 - fx) * image.at(x0, y0 + 1, c) + fx * image.at(x0 + 1, y0 + 1, c))));
      }
  }
  return synthesis::patchFidelity(patches, exemplar);
}

} // namespace

TEST(TextureMesh, SphereMeetsTheSeamScaleAndFidelityTargets) {
  const Exemplar ex(bundledExemplar("brick.png"));
  const TextureMeshResult r = textureMesh(test::makeSphere(64, 32), ex.view(), surfaceOptions(512));
  EXPECT_GT(r.measures.seams.seamPairs, 500u);
  EXPECT_LE(r.measures.seams.ratio, 1.3);
  ASSERT_TRUE(r.measures.scale);
  EXPECT_GE(r.measures.scale->fractionWithin, 0.9);
  EXPECT_NEAR(r.measures.scale->medianPixelsPerUnit / r.textureScale, 1.0, 0.05);
  // Fidelity in exemplar space within 1.5x of a plain 2-D synthesis of the same exemplar, whose
  // neighborhoods are resampled the same way (bilinear, at a random rotation each).
  ASSERT_TRUE(r.measures.fidelity);
  EXPECT_GT(r.measures.fidelity->samples, 300u);
  const synthesis::SynthesisResult plane = synthesis::synthesize2d(ex.analysis, {0, 0, 256, 256}, {});
  const double fidelity2d = rotatedFidelity(synthesis::applyCoords(plane.coords, ex.image), ex.image, 1024);
  std::cout << "fidelity in exemplar space: surface " << r.measures.fidelity->fidelity << ", 2-D " << fidelity2d << "\n";
  EXPECT_LE(r.measures.fidelity->fidelity, 1.5 * fidelity2d);
}

TEST(TextureMesh, ScaleFollowsTheRequestedScale) {
  const Exemplar ex(stripes());
  for (double factor : {0.5, 2.0}) {
    TextureMeshOptions o = surfaceOptions(256);
    o.textureScale = 0;
    TextureMeshResult base = textureMesh(test::makeSphere(48, 24), ex.view(), o);
    o.textureScale = base.textureScale * factor;
    const TextureMeshResult r = textureMesh(test::makeSphere(48, 24), ex.view(), o);
    ASSERT_TRUE(r.measures.scale);
    EXPECT_NEAR(r.measures.scale->medianPixelsPerUnit / o.textureScale, 1.0, 0.1) << factor;
  }
}

TEST(TextureMesh, StripesFollowTheFieldOnACylinder) {
  // The cylinder's axis is z; the field points along it, so the exemplar's "up" runs along the
  // axis: vertical stripes (varying along x only) must run along the axis, horizontal ones around it.
  const geometry::Mesh cylinder = test::makeCylinder(64, 16, 1.0f, 3.0f);
  const Eigen::Vector3d axis(0, 0, 1);
  const Exemplar vertical(stripes()), horizontal(transposed(stripes()));
  const TextureMeshResult a = textureMesh(cylinder, vertical.view(), surfaceOptions(512, {0, 0, 1}));
  const TextureMeshResult b = textureMesh(cylinder, horizontal.view(), surfaceOptions(512, {0, 0, 1}));
  const double alongA = gradientAlong(a, axis), alongB = gradientAlong(b, axis);
  std::cout << "gradient energy along the axis: vertical stripes " << alongA << ", horizontal " << alongB << "\n";
  EXPECT_LT(alongA, 0.25) << "vertical stripes should run along the axis";
  EXPECT_GT(alongB, 0.75) << "horizontal stripes should run around the axis";
  // The curvature field follows the direction of least curvature: the axis again (less exactly
  // than a given direction, since it is estimated from the mesh: 0.27 measured at 512²).
  TextureMeshOptions curvature = surfaceOptions(512);
  curvature.field.kind = geometry::TangentFieldKind::Curvature;
  const double alongCurvature = gradientAlong(textureMesh(cylinder, vertical.view(), curvature), axis);
  EXPECT_LT(alongCurvature, 0.35) << "the curvature field should run along the axis";
  // Seams: a real exemplar (perfect stripes have many equally good phases, so synthesis leaves
  // dislocations in them inside charts and across seams alike).
  const Exemplar brick(bundledExemplar("brick.png"));
  const TextureMeshResult c = textureMesh(cylinder, brick.view(), surfaceOptions(512, {0, 0, 1}));
  EXPECT_GT(c.measures.seams.seamPairs, 500u);
  EXPECT_LE(c.measures.seams.ratio, 1.3);
}

TEST(TextureMesh, CubeSeamsAreContinuous) {
  // A direction with a component on every face, so no face is a singularity of the field.
  const geometry::Mesh cube = makeCube(8);
  const Exemplar brick(bundledExemplar("brick.png"));
  const TextureMeshResult r = textureMesh(cube, brick.view(), surfaceOptions(512, {1, 2, 3}));
  EXPECT_GE(r.atlas.report.charts, 6u);
  EXPECT_GT(r.measures.seams.seamPairs, 500u);
  EXPECT_LE(r.measures.seams.ratio, 1.3);
  ASSERT_TRUE(r.measures.scale);
  EXPECT_GE(r.measures.scale->fractionWithin, 0.9);
  // A checker is the hard case: every square edge is a sharp step that a seam must match exactly.
  const Exemplar squares(checker());
  const TextureMeshResult c = textureMesh(cube, squares.view(), surfaceOptions(512, {1, 2, 3}));
  EXPECT_LE(c.measures.seams.ratio, 1.3);
}

TEST(TextureMesh, ThreadCountDoesNotChangeTheTexture) {
  const Exemplar ex(bundledExemplar("brick.png"));
  TextureMeshOptions o = surfaceOptions(256);
  o.measure = false;
  const TextureMeshResult one = textureMesh(test::makeSphere(32, 16), ex.view(), o, Context{.threads = 1});
  const TextureMeshResult two = textureMesh(test::makeSphere(32, 16), ex.view(), o, Context{.threads = 2});
  EXPECT_EQ(one.coords, two.coords);
  EXPECT_EQ(one.baseColor->pixels, two.baseColor->pixels);
  o.surface.seed = 2;
  const TextureMeshResult other = textureMesh(test::makeSphere(32, 16), ex.view(), o);
  EXPECT_NE(one.coords, other.coords);
}

// Pairs of neighboring chart texels whose exemplar coordinates are continuous only across the
// exemplar's wrap (as synthesis::wrapCrossings counts them in 2-D).
int64_t atlasWrapCrossings(const TextureMeshResult& r, int exemplarWidth, int exemplarHeight) {
  std::map<std::pair<int, int>, uint32_t> coordAt;
  for (size_t s = 0; s < r.sites.size(); ++s) coordAt[{r.sites.x[s], r.sites.y[s]}] = r.coords[s];
  auto crosses = [](float a, float b, int size) {
    const float d = std::fabs(a - b);
    return d > 2 && float(size) - d <= 2;
  };
  int64_t count = 0;
  for (const auto& [xy, c] : coordAt)
    for (const auto& next : {std::pair{xy.first + 1, xy.second}, std::pair{xy.first, xy.second + 1}}) {
      const auto n = coordAt.find(next);
      if (n != coordAt.end())
        count += crosses(synthesis::surfaceU(c), synthesis::surfaceU(n->second), exemplarWidth) ||
                 crosses(synthesis::surfaceV(c), synthesis::surfaceV(n->second), exemplarHeight);
    }
  return count;
}

TEST(TextureMesh, ClampedPhotographIsNeverReadAcrossItsBorder) {
  const Image photo = bundledExemplar("photos/rock.png");
  ASSERT_EQ(synthesis::detectExemplarWrap(photo), synthesis::ExemplarWrap::Clamp);
  TextureMeshOptions o = surfaceOptions(256);
  o.measure = false;
  const TextureMeshResult tile = textureMesh(test::makeSphere(32, 16), Exemplar(photo).view(), o);
  const TextureMeshResult clamp =
      textureMesh(test::makeSphere(32, 16), Exemplar(photo, synthesis::ExemplarWrap::Clamp).view(), o);
  EXPECT_GT(atlasWrapCrossings(tile, photo.width, photo.height), 0);
  EXPECT_EQ(atlasWrapCrossings(clamp, photo.width, photo.height), 0);
}

TEST(TextureMesh, InconsistentWindingIsRepairedAndReported) {
  // A new user's exporter flipped every other face: the job re-orients the mesh, so the charts
  // and the texture are those of the consistent mesh (before the repair: ~5x the charts).
  const Exemplar ex(bundledExemplar("brick.png"));
  TextureMeshOptions o = surfaceOptions(256);
  o.measure = false;
  const geometry::Mesh good = test::makeSphere(32, 16);
  geometry::Mesh bad = good;
  for (size_t t = 1; t < bad.triangleCount(); t += 2) std::swap(bad.triangles[t][1], bad.triangles[t][2]);
  const TextureMeshResult a = textureMesh(good, ex.view(), o);
  const TextureMeshResult b = textureMesh(bad, ex.view(), o);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.atlas.report.charts, b.atlas.report.charts);
  EXPECT_EQ(a.baseColor->pixels, b.baseColor->pixels);
  EXPECT_TRUE(a.preparation.repairs.empty());
  ASSERT_EQ(b.preparation.repairs.size(), 1u);
  EXPECT_NE(b.preparation.repairs[0].find("re-oriented " + std::to_string(bad.triangleCount() / 2)), std::string::npos)
      << b.preparation.repairs[0];
}

TEST(TextureMesh, SolidModeTexelsAreTheSolidTextureAtTheirPositions) {
  // A small exemplar keeps the solid precomputation short.
  const Image full = bundledExemplar("marble.png");
  Image small(32, 32, full.channels);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      for (int c = 0; c < full.channels; ++c) small.at(x, y, c) = full.at(x, y, c);
  const synthesis::SolidAnalysis solid = synthesis::analyzeSolid(small, small, small, {});
  TextureExemplar e;
  e.color = &small;
  e.solidAnalysis = &solid;
  TextureMeshOptions o = surfaceOptions(256);
  o.mode = TextureMode::Solid;
  const TextureMeshResult r = textureMesh(test::makeSphere(32, 16), e, o);
  EXPECT_LE(r.measures.seams.ratio, 1.1);
  EXPECT_GT(r.solid.voxelsRequested, 1000);
  EXPECT_FALSE(r.solid.trilinear());
  // Texels against a request of just their voxels (any subset gives the same values).
  std::vector<size_t> picked;
  std::vector<synthesis::Voxel> voxels;
  for (size_t s = 0; s < r.sites.size(); s += r.sites.size() / 40) {
    const Float3& p = r.atlas.fields.position.at(r.sites.x[s], r.sites.y[s]);
    picked.push_back(s);
    voxels.push_back({int64_t(std::floor(double(p.x) * r.textureScale)), int64_t(std::floor(double(p.y) * r.textureScale)),
                      int64_t(std::floor(double(p.z) * r.textureScale))});
  }
  const synthesis::SolidSynthesisResult direct = synthesis::synthesizeSolid(solid, voxels, o.solid);
  std::vector<float> color;
  synthesis::solidColors(direct.triples, small, small, small, color);
  const int channels = r.baseColor->channels;
  ASSERT_EQ(color.size(), picked.size() * size_t(channels));
  for (size_t i = 0; i < picked.size(); ++i)
    for (int c = 0; c < channels; ++c)
      EXPECT_FLOAT_EQ(r.baseColor->at(r.sites.x[picked[i]], r.sites.y[picked[i]], c), color[i * size_t(channels) + size_t(c)])
          << "site " << picked[i];
}

TEST(TextureMesh, CompanionMapsUseTheSameCoordinates) {
  const Exemplar ex(bundledExemplar("brick.png"));
  Image flatNormal(ex.image.width, ex.image.height, 3), rough(ex.image.width, ex.image.height, 1);
  for (int y = 0; y < ex.image.height; ++y)
    for (int x = 0; x < ex.image.width; ++x) {
      flatNormal.at(x, y, 0) = flatNormal.at(x, y, 1) = 0.5f;
      flatNormal.at(x, y, 2) = 1.0f;
      rough.at(x, y, 0) = ex.image.at(x, y, 0);  // roughness = the exemplar's red channel
    }
  TextureExemplar e = ex.view();
  e.normal = &flatNormal;
  e.roughness = &rough;
  TextureMeshOptions o = surfaceOptions(256);
  o.measure = false;
  const TextureMeshResult r = textureMesh(test::makeSphere(32, 16), e, o);
  ASSERT_TRUE(r.normal && r.metallicRoughness);
  for (size_t s = 0; s < r.sites.size(); s += 97) {
    const int x = r.sites.x[s], y = r.sites.y[s];
    EXPECT_NEAR(r.metallicRoughness->at(x, y, 1), r.baseColor->at(x, y, 0), 1e-5f);
    // A flat normal stays flat whatever the rotation of the texel's frame.
    EXPECT_NEAR(r.normal->at(x, y, 2), 1.0f, 1e-5f);
  }
  EXPECT_TRUE(r.mesh.materials.at(0).normalTexture);
  EXPECT_TRUE(r.mesh.materials.at(0).metallicRoughnessTexture);
}

TEST(TextureMesh, NormalMapsTurnWithTheTexture) {
  // A plane facing +z, the texture's "up" along +y: the exemplar's right is +x on the surface. A
  // normal map tilted to the exemplar's right must tilt the shaded normal towards +x, whatever
  // rotation the packer gave the chart, once decoded the way glTF viewers do (tangent along +u,
  // bitangent along +v of the mesh's UVs).
  const Exemplar ex(bundledExemplar("brick.png"));
  Image tilted(ex.image.width, ex.image.height, 3);
  const Eigen::Vector3f tilt = Eigen::Vector3f(0.5f, 0.0f, 1.0f).normalized();
  for (int y = 0; y < tilted.height; ++y)
    for (int x = 0; x < tilted.width; ++x)
      for (int c = 0; c < 3; ++c) tilted.at(x, y, c) = 0.5f * tilt[c] + 0.5f;
  TextureExemplar e = ex.view();
  e.normal = &tilted;
  TextureMeshOptions o = surfaceOptions(256, {0, 1, 0});
  o.measure = false;
  const geometry::Mesh plane = test::makePlane(8, 2.0f, 1.0f);
  const TextureMeshResult r = textureMesh(plane, e, o);
  ASSERT_TRUE(r.normal);
  int checked = 0;
  for (size_t s = 0; s < r.sites.size(); s += 53) {
    const SurfaceSample& sample = r.atlas.fields.samples.at(r.sites.x[s], r.sites.y[s]);
    const size_t t = sample.triangle;
    const Eigen::Vector3f p0 = r.mesh.positions[r.mesh.triangles[t][0]], p1 = r.mesh.positions[r.mesh.triangles[t][1]],
                          p2 = r.mesh.positions[r.mesh.triangles[t][2]];
    const Eigen::Vector2f u0 = r.mesh.uvs[3 * t], u1 = r.mesh.uvs[3 * t + 1], u2 = r.mesh.uvs[3 * t + 2];
    Eigen::Matrix2f duv;
    duv << u1 - u0, u2 - u0;
    Eigen::Matrix<float, 3, 2> dp;
    dp << p1 - p0, p2 - p0;
    const Eigen::Matrix<float, 3, 2> dPduv = dp * duv.inverse();  // columns: ∂P/∂u, ∂P/∂v
    const Eigen::Vector3f n(0, 0, 1);
    const Eigen::Vector3f tangent = (dPduv.col(0) - n * n.dot(dPduv.col(0))).normalized();
    const float handedness = n.cross(tangent).dot(dPduv.col(1)) < 0 ? -1.0f : 1.0f;
    const Eigen::Vector3f bitangent = handedness * n.cross(tangent);
    const float* m = r.normal->pixel(r.sites.x[s], r.sites.y[s]);
    const Eigen::Vector3f shaded =
        ((2 * m[0] - 1) * tangent + (2 * m[1] - 1) * bitangent + (2 * m[2] - 1) * n).normalized();
    EXPECT_NEAR(shaded.x(), tilt.x(), 0.05f) << "site " << s;
    EXPECT_NEAR(shaded.y(), 0.0f, 0.05f) << "site " << s;
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

TEST(TextureMesh, RefusesBadInput) {
  const Exemplar ex(bundledExemplar("brick.png"));
  geometry::Mesh empty;
  EXPECT_THROW(textureMesh(empty, ex.view(), surfaceOptions(256)), Error);
  TextureMeshOptions huge = surfaceOptions(256);
  huge.textureScale = 1e6;  // a whole exemplar inside one texel
  EXPECT_THROW(textureMesh(test::makeSphere(16, 8), ex.view(), huge), Error);
  Image wrongSize(8, 8, 1);
  TextureExemplar e = ex.view();
  e.roughness = &wrongSize;
  EXPECT_THROW(textureMesh(test::makeSphere(16, 8), e, surfaceOptions(256)), Error);
  TextureMeshOptions solid = surfaceOptions(256);
  solid.mode = TextureMode::Solid;
  EXPECT_THROW(textureMesh(test::makeSphere(16, 8), ex.view(), solid), Error);  // no solid analysis
}
