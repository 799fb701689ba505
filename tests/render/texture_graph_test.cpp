// SPDX-License-Identifier: GPL-3.0-or-later
// texfab texture with an exemplar graph (synthesis/synthesize_surface_graph.h): on a sphere, the
// exemplar that governs each scale is reproduced as faithfully as a single-exemplar surface
// texture of it; determinism; bad input.
#include "core/error.h"
#include "core/image_io.h"
#include "render/texture_mesh.h"
#include "synthesis/analyze_exemplar.h"
#include "synthesis/synthesize_surface_graph.h"
#include "tests/atlas/test_meshes.h"

#include <gtest/gtest.h>

#include <iostream>

using namespace texfab;
using namespace texfab::render;

namespace {

Image photo(const char* name) {
  return readImage(std::filesystem::path(TEXFAB_SOURCE_DIR) / "models" / "exemplars" / "photos" / name);
}

// The two-node graph: rock regions detailed by stone grain at 1/16 the scale.
struct RockStone {
  synthesis::ExemplarGraph graph;
  synthesis::GraphAnalysis analysis;
  RockStone() {
    graph.names = {"rock", "stone"};
    graph.exemplars = {photo("rock.png"), photo("stone.png")};
    graph.edges = {{0, 1, 4}};
    analysis = synthesis::analyzeGraph(graph);
  }
  TextureExemplar view() const {
    TextureExemplar e;
    e.color = &graph.exemplars[0];
    e.graph = &analysis;
    return e;
  }
};

TextureMeshOptions sphereOptions() {
  TextureMeshOptions o;
  o.atlas.pack.width = o.atlas.pack.height = 512;
  o.field.direction = {0, 0, 1};
  return o;
}

const geometry::Mesh& sphere() {
  static const geometry::Mesh mesh = test::makeSphere(64, 32);
  return mesh;
}

// The texture scale that puts `pixelsPerTexel` exemplar pixels in a texel of sphereOptions' atlas.
double scaleFor(double pixelsPerTexel) {
  const atlas::GenerateAtlasResult a = atlas::generateAtlas(sphere(), sphereOptions().atlas);
  return pixelsPerTexel * a.atlas.texelsPerUnit;
}

// Share of the sites whose coordinate points into node `node`'s tiles.
double shareOfNode(const TextureMeshResult& r, const synthesis::GraphAnalysis& a, int node) {
  size_t count = 0;
  for (uint32_t c : r.coords) count += int(synthesis::coordV(c) / uint32_t(a.side << synthesis::kSubpixelBits)) == node;
  return double(count) / double(r.coords.size());
}

} // namespace

// At one root pixel per texel the rock governs; sixteen times finer, the stone at its own
// resolution. Each within 1.3x the fidelity (7x7, exemplar space) of a single-exemplar surface
// texture of the governing exemplar at the same texel density.
TEST(TextureGraph, EachScaleIsAsFaithfulAsASingleExemplarSurfaceTexture) {
  const RockStone rs;
  for (const auto& [rootPixelsPerTexel, node] : {std::pair{1.0, 0}, std::pair{1.0 / 16, 1}}) {
    TextureMeshOptions o = sphereOptions();
    o.textureScale = scaleFor(rootPixelsPerTexel);
    const TextureMeshResult graph = textureMesh(sphere(), rs.view(), o);
    const Image& exemplar = rs.graph.exemplars[size_t(node)];
    // Neighbourhoods in the governing exemplar's pixels: J (root pixels) times the scale ratio.
    synthesis::SurfaceLevel sites = graph.sites;
    for (auto& j : sites.jacobian)
      for (float& v : j) v /= float(rootPixelsPerTexel);
    const double fidelity = measureSurfaceFidelity(sites, *graph.baseColor, exemplar, graph.atlas.fields, 1024).fidelity;

    synthesis::AnalysisOptions single;
    single.wrap = synthesis::detectExemplarWrap(exemplar);
    const synthesis::ExemplarAnalysis analysis = synthesis::analyzeExemplar(exemplar, single);
    TextureExemplar alone;
    alone.color = &exemplar;
    alone.analysis = &analysis;
    o.textureScale = scaleFor(1.0);
    const TextureMeshResult reference = textureMesh(sphere(), alone, o);
    const double ratio = fidelity / reference.measures.fidelity->fidelity;
    std::cout << rs.graph.names[size_t(node)] << ": graph " << fidelity << ", alone "
              << reference.measures.fidelity->fidelity << ", ratio " << ratio << ", share "
              << shareOfNode(graph, rs.analysis, node) << "\n";
    EXPECT_LE(ratio, 1.3) << rs.graph.names[size_t(node)];
    EXPECT_GE(shareOfNode(graph, rs.analysis, node), 0.8) << rs.graph.names[size_t(node)] << " does not govern";
    RecordProperty(rs.graph.names[size_t(node)] + "_fidelity_ratio", std::to_string(ratio));
  }
}

