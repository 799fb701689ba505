// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/io/mesh_io.h"

#include "core/error.h"
#include "core/files.h"
#include "core/image_io.h"
#include "geometry/io/mesh_formats.h"


#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <fstream>
#include <memory>

namespace texfab::geometry {
namespace fs = std::filesystem;

MeshFormat meshFormatOf(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".obj") return MeshFormat::Obj;
  if (ext == ".ply") return MeshFormat::Ply;
  if (ext == ".off") return MeshFormat::Off;
  if (ext == ".stl") return MeshFormat::Stl;
  if (ext == ".gltf") return MeshFormat::Gltf;
  if (ext == ".glb") return MeshFormat::Glb;
  if (ext == ".3mf") return MeshFormat::ThreeMf;
  throw Error(path.string() + ": unknown mesh format '" + ext + "' (expected .obj, .ply, .off, .stl, .gltf, .glb or .3mf)");
}

const char* meshFormatName(MeshFormat format) {
  switch (format) {
  case MeshFormat::Obj: return "OBJ";
  case MeshFormat::Ply: return "PLY";
  case MeshFormat::Off: return "OFF";
  case MeshFormat::Stl: return "STL";
  case MeshFormat::Gltf: return "glTF";
  case MeshFormat::Glb: return "GLB";
  case MeshFormat::ThreeMf: return "3MF";
  }
  return "?";
}

bool meshFormatCarriesTextures(MeshFormat format) {
  return format == MeshFormat::Obj || meshFormatIsGltf(format) || format == MeshFormat::ThreeMf;  // 3MF: base colour only
}

Mesh readMesh(const fs::path& path, const Context& ctx) {
  const MeshFormat format = meshFormatOf(path);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw Error(path.string() + ": no such file");
  Mesh mesh;
  switch (format) {
  case MeshFormat::Obj: mesh = detail::readObj(path, ctx); break;
  case MeshFormat::Ply: mesh = detail::readPly(path); break;
  case MeshFormat::Off: mesh = detail::readOff(path); break;
  case MeshFormat::Stl: mesh = detail::readStl(path); break;
  case MeshFormat::Gltf:
  case MeshFormat::Glb: mesh = detail::readGltf(path); break;
  case MeshFormat::ThreeMf: mesh = detail::read3mf(path); break;
  }
  validateMesh(mesh, path.string());
  return mesh;
}

namespace {

using SideFiles = std::vector<std::pair<fs::path, fs::path>>;  // (temporary, final)

// Runs write(tmp, sideFiles) for `path`; on failure the temporaries are removed. Side files
// (textures, MTL, .bin) are committed first, the model last: it never points at missing files.
template <class Write>
void writeCommitted(const fs::path& path, Write&& write) {
  checkOutputLocation(path);
  const fs::path tmp = temporaryPathFor(path);
  SideFiles sideFiles;
  try {
    write(tmp, sideFiles);
  } catch (...) {
    discardTemporary(tmp);
    for (const auto& side : sideFiles) discardTemporary(side.first);
    throw;
  }
  for (const auto& side : sideFiles) commitFile(side.first, side.second);
  commitFile(tmp, path);
}

} // namespace

void writeMesh(const Mesh& mesh, const fs::path& path, const MeshWriteOptions& options) {
  const MeshFormat format = meshFormatOf(path);
  validateMesh(mesh, path.string());
  if (options.draco && !meshFormatIsGltf(format))
    throw Error(path.string() + ": Draco compression needs a .glb or .gltf output");
  writeCommitted(path, [&](const fs::path& tmp, SideFiles& sideFiles) {
    switch (format) {
    case MeshFormat::Obj: detail::writeObj(mesh, path, tmp, options, sideFiles); break;
    case MeshFormat::Ply: detail::writePly(mesh, tmp, options.binary); break;
    case MeshFormat::Off: detail::writeOff(mesh, tmp); break;
    case MeshFormat::Stl: detail::writeStl(mesh, tmp, options.binary); break;
    case MeshFormat::Gltf: detail::writeGltf(mesh, path, tmp, false, options, sideFiles); break;
    case MeshFormat::Glb: detail::writeGltf(mesh, path, tmp, true, options, sideFiles); break;
    case MeshFormat::ThreeMf:
      detail::write3mf(mesh, path, tmp, millimetresPerUnit(mesh, options) * upToZ(options.up));
      break;
    }
  });
}

