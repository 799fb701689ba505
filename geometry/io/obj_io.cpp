// SPDX-License-Identifier: GPL-3.0-or-later
// Wavefront OBJ + MTL reading and writing.
#include "core/context.h"
#include "core/error.h"
#include "core/files.h"
#include "core/image_io.h"
#include "geometry/io/mesh_formats.h"
#include "geometry/io/model_path.h"

#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace texfab::geometry::detail {
namespace fs = std::filesystem;

namespace {

std::string lineError(const fs::path& path, size_t line, const std::string& what) {
  return path.string() + ":" + std::to_string(line) + ": " + what;
}

// The file name of a map_* statement: the words after any "-option value..." pairs.
std::string mapFileName(const std::vector<std::string_view>& words) {
  static const std::map<std::string, int, std::less<>> argCount{
      {"-blendu", 1}, {"-blendv", 1}, {"-bm", 1}, {"-boost", 1}, {"-cc", 1}, {"-clamp", 1}, {"-imfchan", 1},
      {"-mm", 2},     {"-o", 3},      {"-s", 3},  {"-t", 3},     {"-texres", 1}, {"-type", 1}};
  size_t i = 1;
  while (i < words.size() && words[i].size() > 1 && words[i][0] == '-') {
    const auto it = argCount.find(words[i]);
    if (it == argCount.end()) break;
    ++i;
    // -o/-s/-t take 1 to 3 numbers.
    for (int k = 0; k < it->second && i < words.size(); ++k) {
      float f;
      if (!parseFloat(words[i], f) && !(it->second == 1)) break;
      ++i;
    }
  }
  std::string name;
  for (; i < words.size(); ++i) {
    if (!name.empty()) name += ' ';
    name.append(words[i]);
  }
  return name;
}

// Textures by file, each decoded once. A missing texture file is a warning: the material loads
// without it, as in every OBJ reader.
struct TextureCache {
  const Context& ctx;
  std::map<fs::path, std::pair<std::shared_ptr<const Image>, std::shared_ptr<const EncodedImage>>> images;
  Texture load(const fs::path& mtl, const std::string& reference) {
    const fs::path file = resolveModelReference(mtl, reference);
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) {
      ctx.warn(file.string() + ": texture not found; " + mtl.filename().string() + " is read without it");
      return {};
    }
    auto& [image, encoded] = images[file];
    if (!image) {
      std::vector<uint8_t> bytes = readFileBytes(file, uint64_t(1) << 30);
      if (const std::optional<ImageCodec> codec = imageCodecOf(bytes)) {
        image = std::make_shared<const Image>(decodeImage(bytes, file.string()));
        encoded = std::make_shared<const EncodedImage>(EncodedImage{std::move(bytes), *codec});
      } else {
        image = std::make_shared<const Image>(readImage(file));
      }
    }
    Texture texture;
    texture.image = image;
    texture.encoded = encoded;
    texture.name = file.filename().string();
    return texture;
  }
};

