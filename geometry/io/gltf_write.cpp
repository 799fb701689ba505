// SPDX-License-Identifier: GPL-3.0-or-later
// glTF 2.0 writing (.glb and .gltf with data URIs), built directly as JSON so that every detail
// the Khronos validator checks (alignment, min/max, unit normals, targets) is under our control.
#include "core/error.h"
#include "core/files.h"
#include "core/image_io.h"
#include "core/ktx2_write.h"
#include "geometry/io/mesh_formats.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <span>
#include <tuple>

namespace texfab::geometry::detail {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kFloat = 5126, kUnsignedInt = 5125, kUnsignedShort = 5123;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

std::string encodeBase64(std::span<const uint8_t> data) {
  static const char* chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((data.size() + 2) / 3 * 4);
  for (size_t i = 0; i < data.size(); i += 3) {
    const uint32_t n = uint32_t(data[i]) << 16 | (i + 1 < data.size() ? uint32_t(data[i + 1]) << 8 : 0) |
                       (i + 2 < data.size() ? uint32_t(data[i + 2]) : 0);
    out += chars[(n >> 18) & 63];
    out += chars[(n >> 12) & 63];
    out += i + 1 < data.size() ? chars[(n >> 6) & 63] : '=';
    out += i + 2 < data.size() ? chars[n & 63] : '=';
  }
  return out;
}

class GltfBuilder {
public:
  int bufferView(const void* data, size_t size, int target) {
    align(4);
    json view = {{"buffer", 0}, {"byteOffset", buffer_.size()}, {"byteLength", size}};
    if (target) view["target"] = target;
    buffer_.insert(buffer_.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + size);
    views_.push_back(view);
    return int(views_.size() - 1);
  }

  template <int N>
  int accessor(const std::vector<Eigen::Matrix<float, N, 1>>& values, const char* type, bool minMax, int view = -2) {
    json a = {{"componentType", kFloat}, {"count", values.size()}, {"type", type}};
    if (view == -2) view = bufferView(values.data(), values.size() * sizeof(float) * N, kArrayBuffer);
    if (view >= 0) a["bufferView"] = view;
    if (minMax) {
      Eigen::Matrix<float, N, 1> lo = values[0], hi = values[0];
      for (const auto& v : values) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
      a["min"] = std::vector<float>(lo.data(), lo.data() + N);
      a["max"] = std::vector<float>(hi.data(), hi.data() + N);
    }
    accessors_.push_back(a);
    return int(accessors_.size() - 1);
  }

  int indexAccessor(const std::vector<uint32_t>& indices, size_t vertexCount, bool withView) {
    const bool shortIndices = vertexCount <= 65535;
    json a = {{"componentType", shortIndices ? kUnsignedShort : kUnsignedInt}, {"count", indices.size()}, {"type", "SCALAR"}};
    if (withView) {
      if (shortIndices) {
        std::vector<uint16_t> s(indices.begin(), indices.end());
        a["bufferView"] = bufferView(s.data(), s.size() * 2, kElementArrayBuffer);
      } else {
        a["bufferView"] = bufferView(indices.data(), indices.size() * 4, kElementArrayBuffer);
      }
    }
    accessors_.push_back(a);
    return int(accessors_.size() - 1);
  }

  std::vector<uint8_t>& buffer() { return buffer_; }
  json& views() { return views_; }
  json& accessors() { return accessors_; }
  void align(size_t n) {
    while (buffer_.size() % n) buffer_.push_back(0);
  }

private:
  std::vector<uint8_t> buffer_;
  json views_ = json::array();
  json accessors_ = json::array();
};

// A glTF vertex = one distinct (position, uv, normal, tangent) combination of a primitive's corners.
struct CornerKey {
  uint32_t position;
  std::array<float, 9> attributes;
  bool operator<(const CornerKey& o) const { return std::tie(position, attributes) < std::tie(o.position, o.attributes); }
};

// A file name as a URI reference: unreserved characters kept, the rest %-escaped.
std::string uriOf(const std::string& name) {
  static const char* hex = "0123456789ABCDEF";
  std::string uri;
  for (unsigned char c : name) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') uri += char(c);
    else uri.append({'%', hex[c >> 4], hex[c & 15]});
  }
  return uri;
}

} // namespace

