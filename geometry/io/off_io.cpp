// SPDX-License-Identifier: GPL-3.0-or-later
// OFF (Object File Format, as in CGAL's data set) reading and writing. ASCII only.
#include "core/error.h"
#include "geometry/io/mesh_formats.h"

#include <cmath>

namespace texfab::geometry::detail {
namespace fs = std::filesystem;

Mesh readOff(const fs::path& path) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  const char* text = reinterpret_cast<const char*>(bytes.data());
  TextCursor cursor(text, text + bytes.size());
  // Tokens across lines, skipping comments.
  std::vector<std::string_view> words;
  size_t next = 0;
  auto token = [&]() -> std::string_view {
    while (next >= words.size()) {
      if (cursor.atEnd()) throw Error(path.string() + ": truncated OFF file");
      std::string_view line = cursor.nextLine();
      const size_t hash = line.find('#');
      if (hash != std::string_view::npos) line = line.substr(0, hash);
      words = splitWords(line);
      next = 0;
    }
    return words[next++];
  };
  auto integer = [&](const char* what) {
    long long v = 0;
    const std::string_view w = token();
    if (!parseInt(w, v)) throw Error(path.string() + ":" + std::to_string(cursor.lineNumber()) + ": expected " + what +
                                     ", found '" + std::string(w) + "'");
    return v;
  };
  auto number = [&]() {
    float v = 0;
    const std::string_view w = token();
    if (!parseFloat(w, v))
      throw Error(path.string() + ":" + std::to_string(cursor.lineNumber()) + ": expected a number, found '" + std::string(w) + "'");
    return v;
  };
  const std::string_view magic = token();
  const bool hasMagic = magic.size() >= 3 && magic.substr(magic.size() - 3) == "OFF";
  if (hasMagic && (magic.find('4') != std::string_view::npos || magic.front() == 'n'))
    throw Error(path.string() + ": only 3-D OFF files are supported ('" + std::string(magic) + "')");
  const bool colors = hasMagic && magic.find('C') != std::string_view::npos;
  const bool normals = hasMagic && magic.find('N') != std::string_view::npos;
  const bool texcoords = hasMagic && magic.find("ST") != std::string_view::npos;
  if (!hasMagic) next = 0; // header counts without the magic word
  const long long nv = integer("the vertex count"), nf = integer("the face count");
  (void)integer("the edge count");
  if (nv < 0 || nf < 0 || uint64_t(nv) > bytes.size() / 6 || uint64_t(nf) > bytes.size() / 8)
    throw Error(path.string() + ": OFF counts (" + std::to_string(nv) + " vertices, " + std::to_string(nf) +
                " faces) do not fit the file");
  Mesh mesh;
  mesh.positions.resize(size_t(nv));
  for (auto& p : mesh.positions) {
    // One statement per coordinate: argument evaluation order is unspecified.
    p.x() = number();
    p.y() = number();
    p.z() = number();
    if (normals) number(), number(), number();
    if (colors) {
      // Colour: 3 or 4 numbers up to the end of the line.
      while (next < words.size()) ++next;
    }
    if (texcoords) number(), number();
  }
  std::vector<uint32_t> face;
  std::vector<Eigen::Vector3f> facePositions;
  for (long long f = 0; f < nf; ++f) {
    const long long n = integer("a face size");
    if (n < 3 || n > 1000000) throw Error(path.string() + ": OFF face " + std::to_string(f) + " has " + std::to_string(n) + " vertices");
    face.clear();
    for (long long k = 0; k < n; ++k) {
      const long long v = integer("a vertex index");
      if (v < 0 || v >= nv)
        throw Error(path.string() + ": OFF face " + std::to_string(f) + " uses vertex " + std::to_string(v) +
                    " but there are " + std::to_string(nv) + " vertices");
      face.push_back(uint32_t(v));
    }
    facePositions.clear();
    for (uint32_t v : face) facePositions.push_back(mesh.positions[v]);
    for (const auto& tri : triangulatePolygon(facePositions)) mesh.triangles.push_back({face[tri[0]], face[tri[1]], face[tri[2]]});
    // Optional face colour: rest of the line.
    next = words.size();
  }
  return mesh;
}

void writeOff(const Mesh& mesh, const fs::path& tmp) {
  std::string out = "OFF\n" + std::to_string(mesh.positions.size()) + " " + std::to_string(mesh.triangles.size()) + " 0\n";
  char buf[96];
  for (const auto& p : mesh.positions) {
    std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", double(p.x()), double(p.y()), double(p.z()));
    out += buf;
  }
  for (const auto& t : mesh.triangles) out += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  writeFileBytes(tmp, out, tmp);
}

} // namespace texfab::geometry::detail
