// SPDX-License-Identifier: GPL-3.0-or-later
// STL reading (ASCII and binary; identical corner positions are welded into shared vertices) and
// writing.
#include "core/error.h"
#include "geometry/io/mesh_formats.h"

#include <bit>
#include <cstring>
#include <unordered_map>

namespace texfab::geometry::detail {
namespace fs = std::filesystem;

namespace {

struct PositionHash {
  size_t operator()(const Eigen::Vector3f& p) const {
    uint32_t b[3];
    std::memcpy(b, p.data(), sizeof b);
    return (size_t(b[0]) * 73856093u) ^ (size_t(b[1]) * 19349663u) ^ (size_t(b[2]) * 83492791u);
  }
};
struct PositionEqual {
  bool operator()(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const { return a == b; }
};

class Welder {
public:
  explicit Welder(Mesh& mesh) : mesh_(mesh) {}
  uint32_t add(const Eigen::Vector3f& p) {
    const auto [it, inserted] = index_.emplace(p, uint32_t(mesh_.positions.size()));
    if (inserted) mesh_.positions.push_back(p);
    return it->second;
  }

private:
  Mesh& mesh_;
  std::unordered_map<Eigen::Vector3f, uint32_t, PositionHash, PositionEqual> index_;
};

float readFloatLE(const uint8_t* p) {
  uint8_t b[4];
  std::memcpy(b, p, 4);
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + 4);
  float f;
  std::memcpy(&f, b, 4);
  return f;
}

} // namespace

Mesh readStl(const fs::path& path) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  Mesh mesh;
  Welder welder(mesh);
  uint32_t count = 0;
  if (bytes.size() >= 84) {
    std::memcpy(&count, bytes.data() + 80, 4);
    if constexpr (std::endian::native == std::endian::big) count = __builtin_bswap32(count);
  }
  const bool binary = bytes.size() >= 84 && uint64_t(84) + uint64_t(count) * 50 == bytes.size();
  const std::string_view head(reinterpret_cast<const char*>(bytes.data()), std::min<size_t>(bytes.size(), 5));
  if (binary) {
    mesh.triangles.reserve(count);
    for (uint32_t t = 0; t < count; ++t) {
      const uint8_t* rec = bytes.data() + 84 + size_t(t) * 50;
      std::array<uint32_t, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        const uint8_t* v = rec + 12 + 12 * k;
        tri[size_t(k)] = welder.add(Eigen::Vector3f(readFloatLE(v), readFloatLE(v + 4), readFloatLE(v + 8)));
      }
      mesh.triangles.push_back(tri);
    }
    return mesh;
  }
  if (head != "solid")
    throw Error(path.string() + (bytes.size() >= 84 ? ": binary STL size does not match its triangle count (" +
                                                          std::to_string(count) + " triangles need " +
                                                          std::to_string(84 + uint64_t(count) * 50) + " bytes, file has " +
                                                          std::to_string(bytes.size()) + ")"
                                                    : ": not an STL file (too short for binary, no 'solid' header)"));
  const char* text = reinterpret_cast<const char*>(bytes.data());
  TextCursor cursor(text, text + bytes.size());
  std::vector<uint32_t> loop;
  bool inLoop = false;
  while (!cursor.atEnd()) {
    const auto words = splitWords(cursor.nextLine());
    if (words.empty()) continue;
    const auto bad = [&](const std::string& what) {
      return Error(path.string() + ":" + std::to_string(cursor.lineNumber()) + ": " + what);
    };
    if (words[0] == "outer") {
      if (inLoop) throw bad("nested 'outer loop'");
      inLoop = true;
      loop.clear();
    } else if (words[0] == "vertex") {
      if (!inLoop) throw bad("'vertex' outside a loop");
      float x, y, z;
      if (words.size() < 4 || !parseFloat(words[1], x) || !parseFloat(words[2], y) || !parseFloat(words[3], z))
        throw bad("bad vertex line");
      if (loop.size() >= 3) throw bad("facet with more than 3 vertices");
      loop.push_back(welder.add(Eigen::Vector3f(x, y, z)));
    } else if (words[0] == "endloop") {
      if (!inLoop || loop.size() != 3) throw bad("facet without exactly 3 vertices");
      mesh.triangles.push_back({loop[0], loop[1], loop[2]});
      inLoop = false;
    }
  }
  if (inLoop) throw Error(path.string() + ": truncated STL file (unterminated facet)");
  return mesh;
}

void writeStl(const Mesh& mesh, const fs::path& tmp, bool binary) {
  std::string out;
  if (binary) {
    out.assign(80, '\0');
    const char header[] = "texfab binary STL";
    std::memcpy(out.data(), header, sizeof header - 1);
    auto put = [&](auto v) {
      char b[sizeof v];
      std::memcpy(b, &v, sizeof v);
      if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof v);
      out.append(b, sizeof v);
    };
    put(uint32_t(mesh.triangles.size()));
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Eigen::Vector3f n = faceNormal(mesh, t);
      for (int k = 0; k < 3; ++k) put(n[k]);
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) put(mesh.corner(t, c)[k]);
      put(uint16_t(0));
    }
  } else {
    out = "solid texfab\n";
    char buf[128];
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Eigen::Vector3f n = faceNormal(mesh, t);
      std::snprintf(buf, sizeof buf, "facet normal %.9g %.9g %.9g\n outer loop\n", double(n.x()), double(n.y()), double(n.z()));
      out += buf;
      for (int c = 0; c < 3; ++c) {
        const Eigen::Vector3f p = mesh.corner(t, c);
        std::snprintf(buf, sizeof buf, "  vertex %.9g %.9g %.9g\n", double(p.x()), double(p.y()), double(p.z()));
        out += buf;
      }
      out += " endloop\nendfacet\n";
    }
    out += "endsolid texfab\n";
  }
  writeFileBytes(tmp, out, tmp);
}

} // namespace texfab::geometry::detail