void readMtl(const fs::path& obj, const std::string& reference, std::vector<Material>& materials,
             std::map<std::string, uint32_t>& byName, TextureCache& textures) {
  const fs::path path = resolveModelReference(obj, reference);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    textures.ctx.warn(path.string() + ": material library not found; " + obj.filename().string() +
                      " is read with plain materials");
    return;
  }
  const std::vector<uint8_t> bytes = readFileBytes(path, uint64_t(256) << 20);
  TextCursor cursor(reinterpret_cast<const char*>(bytes.data()), reinterpret_cast<const char*>(bytes.data() + bytes.size()));
  Material* current = nullptr;
  while (!cursor.atEnd()) {
    const std::string_view line = cursor.nextLine();
    const auto words = splitWords(line);
    if (words.empty() || words[0][0] == '#') continue;
    const std::string_view key = words[0];
    if (key == "newmtl") {
      std::string name = words.size() > 1 ? std::string(words[1]) : std::string();
      byName[name] = uint32_t(materials.size());
      materials.push_back(importedMaterial(name));  // a dielectric unless Pm says otherwise
      current = &materials.back();
      continue;
    }
    if (!current) continue;
    auto number = [&](size_t i) {
      float f = 0;
      if (i >= words.size() || !parseFloat(words[i], f) || !std::isfinite(f))
        throw Error(lineError(path, cursor.lineNumber(), "expected a number after '" + std::string(key) + "'"));
      return f;
    };
    if (key == "Kd") {
      current->baseColorFactor.head<3>() = Eigen::Vector3f(number(1), number(2), number(3));
    } else if (key == "d") {
      current->baseColorFactor.w() = number(1);
    } else if (key == "Tr") {
      current->baseColorFactor.w() = 1.0f - number(1);
    } else if (key == "Pr") {
      current->roughnessFactor = number(1);
    } else if (key == "Pm") {
      current->metallicFactor = number(1);
    } else if (key == "Ns" ) {
      // Blinn-Phong exponent to roughness: alpha = sqrt(2 / (Ns + 2)), roughness = sqrt(alpha).
      current->roughnessFactor = std::sqrt(std::sqrt(2.0f / (std::max(number(1), 0.0f) + 2.0f)));
    } else if (key == "map_Kd" || key == "norm" || key == "map_Pr" || key == "map_Pm" || key == "map_Bump" ||
               key == "bump") {
      const std::string file = mapFileName(words);
      if (file.empty()) throw Error(lineError(path, cursor.lineNumber(), "'" + std::string(key) + "' names no file"));
      if (key == "map_Kd") {
        current->baseColorTexture = textures.load(path, file);
      } else if (key == "norm" || key == "map_Bump" || key == "bump") {
        // norm is a normal map; map_Bump/bump are too when they have colour (Blender and most
        // exporters write normal maps there), a height map when grey (not used). norm wins.
        if (key == "norm" || !current->normalTexture) {
          Texture t = textures.load(path, file);
          if (key == "norm" || (t && t.image->channels >= 3)) current->normalTexture = std::move(t);
        }
      } else {
        // map_Pr and map_Pm are single channels that glTF packs into one texture: not combined here.
        (void)resolveModelReference(path, file);
      }
    }
  }
  for (Material& m : materials) {
    m.baseColorFactor = m.baseColorFactor.cwiseMax(0.0f).cwiseMin(1.0f);
    m.blend = m.baseColorFactor.w() < 1.0f;
    m.metallicFactor = std::clamp(m.metallicFactor, 0.0f, 1.0f);
    m.roughnessFactor = std::clamp(m.roughnessFactor, 0.0f, 1.0f);
  }
}

// One "v/vt/vn" reference; 0 = absent.
struct CornerRef {
  long long v = 0, vt = 0, vn = 0;
};

// An OBJ file's statements into a mesh: v, vt, vn, f (polygons triangulated), mtllib, usemtl;
// o, g, s, l, p and the rest carry nothing texfab keeps.
class ObjBuilder {
public:
  ObjBuilder(const fs::path& path, const Context& ctx) : path_(path), textures_{ctx, {}} {}

  void statement(std::string_view line, const std::vector<std::string_view>& words, size_t lineNumber) {
    line_ = lineNumber;
    const std::string_view key = words[0];
    auto number = [&](size_t i) {
      float f = 0;
      if (i >= words.size() || !parseFloat(words[i], f)) throw bad("expected a number in '" + std::string(key) + "' statement");
      return f;
    };
    if (key == "v") mesh_.positions.emplace_back(number(1), number(2), number(3));
    else if (key == "vt") vts_.emplace_back(number(1), words.size() > 2 ? number(2) : 0.0f);
    else if (key == "vn") vns_.emplace_back(number(1), number(2), number(3));
    else if (key == "f") face(words);
    else if (key == "mtllib") materialLibraries(line, words);
    else if (key == "usemtl") useMaterial(words.size() > 1 ? std::string(words[1]) : std::string());
  }

