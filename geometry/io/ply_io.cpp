// SPDX-License-Identifier: GPL-3.0-or-later
// PLY (Stanford polygon format), ASCII and binary, reading and writing.
#include "core/error.h"
#include "geometry/io/mesh_formats.h"

#include <algorithm>
#include <array>
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

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  size_t bodyStart = 0;  ///< the first byte after end_header's line
};

Header readHeader(const fs::path& path, std::string_view all) {
  if (all.substr(0, 3) != "ply") throw Error(path.string() + ": not a PLY file (no 'ply' magic)");
  const size_t headerEnd = all.find("end_header");
  if (headerEnd == std::string_view::npos) throw Error(path.string() + ": PLY header has no end_header");
  Header h;
  h.bodyStart = headerEnd + 10;
  if (h.bodyStart < all.size() && all[h.bodyStart] == '\r') ++h.bodyStart;
  if (h.bodyStart < all.size() && all[h.bodyStart] == '\n') ++h.bodyStart;
  TextCursor cursor(all.data(), all.data() + headerEnd);
  bool haveFormat = false;
  while (!cursor.atEnd()) {
    const auto words = splitWords(cursor.nextLine());
    if (words.empty()) continue;
    const auto bad = [&](const std::string& what) {
      return Error(path.string() + ":" + std::to_string(cursor.lineNumber()) + ": " + what);
    };
    if (words[0] == "format") {
      if (words.size() < 2) throw bad("format line without a format");
      if (words[1] == "ascii") h.encoding = Encoding::Ascii;
      else if (words[1] == "binary_little_endian") h.encoding = Encoding::Little;
      else if (words[1] == "binary_big_endian") h.encoding = Encoding::Big;
      else throw bad("unknown PLY format '" + std::string(words[1]) + "'");
      haveFormat = true;
    } else if (words[0] == "element") {
      long long count = 0;
      if (words.size() < 3 || !parseInt(words[2], count) || count < 0) throw bad("bad element line");
      h.elements.push_back({std::string(words[1]), uint64_t(count), {}});
    } else if (words[0] == "property") {
      if (h.elements.empty()) throw bad("property before any element");
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
      h.elements.back().properties.push_back(prop);
    }
  }
  if (!haveFormat) throw Error(path.string() + ": PLY header has no format line");
  return h;
}

// The body's elements into a mesh: vertices (positions, per-vertex UVs and normals) and faces
// (triangulated, with per-corner texcoords and material indices); other elements are skipped.
class MeshBuilder {
public:
  MeshBuilder(const fs::path& path, BodyReader& body, Encoding encoding) : path_(path), body_(body), encoding_(encoding) {}

  void read(const Element& element) {
    checkCount(element);
    if (element.properties.empty() && element.name != "vertex") return;  // items without data: nothing to read
    const bool isVertex = element.name == "vertex", isFace = element.name == "face";
    auto find = [&](std::initializer_list<const char*> names) -> int {
      for (const char* n : names)
        for (size_t i = 0; i < element.properties.size(); ++i)
          if (element.properties[i].name == n && !element.properties[i].list) return int(i);
      return -1;
    };
    const std::array<int, 3> position = {find({"x"}), find({"y"}), find({"z"})};
    const std::array<int, 3> normal = {find({"nx"}), find({"ny"}), find({"nz"})};
    const std::array<int, 2> uv = {find({"s", "u", "texture_u", "texture_s"}), find({"t", "v", "texture_v", "texture_t"})};
    const int material = find({"material_index"});
    if (isVertex) {
      if (*std::min_element(position.begin(), position.end()) < 0)
        throw Error(path_.string() + ": PLY vertex element lacks x, y or z");
      mesh_.positions.reserve(element.count);
    }
    for (uint64_t item = 0; item < element.count; ++item) {
      values_.assign(element.properties.size(), 0.0);
      facePositions_.clear();
      faceCorners_.clear();
      for (size_t pi = 0; pi < element.properties.size(); ++pi) {
        const Property& prop = element.properties[pi];
        values_[pi] = prop.list ? readList(element, prop, isFace, item) : body_.read(prop.type);
      }
      if (isVertex) {
        auto at = [&](int i) { return float(values_[size_t(i)]); };
        mesh_.positions.emplace_back(at(position[0]), at(position[1]), at(position[2]));
        if (uv[0] >= 0 && uv[1] >= 0) vertexUvs_.emplace_back(at(uv[0]), at(uv[1]));
        if (*std::min_element(normal.begin(), normal.end()) >= 0)
          vertexNormals_.emplace_back(at(normal[0]), at(normal[1]), at(normal[2]));
      }
      if (isFace) {
        if (material >= 0) addMaterial(values_[size_t(material)]);
        if (cornerUvs_.size() != 3 * mesh_.triangles.size()) haveCornerUvs_ = false;
      }
    }
  }