TEST(TextureGraph, ThreadsDoNotChangeTheTextureAndTheSeedDoes) {
  const RockStone rs;
  TextureMeshOptions o = sphereOptions();
  o.atlas.pack.width = o.atlas.pack.height = 256;
  o.measure = false;
  o.textureScale = scaleFor(0.25);
  const TextureMeshResult one = textureMesh(sphere(), rs.view(), o, Context{.threads = 1});
  const TextureMeshResult two = textureMesh(sphere(), rs.view(), o, Context{.threads = 2});
  EXPECT_EQ(one.coords, two.coords);
  EXPECT_EQ(one.baseColor->pixels, two.baseColor->pixels);
  o.surface.seed = 2;
  EXPECT_NE(textureMesh(sphere(), rs.view(), o).coords, one.coords);
}

// A companion map follows the colours through both exemplars and every level: with each exemplar's
// red channel as its roughness, every texel's roughness is its colour's red.
TEST(TextureGraph, CompanionMapsFollowTheColoursThroughEveryExemplar) {
  const RockStone rs;
  synthesis::GraphMap red{"roughness", {}};
  for (const Image& e : rs.graph.exemplars) {
    Image r(e.width, e.height, 1);
    for (int y = 0; y < e.height; ++y)
      for (int x = 0; x < e.width; ++x) r.at(x, y, 0) = e.at(x, y, 0);
    red.perNode.push_back(r);
  }
  const Image roughness = synthesis::graphMapAtlas(red);
  TextureExemplar e = rs.view();
  e.roughness = &roughness;
  TextureMeshOptions o = sphereOptions();
  o.atlas.pack.width = o.atlas.pack.height = 256;
  o.measure = false;
  o.textureScale = scaleFor(1) / 2;
  const TextureMeshResult r = textureMesh(sphere(), e, o);
  EXPECT_GT(shareOfNode(r, rs.analysis, 0), 0.05);
  EXPECT_GT(shareOfNode(r, rs.analysis, 1), 0.05);
  ASSERT_TRUE(r.metallicRoughness);
  for (size_t s = 0; s < r.sites.size(); ++s)
    ASSERT_EQ(r.metallicRoughness->at(r.sites.x[s], r.sites.y[s], 1), r.baseColor->at(r.sites.x[s], r.sites.y[s], 0))
        << "site " << s;
}

TEST(TextureGraph, RefusesWhatItCannotDo) {
  const RockStone rs;
  TextureMeshOptions o = sphereOptions();
  o.mode = TextureMode::Solid;
  EXPECT_THROW(textureMesh(sphere(), rs.view(), o), Error);
  o.mode = TextureMode::Surface;
  TextureExemplar withMaps = rs.view();
  withMaps.height = &rs.graph.exemplars[1];  // not packed as the graph's colours (graphMapAtlas)
  EXPECT_THROW(textureMesh(sphere(), withMaps, o), Error);
  EXPECT_THROW(textureMesh(sphere(), rs.view(), o, Context{.backend = Backend::Vulkan}), Error);
}