  Mesh finish() && {
    mesh_.triangles.resize(corners_.size() / 3);
    bool anyVt = false, anyVn = false;
    for (const CornerRef& c : corners_) {
      anyVt |= c.vt != 0;
      anyVn |= c.vn != 0;
    }
    for (size_t t = 0; t < mesh_.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) mesh_.triangles[t][size_t(k)] = uint32_t(corners_[3 * t + size_t(k)].v - 1);
    if (anyVt) {
      mesh_.uvs.resize(corners_.size(), Eigen::Vector2f::Zero());
      for (size_t c = 0; c < corners_.size(); ++c)
        if (corners_[c].vt) mesh_.uvs[c] = vts_[size_t(corners_[c].vt - 1)];
    }
    if (anyVn) {
      mesh_.normals.resize(corners_.size());
      for (size_t c = 0; c < corners_.size(); ++c) {
        const Eigen::Vector3f n = corners_[c].vn ? vns_[size_t(corners_[c].vn - 1)] : faceNormal(mesh_, c / 3);
        mesh_.normals[c] = importedNormal(n, mesh_, c / 3, path_);
      }
    }
    if (mesh_.materials.empty() || !anyMaterialUsed_) mesh_.faceMaterials.clear();
    return std::move(mesh_);
  }

private:
  Error bad(const std::string& what) const { return Error(lineError(path_, line_, what)); }

  // "v", "v/vt", "v//vn" or "v/vt/vn"; negative indices count back from the end of the lists so far.
  CornerRef corner(std::string_view word) const {
    CornerRef ref;
    std::string_view w = word;
    long long* slots[3] = {&ref.v, &ref.vt, &ref.vn};
    for (int s = 0; s < 3 && !w.empty(); ++s) {
      const size_t slash = w.find('/');
      const std::string_view part = w.substr(0, slash);
      if (!part.empty() && !parseInt(part, *slots[s])) throw bad("bad face index '" + std::string(word) + "'");
      if (slash == std::string_view::npos) break;
      w = w.substr(slash + 1);
    }
    auto fix = [&](long long& idx, size_t count, const char* what) {
      if (idx < 0) idx += (long long)count + 1;
      else if (idx == 0 && slots[0] == &idx) throw bad("face index 0 (OBJ indices start at 1)");
      if (idx < 0 || idx > (long long)count)
        throw bad(std::string(what) + " index " + std::to_string(idx) + " out of range (" + std::to_string(count) + " defined)");
    };
    fix(ref.v, mesh_.positions.size(), "vertex");
    if (ref.v == 0) throw bad("face corner without a vertex index");
    if (ref.vt != 0) fix(ref.vt, vts_.size(), "texture coordinate");
    if (ref.vn != 0) fix(ref.vn, vns_.size(), "normal");
    return ref;
  }

  void face(const std::vector<std::string_view>& words) {
    polygon_.clear();
    for (size_t i = 1; i < words.size(); ++i) polygon_.push_back(corner(words[i]));
    if (polygon_.size() < 3) throw bad("face with fewer than 3 corners");
    if (polygon_.size() == 3) {
      corners_.insert(corners_.end(), polygon_.begin(), polygon_.end());
      mesh_.faceMaterials.push_back(material_);
      return;
    }
    polygonPositions_.clear();
    for (const CornerRef& r : polygon_) polygonPositions_.push_back(mesh_.positions[size_t(r.v - 1)]);
    for (const auto& tri : triangulatePolygon(polygonPositions_)) {
      for (uint32_t k : tri) corners_.push_back(polygon_[k]);
      mesh_.faceMaterials.push_back(material_);
    }
  }

