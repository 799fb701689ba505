// SPDX-License-Identifier: GPL-3.0-or-later
// texfab slice end to end: a small print with its manifest (checksums of the files written), the
// preview and the report; shards through the command line merged by merge-slices; bad input and a
// disk that fills up: one line, a non-zero exit, and no output.
#include "core/downsample.h"
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "print/slice_writer.h"
#include "tests/atlas/test_meshes.h"
#include "tests/geometry/solid_meshes.h"
#include "tests/golden/golden_cases.h"
#include "tests/print/icc_test_profiles.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace {
namespace fs = std::filesystem;
using texfab::test::TempDir;

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Runs `texfab slice ARGS`.
texfab::test::CliResult slice(const std::string& args) { return texfab::test::runCli("slice " + args); }

// Built by appending: GCC 12 warns falsely (-Wrestrict) on "'" + std::string.
std::string quoted(const fs::path& p) {
  std::string q(1, '\'');
  q.append(p.string()).push_back('\'');
  return q;
}

// A 6 mm sphere as an OFF file, written once per test folder.
fs::path sphereModel(const TempDir& dir) {
  const fs::path p = dir / "sphere.off";
  texfab::geometry::writeMesh(texfab::test::makeIcoSphere(3.0f, 3), p);
  return p;
}

const std::string kSmall = " --height 6 --dpi 127 --layer 0.2 --shell 0.6 -q";  // 30^3 voxels

TEST(CliSlice, WritesLayersManifestPreviewAndReport) {
  TempDir dir;
  const fs::path model = sphereModel(dir);
  ASSERT_EQ(slice(quoted(model) + " -o " + quoted(dir / "out") + kSmall + " --preview " + quoted(dir / "p.png") +
                  " --report " + quoted(dir / "r.json")).status,
            0);
  const nlohmann::json m = nlohmann::json::parse(readText(dir / "out" / "slices.json"));
  EXPECT_EQ(m["layers"]["count"], 30);
  EXPECT_EQ(m["print"]["image"]["width"], 30);
  EXPECT_EQ(m["print"]["materials"].size(), 6u);
  ASSERT_EQ(m["files"].size(), 30u);
  for (const auto& f : m["files"]) {
    const std::string text = readText(dir / "out" / f["file"].get<std::string>());
    const std::vector<uint8_t> bytes(text.begin(), text.end());
    EXPECT_EQ(texfab::print::sha256Hex(bytes), f["sha256"]);
    EXPECT_EQ(texfab::readImage(dir / "out" / f["file"].get<std::string>()).width, 30);
  }
  const texfab::Image preview = texfab::readImage(dir / "p.png");
  EXPECT_GT(preview.width, 200);
  const nlohmann::json r = nlohmann::json::parse(readText(dir / "r.json"));
  EXPECT_GT(r["voxels"]["shell"].get<int64_t>(), 0);
  EXPECT_LT(r["voxels"]["shell"].get<int64_t>(), r["voxels"]["inside"].get<int64_t>());
}

// A 2 x 6 x 1 box (x, y, z), wound outward, or with two triangles flipped.
fs::path boxModel(const TempDir& dir, bool flipped) {
  const fs::path p = dir / (flipped ? "flipped.obj" : "box.obj");
  std::ofstream(p) << "v 0 0 0\nv 2 0 0\nv 2 6 0\nv 0 6 0\nv 0 0 1\nv 2 0 1\nv 2 6 1\nv 0 6 1\n"
                   << (flipped ? "f 1 3 4\nf 1 2 3\n" : "f 1 4 3\nf 1 3 2\n")
                   << "f 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
  return p;
}