namespace {

// The mesh as written: normals present and unit, tangents with w = ±1 where a normal map or
// anisotropy needs them (as the validator checks).
Mesh preparedForGltf(const Mesh& input, const MeshWriteOptions& options) {
  Mesh mesh = input;
  if (!mesh.hasNormals()) computeSmoothNormals(mesh);
  bool needsTangents = false;
  for (const Material& m : mesh.materials) needsTangents |= m.normalTexture || m.anisotropy;
  if (mesh.hasUvs() && !mesh.hasTangents() && needsTangents && options.computeMissingTangents) computeTangents(mesh);
  if (!mesh.hasUvs()) mesh.tangents.clear();
  for (auto& n : mesh.normals) n = n.squaredNorm() > 0 ? Eigen::Vector3f(n.normalized()) : Eigen::Vector3f(0, 0, 1);
  for (auto& t : mesh.tangents) {
    Eigen::Vector3f xyz = t.head<3>();
    xyz = xyz.squaredNorm() > 0 ? Eigen::Vector3f(xyz.normalized()) : Eigen::Vector3f(1, 0, 0);
    t = Eigen::Vector4f(xyz.x(), xyz.y(), xyz.z(), t.w() < 0 ? -1.0f : 1.0f);
  }
  return mesh;
}

bool sameTexture(const Texture& a, const Texture& b) {
  return a.image == b.image && a.mips == b.mips && a.encodedMips == b.encodedMips && a.offset == b.offset &&
         a.scale == b.scale && a.rotation == b.rotation;
}

bool sameMaterial(const Material& a, const Material& b) {
  return a.name == b.name && a.baseColorFactor == b.baseColorFactor && a.metallicFactor == b.metallicFactor &&
         a.roughnessFactor == b.roughnessFactor && a.normalScale == b.normalScale && a.doubleSided == b.doubleSided &&
         a.blend == b.blend && sameTexture(a.baseColorTexture, b.baseColorTexture) &&
         sameTexture(a.metallicRoughnessTexture, b.metallicRoughnessTexture) && sameTexture(a.normalTexture, b.normalTexture) &&
         a.anisotropy.strength == b.anisotropy.strength && a.anisotropy.rotation == b.anisotropy.rotation &&
         sameTexture(a.anisotropy.texture, b.anisotropy.texture);
}

// A glTF document being built: its meshes, and the materials, textures and images they share.
class GltfDocument {
public:
  GltfDocument(const fs::path& path, const fs::path& tmp, bool binary, const MeshWriteOptions& options,
               std::vector<std::pair<fs::path, fs::path>>& sideFiles)
      : path_(path), tmp_(tmp), binary_(binary), external_(!binary && !options.embed), options_(options),
        sideFiles_(sideFiles) {}

  /// Adds a mesh (prepared) and returns its index. Its materials are written in its order; those
  /// equal to a material of an earlier mesh are shared with it.
  int addMesh(const Mesh& mesh, const std::string& name);
  void addNode(json node) { nodes_.push_back(std::move(node)); }
  /// Writes the file to `tmp` (side files committed by the caller).
  void write();

private:
  void sideFile(const std::string& name, std::string_view bytes);
  int addImage(std::span<const uint8_t> bytes, const char* mime, const char* extension);
  json textureInfo(const Texture& t, bool colour);
  int material(const Material& m, bool textured, bool firstMesh);
  json primitives(const Mesh& mesh, const std::vector<int>& materialIndex);

