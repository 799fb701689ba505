// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end tests of `texfab synth` and `texfab stats`, through the real binary.
#include "core/crop.h"
#include "core/image_io.h"
#include "synthesis/backend.h"
#include "synthesis/coord_map.h"
#include "synthesis/graph_file.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace texfab {
namespace {

using test::TempDir;

const std::string kBrick = std::string(TEXFAB_SOURCE_DIR) + "/models/exemplars/brick.png";

using Outcome = test::CliResult;

Outcome texfab(const std::string& args) { return test::runCli(args); }

std::string cacheArg(const TempDir& dir) { return " --cache-dir " + (dir / "cache").string(); }

TEST(CliSynth, BadInputGivesOneLineErrorAndNoOutput) {
  TempDir dir;
  { std::ofstream(dir / "text.png") << "not an image"; }
  Image tiny(1, 1, 3);
  writeImage(tiny, dir / "tiny.png");
  const std::string out = (dir / "out.png").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {(dir / "text.png").string() + " -o " + out, "text.png"},
      {(dir / "missing.png").string() + " -o " + out, "missing.png"},
      {(dir / "tiny.png").string() + " -o " + out, "1x1"},
      {kBrick + " -o " + out + " --size 70000x16", "70000"},
      {kBrick + " -o " + out + " --size 0x16", "--size: expected N or WxH, each 1 to 65536"},
      {kBrick + " -o " + out + " --size 65536x65536 -q", "GiB"},
      {kBrick + " -o " + out + " --jitter 2", "jitter"},
      {kBrick + " -o " + out + " --window 1,2,3", "--window: expected 4 comma-separated numbers"},
      {kBrick + " -o " + out + " --frobnicate", "frobnicate"},
      {kBrick + " -o " + (dir / "nofolder" / "x.png").string(), "nofolder"},
      {kBrick + " -o " + out + " --apply " + (dir / "tiny.png").string() + ":" + (dir / "c.png").string(), "1x1"},
  };
  for (const auto& [args, mention] : cases) {
    SCOPED_TRACE(args);
    const Outcome o = texfab("synth " + args + cacheArg(dir));
    EXPECT_NE(o.status, 0);
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_NE(o.err.find("error"), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(mention), std::string::npos) << o.err;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_FALSE(std::filesystem::exists(dir / "c.png"));
  }
  // Nothing but the inputs and the cache is left in the folder: no temporary files either.
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_TRUE(entry.path().filename() == "text.png" || entry.path().filename() == "tiny.png" ||
                entry.path().filename() == "cache")
        << entry.path();
}