// The print stands the model as the previews do (y up for OBJ; --up z lays it down), --height
// measures it along that axis, and the manifest says the print's size. A model wound
// inconsistently is re-oriented, as texture and fracture do, and prints the same layers.
TEST(CliSlice, StandsTheModelUpAndRepairsItsWinding) {
  TempDir dir;
  const std::string common = " --height 6 --dpi 25.4 --layer 0.5 --shell 0.6";  // 1 mm pixels
  const texfab::test::CliResult upright = slice(quoted(boxModel(dir, false)) + " -o " + quoted(dir / "y") + common + " -q");
  ASSERT_EQ(upright.status, 0) << upright.err;
  const nlohmann::json y = nlohmann::json::parse(readText(dir / "y" / "slices.json"));
  EXPECT_EQ(y["layers"]["count"], 12);  // 6 mm at 0.5 mm
  EXPECT_NEAR(y["print"]["size_mm"][0].get<double>(), 2.0, 1e-9);
  EXPECT_NEAR(y["print"]["size_mm"][1].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(y["print"]["size_mm"][2].get<double>(), 6.0, 1e-9);
  ASSERT_EQ(slice(quoted(boxModel(dir, false)) + " -o " + quoted(dir / "z") + common + " -q --up z").status, 0);
  const nlohmann::json z = nlohmann::json::parse(readText(dir / "z" / "slices.json"));
  EXPECT_NEAR(z["print"]["size_mm"][0].get<double>(), 12.0, 1e-9);  // 6 mm per unit
  EXPECT_NEAR(z["print"]["size_mm"][1].get<double>(), 36.0, 1e-9);

  const texfab::test::CliResult flipped = slice(quoted(boxModel(dir, true)) + " -o " + quoted(dir / "f") + common);
  ASSERT_EQ(flipped.status, 0) << flipped.err;
  EXPECT_NE(flipped.err.find("re-oriented 2 triangles"), std::string::npos) << flipped.err;
  const nlohmann::json f = nlohmann::json::parse(readText(dir / "f" / "slices.json"));
  ASSERT_EQ(f["files"].size(), y["files"].size());
  for (size_t i = 0; i < f["files"].size(); ++i) EXPECT_EQ(f["files"][i]["sha256"], y["files"][i]["sha256"]) << i;
}

// The report says how far the print's colour is from the colour asked for, as a person sees it
// (CIEDE2000 over 16^3 blocks), the same on any thread count; below 1.5 on average (about what a
// person notices side by side) for the blue-noise dither of a marble.
TEST(CliSlice, ReportsTheColourAsPrinted) {
  TempDir dir;
  const fs::path elephant = fs::path(TEXFAB_SOURCE_DIR) / "models" / "meshes" / "elephant.off";
  const fs::path marble = fs::path(TEXFAB_SOURCE_DIR) / "models" / "exemplars" / "marble.png";
  nlohmann::json error[2];
  for (int threads : {1, 2}) {
    const std::string name = "t" + std::to_string(threads);
    // --texture-scale: about one solid voxel per print voxel; the default (texture's) would sample
    // one in 16 on this 8 mm print, each with its own dependency chain.
    const texfab::test::CliResult run =
        slice(quoted(elephant) + " -e " + quoted(marble) + " -o " + quoted(dir / name) + " --height 8 --dpi 300" +
              " --texture-scale 120" +
              " --layer 0.05 --shell 1.5 -q --threads " + std::to_string(threads) + " --cache-dir " +
              quoted(dir / "cache") + " --report " + quoted(dir / (name + ".json")));
    ASSERT_EQ(run.status, 0) << run.err;
    error[threads - 1] = nlohmann::json::parse(readText(dir / (name + ".json")))["color_error"];
  }
  EXPECT_GT(error[0]["blocks"].get<int>(), 5);
  EXPECT_LT(error[0]["delta_e2000_mean"].get<double>(), 1.5);
  EXPECT_LE(error[0]["delta_e2000_p95"].get<double>(), error[0]["delta_e2000_max"].get<double>());
  EXPECT_EQ(error[0], error[1]);
}

TEST(CliSlice, ShardsMergeIntoTheFullRun) {
  TempDir dir;
  const fs::path model = sphereModel(dir);
  texfab::writeImage(texfab::golden::marble32(), dir / "marble32.png");  // a small exemplar: a fast analysis
  const std::string common = quoted(model) + kSmall + " -e " + quoted(dir / "marble32.png") +
                             " --feature-size 2 --cache-dir " + quoted(dir / "cache");
  ASSERT_EQ(slice(common + " -o " + quoted(dir / "full") + " --threads 2").status, 0);
  for (int i = 0; i < 3; ++i)
    ASSERT_EQ(slice(common + " -o " + quoted(dir / ("part" + std::to_string(i))) + " --shard " + std::to_string(i) +
                    "/3 --threads 1").status,
              0);
  ASSERT_EQ(slice(common + " -o " + quoted(dir / "lo") + " --layers 10:20").status, 0);
  const std::string merge = std::string(TEXFAB_CLI) + " merge-slices " + quoted(dir / "part2") + " " +
                            quoted(dir / "part0") + " " + quoted(dir / "part1") + " -o " + quoted(dir / "merged");
  ASSERT_EQ(texfab::test::run(merge), 0);
  for (const auto& e : fs::directory_iterator(dir / "full"))
    EXPECT_EQ(readText(e.path()), readText(dir / "merged" / e.path().filename())) << e.path().filename();
  EXPECT_EQ(readText(dir / "lo" / "slice_00015.png"), readText(dir / "full" / "slice_00015.png"));
}

// The voxels' solid synthesis on the Vulkan backend: the CPU's layers, byte for byte.
TEST(CliSlice, VulkanBackendWritesTheCpusLayers) {
  if (const std::string missing = texfab::test::vulkanDeviceMissing(); !missing.empty()) GTEST_SKIP() << missing;
  TempDir dir;
  const fs::path model = sphereModel(dir);
  texfab::writeImage(texfab::golden::marble32(), dir / "marble32.png");
  const std::string common = quoted(model) + kSmall + " -e " + quoted(dir / "marble32.png") +
                             " --feature-size 2 --cache-dir " + quoted(dir / "cache");
  ASSERT_EQ(slice(common + " -o " + quoted(dir / "cpu")).status, 0);
  const auto vulkan = slice(common + " -o " + quoted(dir / "vulkan") + " --backend vulkan --device 0");
  ASSERT_EQ(vulkan.status, 0) << vulkan.err;
  for (const auto& e : fs::directory_iterator(dir / "cpu"))
    EXPECT_EQ(readText(e.path()), readText(dir / "vulkan" / e.path().filename())) << e.path().filename();
}

// One line on stderr, exit status `status` (1: a flag's value, 2: bad input), and no output folder.
void expectRefused(const TempDir& dir, const std::string& args, const std::string& message, int status = 2) {
  const fs::path out = dir / "refused";
  const texfab::test::CliResult r = slice(args + " -o " + quoted(out));
  const std::string& err = r.err;
  EXPECT_EQ(r.status, status) << args << ": " << err;
  EXPECT_NE(err.find(message), std::string::npos) << args << ": " << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_FALSE(fs::exists(out)) << args;
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".refused"), std::string::npos) << "left behind: " << e.path();
}

