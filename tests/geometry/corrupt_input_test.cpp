// SPDX-License-Identifier: GPL-3.0-or-later
// Fuzz-style robustness: real files of every format, truncated and mutated deterministically,
// must either load or fail with texfab::Error: never crash, hang, leak or throw anything else.
// Run it under AddressSanitizer/UBSan with a -DTEXFAB_SANITIZE=ON build (see the README).
#include "geometry/io/mesh_io.h"
#include "tests/geometry/test_meshes.h"

#include <fstream>

using namespace texfab;
using namespace texfab::geometry;
using texfab::test::TempDir;

namespace {

std::string readAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

uint32_t mix(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  return x ^ (x >> 16);
}

// Variant i of `original`: truncations at many lengths, then 1-8 random byte changes (random
// values, digits, structural characters, 0xff runs), then duplicated or deleted spans.
std::string mutate(const std::string& original, uint32_t i) {
  std::string s = original;
  const uint32_t kind = i % 4;
  uint32_t h = mix(i * 2654435761u + 1);
  if (kind == 0 || s.size() < 8) {
    s.resize(size_t(h % (s.size() + 1)));
    return s;
  }
  const int changes = 1 + int((h >> 8) % 8);
  for (int c = 0; c < changes; ++c) {
    h = mix(h);
    const size_t at = h % s.size();
    const char structural[] = "{}[]\",:-0123456789e.\n /\\%";
    switch ((h >> 24) % 4) {
    case 0: s[at] = char(h >> 16); break;
    case 1: s[at] = structural[(h >> 12) % (sizeof structural - 1)]; break;
    case 2: s[at] = '\xff'; break;
    default:
      if (kind == 3) s.erase(at, std::min<size_t>((h >> 10) % 64, s.size() - at));
      else s.insert(at, s.substr(at, std::min<size_t>((h >> 10) % 64, s.size() - at)));
    }
    if (s.empty()) break;
  }
  return s;
}

} // namespace

class CorruptInput : public ::testing::TestWithParam<std::string> {};

TEST_P(CorruptInput, NeverCrashesOnlyTexfabErrors) {
  TempDir dir("texfab-fuzz");
  const std::string name = GetParam();
  // The original: the textured cube (OBJ, glTF, PLY) or a bundled CGAL mesh (OFF, STL).
  Mesh source = texfab::test::texturedCube();
  MeshWriteOptions options;
  options.binary = name.find("ascii") == std::string::npos;
  options.draco = name.find("draco") != std::string::npos;
  const std::filesystem::path original = dir / ("original" + std::filesystem::path(name).extension().string());
  writeMesh(source, original, options);
  const std::string bytes = readAll(original);
  ASSERT_NO_THROW(readMesh(original));
  const std::filesystem::path target = dir / ("mutant" + original.extension().string());
  // The mutated OBJ still names original.mtl, which stays intact in this first loop.
  const int variants = 300;
  int loaded = 0, refused = 0;
  for (int i = 0; i < variants; ++i) {
    std::string m = mutate(bytes, uint32_t(i));
    std::ofstream(target, std::ios::binary | std::ios::trunc) << m;
    try {
      const Mesh mesh = readMesh(target);
      validateMesh(mesh, "mutant");  // whatever loads must be a valid mesh
      ++loaded;
    } catch (const Error& e) {
      ++refused;
      const std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_FALSE(what.empty());
    } catch (const std::exception& e) {
      ADD_FAILURE() << name << " variant " << i << ": non-texfab exception: " << e.what();
    }
  }
  EXPECT_EQ(loaded + refused, variants);
  EXPECT_GT(refused, 0) << "no variant was refused: the mutations are not reaching the parser";
  if (original.extension() == ".obj") {
    // Mutate the MTL too, with the OBJ intact.
    const std::string mtl = readAll(dir / "original.mtl");
    for (int i = 0; i < 100; ++i) {
      std::ofstream(dir / "original.mtl", std::ios::binary | std::ios::trunc) << mutate(mtl, uint32_t(i));
      try {
        readMesh(original);
      } catch (const Error&) {
      } catch (const std::exception& e) {
        ADD_FAILURE() << "MTL variant " << i << ": non-texfab exception: " << e.what();
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, CorruptInput,
                         ::testing::Values("cube.obj", "cube.ply", "cube_ascii.ply", "cube.off", "cube.stl", "cube_ascii.stl",
                                           "cube.glb", "cube.gltf", "cube_draco.glb"),
                         [](const auto& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '.', '_');
                           return n;
                         });
