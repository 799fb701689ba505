// SPDX-License-Identifier: GPL-3.0-or-later
// Bad input: references escaping the model's folder, non-finite coordinates, bad indices, empty
// models, glTF accessors overrunning their buffers. Each must fail with one line naming the file
// and the problem; the command line exits 2 and writes nothing.
#include "geometry/io/mesh_io.h"
#include "geometry/io/model_path.h"
#include "tests/geometry/test_meshes.h"

#include <fstream>

using namespace texfab;
using namespace texfab::geometry;
using texfab::test::errorOf;
using texfab::test::TempDir;

namespace {

void write(const std::filesystem::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

void expectOneLineError(const std::string& message, const std::string& file, const std::string& mentions) {
  EXPECT_FALSE(message.empty()) << "no texfab::Error for " << file;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_NE(message.find(file), std::string::npos) << "message does not name the file: " << message;
  EXPECT_NE(message.find(mentions), std::string::npos) << "message does not say '" << mentions << "': " << message;
}

const char* kTriangleGltf = R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":COUNT,"type":"VEC3"}],
 "bufferViews":[{"buffer":0,"byteLength":36}],
 "buffers":[{"byteLength":36,"uri":"URI"}]})";

std::string gltfWith(const std::string& uri, int count = 3) {
  const std::string t = kTriangleGltf;
  const size_t c = t.find("COUNT"), u = t.find("URI");
  std::string s;
  s.append(t, 0, c).append(std::to_string(count)).append(t, c + 5, u - c - 5).append(uri).append(t, u + 3);
  return s;
}

} // namespace

TEST(ModelPath, RefusesReferencesLeavingTheFolder) {
  TempDir dir("texfab-path");
  const auto model = dir / "m.obj";
  for (const char* ref : {"../x.png", "a/../../x.png", "/etc/passwd", "\\\\server\\x.png", "C:\\x.png",
                                "file:///etc/passwd", "http://example.com/x.png", "..\\x.png", ""})
    EXPECT_FALSE(errorOf([&] { resolveModelReference(model, ref); }).empty()) << ref;
  EXPECT_FALSE(errorOf([&] { resolveModelReference(model, "%2E%2E/x.png", true); }).empty());
  EXPECT_FALSE(errorOf([&] { resolveModelReference(model, "%zz.png", true); }).empty());
  EXPECT_EQ(resolveModelReference(model, "tex/a b.png"), dir.path() / "tex/a b.png");
  EXPECT_EQ(resolveModelReference(model, "a%20b.png", true), dir.path() / "a b.png");
  // A symbolic link inside the folder that points outside it.
  std::filesystem::create_directory_symlink("/etc", dir / "etc");
  EXPECT_FALSE(errorOf([&] { resolveModelReference(model, "etc/passwd"); }).empty());
}

TEST(ModelPath, ModelsThatEscapeAreRefused) {
  TempDir outer("texfab-escape");
  std::filesystem::create_directory(outer / "model");
  write(outer / "secret.mtl", "newmtl x\nKd 1 0 0\n");
  write(outer / "secret.bin", std::string(36, '\0'));
  write(outer / "model/a.obj", "mtllib ../secret.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expectOneLineError(errorOf([&] { readMesh(outer / "model/a.obj"); }), "a.obj", "..");
  write(outer / "model/b.mtl", "newmtl x\nmap_Kd /etc/passwd\n");
  write(outer / "model/b.obj", "mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n");
  expectOneLineError(errorOf([&] { readMesh(outer / "model/b.obj"); }), "b.mtl", "absolute");
  for (const char* uri : {"../secret.bin", "%2E%2E/secret.bin", "file:///etc/passwd", "http://example.com/a.bin",
                                "/etc/passwd"}) {
    write(outer / "model/c.gltf", gltfWith(uri));
    expectOneLineError(errorOf([&] { readMesh(outer / "model/c.gltf"); }), "c.gltf", "reference");
  }
}

TEST(BadInput, EachProblemGetsAOneLineError) {
  TempDir dir("texfab-bad");
  struct Case {
    const char* file;
    std::string content;
    const char* mentions;
  };
  const std::vector<Case> cases = {
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "NaN"},
      {"inf.off", "OFF\n3 1 0\n0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n", "infinite"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "out of range"},
      {"range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "uses vertex 3"},
      {"range.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n",
       "uses vertex 9"},
      {"empty.obj", "v 0 0 0\nv 1 0 0\n", "no triangles"},
      {"empty.stl", "solid x\nendsolid x\n", "no triangles"},
      {"short.stl", std::string(84, '\0') + std::string(10, 'x'), "size does not match"},
      {"truncated.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                        "property float z\nend_header\n" + std::string(20, '\0'),
       "exceeds"},
      {"huge.off", "OFF\n1000000000 1 0\n0 0 0\n", "do not fit"},
      {"notjson.gltf", "{\"asset\": ", "not valid glTF JSON"},
      {"overrun.gltf", gltfWith("data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA", 30),
       "overruns"},
      {"badindex.gltf", gltfWith("data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA", 3)
                            .replace(std::string(kTriangleGltf).find("\"attributes\"") + 0, 0, "\"indices\":5,"),
       "indices"},
      {"truncated.glb", "glTF\x02\0\0\0\xff\0\0\0", "truncated"},
  };
  for (const Case& c : cases) {
    write(dir / c.file, c.content);
    expectOneLineError(errorOf([&] { readMesh(dir / c.file); }), c.file, c.mentions);
  }
}

TEST(BadInput, CommandLineExitsTwoAndWritesNothing) {
  TempDir dir("texfab-cli");
  write(dir / "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  for (const std::string& args : {"convert '" + (dir / "bad.obj").string() + "' '" + (dir / "out.glb").string() + "'",
                                 "render '" + (dir / "bad.obj").string() + "' -o '" + (dir / "out.png").string() + "'",
                                 "info '" + (dir / "bad.obj").string() + "'"}) {
    const texfab::test::CliResult r = texfab::test::runCli(args);
    EXPECT_EQ(r.status, 2) << args;
    EXPECT_NE(r.err.find("bad.obj"), std::string::npos) << r.err;
    EXPECT_EQ(r.errLines(), 1u) << r.err;
  }
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_TRUE(entry.path().filename() == "bad.obj" || entry.path().filename() == "err.txt") << entry.path();
}
