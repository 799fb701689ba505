// SPDX-License-Identifier: GPL-3.0-or-later
// Textured 3MF: files texfab writes read back with lib3mf itself (geometry, per-corner UVs in a
// texture2d group, the texture's pixels, base material colours), texfab's own reader round trip,
// and `texfab convert` and `texfab texture` writing 3MF.
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "tests/geometry/test_meshes.h"

#include <Model/COM/NMR_DLLInterfaces.h>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>

namespace texfab::test {
namespace {

namespace fs = std::filesystem;
using namespace NMR;

struct Owned {
  PLib3MFBase* p = nullptr;
  ~Owned() {
    if (p) lib3mf_release(p);
  }
};

// The texturedCube's faces as written: material 0 (textured) on the first six triangles.
TEST(ThreeMf, Lib3mfReadsGeometryUvsAndTexture) {
  TempDir dir;
  const geometry::Mesh cube = texturedCube();
  geometry::writeMesh(cube, dir / "cube.3mf");
  Owned model, reader, objects, object, properties;
  ASSERT_EQ(lib3mf_createmodel(&model.p), LIB3MF_OK);
  ASSERT_EQ(lib3mf_model_queryreader(model.p, "3mf", &reader.p), LIB3MF_OK);
  ASSERT_EQ(lib3mf_reader_readfromfileutf8(reader.p, (dir / "cube.3mf").c_str()), LIB3MF_OK);
  ASSERT_EQ(lib3mf_model_getmeshobjects(model.p, &objects.p), LIB3MF_OK);
  BOOL more = false;
  ASSERT_EQ(lib3mf_resourceiterator_movenext(objects.p, &more), LIB3MF_OK);
  ASSERT_TRUE(more);
  ASSERT_EQ(lib3mf_resourceiterator_getcurrent(objects.p, &object.p), LIB3MF_OK);
  DWORD nv = 0, nt = 0;
  lib3mf_meshobject_getvertexcount(object.p, &nv);
  lib3mf_meshobject_gettrianglecount(object.p, &nt);
  ASSERT_EQ(nv, cube.vertexCount());
  ASSERT_EQ(nt, cube.triangleCount());
  for (DWORD i = 0; i < nv; ++i) {
    MODELMESHVERTEX v;
    lib3mf_meshobject_getvertex(object.p, i, &v);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(v.m_fPosition[k], cube.positions[i][k]);
  }
  ASSERT_EQ(lib3mf_meshobject_createpropertyhandler(object.p, &properties.p), LIB3MF_OK);
  DWORD textureId = 0;
  for (DWORD t = 0; t < nt; ++t) {
    MODELMESHTRIANGLE tri;
    lib3mf_meshobject_gettriangle(object.p, t, &tri);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(tri.m_nIndices[k], cube.triangles[t][size_t(k)]);
    if (cube.materialOf(t) == 0) {
      MODELMESHTEXTURE2D uv{};
      ASSERT_EQ(lib3mf_propertyhandler_gettexture(properties.p, t, &uv), LIB3MF_OK);
      ASSERT_NE(uv.m_nTextureID, 0u);
      textureId = uv.m_nTextureID;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(uv.m_fU[k], cube.uvs[3 * t + size_t(k)].x());
        EXPECT_EQ(uv.m_fV[k], cube.uvs[3 * t + size_t(k)].y());
      }
    } else {
      DWORD group = 0, index = 0;
      ASSERT_EQ(lib3mf_propertyhandler_getbasematerial(properties.p, t, &group, &index), LIB3MF_OK);
      Owned materials;
      ASSERT_EQ(lib3mf_model_getbasematerialbyid(model.p, group, &materials.p), LIB3MF_OK);
      BYTE r = 0, g = 0, b = 0, a = 0;
      lib3mf_basematerial_getdisplaycolor(materials.p, index, &r, &g, &b, &a);
      // Linear factor 0.2, 0.4, 0.6 in sRGB bytes.
      EXPECT_EQ(int(r), 124);
      EXPECT_EQ(int(g), 170);
      EXPECT_EQ(int(b), 203);
    }
  }
  // The texture: the material's image, as PNG bytes in the package.
  Owned texture, attachment;
  ASSERT_EQ(lib3mf_model_gettexture2dbyid(model.p, textureId, &texture.p), LIB3MF_OK);
  ASSERT_EQ(lib3mf_texture2d_getattachment(texture.p, &attachment.p), LIB3MF_OK);
  ULONG64 size = 0;
  lib3mf_attachment_getstreamsize(attachment.p, &size);
  std::vector<uint8_t> png(size);
  ASSERT_EQ(lib3mf_attachment_writetobuffer(attachment.p, png.data(), size), LIB3MF_OK);
  const Image image = decodeImage(png, "texture");
  const Image& expected = *cube.materials[0].baseColorTexture.image;
  ASSERT_EQ(image.width, expected.width);
  ASSERT_EQ(image.height, expected.height);
  // The factor (1, 0.9, 0.8) is multiplied in (linear light); red is untouched.
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) EXPECT_NEAR(image.at(x, y, 0), expected.at(x, y, 0), 0.5f / 255);
}