TEST(CliSlice, BadInputIsRefusedWithoutOutput) {
  TempDir dir;
  const std::string model = quoted(sphereModel(dir)) + " -q";
  expectRefused(dir, model + " --dpi 0", "--dpi", 1);
  expectRefused(dir, model + " --dpi 600,-3", "--dpi", 1);
  expectRefused(dir, model + " --height -5", "--height", 1);
  expectRefused(dir, model + " --height nan", "--height", 1);
  expectRefused(dir, model + " --layer 0", "--layer", 1);
  expectRefused(dir, model + " --shell -1", "--shell", 1);
  expectRefused(dir, model + " --layers 5:99999", "--layers");
  expectRefused(dir, model + " --layers 5:2", "--layers", 1);
  expectRefused(dir, model + " --shard 3/3", "--shard", 1);
  expectRefused(dir, model + " --dither sparkle", "--dither", 1);
  expectRefused(dir, model + " --core gold", "no material named 'gold'");
  expectRefused(dir, quoted(dir / "missing.off"), "missing.off");
  expectRefused(dir, model + " --bogus", "bogus", 1);
  std::ofstream(dir / "none.json") << R"({"materials": []})";
  expectRefused(dir, model + " --materials " + quoted(dir / "none.json"), "no materials");
  std::ofstream(dir / "bad.json") << R"([{"name": "Red", "color": "#FF00"}])";
  expectRefused(dir, model + " --materials " + quoted(dir / "bad.json"), "#RRGGBB");
  // An open model that cannot be repaired: a sphere without its top cap (a hole of 1,200 edges,
  // above the 1,000 that are filled) and one more triangle that touches that hole at one vertex, so
  // that the hole is not a simple loop and fans cannot close it.
  const int around = 1200;
  texfab::geometry::Mesh open = texfab::test::makeSphere(around, 4, 3.0f);
  open.triangles.erase(open.triangles.begin() + around, open.triangles.begin() + around + 1);  // touches vertex 1
  open.triangles.erase(open.triangles.begin(), open.triangles.begin() + around);              // the cap
  texfab::geometry::writeMesh(open, dir / "open.off");
  expectRefused(dir, quoted(dir / "open.off") + " -q", "the model is open: a hole of");
  // A layer larger than this machine's memory.
  expectRefused(dir, model + " --height 250 --dpi 100000 --layer 10", "of this machine's");
}