  // A name may contain spaces; several libraries may be listed, but that is rare: the whole rest
  // of the line first, then each word.
  void materialLibraries(std::string_view line, const std::vector<std::string_view>& words) {
    if (words.size() < 2) return;
    const std::string rest(line.substr(size_t(words[1].data() - line.data())));
    std::error_code ec;  // a name the system refuses (too long, ...) names no file
    if (words.size() == 2 || fs::exists(path_.parent_path() / rest, ec)) {
      readMtl(path_, words.size() == 2 ? std::string(words[1]) : rest, mesh_.materials, byName_, textures_);
    } else {
      for (size_t i = 1; i < words.size(); ++i) readMtl(path_, std::string(words[i]), mesh_.materials, byName_, textures_);
    }
  }

  void useMaterial(const std::string& name) {
    if (!byName_.count(name)) {
      // Unknown material: a plain grey one (many exporters reference materials they did not write).
      Material m = importedMaterial(name);
      m.baseColorFactor = Eigen::Vector4f(0.8f, 0.8f, 0.8f, 1.0f);
      byName_[name] = uint32_t(mesh_.materials.size());
      mesh_.materials.push_back(std::move(m));
    }
    material_ = byName_[name];
    anyMaterialUsed_ = true;
  }

  const fs::path& path_;
  size_t line_ = 0;
  Mesh mesh_;
  std::vector<Eigen::Vector2f> vts_;
  std::vector<Eigen::Vector3f> vns_;
  std::vector<CornerRef> corners_;  // 3 per triangle
  std::map<std::string, uint32_t> byName_;
  TextureCache textures_;
  uint32_t material_ = 0;
  bool anyMaterialUsed_ = false;
  std::vector<CornerRef> polygon_;                // the current face
  std::vector<Eigen::Vector3f> polygonPositions_;
};

} // namespace

Mesh readObj(const fs::path& path, const Context& ctx) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  TextCursor cursor(reinterpret_cast<const char*>(bytes.data()), reinterpret_cast<const char*>(bytes.data() + bytes.size()));
  ObjBuilder builder(path, ctx);
  while (!cursor.atEnd()) {
    const std::string_view line = cursor.nextLine();
    const auto words = splitWords(line);
    if (!words.empty() && words[0][0] != '#') builder.statement(line, words, cursor.lineNumber());
  }
  return std::move(builder).finish();
}

namespace {

std::string safeName(const std::string& name, size_t index) {
  std::string out;
  for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  if (out.empty()) out = "material" + std::to_string(index);
  return out;
}

std::string fmt(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", double(v));
  return buf;
}

} // namespace

namespace {

// Distinct values of a per-corner attribute, in order of first use: the OBJ index of each corner.
template <class V>
std::vector<uint32_t> shareValues(const std::vector<V>& perCorner, std::vector<V>& values) {
  std::map<std::array<float, V::RowsAtCompileTime>, uint32_t> index;
  std::vector<uint32_t> of(perCorner.size());
  for (size_t c = 0; c < perCorner.size(); ++c) {
    std::array<float, V::RowsAtCompileTime> key;
    for (int i = 0; i < V::RowsAtCompileTime; ++i) key[size_t(i)] = perCorner[c][i];
    const auto [it, added] = index.emplace(key, uint32_t(values.size()));
    if (added) values.push_back(perCorner[c]);
    of[c] = it->second;
  }
  return of;
}

} // namespace