TEST(ThreeMf, RoundTripThroughTexfabsReader) {
  TempDir dir;
  geometry::Mesh cube = texturedCube();
  cube.materials[0].baseColorFactor = {1, 1, 1, 1};
  geometry::writeMesh(cube, dir / "cube.3mf");
  const geometry::Mesh back = geometry::readMesh(dir / "cube.3mf");
  ASSERT_EQ(back.positions, cube.positions);
  ASSERT_EQ(back.triangles, cube.triangles);
  ASSERT_EQ(back.materials.size(), 2u);
  for (size_t t = 0; t < cube.triangleCount(); ++t) {
    const geometry::Material& m = back.materials[back.materialOf(t)];
    EXPECT_EQ(bool(m.baseColorTexture), cube.materialOf(t) == 0);
    if (cube.materialOf(t) == 0)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(back.uvs[3 * t + size_t(k)], cube.uvs[3 * t + size_t(k)]);
    else
      EXPECT_NEAR(m.baseColorFactor[2], 0.6f, 0.01f);
  }
  const Image& a = *back.materials[back.materialOf(0)].baseColorTexture.image;
  const Image& b = *cube.materials[0].baseColorTexture.image;
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.channels, b.channels);
  for (size_t i = 0; i < a.pixels.size(); ++i)  // 8-bit PNG in the package: equal to the byte
    ASSERT_EQ(std::lround(a.pixels[i] * 255.0f), std::lround(b.pixels[i] * 255.0f)) << i;
}

uint16_t little16(const std::string& b, size_t at) { return uint16_t(uint8_t(b[at]) | uint8_t(b[at + 1]) << 8); }
uint32_t little32(const std::string& b, size_t at) { return uint32_t(little16(b, at)) | uint32_t(little16(b, at + 2)) << 16; }