// Where fans cannot close a model (two holes that meet at one vertex), the solid repairs of
// fracture do, and the print is that of the whole sphere.
TEST(CliSlice, HolesThatFansCannotCloseAreFilledAsFractureFillsThem) {
  TempDir dir;
  const texfab::geometry::Mesh whole = texfab::test::makeIcoSphere(3.0f, 2);
  texfab::geometry::Mesh open = whole;
  const auto first = open.triangles[0];
  const auto touching = std::find_if(open.triangles.begin() + 1, open.triangles.end(), [&](const auto& t) {
    int shared = 0;
    for (auto a : t)
      for (auto b : first) shared += a == b;
    return shared == 1;
  });
  ASSERT_NE(touching, open.triangles.end());
  open.triangles.erase(touching);
  open.triangles.erase(open.triangles.begin());
  texfab::geometry::writeMesh(whole, dir / "whole.off");
  texfab::geometry::writeMesh(open, dir / "open.off");
  const std::string common = " --height 30 --dpi 50.8 --layer 1 --report ";
  const texfab::test::CliResult w = slice(quoted(dir / "whole.off") + " -o " + quoted(dir / "w") + common + quoted(dir / "w.json"));
  const texfab::test::CliResult o = slice(quoted(dir / "open.off") + " -o " + quoted(dir / "o") + common + quoted(dir / "o.json"));
  ASSERT_EQ(w.status, 0) << w.err;
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_NE(o.err.find("warning: repaired: filled 2 holes"), std::string::npos) << o.err;
  const nlohmann::json wr = nlohmann::json::parse(readText(dir / "w.json")), orr = nlohmann::json::parse(readText(dir / "o.json"));
  EXPECT_TRUE(wr["model"]["preparation"]["repairs"].empty());
  EXPECT_EQ(orr["model"]["preparation"]["use"], "print");
  // A hole of three edges is filled by the very triangle that was removed: the same voxels.
  EXPECT_GT(wr["voxels"]["inside"].get<int64_t>(), 0);
  EXPECT_EQ(orr["voxels"]["inside"], wr["voxels"]["inside"]);
  EXPECT_EQ(orr["voxels"]["shell"], wr["voxels"]["shell"]);
}