TEST(CliSynth, CoordsApplyAndReportAgree) {
  TempDir dir;
  const Image exemplar = readImage(kBrick);
  // A companion "height map": 16-bit, one channel, a function of the exemplar pixel.
  Image height(exemplar.width, exemplar.height, 1, PixelFormat::UInt16);
  for (int y = 0; y < exemplar.height; ++y)
    for (int x = 0; x < exemplar.width; ++x) height.at(x, y, 0) = float(y * exemplar.width + x) / 65535.0f;
  writeImage(height, dir / "height.png");

  const Outcome o = texfab("synth " + kBrick + " -o " + (dir / "out.png").string() + " --size 200x150 --seed 9" +
                               " --coords " + (dir / "coords.png").string() + " --apply " +
                               (dir / "height.png").string() + ":" + (dir / "out_height.png").string() +
                               " --report " + (dir / "report.json").string() + cacheArg(dir));
  ASSERT_EQ(o.status, 0) << o.err;
  const Image out = readImage(dir / "out.png");
  const synthesis::CoordMap coords = synthesis::readCoordMap(dir / "coords.png", exemplar.width, exemplar.height);
  ASSERT_EQ(coords.width, 200);
  ASSERT_EQ(coords.height, 150);
  EXPECT_EQ(synthesis::applyCoords(coords, exemplar).pixels, out.pixels);
  const Image outHeight = readImage(dir / "out_height.png");
  EXPECT_EQ(outHeight.format, PixelFormat::UInt16);
  for (int y = 0; y < 150; ++y)
    for (int x = 0; x < 200; ++x) {
      const uint32_t c = coords.at(x, y);
      ASSERT_EQ(std::lround(outHeight.at(x, y, 0) * 65535.0f),
                long(synthesis::coordV(c) * uint32_t(exemplar.width) + synthesis::coordU(c)));
    }

  std::ifstream in(dir / "report.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  for (const char* key : {"fidelity", "histogram_distance", "coherence", "coverage", "shifted_correlation"})
    EXPECT_TRUE(report["measures"].contains(key)) << key;
  for (const char* key : {"load", "analysis", "synthesis", "resolve", "write"})
    EXPECT_TRUE(report["timings"].contains(key)) << key;
  EXPECT_FALSE(report["exemplar"]["analysis_cached"].get<bool>());

  // The second run finds the analysis in the cache and produces the same image.
  const Outcome again = texfab("synth " + kBrick + " -o " + (dir / "again.png").string() +
                                   " --size 200x150 --seed 9 --report " + (dir / "again.json").string() + cacheArg(dir));
  ASSERT_EQ(again.status, 0) << again.err;
  std::ifstream in2(dir / "again.json");
  EXPECT_TRUE(nlohmann::json::parse(in2)["exemplar"]["analysis_cached"].get<bool>());
  EXPECT_EQ(readImage(dir / "again.png").pixels, out.pixels);
}

// A tileable output a few times the exemplar's size is checked for repetition (the shifted
// self-correlation at the exemplar's period, as stats measures it): the report says whether it
// repeats, and exactly then a one-line warning does too.
TEST(CliSynth, SmallTilesThatRepeatTheExemplarAreReportedAndWarned) {
  TempDir dir;
  auto synth = [&](const std::string& args) {
    const Outcome o = texfab("synth " + kBrick + " -o " + (dir / "t.png").string() + " --tileable -q " + args +
                             " --report " + (dir / "t.json").string() + cacheArg(dir));
    EXPECT_EQ(o.status, 0) << o.err;
    std::ifstream in(dir / "t.json");
    return std::pair{o.err, nlohmann::json::parse(in)};
  };
  auto warned = [](const std::string& err) { return err.find("repeats its 96x96 exemplar") != std::string::npos; };
  // No jitter: the tile is the exemplar repeated, whatever the synthesis.
  {
    const auto [err, report] = synth("--size 192 --jitter 0");
    EXPECT_GT(report["repetition"]["shifted_correlation"].get<double>(), 0.9);
    EXPECT_TRUE(report["repetition"]["repeats"].get<bool>());
    EXPECT_TRUE(warned(err)) << err;
  }
  // Twice the exemplar: the warning follows the measure, which is the one stats reports.
  for (const char* seed : {"1", "2", "3"}) {
    const auto [err, report] = synth("--size 192 --seed " + std::string(seed));
    const double repetition = report["repetition"]["shifted_correlation"].get<double>();
    EXPECT_DOUBLE_EQ(repetition, report["measures"]["shifted_correlation"].get<double>());
    EXPECT_EQ(report["repetition"]["repeats"].get<bool>(), repetition > report["repetition"]["limit"].get<double>());
    EXPECT_EQ(warned(err), repetition > 0.25) << "seed " << seed << ": " << err;
  }
  // Four times the exemplar, as --help advises: no repetition.
  {
    const auto [err, report] = synth("--size 384 --seed 2");
    EXPECT_LE(report["repetition"]["shifted_correlation"].get<double>(), 0.25);
    EXPECT_FALSE(warned(err)) << err;
  }
}

TEST(CliSynth, WindowsMatchTheFullImage) {
  TempDir dir;
  ASSERT_EQ(texfab("synth " + kBrick + " -q -o " + (dir / "full.png").string() + " --window -64,-32,256,192 --threads 2" +
                       cacheArg(dir)).status, 0);
  ASSERT_EQ(texfab("synth " + kBrick + " -q -o " + (dir / "part.png").string() + " --window 10,-5,40,30 --threads 1" +
                       cacheArg(dir)).status, 0);
  const Image full = readImage(dir / "full.png"), part = readImage(dir / "part.png");
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(part.at(x, y, c), full.at(x + 74, y + 27, c));
}

// synth --graph: a two-exemplar graph at two zooms; windows agree with the full image; tiles; a bad
// graph file, or flags that do not go together, is one line and no output.
TEST(CliSynth, ExemplarGraphsAtAnyZoom) {
  TempDir dir;
  const std::string photos = std::string(TEXFAB_SOURCE_DIR) + "/models/exemplars/photos/";
  auto graphFile = [&](const std::string& name, const std::string& edges) {
    std::ofstream(dir / name) << R"({"exemplars": [{"name": "rock", "image": ")" << photos << R"(rock.png"},
      {"name": "stone", "image": ")" << photos << R"(stone.png"}], "edges": [)" << edges << "]}";
    return (dir / name).string();
  };
  const std::string graph = graphFile("g.json", R"({"from": "rock", "to": "stone", "scale": 16})");
  for (const char* zoom : {"1", "16"}) {
    const Outcome o = texfab("synth --graph " + graph + " --zoom " + zoom + " -q -o " + (dir / "full.png").string() +
                             " --window -20,-10,96,64 --report " + (dir / "r.json").string());
    ASSERT_EQ(o.status, 0) << o.err;
    ASSERT_EQ(texfab("synth --graph " + graph + " --zoom " + zoom + " -q -o " + (dir / "part.png").string() +
                     " --window 5,7,30,20 --threads 1").status, 0);
    const Image full = readImage(dir / "full.png"), part = readImage(dir / "part.png");
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 30; ++x)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(part.at(x, y, c), full.at(x + 25, y + 17, c)) << "zoom " << zoom;
    std::ifstream in(dir / "r.json");
    const nlohmann::json report = nlohmann::json::parse(in);
    EXPECT_EQ(report["graph"]["deepest_level"], 7 + 4);
    EXPECT_EQ(report["graph"]["colors"], "coarse");
  }
  // --tileable: a 256 tile wraps all 8 levels of the 128-pixel rock at zoom 1; a 96 tile the finest 5,
  // and says so (SynthesizeGraph.TileableOutputsRepeatAtTheirPeriod checks the repetition).
  for (const auto& [size, warning] : {std::pair{"256", ""}, std::pair{"96", "a 96x96 tile at zoom 1 wraps 5 of 8 levels"}}) {
    const Outcome o = texfab("synth --graph " + graph + " --tileable --size " + size + " -o " +
                             (dir / "tile.png").string() + " --report " + (dir / "t.json").string());
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_EQ(o.err.find("warning") != std::string::npos, *warning != 0) << o.err;
    EXPECT_NE(o.err.find(warning), std::string::npos) << o.err;
    std::ifstream report(dir / "t.json");
    EXPECT_EQ(nlohmann::json::parse(report)["parameters"]["tileable"], true);
  }
  // Regions: a rectangle for one edge, a mask image for the other.
  Image mask(128, 128, 1);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) mask.at(x, y, 0) = x >= 64 ? 1.0f : 0.0f;
  writeImage(mask, dir / "mask.png");
  std::ofstream(dir / "regions.json") << R"({"exemplars": [{"name": "rock", "image": ")" << photos << R"(rock.png"},
    {"name": "stone", "image": ")" << photos << R"(stone.png"}, {"name": "wood", "image": ")" << photos << R"(wood.png"}],
    "edges": [{"from": "rock", "to": "stone", "scale": 16, "region": [0, 0, 64, 128]},
              {"from": "rock", "to": "wood", "scale": 16, "region": "mask.png"}]})";
  ASSERT_EQ(texfab("synth --graph " + (dir / "regions.json").string() + " --zoom 16 --size 64 -q -o " +
                   (dir / "regions.png").string()).status, 0);
  const std::string out = (dir / "out.png").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--graph " + graphFile("b1.json", R"({"from": "rock", "to": "stone", "scale": 12})"),
       "scale 12 must be a power of two greater than 1"},
      {"--graph " + graphFile("b2.json", R"({"from": "rock", "to": "gravel", "scale": 4})"),
       "no exemplar is named 'gravel'"},
      {"--graph " + graphFile("b3.json", R"({"from": "rock", "to": "stone", "scale": 2, "region": [0, 0, 0, 8]})"),
       "region width and height must be 1 to 128"},
      {"--graph " + graphFile("b7.json", R"({"from": "rock", "to": "stone", "scale": 2, "weight": 1})"),
       "unknown field 'weight'"},
      {"--graph " + graphFile("b4.json", R"({"from": "rock", "to": "stone", "scale": 1})"), "greater than 1"},
      {"--graph " + graphFile("b5.json", R"({"from": "rock", "to": "stone", "scale": 32})"),
       "use exemplars of at least 256 pixels or a smaller scale"},
      {"--graph " + graphFile("b6.json", ""), "'stone' is not reached from the root 'rock'"},
      {"--graph " + (dir / "none.json").string(), "cannot open the graph file"},
      {"--graph " + graph + " --zoom 3", "--zoom: expected a power of two"},
      {"--graph " + graph + " --tileable --window 0,0,64,64", "cannot be combined"},
      {"--graph " + graph + " --tileable --size 47", "must be a multiple of the interleave (2)"},
      {kBrick + " --graph " + graph, "not both"},
      {kBrick + " --zoom 2", "--zoom needs --graph"},
  };
  for (const auto& [args, mention] : cases) {
    SCOPED_TRACE(args);
    const Outcome o = texfab("synth " + args + " -q -o " + out);
    EXPECT_NE(o.status, 0);
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_NE(o.err.find(mention), std::string::npos) << o.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

// Exemplars of different sizes: the smaller are magnified to the largest side and every edge's
// scale follows, so that each pixel keeps its size (synthesis::withOneSide). A 64² rock root detailed
// by the 128² stone at scale 16 reads as a 128² root magnified twice, an edge of scale 8 and its
// region (in the rock's own pixels) magnified; --zoom counts the rock's pixels as given, so that the
// output is the one of the graph given at one size, at half the zoom. The other way round, a 64² stone under the 128² rock, the edge's scale doubles. A finer exemplar that
// spans more than half of the coarser one is refused with the scale it needs.
TEST(CliSynth, ExemplarGraphsMixSizes) {
  TempDir dir;
  const std::string photos = std::string(TEXFAB_SOURCE_DIR) + "/models/exemplars/photos/";
  const Image rock = readImage(photos + "rock.png"), stone = readImage(photos + "stone.png");
  writeImage(crop(rock, 0, 0, 64, 64), dir / "rock64.png");  // 8-bit values: read back as they are
  writeImage(crop(stone, 0, 0, 64, 64), dir / "stone64.png");
  auto graphFile = [&](const std::string& name, const std::string& root, const std::string& detail, const std::string& edge) {
    std::ofstream(dir / name) << R"({"exemplars": [{"name": "rock", "image": ")" << root << R"("},
      {"name": "stone", "image": ")" << detail << R"("}], "edges": [{"from": "rock", "to": "stone", )" << edge << "}]}";
    return (dir / name).string();
  };
  const std::string mixed = graphFile("mixed.json", "rock64.png", photos + "stone.png", R"("scale": 16, "region": [0, 0, 32, 64])");
  const synthesis::ExemplarGraph g = synthesis::readExemplarGraph(mixed);
  EXPECT_EQ(g.side(), 128);
  EXPECT_EQ(g.exemplars[1].pixels, stone.pixels);  // the largest as given
  EXPECT_EQ(g.rootMagnification, 2);
  ASSERT_EQ(g.edges.size(), 1u);
  EXPECT_EQ(g.edges[0].octaves, 3);
  EXPECT_TRUE(g.edges[0].covers(63, 127, 128));
  EXPECT_FALSE(g.edges[0].covers(64, 0, 128));
  const synthesis::ExemplarGraph under =
      synthesis::readExemplarGraph(graphFile("under.json", photos + "rock.png", "stone64.png", R"("scale": 16)"));
  EXPECT_EQ(under.side(), 128);
  EXPECT_EQ(under.rootMagnification, 1);
  EXPECT_EQ(under.edges[0].octaves, 5);

  // The same texture described at one size: the rock as withOneSide magnified it (a float EXR, so
  // that it reads back bit for bit) and the edge's scale halved, seen at half the zoom, since a
  // pixel of the rock as given is two of it.
  Image magnifiedRock = g.exemplars[0];
  magnifiedRock.format = PixelFormat::Float;
  writeImage(magnifiedRock, dir / "rock128.exr");
  ASSERT_EQ(readImage(dir / "rock128.exr").pixels, magnifiedRock.pixels);
  const std::string one = graphFile("one.json", "rock128.exr", photos + "stone.png", R"("scale": 8, "region": [0, 0, 64, 128])");
  for (const auto& [zoom, oneZoom] : {std::pair{"1", "0.5"}, std::pair{"16", "8"}}) {
    const Outcome o = texfab("synth --graph " + mixed + " --zoom " + zoom + " --size 64 -q -o " + (dir / "a.png").string() +
                             " --report " + (dir / "r.json").string() + cacheArg(dir));
    ASSERT_EQ(o.status, 0) << o.err;
    ASSERT_EQ(texfab("synth --graph " + one + " --zoom " + oneZoom + " --size 64 -q -o " + (dir / "b.png").string() +
                     cacheArg(dir)).status, 0);
    EXPECT_EQ(readImage(dir / "a.png").pixels, readImage(dir / "b.png").pixels) << "zoom " << zoom;
    std::ifstream in(dir / "r.json");
    EXPECT_EQ(nlohmann::json::parse(in)["graph"]["root_magnification"], 2);
  }
  // Each block of the magnified rock averages to its pixel as given.
  const Image rock64 = crop(rock, 0, 0, 64, 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) {
        const float block = 0.25f * (magnifiedRock.at(2 * x, 2 * y, c) + magnifiedRock.at(2 * x + 1, 2 * y, c) +
                                     magnifiedRock.at(2 * x, 2 * y + 1, c) + magnifiedRock.at(2 * x + 1, 2 * y + 1, c));
        ASSERT_NEAR(block, rock64.at(x, y, c), 1e-6f);
      }

  const Outcome refused = texfab("synth --graph " + graphFile("wide.json", "rock64.png", photos + "stone.png", R"("scale": 2)") +
                                 " --size 32 -q -o " + (dir / "wide.png").string());
  EXPECT_NE(refused.status, 0);
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_NE(refused.err.find("the second spans 64 pixels of the first"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("a scale of at least 4"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "wide.png"));
}

