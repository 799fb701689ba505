// SPDX-License-Identifier: GPL-3.0-or-later
// PLY (Stanford polygon format), ASCII and binary, reading and writing.
#include "geometry/mesh_formats.h"
#include "render/image/error.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>

namespace texfab::geometry::detail {
namespace fs = std::filesystem;

namespace {

enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool scalarFromName(std::string_view n, Scalar& s) {
  if (n == "char" || n == "int8") s = Scalar::Int8;
  else if (n == "uchar" || n == "uint8") s = Scalar::UInt8;
  else if (n == "short" || n == "int16") s = Scalar::Int16;
  else if (n == "ushort" || n == "uint16") s = Scalar::UInt16;
  else if (n == "int" || n == "int32") s = Scalar::Int32;
  else if (n == "uint" || n == "uint32") s = Scalar::UInt32;
  else if (n == "float" || n == "float32") s = Scalar::Float32;
  else if (n == "double" || n == "float64") s = Scalar::Float64;
  else return false;
  return true;
}

size_t scalarSize(Scalar s) {
  switch (s) {
  case Scalar::Int8: case Scalar::UInt8: return 1;
  case Scalar::Int16: case Scalar::UInt16: return 2;
  case Scalar::Int32: case Scalar::UInt32: case Scalar::Float32: return 4;
  case Scalar::Float64: return 8;
  }
  return 1;
}

struct Property {
  std::string name;
  Scalar type = Scalar::Float32;
  bool list = false;
  Scalar countType = Scalar::UInt8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Encoding { Ascii, Little, Big };

// Reads scalars from the body, ASCII or binary, with bounds checks.
class BodyReader {
public:
  BodyReader(const fs::path& path, const uint8_t* p, const uint8_t* end, Encoding encoding)
      : path_(path), p_(p), end_(end), encoding_(encoding) {}

  double read(Scalar s) {
    if (encoding_ == Encoding::Ascii) return readAscii();
    const size_t n = scalarSize(s);
    if (size_t(end_ - p_) < n) throw Error(path_.string() + ": truncated PLY data");
    uint8_t b[8];
    std::memcpy(b, p_, n);
    p_ += n;
    if ((encoding_ == Encoding::Big) != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    switch (s) {
    case Scalar::Int8: { int8_t v; std::memcpy(&v, b, 1); return v; }
    case Scalar::UInt8: return b[0];
    case Scalar::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
    case Scalar::UInt16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
    case Scalar::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
    case Scalar::UInt32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
    case Scalar::Float32: { float v; std::memcpy(&v, b, 4); return v; }
    case Scalar::Float64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }
  size_t remaining() const { return size_t(end_ - p_); }

private:
  double readAscii() {
    while (p_ < end_ && std::isspace(*p_)) ++p_;
    const uint8_t* start = p_;
    while (p_ < end_ && !std::isspace(*p_)) ++p_;
    if (start == p_) throw Error(path_.string() + ": truncated PLY data");
    float f;
    if (!parseFloat(std::string_view(reinterpret_cast<const char*>(start), size_t(p_ - start)), f))
      throw Error(path_.string() + ": bad number '" + std::string(reinterpret_cast<const char*>(start), size_t(p_ - start)) +
                  "' in PLY data");
    return f;
  }
  const fs::path& path_;
  const uint8_t* p_;
  const uint8_t* end_;
  Encoding encoding_;
};

} // namespace

Mesh readPly(const fs::path& path) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  const char* text = reinterpret_cast<const char*>(bytes.data());
  // Header: up to "end_header\n".
  const std::string_view all(text, bytes.size());
  if (all.substr(0, 3) != "ply") throw Error(path.string() + ": not a PLY file (no 'ply' magic)");
  const size_t headerEnd = all.find("end_header");
  if (headerEnd == std::string_view::npos) throw Error(path.string() + ": PLY header has no end_header");
  size_t bodyStart = headerEnd + 10;
  if (bodyStart < all.size() && all[bodyStart] == '\r') ++bodyStart;
  if (bodyStart < all.size() && all[bodyStart] == '\n') ++bodyStart;
  TextCursor cursor(text, text + headerEnd);
  Encoding encoding = Encoding::Ascii;
  bool haveFormat = false;
  std::vector<Element> elements;
  while (!cursor.atEnd()) {
    const auto words = splitWords(cursor.nextLine());
    if (words.empty()) continue;
    const auto bad = [&](const std::string& what) {
      return Error(path.string() + ":" + std::to_string(cursor.lineNumber()) + ": " + what);
    };
    if (words[0] == "format") {
      if (words.size() < 2) throw bad("format line without a format");
      if (words[1] == "ascii") encoding = Encoding::Ascii;
      else if (words[1] == "binary_little_endian") encoding = Encoding::Little;
      else if (words[1] == "binary_big_endian") encoding = Encoding::Big;
      else throw bad("unknown PLY format '" + std::string(words[1]) + "'");
      haveFormat = true;
    } else if (words[0] == "element") {
      long long count = 0;
      if (words.size() < 3 || !parseInt(words[2], count) || count < 0) throw bad("bad element line");
      elements.push_back({std::string(words[1]), uint64_t(count), {}});
    } else if (words[0] == "property") {
      if (elements.empty()) throw bad("property before any element");
      Property prop;
      if (words.size() >= 5 && words[1] == "list") {
        if (!scalarFromName(words[2], prop.countType) || !scalarFromName(words[3], prop.type)) throw bad("bad list property type");
        prop.list = true;
        prop.name = words[4];
      } else if (words.size() >= 3) {
        if (!scalarFromName(words[1], prop.type)) throw bad("unknown property type '" + std::string(words[1]) + "'");
        prop.name = words[2];
      } else {
        throw bad("bad property line");
      }
      elements.back().properties.push_back(prop);
    }
  }
  if (!haveFormat) throw Error(path.string() + ": PLY header has no format line");