// A print coarser than its solid texture is synthesized from a smaller copy of the exemplar, the
// prefiltered texture (point-sampling the full one would alias, and cost a dependency chain per
// voxel): the very layers of slicing that copy at its own scale; the manifest says so, with the
// scale in the given exemplar's pixels.
TEST(CliSlice, CoarsePrintsAreSynthesizedFromASmallerCopy) {
  TempDir dir;
  const fs::path elephant = fs::path(TEXFAB_SOURCE_DIR) / "models" / "meshes" / "elephant.off";
  const fs::path marble = fs::path(TEXFAB_SOURCE_DIR) / "models" / "exemplars" / "marble.png";
  texfab::Image copy = texfab::downsample(texfab::readImage(marble), 4);
  copy.format = texfab::PixelFormat::Float;  // the copy's values exactly
  texfab::writeImage(copy, dir / "marble32.exr");
  const std::string common = quoted(elephant) + " --mode solid --height 8 --dpi 300 --layer 0.1 --layers 30:33" +
                             " --exemplar-wrap tile --no-cache";
  const texfab::test::CliResult given =
      slice(common + " -e " + quoted(marble) + " --texture-scale 1536 -o " + quoted(dir / "given"));
  ASSERT_EQ(given.status, 0) << given.err;
  EXPECT_NE(given.err.find("synthesized from a copy 4 times smaller (32x32)"), std::string::npos) << given.err;
  const texfab::test::CliResult small =
      slice(common + " -e " + quoted(dir / "marble32.exr") + " --texture-scale 384 -o " + quoted(dir / "copy"));
  ASSERT_EQ(small.status, 0) << small.err;
  const nlohmann::json g = nlohmann::json::parse(readText(dir / "given" / "slices.json"));
  const nlohmann::json c = nlohmann::json::parse(readText(dir / "copy" / "slices.json"));
  EXPECT_EQ(g["print"]["source"]["colors"]["downsampled"], 4);
  EXPECT_EQ(g["print"]["source"]["colors"]["texture_scale"], 1536.0);
  EXPECT_EQ(c["print"]["source"]["colors"]["downsampled"], 1);
  ASSERT_EQ(g["files"].size(), 3u);
  ASSERT_EQ(c["files"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(g["files"][i]["sha256"], c["files"][i]["sha256"]) << i;
}

// --icc-profile: the manifest names the profile; a file that is not a usable printer profile and
// materials outside the profile's gamut are refused, one line each, before any output.
TEST(CliSlice, IccProfileIsUsedOrRefused) {
  TempDir dir;
  const std::string model = quoted(sphereModel(dir)) + kSmall;
  texfab::test::writeRgbProfile(dir / "narrow.icc", 0.3, cmsSigOutputClass);
  std::ofstream(dir / "muted.json") << R"([{"name": "C", "color": "#5AA0B4"}, {"name": "M", "color": "#B46E96"},
    {"name": "Y", "color": "#C8BE78"}, {"name": "K", "color": "#3C3C3C"}, {"name": "W", "color": "#E6E6E6"}])";
  const std::string muted = " --materials " + quoted(dir / "muted.json") + " --core W";
  const auto run = slice(model + muted + " --icc-profile " + quoted(dir / "narrow.icc") + " -o " + quoted(dir / "out") +
                         " --report " + quoted(dir / "r.json"));
  ASSERT_EQ(run.status, 0) << run.err;
  const nlohmann::json m = nlohmann::json::parse(readText(dir / "out" / "slices.json"));
  EXPECT_EQ(m["print"]["icc_profile"]["file"], "narrow.icc");
  EXPECT_EQ(m["print"]["icc_profile"]["description"], "texfab test RGB");
  const std::string profile = readText(dir / "narrow.icc");
  EXPECT_EQ(m["print"]["icc_profile"]["sha256"], texfab::print::sha256Hex(std::vector<uint8_t>(profile.begin(), profile.end())));
  EXPECT_EQ(m["print"]["mix"], "cielab");
  EXPECT_EQ(nlohmann::json::parse(readText(dir / "r.json"))["print"]["icc_profile"]["file"], "narrow.icc");
  const auto rgb = slice(model + " --mix linear-rgb -o " + quoted(dir / "rgb"));
  ASSERT_EQ(rgb.status, 0) << rgb.err;
  EXPECT_EQ(nlohmann::json::parse(readText(dir / "rgb" / "slices.json"))["print"]["mix"], "linear-rgb");

  std::ofstream(dir / "garbage.icc") << "not a profile at all, but long enough to be read as a header by mistake.....";
  expectRefused(dir, model + " --icc-profile " + quoted(dir / "garbage.icc"), "not an ICC profile");
  expectRefused(dir, model + " --icc-profile " + quoted(dir / "missing.icc"), "cannot open ICC profile");
  texfab::test::writeRgbProfile(dir / "scanner.icc", 0.0, cmsSigInputClass);
  expectRefused(dir, model + " --icc-profile " + quoted(dir / "scanner.icc"), "class 'input'");
  texfab::test::writeLabProfile(dir / "lab.icc");
  expectRefused(dir, model + " --icc-profile " + quoted(dir / "lab.icc"), "lab.icc");
  // The default (pure CMYK) materials lie outside the narrow printer's gamut.
  expectRefused(dir, model + " --icc-profile " + quoted(dir / "narrow.icc"), "material 'VeroCyan'");
  expectRefused(dir, model + " --mix sideways", "--mix", 1);
}