// 3MF is in millimetres: a unit scales the model's coordinates, a height its extent along the up
// axis. The archive is plain zip, as every reader takes it (assimp 5.2 refused lib3mf's own, whose
// entries carry Zip64 fields and the date 1980-00-00): no extra fields, a real date.
TEST(ThreeMf, SizedInMillimetresInAPlainArchive) {
  TempDir dir;
  const geometry::Mesh cube = texturedCube();
  geometry::writeMesh(cube, dir / "inches.3mf", {.millimetresPerUnit = 25.4});
  const geometry::Mesh inches = geometry::readMesh(dir / "inches.3mf");
  ASSERT_EQ(inches.positions.size(), cube.positions.size());
  for (size_t i = 0; i < cube.positions.size(); ++i)
    EXPECT_LT((inches.positions[i] - 25.4f * cube.positions[i]).norm(), 1e-4f) << i;

  geometry::MeshWriteOptions tall;
  tall.heightMm = 80;
  tall.up = {0, 0, 1};
  geometry::writeMesh(cube, dir / "tall.3mf", tall);
  const geometry::BoundingBox box = geometry::boundingBox(geometry::readMesh(dir / "tall.3mf"));
  EXPECT_NEAR(box.max.z() - box.min.z(), 80.0f, 1e-3f);
  EXPECT_NEAR((box.max.x() - box.min.x()) / (box.max.z() - box.min.z()),
              (geometry::boundingBox(cube).max.x() - geometry::boundingBox(cube).min.x()) /
                  (geometry::boundingBox(cube).max.z() - geometry::boundingBox(cube).min.z()),
              1e-5f);

  std::ifstream in(dir / "tall.3mf", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  int entries = 0;
  for (size_t at = 0; at + 30 <= bytes.size() && little32(bytes, at) == 0x04034b50; ++entries) {
    EXPECT_EQ(little16(bytes, at + 28), 0) << "extra fields in entry " << entries;
    EXPECT_EQ(little16(bytes, at + 12), (1 << 5) | 1) << "date of entry " << entries;  // 1980-01-01
    EXPECT_EQ(little16(bytes, at + 6) & 8, 0);  // sizes in the header, no data descriptor
    at += 30 + little16(bytes, at + 26) + little16(bytes, at + 28) + little32(bytes, at + 18);
  }
  EXPECT_GE(entries, 4);  // the model, content types, relationships, the texture
}

TEST(ThreeMf, ConvertAndTextureWriteIt) {
  TempDir dir;
  const fs::path obj = fs::path(TEXFAB_SOURCE_DIR) / "models/meshes/marble_cube.obj";
  ASSERT_EQ(test::runCli("convert '" + obj.string() + "' '" + (dir / "c.3mf").string() + "' -q").status, 0);
  const geometry::Mesh converted = geometry::readMesh(dir / "c.3mf");
  EXPECT_EQ(converted.triangleCount(), geometry::readMesh(obj).triangleCount());
  EXPECT_TRUE(converted.hasUvs());
  // --height: the model's extent along its up axis (y for OBJ) in mm, turned to 3MF's build
  // direction (+z) so that it stands in a slicer; only for 3MF.
  ASSERT_EQ(test::runCli("convert '" + obj.string() + "' '" + (dir / "h.3mf").string() + "' -q --height 80").status, 0);
  const geometry::BoundingBox sized = geometry::boundingBox(geometry::readMesh(dir / "h.3mf"));
  const geometry::BoundingBox source = geometry::boundingBox(geometry::readMesh(obj));
  EXPECT_NEAR(sized.max.z() - sized.min.z(), 80.0f, 1e-3f);
  EXPECT_NEAR((sized.max.y() - sized.min.y()) / 80.0f, (source.max.z() - source.min.z()) / (source.max.y() - source.min.y()),
              1e-4f);
  const test::CliResult notThreeMf =
      test::runCli("convert '" + obj.string() + "' '" + (dir / "h.glb").string() + "' -q --height 80");
  EXPECT_EQ(notThreeMf.status, 1) << notThreeMf.err;
  EXPECT_NE(notThreeMf.err.find("--height"), std::string::npos) << notThreeMf.err;
  EXPECT_FALSE(fs::exists(dir / "h.glb"));
  EXPECT_EQ(test::runCli("convert '" + obj.string() + "' '" + (dir / "u.3mf").string() + "' -q --unit furlong").status, 1);
  const fs::path exemplar = fs::path(TEXFAB_SOURCE_DIR) / "models/exemplars/brick.png";
  const fs::path knot = fs::path(TEXFAB_SOURCE_DIR) / "models/meshes/knot1.off";
  ASSERT_EQ(test::runCli("texture '" + knot.string() + "' -e '" + exemplar.string() + "' -o '" + (dir / "t.3mf").string() +
                         "' --resolution 256 -q --no-cache")
                .status,
            0);
  const geometry::Mesh textured = geometry::readMesh(dir / "t.3mf");
  ASSERT_EQ(textured.materials.size(), 1u);
  EXPECT_EQ(textured.materials[0].baseColorTexture.image->width, 256);
}

// PrusaSlicer (Debian's, its command line without a display) reads texfab's 3MF: at the size asked
// for, standing along +z, closed; and a textured one.
TEST(ThreeMf, PrusaSlicerOpensItAtItsSize) {
  if (test::run("command -v prusa-slicer >/dev/null 2>&1") != 0) GTEST_SKIP() << "prusa-slicer not installed";
  TempDir dir;
  const fs::path elephant = fs::path(TEXFAB_SOURCE_DIR) / "models/meshes/elephant.off";
  ASSERT_EQ(test::runCli("convert '" + elephant.string() + "' '" + (dir / "e.3mf").string() + "' -q --height 80").status, 0);
  geometry::Mesh textured = texturedCube();
  geometry::writeMesh(textured, dir / "cube.3mf");
  for (const char* name : {"e.3mf", "cube.3mf"}) {
    const fs::path info = dir / (std::string(name) + ".txt");
    ASSERT_EQ(test::run("prusa-slicer --info '" + (dir / name).string() + "' > '" + info.string() + "' 2>&1"), 0) << name;
    std::ifstream in(info);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("manifold = yes"), std::string::npos) << text;
    if (std::string(name) == "e.3mf") {
      EXPECT_NE(text.find("size_z = 80.0000"), std::string::npos) << text;
    }
  }
}

} // namespace
} // namespace texfab::test