  fs::path path_, tmp_;
  bool binary_, external_;  // external: a .gltf with its buffer and images beside it
  const MeshWriteOptions& options_;
  std::vector<std::pair<fs::path, fs::path>>& sideFiles_;
  GltfBuilder b_;
  bool usesTransform_ = false, usesWebp_ = false, usesBasisu_ = false, usesAnisotropy_ = false;
  json materials_ = json::array(), textures_ = json::array(), images_ = json::array();
  json meshes_ = json::array(), nodes_ = json::array();
  struct StoredImage {
    int index;          // in images_
    ImageCodec codec;
    int ktx2 = -1;      // the image of its own MIP chain (Texture::mips), when it has one
  };
  std::map<const Image*, StoredImage> stored_;  // one image per distinct Image object
  std::vector<std::pair<Material, bool>> written_;  // (material, textured) per materials_ entry
};

int GltfDocument::addMesh(const Mesh& mesh, const std::string& name) {
  std::vector<Material> materialList = mesh.materials;
  if (materialList.empty()) {
    // A plain dielectric, not glTF's default (metallicFactor 1), which viewers show as dark metal.
    Material plain;
    plain.metallicFactor = 0.0f;
    plain.roughnessFactor = 0.5f;
    materialList.push_back(plain);
  }
  std::vector<int> materialIndex;
  for (const Material& m : materialList) materialIndex.push_back(material(m, mesh.hasUvs(), meshes_.empty()));
  json entry = {{"primitives", primitives(mesh, materialIndex)}};
  if (!name.empty()) entry["name"] = name;
  meshes_.push_back(entry);
  return int(meshes_.size() - 1);
}

void GltfDocument::sideFile(const std::string& name, std::string_view bytes) {
  const fs::path final = path_.parent_path() / name;
  const fs::path side = temporaryPathFor(final);
  sideFiles_.emplace_back(side, final);
  writeFileBytes(side, bytes, final);
}

// A new entry of images_: in the GLB's buffer, a file beside a .gltf, or a data URI.
int GltfDocument::addImage(std::span<const uint8_t> bytes, const char* mime, const char* extension) {
  json entry;
  if (binary_) {
    entry = {{"bufferView", b_.bufferView(bytes.data(), bytes.size(), 0)}, {"mimeType", mime}};
  } else if (external_) {
    const std::string name = path_.stem().string() + "_" + std::to_string(images_.size()) + extension;
    sideFile(name, {reinterpret_cast<const char*>(bytes.data()), bytes.size()});
    entry = {{"uri", uriOf(name)}};
  } else {
    entry = {{"uri", std::string("data:") + mime + ";base64," + encodeBase64(bytes)}};
  }
  images_.push_back(entry);
  return int(images_.size() - 1);
}

json GltfDocument::textureInfo(const Texture& t, bool colour) {
  auto it = stored_.find(t.image.get());
  if (it == stored_.end()) {
    const EncodedImage file = storedImage(t, options_);
    StoredImage image{addImage(file.bytes, mimeTypeOf(file.codec), extensionOf(file.codec)), file.codec};
    if (t.mips) {
      Ktx2Options ktx;
      ktx.srgb = colour;
      ktx.zstdLevel = 9;  // most of level 19's ratio in a tenth of its time (docs/normal-map-filtering.md)
      image.ktx2 = addImage(encodeKtx2Uastc(*t.mips, ktx), "image/ktx2", ".ktx2");
    } else if (t.encodedMips) {
      image.ktx2 = addImage(*t.encodedMips, "image/ktx2", ".ktx2");
    }
    it = stored_.emplace(t.image.get(), image).first;
  }
  const StoredImage& image = it->second;
  // A WebP image is the source of EXT_texture_webp (required: there is no fallback image).
  json texture = {{"sampler", 0}};
  if (image.codec == ImageCodec::Webp) {
    texture["extensions"]["EXT_texture_webp"] = {{"source", image.index}};
    usesWebp_ = true;
  } else {
    texture["source"] = image.index;
  }
  // Its own MIP chain as KTX2 for viewers with KHR_texture_basisu; the image is the fallback.
  if (image.ktx2 >= 0) {
    texture["extensions"]["KHR_texture_basisu"] = {{"source", image.ktx2}};
    usesBasisu_ = true;
  }
  textures_.push_back(texture);
  json info = {{"index", int(textures_.size() - 1)}};
  if (t.hasTransform()) {
    info["extensions"]["KHR_texture_transform"] = {
        {"offset", {t.offset.x(), t.offset.y()}}, {"scale", {t.scale.x(), t.scale.y()}}, {"rotation", t.rotation}};
    usesTransform_ = true;
  }
  return info;
}

// The material's index: a new entry, or (after the first mesh) an equal one already written.
int GltfDocument::material(const Material& m, bool textured, bool firstMesh) {
  if (!firstMesh)
    for (size_t i = 0; i < written_.size(); ++i)
      if (written_[i].second == textured && sameMaterial(written_[i].first, m)) return int(i);
  json pbr = {{"baseColorFactor", {m.baseColorFactor.x(), m.baseColorFactor.y(), m.baseColorFactor.z(), m.baseColorFactor.w()}},
              {"metallicFactor", m.metallicFactor},
              {"roughnessFactor", m.roughnessFactor}};
  if (textured && m.baseColorTexture) pbr["baseColorTexture"] = textureInfo(m.baseColorTexture, true);
  if (textured && m.metallicRoughnessTexture) pbr["metallicRoughnessTexture"] = textureInfo(m.metallicRoughnessTexture, false);
  json material = {{"pbrMetallicRoughness", pbr}};
  if (!m.name.empty()) material["name"] = m.name;
  if (textured && m.normalTexture) {
    material["normalTexture"] = textureInfo(m.normalTexture, false);
    if (m.normalScale != 1.0f) material["normalTexture"]["scale"] = m.normalScale;
  }
  if (textured && m.anisotropy) {  // its directions are relative to tangents, which need UVs
    json anisotropy = {{"anisotropyStrength", m.anisotropy.strength}};
    if (m.anisotropy.rotation != 0) anisotropy["anisotropyRotation"] = m.anisotropy.rotation;
    if (m.anisotropy.texture) anisotropy["anisotropyTexture"] = textureInfo(m.anisotropy.texture, false);
    material["extensions"]["KHR_materials_anisotropy"] = anisotropy;
    usesAnisotropy_ = true;
  }
  if (m.doubleSided) material["doubleSided"] = true;
  if (m.blend) material["alphaMode"] = "BLEND";
  materials_.push_back(material);
  written_.emplace_back(m, textured);
  return int(materials_.size() - 1);
}

// One primitive per (material, tag).
json GltfDocument::primitives(const Mesh& mesh, const std::vector<int>& materialIndex) {
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> groups;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) groups[{mesh.materialOf(t), mesh.tagOf(t)}].push_back(uint32_t(t));
  json primitives = json::array();
  for (const auto& [key, tris] : groups) {
    VertexArrays v;
    std::map<CornerKey, uint32_t> vertexOf;
    for (uint32_t t : tris)
      for (int k = 0; k < 3; ++k) {
        const size_t c = 3 * size_t(t) + size_t(k);
        CornerKey ck{mesh.triangles[t][size_t(k)], {}};
        if (mesh.hasUvs()) ck.attributes[0] = mesh.uvs[c].x(), ck.attributes[1] = mesh.uvs[c].y();
        for (int i = 0; i < 3; ++i) ck.attributes[size_t(2 + i)] = mesh.normals[c][i];
        if (mesh.hasTangents())
          for (int i = 0; i < 4; ++i) ck.attributes[size_t(5 + i)] = mesh.tangents[c][i];
        const auto [it, inserted] = vertexOf.emplace(ck, uint32_t(v.positions.size()));
        if (inserted) {
          v.positions.push_back(mesh.positions[ck.position]);
          v.normals.push_back(mesh.normals[c]);
          if (mesh.hasUvs()) v.uvs.emplace_back(mesh.uvs[c].x(), 1.0f - mesh.uvs[c].y());
          if (mesh.hasTangents()) v.tangents.push_back(mesh.tangents[c]);
        }
        v.indices.push_back(it->second);
      }
    json primitive = {{"mode", 4}, {"material", materialIndex[key.first]}};
    if (key.second != 0) primitive["extras"] = {{"texfab:tag", key.second}};
    json attributes;
    if (options_.draco) {
      DracoAttributeIds ids;
      const std::vector<uint8_t> compressed = encodeDraco(v, options_, ids);
      // Accessors describe the decoded data: decode once to get its exact count and bounds.
      const VertexArrays decoded = decodeDraco(compressed.data(), compressed.size(), ids, path_.string());
      const int view = b_.bufferView(compressed.data(), compressed.size(), 0);
      json dracoAttributes;
      attributes["POSITION"] = b_.accessor<3>(decoded.positions, "VEC3", true, -1);
      dracoAttributes["POSITION"] = ids.position;
      attributes["NORMAL"] = b_.accessor<3>(decoded.normals, "VEC3", false, -1);
      dracoAttributes["NORMAL"] = ids.normal;
      if (ids.uv >= 0) {
        attributes["TEXCOORD_0"] = b_.accessor<2>(decoded.uvs, "VEC2", false, -1);
        dracoAttributes["TEXCOORD_0"] = ids.uv;
      }
      if (ids.tangent >= 0) {
        attributes["TANGENT"] = b_.accessor<4>(decoded.tangents, "VEC4", false, -1);
        dracoAttributes["TANGENT"] = ids.tangent;
      }
      primitive["indices"] = b_.indexAccessor(decoded.indices, decoded.positions.size(), false);
      primitive["extensions"]["KHR_draco_mesh_compression"] = {{"bufferView", view}, {"attributes", dracoAttributes}};
    } else {
      attributes["POSITION"] = b_.accessor<3>(v.positions, "VEC3", true);
      attributes["NORMAL"] = b_.accessor<3>(v.normals, "VEC3", false);
      if (!v.uvs.empty()) attributes["TEXCOORD_0"] = b_.accessor<2>(v.uvs, "VEC2", false);
      if (!v.tangents.empty()) attributes["TANGENT"] = b_.accessor<4>(v.tangents, "VEC4", false);
      primitive["indices"] = b_.indexAccessor(v.indices, v.positions.size(), true);
    }
    primitive["attributes"] = attributes;
    primitives.push_back(primitive);
  }
  return primitives;
}