void writeObj(const Mesh& input, const fs::path& path, const fs::path& tmp, const MeshWriteOptions& options,
              std::vector<std::pair<fs::path, fs::path>>& sideFiles) {
  Mesh mesh = input;
  if (!mesh.hasNormals()) computeSmoothNormals(mesh);
  const std::string stem = path.stem().string();
  const fs::path folder = path.parent_path();
  std::ostringstream mtl;
  std::map<const Image*, std::string> written;
  auto textureFile = [&](const Texture& texture, const std::string& material, const char* kind) {
    const auto it = written.find(texture.image.get());
    if (it != written.end()) return it->second;
    const EncodedImage file = storedImage(texture, options);
    const std::string name = stem + "_" + material + "_" + kind + extensionOf(file.codec);
    const fs::path final = folder / name;
    const fs::path side = temporaryPathFor(final);
    sideFiles.emplace_back(side, final);
    writeFileBytes(side, std::string_view(reinterpret_cast<const char*>(file.bytes.data()), file.bytes.size()), final);
    written[texture.image.get()] = name;
    return name;
  };
  const size_t materialCount = std::max<size_t>(1, mesh.materials.size());
  std::vector<std::string> names(materialCount);
  if (!mesh.materials.empty()) {
    mtl << "# texfab\n";
    for (size_t i = 0; i < mesh.materials.size(); ++i) {
      const Material& m = mesh.materials[i];
      names[i] = safeName(m.name, i);
      for (size_t j = 0; j < i; ++j)
        if (names[j] == names[i]) names[i].append("_").append(std::to_string(i));
      mtl << "\nnewmtl " << names[i] << "\n";
      mtl << "Kd " << fmt(m.baseColorFactor.x()) << ' ' << fmt(m.baseColorFactor.y()) << ' ' << fmt(m.baseColorFactor.z()) << "\n";
      mtl << "d " << fmt(m.baseColorFactor.w()) << "\n";
      mtl << "Pr " << fmt(m.roughnessFactor) << "\nPm " << fmt(m.metallicFactor) << "\n";
      if (m.baseColorTexture) mtl << "map_Kd " << textureFile(m.baseColorTexture, names[i], "basecolor") << "\n";
      if (m.normalTexture) {
        // map_Bump is where Blender and most readers look for a normal map; norm is the PBR
        // extension's name for it.
        const std::string file = textureFile(m.normalTexture, names[i], "normal");
        mtl << "map_Bump " << file << "\nbump " << file << "\nnorm " << file << "\n";
      }
      if (m.metallicRoughnessTexture)
        mtl << "map_Pr " << textureFile(m.metallicRoughnessTexture, names[i], "metallicroughness") << "\n";
    }
    const fs::path final = folder / (stem + ".mtl");
    const fs::path side = temporaryPathFor(final);
    sideFiles.emplace_back(side, final);
    writeFileBytes(side, mtl.str(), final);
  }
  std::vector<Eigen::Vector2f> vts;
  std::vector<Eigen::Vector3f> vns;
  const std::vector<uint32_t> vtOf = shareValues(mesh.uvs, vts);
  const std::vector<uint32_t> vnOf = shareValues(mesh.normals, vns);
  std::string out;
  out.reserve(mesh.positions.size() * 40 + vts.size() * 30 + vns.size() * 40 + mesh.triangles.size() * 40);
  out += "# texfab\n";
  if (!mesh.materials.empty()) out += "mtllib " + stem + ".mtl\n";
  for (const auto& p : mesh.positions) out += "v " + fmt(p.x()) + ' ' + fmt(p.y()) + ' ' + fmt(p.z()) + '\n';
  for (const auto& uv : vts) out += "vt " + fmt(uv.x()) + ' ' + fmt(uv.y()) + '\n';
  for (const auto& n : vns) out += "vn " + fmt(n.x()) + ' ' + fmt(n.y()) + ' ' + fmt(n.z()) + '\n';
  uint32_t current = UINT32_MAX;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!mesh.materials.empty() && mesh.materialOf(t) != current) {
      current = mesh.materialOf(t);
      out += "usemtl " + names[current] + '\n';
    }
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      const size_t c = 3 * t + size_t(k);
      out += ' ' + std::to_string(mesh.triangles[t][size_t(k)] + 1) + '/';
      if (mesh.hasUvs()) out += std::to_string(vtOf[c] + 1);
      out += '/' + std::to_string(vnOf[c] + 1);
    }
    out += '\n';
  }
  writeFileBytes(tmp, out, path);
}

} // namespace texfab::geometry::detail