// synth --graph --apply: a graph's companion maps follow the colours. With each exemplar's own image
// as its "normal" map and its red channel as its "height" map, the applied maps are the output's
// colours and their red channel, at a coarse and a fine zoom; --coords gives them again. Maps missing on one exemplar, of
// another size or of an unknown kind, and a map the graph does not give, are refused.
TEST(CliSynth, ExemplarGraphCompanionMapsFollowTheColours) {
  TempDir dir;
  const std::string photos = std::string(TEXFAB_SOURCE_DIR) + "/models/exemplars/photos/";
  for (const char* name : {"rock", "stone"}) {
    const Image e = readImage(photos + name + ".png");
    Image red(e.width, e.height, 1);
    for (int y = 0; y < e.height; ++y)
      for (int x = 0; x < e.width; ++x) red.at(x, y, 0) = e.at(x, y, 0);
    writeImage(red, dir / (std::string(name) + "-h.png"));
  }
  auto graphFile = [&](const std::string& name, const std::string& rockMaps, const std::string& stoneMaps,
                       const std::string& colors = "own") {
    std::ofstream(dir / name) << R"({"exemplars": [{"name": "rock", "image": ")" << photos << R"(rock.png", "maps": )"
                              << rockMaps << R"(}, {"name": "stone", "image": ")" << photos << R"(stone.png", "maps": )"
                              << stoneMaps << R"(}], "edges": [{"from": "rock", "to": "stone", "scale": 16}], "colors": ")"
                              << colors << R"("})";
    return (dir / name).string();
  };
  const std::string rockMaps = R"({"normal": ")" + photos + R"(rock.png", "height": "rock-h.png"})";
  const std::string stoneMaps = R"({"normal": ")" + photos + R"(stone.png", "height": "stone-h.png"})";
  const std::string graph = graphFile("g.json", rockMaps, stoneMaps);
  // In the rock's colours (the default) the stone's colours move, its maps do not.
  const Outcome coarse = texfab("synth --graph " + graphFile("coarse.json", rockMaps, stoneMaps, "coarse") +
                                " --zoom 16 --size 96 -q -o " + (dir / "cc.png").string() + " --apply normal:" +
                                (dir / "cn.png").string());
  ASSERT_EQ(coarse.status, 0) << coarse.err;
  EXPECT_NE(readImage(dir / "cn.png").pixels, readImage(dir / "cc.png").pixels);
  for (const char* zoom : {"1", "16"}) {
    SCOPED_TRACE(zoom);
    const Outcome o = texfab("synth --graph " + graph + " --zoom " + zoom + " --size 96 -q -o " +
                             (dir / "c.png").string() + " --apply normal:" + (dir / "n.png").string() +
                             " --apply height:" + (dir / "h.png").string() + " --coords " + (dir / "xy.png").string());
    ASSERT_EQ(o.status, 0) << o.err;
    const Image c = readImage(dir / "c.png"), n = readImage(dir / "n.png"), h = readImage(dir / "h.png");
    EXPECT_EQ(n.pixels, c.pixels);
    // The coordinate map names positions in the packed exemplars: it gives the colours again.
    const synthesis::ExemplarGraph g = synthesis::readExemplarGraph(graph);
    const Image atlas = synthesis::graphMapAtlas(*g.map("normal"));
    writeImage(synthesis::applyCoords(synthesis::readCoordMap(dir / "xy.png", atlas.width, atlas.height), atlas),
               dir / "again.png");
    EXPECT_EQ(readImage(dir / "again.png").pixels, c.pixels);
    ASSERT_EQ(h.channels, 1);
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x) ASSERT_EQ(h.at(x, y, 0), c.at(x, y, 0)) << x << "," << y;
  }
  const std::string out = (dir / "out.png").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {graphFile("m1.json", R"({"height": "rock-h.png"})", "{}"), "'stone' has no height map while others have one"},
      {graphFile("m2.json", R"({"height": "rock-h.png"})", R"({"height": ")" + photos + R"(dune.png"})"),
       "the height map of exemplar 'stone' is 128x96, its exemplar 128x128"},
      {graphFile("m3.json", R"({"gloss": "rock-h.png"})", R"({"gloss": "stone-h.png"})"), "unknown field 'gloss'"},
      {graph + " --apply roughness:" + (dir / "r.png").string(), "gives no 'roughness' map"},
      {graphFile("c.json", rockMaps, stoneMaps, "fine"), "colors 'fine' must be 'coarse'"},
  };
  for (const auto& [args, mention] : cases) {
    SCOPED_TRACE(args);
    const Outcome o = texfab("synth --graph " + args + " --size 16 -q -o " + out);
    EXPECT_NE(o.status, 0);
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_NE(o.err.find(mention), std::string::npos) << o.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

// --backend: an unknown name is a usage error; Vulkan without the device asked for is one line
// (exit 2, no output); auto falls back to the CPU and says so; with a usable device, vulkan writes
// the CPU's bytes. info --devices lists what the loader finds.
TEST(CliSynth, BackendFlags) {
  TempDir dir;
  const std::string common = " -o " + (dir / "out.png").string() + " --size 48x40 --seed 4" + cacheArg(dir);
  const Outcome bad = texfab("synth " + kBrick + common + " --backend gpu");
  EXPECT_EQ(bad.status, 1) << bad.err;
  EXPECT_NE(bad.err.find("expected cpu|vulkan|auto"), std::string::npos) << bad.err;

  const Outcome missing = texfab("synth " + kBrick + common + " --backend vulkan --device 999");
  EXPECT_EQ(missing.status, 2) << missing.err;
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  EXPECT_NE(missing.err.find("error: --backend vulkan: "), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.png"));

  ASSERT_EQ(texfab("synth " + kBrick + common + " -q").status, 0);
  const Image cpu = readImage(dir / "out.png");
  const Outcome fallBack = texfab("synth " + kBrick + common + " --backend auto --device 999");
  ASSERT_EQ(fallBack.status, 0) << fallBack.err;
  EXPECT_NE(fallBack.err.find("backend: CPU ("), std::string::npos) << fallBack.err;
  EXPECT_EQ(readImage(dir / "out.png").pixels, cpu.pixels);

  const Outcome devices = texfab("info --devices --json");
  ASSERT_EQ(devices.status, 0) << devices.err;
  const nlohmann::json list = nlohmann::json::parse(devices.out);
  EXPECT_EQ(list.size(), synthesis::vulkanDevices().size());
  if (const std::string missing = test::vulkanDeviceMissing(); !missing.empty()) GTEST_SKIP() << missing;
  const Outcome vulkan = texfab("synth " + kBrick + common + " --backend vulkan --device 0");
  ASSERT_EQ(vulkan.status, 0) << vulkan.err;
  EXPECT_NE(vulkan.err.find("backend: Vulkan: "), std::string::npos) << vulkan.err;
  EXPECT_EQ(readImage(dir / "out.png").pixels, cpu.pixels);
}

TEST(CliSynth, StatsReportsTheMeasures) {
  TempDir dir;
  ASSERT_EQ(texfab("synth " + kBrick + " -q -o " + (dir / "o.png").string() + " --size 256 --coords " +
                       (dir / "c.exr").string() + cacheArg(dir)).status, 0);
  const Outcome o = texfab("stats " + (dir / "o.png").string() + " --exemplar " + kBrick + " --coords " +
                               (dir / "c.exr").string() + " --baseline-2d --report " + (dir / "s.json").string() +
                               cacheArg(dir));
  ASSERT_EQ(o.status, 0) << o.err;
  for (const char* word : {"fidelity", "completeness", "histogram", "coherence", "coverage", "shifted", "fidelity ratio",
                           "completeness ratio"})
    EXPECT_NE(o.out.find(word), std::string::npos) << word;
  std::ifstream in(dir / "s.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_GT(s["coherence"].get<double>(), 0.0);
  EXPECT_LT(s["coherence"].get<double>(), 1.0);
  // The 2-D baseline is the synthesis `synth` made with its defaults (seed 1): the same image.
  EXPECT_EQ(s["fidelity_ratio"].get<double>(), 1.0);
  EXPECT_EQ(s["completeness_ratio"].get<double>(), 1.0);
  EXPECT_EQ(s["baseline_2d"]["histogram_distance"], s["histogram_distance"]);
  // A tiling of the exemplar measures as one.
  ASSERT_EQ(texfab("synth " + kBrick + " -q -o " + (dir / "t.png").string() + " --size 256 --jitter 0 --coords " +
                       (dir / "t.png.coords.png").string() + cacheArg(dir)).status, 0);
  const Outcome t = texfab("stats " + (dir / "t.png").string() + " --exemplar " + kBrick + " --coords " +
                               (dir / "t.png.coords.png").string() + " --report " + (dir / "t.json").string());
  ASSERT_EQ(t.status, 0) << t.err;
  std::ifstream in2(dir / "t.json");
  const nlohmann::json tj = nlohmann::json::parse(in2);
  EXPECT_DOUBLE_EQ(tj["coherence"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(tj["fidelity"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(tj["completeness"].get<double>(), 0.0);  // the centre 2x2 tiles hold every window
  EXPECT_NEAR(tj["shifted_correlation"].get<double>(), 1.0, 1e-9);
}

TEST(CliSynth, HelpListsEveryCommandAndOption) {
  TempDir dir;
  const Outcome top = texfab("--help");
  EXPECT_EQ(top.status, 0);
  EXPECT_NE(top.out.find("synth"), std::string::npos);
  EXPECT_NE(top.out.find("stats"), std::string::npos);
  const Outcome synth = texfab("synth --help");
  for (const char* flag : {"--size", "--seed", "--jitter", "--window", "--tileable", "--coords", "--apply", "--threads",
                           "--report"})
    EXPECT_NE(synth.out.find(flag), std::string::npos) << flag;
  EXPECT_NE(texfab("").status, 0);  // no command
}

} // namespace
} // namespace texfab