TEST(CliSlice, ExistingOutputNeedsForce) {
  TempDir dir;
  const std::string model = quoted(sphereModel(dir)) + kSmall;
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "keep.txt") << "x";
  const texfab::test::CliResult refused = slice(model + " -o " + quoted(dir / "out"));
  EXPECT_EQ(refused.status, 2);
  EXPECT_NE(refused.err.find("--force"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "out" / "keep.txt"));
  EXPECT_EQ(slice(model + " -o " + quoted(dir / "out") + " --force").status, 0);
  EXPECT_FALSE(fs::exists(dir / "out" / "keep.txt"));
  EXPECT_TRUE(fs::exists(dir / "out" / "slices.json"));
}

TEST(CliSlice, AFullDiskLeavesNoOutput) {
  // A file size limit (ulimit -f, SIGXFSZ ignored) makes a layer's write fail the way a full disk
  // does; the run must stop with one line and leave neither layers nor a manifest.
  TempDir dir;
  const std::string command = "bash -c \"trap '' XFSZ; ulimit -f 1; '" + std::string(TEXFAB_CLI) + "' slice " +
                              quoted(sphereModel(dir)) + kSmall + " --format voxelprint -o " + quoted(dir / "out") +
                              "\" 2>" + quoted(dir / "err.txt");
  EXPECT_EQ(texfab::test::run(command), 2);
  const std::string err = readText(dir / "err.txt");
  EXPECT_NE(err.find("disk full"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".out"), std::string::npos) << "left behind: " << e.path();
  // With --force over a previous print: that print stays as it was.
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "slices.json") << "previous";
  const std::string force = "bash -c \"trap '' XFSZ; ulimit -f 1; '" + std::string(TEXFAB_CLI) + "' slice " +
                            quoted(sphereModel(dir)) + kSmall + " --format voxelprint --force -o " + quoted(dir / "out") +
                            "\" 2>" + quoted(dir / "err.txt");
  EXPECT_EQ(texfab::test::run(force), 2);
  EXPECT_EQ(readText(dir / "out" / "slices.json"), "previous");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "out"), fs::directory_iterator()), 1);
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".out"), std::string::npos) << "left behind: " << e.path();
}

} // namespace