  BodyReader body(path, bytes.data() + std::min(bodyStart, bytes.size()), bytes.data() + bytes.size(), encoding);
  Mesh mesh;
  std::vector<Eigen::Vector2f> vertexUvs;
  std::vector<Eigen::Vector3f> vertexNormals;
  std::vector<Eigen::Vector2f> cornerUvs;
  bool haveCornerUvs = true;
  std::vector<double> values;
  std::vector<Eigen::Vector3f> facePositions;
  std::vector<std::array<uint32_t, 3>> faceCorners;
  for (const Element& element : elements) {
    // Every item takes at least one byte (binary) or two (ASCII: digit and separator): a count
    // larger than the data left is a corrupt header, refused before any allocation.
    size_t minItem = 0;
    for (const Property& p : element.properties) minItem += p.list ? scalarSize(p.countType) : scalarSize(p.type);
    if (encoding == Encoding::Ascii) minItem = 2 * element.properties.size();
    if (minItem > 0 && element.count > body.remaining() / minItem)
      throw Error(path.string() + ": PLY element '" + element.name + "' count " + std::to_string(element.count) +
                  " exceeds the file's data");
    const bool isVertex = element.name == "vertex", isFace = element.name == "face";
    auto find = [&](std::initializer_list<const char*> names) -> int {
      for (const char* n : names)
        for (size_t i = 0; i < element.properties.size(); ++i)
          if (element.properties[i].name == n && !element.properties[i].list) return int(i);
      return -1;
    };
    const int ix = find({"x"}), iy = find({"y"}), iz = find({"z"});
    const int inx = find({"nx"}), iny = find({"ny"}), inz = find({"nz"});
    const int iu = find({"s", "u", "texture_u", "texture_s"}), iv = find({"t", "v", "texture_v", "texture_t"});
    if (isVertex) {
      if (ix < 0 || iy < 0 || iz < 0) throw Error(path.string() + ": PLY vertex element lacks x, y or z");
      mesh.positions.reserve(element.count);
    }
    for (uint64_t item = 0; item < element.count; ++item) {
      values.assign(element.properties.size(), 0.0);
      facePositions.clear();
      faceCorners.clear();
      for (size_t pi = 0; pi < element.properties.size(); ++pi) {
        const Property& prop = element.properties[pi];
        if (!prop.list) {
          values[pi] = body.read(prop.type);
          continue;
        }
        const double countValue = body.read(prop.countType);
        if (!(countValue >= 0) || countValue > 1e6 || countValue != std::floor(countValue))
          throw Error(path.string() + ": bad list length in PLY element '" + element.name + "'");
        const size_t count = size_t(countValue);
        if (encoding != Encoding::Ascii && count * scalarSize(prop.type) > body.remaining())
          throw Error(path.string() + ": truncated PLY data");
        std::vector<double> list(count);
        for (double& v : list) v = body.read(prop.type);
        if (isFace && (prop.name == "vertex_indices" || prop.name == "vertex_index")) {
          if (count < 3) throw Error(path.string() + ": PLY face " + std::to_string(item) + " has fewer than 3 vertices");
          facePositions.clear();
          for (double idx : list) {
            if (!(idx >= 0) || idx >= double(mesh.positions.size()))
              throw Error(path.string() + ": PLY face " + std::to_string(item) + " uses vertex " +
                          std::to_string((long long)idx) + " but there are " + std::to_string(mesh.positions.size()) +
                          " vertices");
            facePositions.push_back(mesh.positions[size_t(idx)]);
          }
          faceCorners = triangulatePolygon(facePositions);
          for (const auto& tri : faceCorners)
            mesh.triangles.push_back({uint32_t(list[tri[0]]), uint32_t(list[tri[1]]), uint32_t(list[tri[2]])});
          values[pi] = double(count);
        } else if (isFace && prop.name == "texcoord") {
          values[pi] = double(count);
          if (count % 2 != 0) throw Error(path.string() + ": PLY face texcoord list has an odd length");
          // Triangulated the same way as the vertex indices (which PLY lists first).
          if (count / 2 == facePositions.size())
            for (const auto& tri : faceCorners)
              for (uint32_t c : tri) cornerUvs.emplace_back(float(list[2 * c]), float(list[2 * c + 1]));
        }
      }
      if (isVertex) {
        mesh.positions.emplace_back(float(values[size_t(ix)]), float(values[size_t(iy)]), float(values[size_t(iz)]));
        if (iu >= 0 && iv >= 0) vertexUvs.emplace_back(float(values[size_t(iu)]), float(values[size_t(iv)]));
        if (inx >= 0 && iny >= 0 && inz >= 0)
          vertexNormals.emplace_back(float(values[size_t(inx)]), float(values[size_t(iny)]), float(values[size_t(inz)]));
      }
      if (isFace) {
        const int im = find({"material_index"});
        if (im >= 0) {
          const double m = values[size_t(im)];
          const size_t tris = mesh.triangles.size() - mesh.faceMaterials.size();
          if (!(m >= 0) || m > 65535) throw Error(path.string() + ": bad PLY material_index");
          mesh.faceMaterials.insert(mesh.faceMaterials.end(), tris, uint32_t(m));
        }
        if (cornerUvs.size() != 3 * mesh.triangles.size()) haveCornerUvs = false;
      }
    }
  }
  const size_t corners = 3 * mesh.triangles.size();
  if (haveCornerUvs && !cornerUvs.empty() && cornerUvs.size() == corners) {
    mesh.uvs = std::move(cornerUvs);
  } else if (vertexUvs.size() == mesh.positions.size() && !vertexUvs.empty()) {
    mesh.uvs.resize(corners);
    for (size_t c = 0; c < corners; ++c) mesh.uvs[c] = vertexUvs[mesh.triangles[c / 3][c % 3]];
  }
  if (vertexNormals.size() == mesh.positions.size() && !vertexNormals.empty()) {
    mesh.normals.resize(corners);
    for (size_t c = 0; c < corners; ++c) {
      const Eigen::Vector3f n = vertexNormals[mesh.triangles[c / 3][c % 3]];
      if (!n.allFinite()) throw Error(path.string() + ": a normal is NaN or infinite");
      mesh.normals[c] = n.squaredNorm() > 0 ? Eigen::Vector3f(n.normalized()) : faceNormal(mesh, c / 3);
    }
  }
  if (!mesh.faceMaterials.empty()) {
    if (mesh.faceMaterials.size() != mesh.triangles.size()) {
      mesh.faceMaterials.clear();
    } else {
      uint32_t maxId = 0;
      for (uint32_t m : mesh.faceMaterials) maxId = std::max(maxId, m);
      mesh.materials.resize(maxId + 1);
      for (Material& m : mesh.materials) {
        m.metallicFactor = 0.0f;
        m.roughnessFactor = 0.8f;
      }
    }
  }
  return mesh;
}

void writePly(const Mesh& mesh, const fs::path& tmp, bool binary) {
  std::vector<Eigen::Vector3f> normals;
  if (mesh.hasNormals()) {
    normals.assign(mesh.positions.size(), Eigen::Vector3f::Zero());
    for (size_t c = 0; c < mesh.normals.size(); ++c) normals[mesh.triangles[c / 3][c % 3]] += mesh.normals[c];
    for (auto& n : normals) n = n.squaredNorm() > 0 ? Eigen::Vector3f(n.normalized()) : Eigen::Vector3f(0, 0, 1);
  }
  const bool materials = mesh.materials.size() > 1 && !mesh.faceMaterials.empty();
  std::ostringstream out;
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment texfab\n";
  out << "element vertex " << mesh.positions.size() << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (mesh.hasNormals()) out << "property float nx\nproperty float ny\nproperty float nz\n";
  out << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\n";
  if (mesh.hasUvs()) out << "property list uchar float texcoord\n";
  if (materials) out << "property int material_index\n";
  out << "end_header\n";
  std::string data = out.str();
  auto put = [&](auto v) {
    if (binary) {
      char b[sizeof v];
      std::memcpy(b, &v, sizeof v);
      if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof v);
      data.append(b, sizeof v);
    } else {
      char b[32];
      if constexpr (std::is_floating_point_v<decltype(v)>) std::snprintf(b, sizeof b, "%.9g ", double(v));
      else std::snprintf(b, sizeof b, "%lld ", (long long)v);
      data += b;
    }
  };
  auto endItem = [&] {
    if (!binary) data.back() = '\n';
  };
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) put(mesh.positions[i][k]);
    if (mesh.hasNormals())
      for (int k = 0; k < 3; ++k) put(normals[i][k]);
    endItem();
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    put(uint8_t(3));
    for (uint32_t v : mesh.triangles[t]) put(int32_t(v));
    if (mesh.hasUvs()) {
      put(uint8_t(6));
      for (int k = 0; k < 3; ++k) {
        put(mesh.uvs[3 * t + size_t(k)].x());
        put(mesh.uvs[3 * t + size_t(k)].y());
      }
    }
    if (materials) put(int32_t(mesh.materialOf(t)));
    endItem();
  }
  writeFileBytes(tmp, data, tmp);
}

} // namespace texfab::geometry::detail