  // Per-corner UVs (per-face texcoords, else per-vertex UVs), normals and materials.
  Mesh finish() && {
    const size_t corners = 3 * mesh_.triangles.size();
    if (haveCornerUvs_ && !cornerUvs_.empty() && cornerUvs_.size() == corners) {
      mesh_.uvs = std::move(cornerUvs_);
    } else if (vertexUvs_.size() == mesh_.positions.size() && !vertexUvs_.empty()) {
      mesh_.uvs.resize(corners);
      for (size_t c = 0; c < corners; ++c) mesh_.uvs[c] = vertexUvs_[mesh_.triangles[c / 3][c % 3]];
    }
    if (vertexNormals_.size() == mesh_.positions.size() && !vertexNormals_.empty()) {
      mesh_.normals.resize(corners);
      for (size_t c = 0; c < corners; ++c) {
        mesh_.normals[c] = importedNormal(vertexNormals_[mesh_.triangles[c / 3][c % 3]], mesh_, c / 3, path_);
      }
    }
    if (mesh_.faceMaterials.size() != mesh_.triangles.size()) {
      mesh_.faceMaterials.clear();
    } else if (!mesh_.faceMaterials.empty()) {
      mesh_.materials.assign(*std::max_element(mesh_.faceMaterials.begin(), mesh_.faceMaterials.end()) + 1,
                             importedMaterial());
    }
    return std::move(mesh_);
  }

private:
  // Every item takes at least one byte (binary) or two (ASCII: digit and separator): a count
  // larger than the data left is a corrupt header, refused before any allocation.
  void checkCount(const Element& element) const {
    size_t minItem = 0;
    for (const Property& p : element.properties) minItem += p.list ? scalarSize(p.countType) : scalarSize(p.type);
    if (encoding_ == Encoding::Ascii) minItem = 2 * element.properties.size();
    if (minItem > 0 && element.count > body_.remaining() / minItem)
      throw Error(path_.string() + ": PLY element '" + element.name + "' count " + std::to_string(element.count) +
                  " exceeds the file's data");
  }

  // A list property; faces' vertex indices and texcoords go into the mesh. Returns its length.
  double readList(const Element& element, const Property& prop, bool isFace, uint64_t item) {
    const double countValue = body_.read(prop.countType);
    if (!(countValue >= 0) || countValue > 1e6 || countValue != std::floor(countValue))
      throw Error(path_.string() + ": bad list length in PLY element '" + element.name + "'");
    const size_t count = size_t(countValue);
    if (encoding_ != Encoding::Ascii && count * scalarSize(prop.type) > body_.remaining())
      throw Error(path_.string() + ": truncated PLY data");
    list_.resize(count);
    for (double& v : list_) v = body_.read(prop.type);
    if (isFace && (prop.name == "vertex_indices" || prop.name == "vertex_index")) addFace(item);
    if (isFace && prop.name == "texcoord") addTexcoords();
    return double(count);
  }

  void addFace(uint64_t item) {
    if (list_.size() < 3) throw Error(path_.string() + ": PLY face " + std::to_string(item) + " has fewer than 3 vertices");
    facePositions_.clear();
    for (double idx : list_) {
      if (!(idx >= 0) || idx >= double(mesh_.positions.size()))
        throw Error(path_.string() + ": PLY face " + std::to_string(item) + " uses vertex " +
                    (std::abs(idx) < 1e15 ? std::to_string((long long)idx) : std::string("beyond any index")) +
                    " but there are " + std::to_string(mesh_.positions.size()) + " vertices");
      facePositions_.push_back(mesh_.positions[size_t(idx)]);
    }
    faceCorners_ = triangulatePolygon(facePositions_);
    for (const auto& tri : faceCorners_)
      mesh_.triangles.push_back({uint32_t(list_[tri[0]]), uint32_t(list_[tri[1]]), uint32_t(list_[tri[2]])});
  }

  // Triangulated the same way as the vertex indices (which PLY lists first).
  void addTexcoords() {
    if (list_.size() % 2 != 0) throw Error(path_.string() + ": PLY face texcoord list has an odd length");
    if (list_.size() / 2 == facePositions_.size())
      for (const auto& tri : faceCorners_)
        for (uint32_t c : tri) cornerUvs_.emplace_back(float(list_[2 * c]), float(list_[2 * c + 1]));
  }

  void addMaterial(double m) {
    if (!(m >= 0) || m > 65535) throw Error(path_.string() + ": bad PLY material_index");
    mesh_.faceMaterials.insert(mesh_.faceMaterials.end(), mesh_.triangles.size() - mesh_.faceMaterials.size(), uint32_t(m));
  }

  const fs::path& path_;
  BodyReader& body_;
  Encoding encoding_;
  Mesh mesh_;
  std::vector<Eigen::Vector2f> vertexUvs_, cornerUvs_;
  std::vector<Eigen::Vector3f> vertexNormals_;
  bool haveCornerUvs_ = true;
  std::vector<double> values_, list_;               // the current item's values, and its current list
  std::vector<Eigen::Vector3f> facePositions_;       // the current face's corners
  std::vector<std::array<uint32_t, 3>> faceCorners_; // and its triangulation
};

} // namespace

Mesh readPly(const fs::path& path) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  const Header header = readHeader(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  BodyReader body(path, bytes.data() + std::min(header.bodyStart, bytes.size()), bytes.data() + bytes.size(), header.encoding);
  MeshBuilder builder(path, body, header.encoding);
  for (const Element& element : header.elements) builder.read(element);
  return std::move(builder).finish();
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