void GltfDocument::write() {
  json doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", "texfab"}};
  json extensionsUsed = json::array();
  json rootNodes = json::array();
  for (size_t i = 0; i < nodes_.size(); ++i) rootNodes.push_back(int(i));
  doc["scene"] = 0;
  doc["scenes"] = json::array({{{"nodes", rootNodes}}});
  doc["nodes"] = nodes_;
  doc["meshes"] = meshes_;
  doc["materials"] = materials_;
  if (!textures_.empty()) {
    doc["textures"] = textures_;
    doc["images"] = images_;
    doc["samplers"] = json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 10497}, {"wrapT", 10497}}});
  }
  b_.align(4);
  if (!b_.views().empty()) doc["bufferViews"] = b_.views();
  if (!b_.accessors().empty()) doc["accessors"] = b_.accessors();
  if (options_.draco) {
    extensionsUsed.push_back("KHR_draco_mesh_compression");
    doc["extensionsRequired"] = json::array({"KHR_draco_mesh_compression"});
  }
  if (usesTransform_) extensionsUsed.push_back("KHR_texture_transform");
  if (usesBasisu_) extensionsUsed.push_back("KHR_texture_basisu");
  if (usesAnisotropy_) extensionsUsed.push_back("KHR_materials_anisotropy");
  if (usesWebp_) {
    extensionsUsed.push_back("EXT_texture_webp");
    if (!doc.contains("extensionsRequired")) doc["extensionsRequired"] = json::array();
    doc["extensionsRequired"].push_back("EXT_texture_webp");
  }
  if (!extensionsUsed.empty()) doc["extensionsUsed"] = extensionsUsed;

  std::string out;
  std::vector<uint8_t>& buffer = b_.buffer();
  if (binary_) {
    if (!buffer.empty()) doc["buffers"] = json::array({{{"byteLength", buffer.size()}}});
    out = packGlb(doc.dump(), buffer.empty() ? nullptr : &buffer, path_.string());
  } else {
    if (!buffer.empty()) {
      std::string uri;
      if (external_) {
        const std::string name = path_.stem().string() + ".bin";
        sideFile(name, {reinterpret_cast<const char*>(buffer.data()), buffer.size()});
        uri = uriOf(name);
      } else {
        uri = "data:application/octet-stream;base64," + encodeBase64(buffer);
      }
      doc["buffers"] = json::array({{{"byteLength", buffer.size()}, {"uri", uri}}});
    }
    out = doc.dump(1) + "\n";
  }
  writeFileBytes(tmp_, out, path_);
}

} // namespace

