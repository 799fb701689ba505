// SPDX-License-Identifier: GPL-3.0-or-later
// texfab fracture and texfab cut end to end on the bundled model: files the Khronos validator and
// assimp accept, one node per piece, a report whose volumes add up and whose cracks match, pieces
// as separate files, the same bytes on one and two threads; bad input fails with one line, exit 1
// (the command line) or 2 (the files), and no output.
#include "core/crop.h"
#include "core/image.h"
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace {
namespace fs = std::filesystem;
using texfab::test::TempDir;

const fs::path kSource(TEXFAB_SOURCE_DIR);
const fs::path kModel = kSource / "models" / "meshes" / "elephant.off";

std::string quoted(const fs::path& p) { return std::string("'").append(p.string()).append("'"); }

// Runs `texfab <command> <args>`.
texfab::test::CliResult texfab(const std::string& command, const std::string& args) {
  return texfab::test::runCli(command + " " + args);
}

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A 32x32 crop of the bundled marble (a short solid precomputation), written into `dir`.
fs::path smallMarble(const fs::path& dir) {
  const texfab::Image full = texfab::readImage(kSource / "models" / "exemplars" / "marble.png");
  texfab::writeImage(texfab::crop(full, 0, 0, 32, 32), dir / "marble32.png");
  return dir / "marble32.png";
}

void expectValid(const fs::path& file) {
  if (const std::string missing = texfab::test::gltfValidatorMissing(); missing.empty()) {
    const std::string report = texfab::test::validateGltf(file);
    EXPECT_EQ(report.rfind("errors=0 warnings=0 ", 0), 0u) << file << ":\n" << report;
  } else {
    std::cout << "glTF validator skipped: " << missing << "\n";
  }
  if (texfab::test::run("command -v assimp >/dev/null 2>&1") == 0) {
    EXPECT_EQ(texfab::test::run("assimp info " + quoted(file) + " >/dev/null 2>&1"), 0) << "assimp cannot load " << file;
  }
}

class CliBreak : public ::testing::Test {
protected:
  TempDir dir{"texfab-break-cli"};
  fs::path exemplar = smallMarble(dir.path());
  // At the elephant's atlas density (about 0.75 texels per unit per texel of the side): the
  // default scale, that of a 2048² atlas, would minify the exemplar 4-16 times in these small atlases.
  std::string common(const std::string& output, int resolution = 256) const {
    const std::string size = std::to_string(resolution);
    return quoted(kModel) + " -e " + quoted(exemplar) + " --resolution " + size + " --interior-resolution " + size +
           " --texture-scale " + std::to_string(0.75 * resolution) +
           " -q --cache-dir " + quoted(dir / "cache") + " -o " + quoted(dir / output);
  }
};

TEST_F(CliBreak, FractureWritesValidPiecesAndAReport) {
  // 512²: the crack-edge seam measure then has some 600 edge samples (at 256², about 100: its
  // ratio then varies by more than 0.3 with the seed).
  const auto run = texfab("fracture", common("pieces.glb", 512) + " --pieces 5 --report " + quoted(dir / "r.json") +
                                           " --separate " + quoted(dir / "parts"));
  ASSERT_EQ(0, run.status) << run.err;
  expectValid(dir / "pieces.glb");
  const nlohmann::json r = nlohmann::json::parse(readText(dir / "r.json"));
  EXPECT_EQ(r["piece_count"], 5);
  EXPECT_LT(std::fabs(r["volume_relative_error"].get<double>()), 1e-6);
  EXPECT_GT(r["cut_area"].get<double>(), 0.0);
  const nlohmann::json& match = r["measures"]["crack_match"];
  EXPECT_LT(match["difference"].get<double>(), 0.3 * match["unrelated_difference"].get<double>());
  EXPECT_LE(r["measures"]["crack_edge_seams"]["ratio"].get<double>(), 1.1);
  // One node (named, placed at its centroid) and mesh per piece, two materials shared.
  const std::string glb = readText(dir / "pieces.glb");
  const nlohmann::json doc = nlohmann::json::parse(texfab::test::glbChunks(glb).first);
  ASSERT_EQ(doc["nodes"].size(), 5u);
  EXPECT_EQ(doc["meshes"].size(), 5u);
  EXPECT_EQ(doc["materials"].size(), 2u);
  EXPECT_EQ(doc["nodes"][0]["name"], "piece_000");
  EXPECT_EQ(doc["nodes"][0]["translation"].size(), 3u);
  for (int i = 0; i < 5; ++i) {
    const fs::path part = dir / "parts" / ("piece_00" + std::to_string(i) + ".glb");
    ASSERT_TRUE(fs::exists(part)) << part;
    EXPECT_EQ(texfab::geometry::readMesh(part).triangleCount(), r["pieces"][size_t(i)]["triangles"].get<size_t>());
  }
  expectValid(dir / "parts" / "piece_000.glb");
  // Each piece carries only its own texels: together they weigh little more than the whole.
  uintmax_t parts = 0;
  for (const auto& e : fs::directory_iterator(dir / "parts")) parts += fs::file_size(e.path());
  EXPECT_LT(parts, 2 * fs::file_size(dir / "pieces.glb")) << parts;
}

// By default the cut faces get the outer texture's texel density, in an atlas sized to fit (at 512^2
// the gutters of the small charts leave 0.65 of it to them, like the outer atlas).
TEST_F(CliBreak, CutFacesKeepTheOuterDensity) {
  const auto run = texfab("fracture", quoted(kModel) + " -e " + quoted(exemplar) + " --resolution 512 --pieces 12 -q" +
                                          " --cache-dir " + quoted(dir / "cache") + " -o " + quoted(dir / "d.glb") +
                                          " --report " + quoted(dir / "d.json"));
  ASSERT_EQ(0, run.status) << run.err;
  const nlohmann::json r = nlohmann::json::parse(readText(dir / "d.json"));
  EXPECT_DOUBLE_EQ(r["interior"]["texels_per_unit"].get<double>(), r["atlas"]["texels_per_unit"].get<double>());
  EXPECT_GE(r["interior"]["utilization"].get<double>(), 0.6);
  expectValid(dir / "d.glb");
}

TEST_F(CliBreak, SameBytesOnOneAndTwoThreads) {
  for (const auto& [output, threads] : {std::pair{"a.glb", "1"}, std::pair{"b.glb", "2"}}) {
    const auto run = texfab("fracture", common(output) + " --pieces 4 --threads " + threads);
    ASSERT_EQ(0, run.status) << run.err;
  }
  EXPECT_EQ(readText(dir / "a.glb"), readText(dir / "b.glb"));
}

// The cut faces' solid synthesis (and the outer texture's) on the Vulkan backend: the CPU's bytes.
TEST_F(CliBreak, VulkanBackendWritesTheCpusBytes) {
  if (const std::string missing = texfab::test::vulkanDeviceMissing(); !missing.empty()) GTEST_SKIP() << missing;
  for (const auto& [output, backend] : {std::pair{"cpu.glb", "cpu"}, std::pair{"vulkan.glb", "vulkan --device 0"}}) {
    const auto run = texfab("fracture", common(output, 128) + " --pieces 3 --backend " + backend);
    ASSERT_EQ(0, run.status) << run.err;
  }
  EXPECT_EQ(readText(dir / "cpu.glb"), readText(dir / "vulkan.glb"));
}

// The tiles method on the cut faces and outside (solid mode): a valid file, the same bytes on one
// and two threads, and the method in the report.
TEST_F(CliBreak, TilesMethodOnCutFacesAndOutside) {
  for (const auto& [output, threads] : {std::pair{"t1.glb", "1"}, std::pair{"t2.glb", "2"}}) {
    const auto run = texfab("cut", common(output) + " --mode solid --solid-method tiles --tile-size 16 --plane 0,0,0,1,0.3,0.2" +
                                       " --threads " + threads + " --report " + quoted(dir / "t.json"));
    ASSERT_EQ(0, run.status) << run.err;
  }
  expectValid(dir / "t1.glb");
  EXPECT_EQ(readText(dir / "t1.glb"), readText(dir / "t2.glb"));
  const nlohmann::json r = nlohmann::json::parse(readText(dir / "t.json"));
  EXPECT_EQ(r["parameters"]["solid_method"], "tiles") << r["parameters"].dump();
}

TEST_F(CliBreak, CutByTwoPlanesAndAPlaneThatMisses) {
  const auto run = texfab("cut", common("cut.glb") + " --plane 0,0,0,1,0,0 --plane 0,0,0,0,1,0.2 --report " +
                                      quoted(dir / "r.json"));
  ASSERT_EQ(0, run.status) << run.err;
  expectValid(dir / "cut.glb");
  const nlohmann::json r = nlohmann::json::parse(readText(dir / "r.json"));
  EXPECT_GE(r["piece_count"].get<int>(), 4);
  EXPECT_LT(std::fabs(r["volume_relative_error"].get<double>()), 1e-6);
  const auto missed = texfab("cut", common("missed.glb") + " --plane 0,0,50,0,0,1 --report " + quoted(dir / "m.json"));
  ASSERT_EQ(0, missed.status) << missed.err;
  EXPECT_NE(missed.err.find("plane 1 misses the model"), std::string::npos) << missed.err;
  EXPECT_EQ(nlohmann::json::parse(readText(dir / "m.json"))["piece_count"], 1);
}

TEST_F(CliBreak, RepairsAnOpenModel) {
  // A cube with one face missing: the hole is filled (and shows the interior).
  std::ofstream(dir / "open.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                     "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\n";
  const auto run = texfab("cut", quoted(dir / "open.obj") + " --interior " + quoted(exemplar) +
                                      " --interior-resolution 128 -o " + quoted(dir / "c.glb") + " --plane 0.5,0.5,0.5,1,0,0");
  ASSERT_EQ(0, run.status) << run.err;
  EXPECT_NE(run.err.find("repaired: filled 1 hole "), std::string::npos) << run.err;
  expectValid(dir / "c.glb");
}

// Two tetrahedra through each other (as Suzanne's eyes go through her head): rebuilt as the
// volume they enclose, with a warning, then fractured.
TEST_F(CliBreak, RebuildsAModelThatIntersectsItself) {
  std::ofstream(dir / "crossing.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0.2 0.2 -0.5\nv 1 1 0.3\nv 0.1 1 0.4\nv 0.3 0.2 1\n"
                                         "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\nf 5 7 6\nf 5 6 8\nf 6 7 8\nf 7 5 8\n";
  const auto run = texfab("fracture", quoted(dir / "crossing.obj") + " --interior " + quoted(exemplar) +
                                          " --pieces 3 --interior-resolution 128 -o " + quoted(dir / "f.glb"));
  ASSERT_EQ(0, run.status) << run.err;
  EXPECT_NE(run.err.find("intersects itself"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("rebuilt as the volume it encloses"), std::string::npos) << run.err;
  expectValid(dir / "f.glb");
}

TEST_F(CliBreak, BadInputFailsWithOneLineAndNoOutput) {
  const std::string model = quoted(kModel), interior = " --interior " + quoted(exemplar);
  // Exit 1: a command line that asks for something impossible; 2: bad input files.
  const std::vector<std::tuple<std::string, std::string, std::string, int>> cases = {
      {"fracture", model + interior + " --pieces 0", "--pieces", 1},
      {"fracture", model + interior + " --pieces 100000", "--pieces", 1},
      {"fracture", model + interior + " --roughness 1", "--roughness", 1},
      {"fracture", model + interior + " --min-volume nan", "--min-volume", 1},
      {"fracture", model + interior + " --impact 0,nan,0", "--impact", 1},
      {"fracture", model + " --pieces 3", "--interior", 1},
      {"fracture", quoted(dir / "missing.off") + interior, "missing.off", 2},
      {"fracture", model + interior + " --pieces 4 --interior-resolution 16", "larger --interior-resolution", 2},
      {"cut", model + interior + " --plane 0,0,0,0,0,0", "normal is zero", 1},
      {"cut", model + interior + " --plane nan,0,0,0,0,1", "--plane", 1},
      {"cut", model + interior + " --plane 1,2,3", "expected 6 comma-separated numbers", 1},
      {"cut", model + interior + " --plane 0,0,0,0,0,1 --explode -1", "--explode", 1},
  };
  for (const auto& [command, args, says, expected] : cases) {
    const auto [status, out, log] = texfab(command, args + " -q -o " + quoted(dir / "out.glb"));
    EXPECT_EQ(status, expected) << args << "\n" << log;
    EXPECT_NE(log.find(says), std::string::npos) << args << "\n" << log;
    EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
    EXPECT_FALSE(fs::exists(dir / "out.glb")) << args;
  }
}

} // namespace
