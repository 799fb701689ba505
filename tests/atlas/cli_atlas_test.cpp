// SPDX-License-Identifier: GPL-3.0-or-later
// texfab atlas end to end: outputs, report, debug images; bad arguments fail before any output.
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

int run(const std::string& args) { return texfab::test::runCli("atlas " + args + " -q").status; }

TEST(CliAtlas, WritesMeshReportAndDebugImages) {
  const fs::path model = fs::path(TEXFAB_SOURCE_DIR) / "models" / "meshes" / "knot1.off";
  if (!fs::exists(model)) GTEST_SKIP() << "models/meshes/knot1.off absent";
  const TempDir dir("texfab-atlas-cli");
  const fs::path& d = dir.path();
  ASSERT_EQ(0, run(model.string() + " -o " + (d / "knot.glb").string() + " --resolution 512 --report " +
                   (d / "r.json").string() + " --debug-images " + (d / "dbg").string()));
  const texfab::geometry::Mesh out = texfab::geometry::readMesh(d / "knot.glb");
  ASSERT_TRUE(out.hasUvs());
  for (const auto& uv : out.uvs) {
    EXPECT_GE(uv.x(), 0.0f);
    EXPECT_LE(uv.x(), 1.0f);
    EXPECT_GE(uv.y(), 0.0f);
    EXPECT_LE(uv.y(), 1.0f);
  }
  std::ifstream in(d / "r.json");
  const nlohmann::json r = nlohmann::json::parse(in);
  EXPECT_EQ(r["atlas"]["flipped_triangles"], 0);
  EXPECT_EQ(r["atlas"]["overlapping_texels"], 0);
  EXPECT_GT(r["atlas"]["utilization"].get<double>(), 0.3);
  EXPECT_TRUE(r["atlas"]["stage_seconds"].contains("packing"));
  EXPECT_TRUE(r["timings"].contains("atlas"));
  for (const char* f : {"chart_ids.png", "normals.png", "jacobian_magnitude.png", "jacobian_anisotropy.png",
                        "checker.png", "checker.glb"})
    EXPECT_TRUE(fs::exists(d / "dbg" / f)) << f;
  // The anisotropy image shows something: white at the 99th percentile of the chart texels.
  const texfab::Image aniso = texfab::readImage(d / "dbg" / "jacobian_anisotropy.png");
  size_t white = 0, lit = 0;
  for (float v : aniso.pixels) white += v >= 0.99f, lit += v >= 0.1f;
  EXPECT_GT(white, 0u);
  EXPECT_GT(lit, aniso.pixels.size() / 20);
}

TEST(CliAtlas, BadArgumentsFailWithoutOutput) {
  const fs::path model = fs::path(TEXFAB_SOURCE_DIR) / "models" / "meshes" / "knot1.off";
  const TempDir dir("texfab-atlas-cli");
  const fs::path& d = dir.path();
  const std::string out = " -o " + (d / "x.glb").string();
  EXPECT_NE(0, run(model.string() + out + " --parameterizer foo"));
  EXPECT_NE(0, run(model.string() + out + " --resolution 1000"));
  EXPECT_NE(0, run(model.string() + out + " --gutter -1"));
  EXPECT_NE(0, run(model.string() + out + " --direction 0,0,0"));
  EXPECT_NE(0, run(model.string() + " -o " + (d / "x.xyz").string()));
  EXPECT_NE(0, run((d / "missing.off").string() + out));
  EXPECT_FALSE(fs::exists(d / "x.glb"));
}

} // namespace