Eigen::Matrix3d upToZ(const Eigen::Vector3f& up) {
  const Eigen::Vector3d u = up.cast<double>().normalized(), z = Eigen::Vector3d::UnitZ();
  if (u.dot(z) < -1 + 1e-12) return Eigen::AngleAxisd(3.14159265358979323846, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return Eigen::Quaterniond::FromTwoVectors(u, z).toRotationMatrix();
}

double millimetresPerUnit(const Mesh& mesh, const MeshWriteOptions& options) {
  if (options.millimetresPerUnit > 0) return options.millimetresPerUnit;
  if (!(options.heightMm > 0)) return 1.0;
  const Eigen::Vector3f up = options.up.normalized();
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const Eigen::Vector3f& p : mesh.positions) {
    lo = std::min(lo, p.dot(up));
    hi = std::max(hi, p.dot(up));
  }
  if (!(hi > lo)) throw Error("the model has no height along its up axis: a print height cannot size it");
  return options.heightMm / double(hi - lo);
}

void writeScene(std::span<const SceneNode> nodes, const fs::path& path, const MeshWriteOptions& options) {
  const MeshFormat format = meshFormatOf(path);
  if (!meshFormatIsGltf(format))
    throw Error(path.string() + ": a scene of several meshes needs a .glb or .gltf output");
  if (nodes.empty()) throw Error(path.string() + ": a scene needs at least one mesh");
  for (const SceneNode& node : nodes) validateMesh(node.mesh, path.string() + " (" + node.name + ")");
  writeCommitted(path, [&](const fs::path& tmp, SideFiles& sideFiles) {
    detail::writeGltfScene(nodes, path, tmp, format == MeshFormat::Glb, options, sideFiles);
  });
}

namespace detail {

EncodedImage storedImage(const Texture& texture, const MeshWriteOptions& options) {
  if (options.textures == TextureEncoding::Keep && texture.encoded) return *texture.encoded;
  const ImageCodec codec = options.textures == TextureEncoding::Jpeg   ? ImageCodec::Jpeg
                           : options.textures == TextureEncoding::Webp ? ImageCodec::Webp
                                                                       : ImageCodec::Png;
  return {encodeImage(*texture.image, codec, options.textureQuality), codec};
}

std::vector<uint8_t> readFileBytes(const fs::path& path, uint64_t maxBytes) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw Error(path.string() + ": cannot open file");
  std::error_code ec;
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) throw Error(path.string() + ": cannot read file size");
  if (size > maxBytes) throw Error(path.string() + ": file is too large (" + std::to_string(size) + " bytes)");
  std::vector<uint8_t> bytes(size);
  if (size > 0 && std::fread(bytes.data(), 1, size, file.get()) != size)
    throw Error(path.string() + ": read error");
  return bytes;
}

void writeFileBytes(const fs::path& path, std::string_view bytes, const fs::path& shownAs) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw Error(systemError(shownAs, "cannot create file", errno));
  out.write(bytes.data(), std::streamsize(bytes.size()));
  if (!out.flush()) throw Error(systemError(shownAs, "cannot write file", errno));
}

std::string_view TextCursor::nextLine() {
  const char* start = p_;
  while (p_ < end_ && *p_ != '\n' && *p_ != '\r') ++p_;
  std::string_view line(start, size_t(p_ - start));
  if (p_ < end_ && *p_ == '\r') ++p_;
  if (p_ < end_ && *p_ == '\n') ++p_;
  ++line_;
  return line;
}

Material importedMaterial(std::string name) {
  Material m;
  m.name = std::move(name);
  m.metallicFactor = 0.0f;
  m.roughnessFactor = 0.8f;
  return m;
}

Eigen::Vector3f importedNormal(const Eigen::Vector3f& n, const Mesh& mesh, size_t t, const fs::path& path) {
  if (!n.allFinite()) throw Error(path.string() + ": a normal is NaN or infinite");
  return n.squaredNorm() > 0 ? Eigen::Vector3f(n.normalized()) : faceNormal(mesh, t);
}

std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

bool parseFloat(std::string_view word, float& value) {
  const char* b = word.data();
  if (!word.empty() && *b == '+') ++b;
  const auto [end, ec] = std::from_chars(b, word.data() + word.size(), value);
  return ec == std::errc() && end == word.data() + word.size();
}

bool parseInt(std::string_view word, long long& value) {
  const char* b = word.data();
  if (!word.empty() && *b == '+') ++b;
  const auto [end, ec] = std::from_chars(b, word.data() + word.size(), value);
  return ec == std::errc() && end == word.data() + word.size();
}

} // namespace detail
} // namespace texfab::geometry