std::string packGlb(std::string_view json, const std::vector<uint8_t>* bin, const std::string& shownAs) {
  const size_t jsonBytes = (json.size() + 3) / 4 * 4, binBytes = bin ? (bin->size() + 3) / 4 * 4 : 0;
  const uint64_t total = 12 + 8 + uint64_t(jsonBytes) + (bin ? 8 + uint64_t(binBytes) : 0);
  if (total > UINT32_MAX) throw Error(shownAs + ": the model is too large for a GLB file (4 GiB)");
  std::string out;
  out.reserve(size_t(total));
  auto put32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) out += char((v >> (8 * i)) & 0xff);
  };
  put32(kGlbMagic);
  put32(2);
  put32(uint32_t(total));
  put32(uint32_t(jsonBytes));
  put32(kGlbChunkJson);
  out += json;
  out.append(jsonBytes - json.size(), ' ');
  if (bin) {
    put32(uint32_t(binBytes));
    put32(kGlbChunkBin);
    out.append(reinterpret_cast<const char*>(bin->data()), bin->size());
    out.append(binBytes - bin->size(), '\0');
  }
  return out;
}

void writeGltfScene(std::span<const SceneNode> nodes, const fs::path& path, const fs::path& tmp, bool binary,
                    const MeshWriteOptions& options, std::vector<std::pair<fs::path, fs::path>>& sideFiles) {
  GltfDocument doc(path, tmp, binary, options, sideFiles);
  for (const SceneNode& node : nodes) {
    json entry = {{"mesh", doc.addMesh(preparedForGltf(node.mesh, options), node.name)}};
    if (!node.name.empty()) entry["name"] = node.name;
    if (node.translation != Eigen::Vector3f::Zero())
      entry["translation"] = {node.translation.x(), node.translation.y(), node.translation.z()};
    doc.addNode(entry);
  }
  doc.write();
}

void writeGltf(const Mesh& mesh, const fs::path& path, const fs::path& tmp, bool binary, const MeshWriteOptions& options,
               std::vector<std::pair<fs::path, fs::path>>& sideFiles) {
  GltfDocument doc(path, tmp, binary, options, sideFiles);
  doc.addNode({{"mesh", doc.addMesh(preparedForGltf(mesh, options), "")}});
  doc.write();
}

} // namespace texfab::geometry::detail
