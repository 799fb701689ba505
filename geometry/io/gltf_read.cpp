// SPDX-License-Identifier: GPL-3.0-or-later
// glTF 2.0 reading (.gltf and .glb) through tinygltf, with texfab's own checks around it:
// references are resolved inside the model's folder only, every accessor and buffer view is
// bounds-checked here, and images are decoded here (tinygltf is given the document without its
// image list, so it never touches image bytes).
#include "core/error.h"
#include "core/image_io.h"
#include "core/ktx2_write.h"
#include "geometry/io/mesh_formats.h"
#include "geometry/io/model_path.h"

#include <tiny_gltf.h>

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <optional>

namespace texfab::geometry::detail {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {


uint32_t le32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }

const json* member(const json& object, const char* key) {
  if (!object.is_object()) return nullptr;
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

std::vector<uint8_t> decodeBase64(std::string_view text, const std::string& name) {
  static const auto table = [] {
    std::array<int8_t, 256> t{};
    t.fill(-1);
    const char* chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i) t[uint8_t(chars[i])] = int8_t(i);
    return t;
  }();
  std::vector<uint8_t> out;
  out.reserve(text.size() / 4 * 3);
  uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    if (c == '=') break;
    const int v = table[uint8_t(c)];
    if (v < 0) throw Error(name + ": bad character in base64 data URI");
    acc = (acc << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(uint8_t(acc >> bits));
    }
  }
  return out;
}

// The bytes of a data: URI (base64 only, as glTF requires).
std::vector<uint8_t> dataUriBytes(const std::string& uri, const std::string& name) {
  const size_t comma = uri.find(',');
  if (comma == std::string::npos || uri.compare(comma - std::min<size_t>(comma, 7), 7, ";base64") != 0)
    throw Error(name + ": data URI is not base64-encoded");
  return decodeBase64(std::string_view(uri).substr(comma + 1), name);
}

bool isDataUri(const std::string& uri) { return uri.rfind("data:", 0) == 0; }

// tinygltf file-system callbacks: no shell expansion, nothing outside the model's folder.
struct FsContext {
  fs::path folder;
};

bool insideFolder(const std::string& file, const FsContext& context) {
  std::error_code ec;
  const fs::path f = fs::weakly_canonical(context.folder, ec);
  if (ec) return false;
  const fs::path p = fs::weakly_canonical(fs::path(file), ec);
  if (ec) return false;
  const auto [a, b] = std::mismatch(f.begin(), f.end(), p.begin(), p.end());
  return a == f.end();
}

bool fsFileExists(const std::string& file, void* user) {
  std::error_code ec;
  return insideFolder(file, *static_cast<FsContext*>(user)) && fs::is_regular_file(file, ec);
}
std::string fsExpand(const std::string& file, void*) { return file; }
bool fsRead(std::vector<unsigned char>* out, std::string* err, const std::string& file, void* user) {
  if (!insideFolder(file, *static_cast<FsContext*>(user))) {
    if (err) *err += "refused to read outside the model's folder";
    return false;
  }
  try {
    *out = readFileBytes(file, uint64_t(2) << 30);
    return true;
  } catch (const Error& e) {
    if (err) *err += e.what();
    return false;
  }
}
bool fsWrite(std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; }
bool noImageLoader(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

std::string firstLine(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  return line.empty() ? "invalid glTF" : line;
}

class GltfReader {
public:
  GltfReader(const fs::path& path, const tinygltf::Model& model, const json& doc, const json& images)
      : path_(path), name_(path.string()), model_(model), doc_(doc), images_(images) {}

  Mesh read();

private:
  std::pair<const uint8_t*, size_t> bufferViewBytes(int index, const std::string& what) const;
  template <int N>
  std::vector<Eigen::Matrix<float, N, 1>> readFloats(int accessor, const std::string& what) const;
  std::vector<uint32_t> readIndices(int accessor) const;
  void readPrimitive(const tinygltf::Primitive& primitive, const json& primitiveJson, const Eigen::Matrix4d& transform,
                     const std::string& where);
  void visitNode(int node, const Eigen::Matrix4d& parent, int depth);
  Texture texture(const json* textureInfo);
  // The decoded image and its file bytes.
  const std::pair<std::shared_ptr<const Image>, std::shared_ptr<const EncodedImage>>& image(int index);
  // The bytes of image `index` as stored (owned holds them when they are not in a buffer).
  std::pair<const uint8_t*, size_t> imageBytes(int index, std::vector<uint8_t>& owned, const std::string& where);
  Material material(size_t index);

  const fs::path& path_;
  std::string name_;
  const tinygltf::Model& model_;
  const json& doc_;
  const json& images_;
  Mesh mesh_;
  bool anyUv_ = false, anyNormal_ = false, allTangents_ = true;
  std::vector<bool> uvPresent_, normalPresent_; // per primitive instance, for filling gaps
  std::vector<size_t> cornerStart_;
  std::vector<uint8_t> onPath_;
  std::map<int, std::pair<std::shared_ptr<const Image>, std::shared_ptr<const EncodedImage>>> imageCache_;
  bool needDefaultMaterial_ = false;
};

std::pair<const uint8_t*, size_t> GltfReader::bufferViewBytes(int index, const std::string& what) const {
  if (index < 0 || size_t(index) >= model_.bufferViews.size())
    throw Error(name_ + ": " + what + " refers to buffer view " + std::to_string(index) + " which does not exist");
  const tinygltf::BufferView& view = model_.bufferViews[size_t(index)];
  if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
    throw Error(name_ + ": buffer view " + std::to_string(index) + " refers to a missing buffer");
  const std::vector<unsigned char>& data = model_.buffers[size_t(view.buffer)].data;
  if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
    throw Error(name_ + ": buffer view " + std::to_string(index) + " overruns its buffer (offset " +
                std::to_string(view.byteOffset) + " + length " + std::to_string(view.byteLength) + " > " +
                std::to_string(data.size()) + " bytes)");
  return {data.data() + view.byteOffset, view.byteLength};
}

size_t componentSize(int type) {
  switch (type) {
  case TINYGLTF_COMPONENT_TYPE_BYTE: case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
  case TINYGLTF_COMPONENT_TYPE_SHORT: case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
  case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
  default: return 0;
  }
}

double readComponent(const uint8_t* p, int type, bool normalized) {
  switch (type) {
  case TINYGLTF_COMPONENT_TYPE_BYTE: { int8_t v; std::memcpy(&v, p, 1); return normalized ? std::max(v / 127.0, -1.0) : v; }
  case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
  case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; std::memcpy(&v, p, 2); return normalized ? std::max(v / 32767.0, -1.0) : v; }
  case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p, 2); return normalized ? v / 65535.0 : v; }
  case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t v; std::memcpy(&v, p, 4); return v; }
  case TINYGLTF_COMPONENT_TYPE_FLOAT: { float v; std::memcpy(&v, p, 4); return v; }
  default: return 0;
  }
}

template <int N>
std::vector<Eigen::Matrix<float, N, 1>> GltfReader::readFloats(int index, const std::string& what) const {
  if (index < 0 || size_t(index) >= model_.accessors.size())
    throw Error(name_ + ": " + what + " accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = model_.accessors[size_t(index)];
  const std::string where = name_ + ": accessor " + std::to_string(index) + " (" + what + ")";
  if (a.sparse.isSparse) throw Error(where + " is sparse, which texfab does not read");
  const int comps = tinygltf::GetNumComponentsInType(uint32_t(a.type));
  const size_t csize = componentSize(a.componentType);
  if (comps < N || csize == 0) throw Error(where + " has the wrong type or component type");
  const size_t element = size_t(comps) * csize;
  std::vector<Eigen::Matrix<float, N, 1>> out(0);
  // An accessor without a buffer view is all zeros (the base of a sparse accessor): never the
  // geometry of a real model, and an easy way to ask for gigabytes. Refused.
  if (a.bufferView < 0) throw Error(where + " has no buffer view");
  const auto [data, size] = bufferViewBytes(a.bufferView, where);
  const size_t declaredStride = size_t(model_.bufferViews[size_t(a.bufferView)].byteStride);
  const size_t stride = declaredStride ? declaredStride : element;
  if (stride < element) throw Error(where + " has a byte stride smaller than its element");
  if (a.count == 0) return out;
  if (a.count > (size_t(1) << 32)) throw Error(where + " has too many elements");
  const uint64_t need = uint64_t(a.byteOffset) + uint64_t(stride) * uint64_t(a.count - 1) + element;
  if (a.byteOffset > size || need > size || a.count > (size_t(1) << 32))
    throw Error(where + " overruns its buffer view (needs " + std::to_string(need) + " bytes, has " + std::to_string(size) + ")");
  out.resize(a.count);
  for (size_t i = 0; i < a.count; ++i) {
    const uint8_t* p = data + a.byteOffset + i * stride;
    for (int c = 0; c < N; ++c) out[i][c] = float(readComponent(p + size_t(c) * csize, a.componentType, a.normalized));
  }
  return out;
}

std::vector<uint32_t> GltfReader::readIndices(int index) const {
  if (index < 0 || size_t(index) >= model_.accessors.size())
    throw Error(name_ + ": index accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = model_.accessors[size_t(index)];
  if (a.type != TINYGLTF_TYPE_SCALAR || a.normalized ||
      (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
       a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
    throw Error(name_ + ": accessor " + std::to_string(index) + " is not a valid index accessor");
  const auto values = readFloats<1>(index, "indices");
  // Floats hold integers up to 2^24 exactly; re-read 32-bit indices exactly.
  std::vector<uint32_t> out(values.size());
  if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && a.bufferView >= 0) {
    const auto [data, size] = bufferViewBytes(a.bufferView, "indices");
    const size_t stride = model_.bufferViews[size_t(a.bufferView)].byteStride ? model_.bufferViews[size_t(a.bufferView)].byteStride : 4;
    for (size_t i = 0; i < out.size(); ++i) std::memcpy(&out[i], data + a.byteOffset + i * stride, 4);
    (void)size;
  } else {
    for (size_t i = 0; i < out.size(); ++i) out[i] = uint32_t(values[i][0]);
  }
  return out;
}

std::pair<const uint8_t*, size_t> GltfReader::imageBytes(int index, std::vector<uint8_t>& owned, const std::string& where) {
  if (!images_.is_array() || index < 0 || size_t(index) >= images_.size())
    throw Error(name_ + ": texture refers to image " + std::to_string(index) + " which does not exist");
  const json& entry = images_[size_t(index)];
  if (const json* uri = member(entry, "uri"); uri && uri->is_string()) {
    const std::string u = uri->get<std::string>();
    if (isDataUri(u)) owned = dataUriBytes(u, where);
    else owned = readFileBytes(resolveModelReference(path_, u, true), uint64_t(1) << 30);
    return {owned.data(), owned.size()};
  }
  if (const json* view = member(entry, "bufferView"); view && view->is_number_integer())
    return bufferViewBytes(view->get<int>(), where);
  throw Error(where + " has neither a uri nor a bufferView");
}

const std::pair<std::shared_ptr<const Image>, std::shared_ptr<const EncodedImage>>& GltfReader::image(int index) {
  auto& slot = imageCache_[index];
  if (slot.first) return slot;
  const std::string where = name_ + ": image " + std::to_string(index);
  std::vector<uint8_t> owned;
  const auto [data, size] = imageBytes(index, owned, where);
  slot.first = std::make_shared<const Image>(decodeImage({data, size}, where));
  if (const std::optional<ImageCodec> codec = imageCodecOf({data, size}))
    slot.second = std::make_shared<const EncodedImage>(EncodedImage{{data, data + size}, *codec});
  return slot;
}

Texture GltfReader::texture(const json* info) {
  Texture t;
  if (!info || !info->is_object()) return t;
  const json* index = member(*info, "index");
  if (!index || !index->is_number_integer()) throw Error(name_ + ": texture info without an index");
  const int ti = index->get<int>();
  if (ti < 0 || size_t(ti) >= model_.textures.size())
    throw Error(name_ + ": material refers to texture " + std::to_string(ti) + " which does not exist");
  int source = model_.textures[size_t(ti)].source, basisu = -1;
  // EXT_texture_webp names its WebP image in the texture's extension (the core source, if any, is
  // a fallback for readers without it); KHR_texture_basisu a KTX2 image with its own MIP chain.
  if (const json* ts = member(doc_, "textures"); ts && ts->is_array() && size_t(ti) < ts->size())
    if (const json* ext = member((*ts)[size_t(ti)], "extensions")) {
      if (const json* webp = member(*ext, "EXT_texture_webp"))
        if (const json* src = member(*webp, "source"); src && src->is_number_integer()) source = src->get<int>();
      if (const json* ktx = member(*ext, "KHR_texture_basisu"))
        if (const json* src = member(*ktx, "source"); src && src->is_number_integer()) basisu = src->get<int>();
    }
  if (source < 0) return t;
  std::tie(t.image, t.encoded) = image(source);
  // Kept as stored, for writers to carry along with the fallback; an optional extension that names
  // no image is ignored, as a reader without it would.
  if (basisu >= 0 && images_.is_array() && size_t(basisu) < images_.size()) {
    std::vector<uint8_t> owned;
    const auto [data, size] = imageBytes(basisu, owned, name_ + ": image " + std::to_string(basisu));
    if (size >= 12 && std::equal(data, data + 12, kKtx2Identifier.begin()))
      t.encodedMips = std::make_shared<const std::vector<uint8_t>>(data, data + size);
  }
  if (images_.is_array() && size_t(source) < images_.size()) {
    const json* uri = member(images_[size_t(source)], "uri");
    if (uri && uri->is_string() && !isDataUri(uri->get<std::string>())) t.name = fs::path(uri->get<std::string>()).filename().string();
  }
  if (const json* ext = member(*info, "extensions"))
    if (const json* tt = member(*ext, "KHR_texture_transform")) {
      auto vec2 = [&](const char* key, Eigen::Vector2f& v) {
        if (const json* a = member(*tt, key); a && a->is_array() && a->size() == 2 && (*a)[0].is_number() && (*a)[1].is_number())
          v = Eigen::Vector2f((*a)[0].get<float>(), (*a)[1].get<float>());
      };
      vec2("offset", t.offset);
      vec2("scale", t.scale);
      if (const json* r = member(*tt, "rotation"); r && r->is_number()) t.rotation = r->get<float>();
      if (!t.offset.allFinite() || !t.scale.allFinite() || !std::isfinite(t.rotation))
        throw Error(name_ + ": KHR_texture_transform has a non-finite value");
    }
  return t;
}

Material GltfReader::material(size_t index) {
  const tinygltf::Material& m = model_.materials[index];
  const json* mj = nullptr;
  if (const json* ms = member(doc_, "materials"); ms && ms->is_array() && index < ms->size()) mj = &(*ms)[index];
  Material out;
  out.name = m.name;
  const auto& pbr = m.pbrMetallicRoughness;
  if (pbr.baseColorFactor.size() == 4)
    out.baseColorFactor = Eigen::Vector4f(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                                          float(pbr.baseColorFactor[2]), float(pbr.baseColorFactor[3]));
  out.metallicFactor = float(pbr.metallicFactor);
  out.roughnessFactor = float(pbr.roughnessFactor);
  out.normalScale = float(m.normalTexture.scale);
  out.doubleSided = m.doubleSided;
  out.blend = m.alphaMode == "BLEND";
  if (!out.baseColorFactor.allFinite() || !std::isfinite(out.metallicFactor) || !std::isfinite(out.roughnessFactor) ||
      !std::isfinite(out.normalScale))
    throw Error(name_ + ": material " + std::to_string(index) + " has a non-finite factor");
  if (mj) {
    const json* pj = member(*mj, "pbrMetallicRoughness");
    if (pj) {
      out.baseColorTexture = texture(member(*pj, "baseColorTexture"));
      out.metallicRoughnessTexture = texture(member(*pj, "metallicRoughnessTexture"));
    }
    out.normalTexture = texture(member(*mj, "normalTexture"));
    if (const json* ext = member(*mj, "extensions"))
      if (const json* a = member(*ext, "KHR_materials_anisotropy"); a && a->is_object()) {
        const auto number = [&](const char* key) {
          const json* v = member(*a, key);
          return v && v->is_number() ? v->get<float>() : 0.0f;
        };
        out.anisotropy.strength = number("anisotropyStrength");
        out.anisotropy.rotation = number("anisotropyRotation");
        if (!std::isfinite(out.anisotropy.strength) || !std::isfinite(out.anisotropy.rotation))
          throw Error(name_ + ": material " + std::to_string(index) + " has a non-finite KHR_materials_anisotropy value");
        out.anisotropy.strength = std::clamp(out.anisotropy.strength, 0.0f, 1.0f);  // the schema's range
        out.anisotropy.texture = texture(member(*a, "anisotropyTexture"));
      }
  }
  return out;
}

void GltfReader::readPrimitive(const tinygltf::Primitive& p, const json& pj, const Eigen::Matrix4d& transform,
                               const std::string& where) {
  if (p.mode != TINYGLTF_MODE_TRIANGLES && p.mode != TINYGLTF_MODE_TRIANGLE_STRIP && p.mode != TINYGLTF_MODE_TRIANGLE_FAN &&
      p.mode != -1)
    return;  // points and lines carry no surface
  VertexArrays v;
  const json* draco = nullptr;
  if (const json* ext = member(pj, "extensions")) draco = member(*ext, "KHR_draco_mesh_compression");
  auto attribute = [&](const char* name) {
    const auto it = p.attributes.find(name);
    return it == p.attributes.end() ? -1 : it->second;
  };
  if (draco) {
    const json* view = member(*draco, "bufferView");
    const json* attrs = member(*draco, "attributes");
    if (!view || !view->is_number_integer() || !attrs || !attrs->is_object())
      throw Error(name_ + ": " + where + ": malformed KHR_draco_mesh_compression extension");
    auto id = [&](const char* name) {
      const json* a = member(*attrs, name);
      if (!a) return -1;
      if (!a->is_number_integer() || a->get<long long>() < 0 || a->get<long long>() > 1000)
        throw Error(name_ + ": " + where + ": bad Draco attribute id for " + name);
      return a->get<int>();
    };
    DracoAttributeIds ids{id("POSITION"), id("TEXCOORD_0"), id("NORMAL"), id("TANGENT")};
    const auto [data, size] = bufferViewBytes(view->get<int>(), where + " Draco data");
    v = decodeDraco(data, size, ids, name_ + ": " + where);
  } else {
    const int position = attribute("POSITION");
    if (position < 0) throw Error(name_ + ": " + where + " has no POSITION attribute");
    v.positions = readFloats<3>(position, "POSITION");
    if (const int a = attribute("TEXCOORD_0"); a >= 0) v.uvs = readFloats<2>(a, "TEXCOORD_0");
    if (const int a = attribute("NORMAL"); a >= 0) v.normals = readFloats<3>(a, "NORMAL");
    if (const int a = attribute("TANGENT"); a >= 0) v.tangents = readFloats<4>(a, "TANGENT");
    if (p.indices >= 0) {
      v.indices = readIndices(p.indices);
    } else {
      v.indices.resize(v.positions.size());
      for (size_t i = 0; i < v.indices.size(); ++i) v.indices[i] = uint32_t(i);
    }
  }
  const size_t nv = v.positions.size();
  if ((!v.uvs.empty() && v.uvs.size() != nv) || (!v.normals.empty() && v.normals.size() != nv) ||
      (!v.tangents.empty() && v.tangents.size() != nv))
    throw Error(name_ + ": " + where + ": attribute counts differ from the POSITION count");
  for (uint32_t i : v.indices)
    if (i >= nv)
      throw Error(name_ + ": " + where + " uses vertex " + std::to_string(i) + " but has " + std::to_string(nv) + " vertices");
  // Triangle list from the primitive mode.
  std::vector<std::array<uint32_t, 3>> tris;
  const auto& ix = v.indices;
  if (p.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 2; i < ix.size(); ++i)
      tris.push_back(i % 2 ? std::array<uint32_t, 3>{ix[i - 1], ix[i - 2], ix[i]} : std::array<uint32_t, 3>{ix[i - 2], ix[i - 1], ix[i]});
  } else if (p.mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 2; i < ix.size(); ++i) tris.push_back({ix[0], ix[i - 1], ix[i]});
  } else {
    if (ix.size() % 3) throw Error(name_ + ": " + where + ": index count " + std::to_string(ix.size()) + " is not a multiple of 3");
    for (size_t i = 0; i + 2 < ix.size(); i += 3) tris.push_back({ix[i], ix[i + 1], ix[i + 2]});
  }
  // Node transform: positions by M, normals by M^-T, tangents by M; mirror flips the winding.
  const Eigen::Matrix3d linear = transform.topLeftCorner<3, 3>();
  const bool mirror = linear.determinant() < 0;
  const Eigen::Matrix3d normalMatrix = linear.inverse().transpose();
  const uint32_t base = uint32_t(mesh_.positions.size());
  for (const auto& pos : v.positions) {
    const Eigen::Vector4d q = transform * Eigen::Vector4d(pos.x(), pos.y(), pos.z(), 1.0);
    mesh_.positions.emplace_back(q.head<3>().cast<float>());
  }
  int materialIndex = p.material;
  if (materialIndex < -1 || materialIndex >= int(model_.materials.size()))
    throw Error(name_ + ": " + where + " uses material " + std::to_string(materialIndex) + " which does not exist");
  if (materialIndex < 0) needDefaultMaterial_ = true;
  uint32_t tag = 0;
  if (const json* extras = member(pj, "extras"))
    if (const json* t = member(*extras, "texfab:tag"); t && t->is_number_unsigned()) tag = t->get<uint32_t>();
  const size_t firstTri = mesh_.triangles.size();
  for (auto tri : tris) {
    if (mirror) std::swap(tri[1], tri[2]);
    mesh_.triangles.push_back({base + tri[0], base + tri[1], base + tri[2]});
    mesh_.faceMaterials.push_back(materialIndex < 0 ? UINT32_MAX : uint32_t(materialIndex));
    mesh_.faceTags.push_back(tag);
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = tri[size_t(k)];
      mesh_.uvs.push_back(v.uvs.empty() ? Eigen::Vector2f(0, 0) : Eigen::Vector2f(v.uvs[i].x(), 1.0f - v.uvs[i].y()));
      if (!v.normals.empty()) {
        const Eigen::Vector3d n = normalMatrix * v.normals[i].cast<double>();
        mesh_.normals.push_back(n.squaredNorm() > 0 ? n.normalized().cast<float>() : Eigen::Vector3f(0, 0, 0));
      } else {
        mesh_.normals.push_back(Eigen::Vector3f(0, 0, 0)); // filled with face normals later
      }
      if (!v.tangents.empty()) {
        const Eigen::Vector3d t = linear * v.tangents[i].head<3>().cast<double>();
        const Eigen::Vector3f tn = t.squaredNorm() > 0 ? t.normalized().cast<float>() : Eigen::Vector3f(1, 0, 0);
        mesh_.tangents.emplace_back(tn.x(), tn.y(), tn.z(), (v.tangents[i].w() < 0) != mirror ? -1.0f : 1.0f);
      } else {
        mesh_.tangents.emplace_back(0, 0, 0, 0);
      }
    }
  }
  anyUv_ |= !v.uvs.empty();
  anyNormal_ |= !v.normals.empty();
  allTangents_ &= !v.tangents.empty() || tris.empty();
  if (v.normals.empty())
    for (size_t t = firstTri; t < mesh_.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) mesh_.normals[3 * t + size_t(k)] = faceNormal(mesh_, t);
}

void GltfReader::visitNode(int node, const Eigen::Matrix4d& parent, int depth) {
  if (node < 0 || size_t(node) >= model_.nodes.size()) throw Error(name_ + ": node " + std::to_string(node) + " does not exist");
  if (depth > 256 || onPath_[size_t(node)]) throw Error(name_ + ": the node hierarchy has a cycle");
  onPath_[size_t(node)] = 1;
  const tinygltf::Node& n = model_.nodes[size_t(node)];
  Eigen::Matrix4d local = Eigen::Matrix4d::Identity();
  if (n.matrix.size() == 16) {
    for (int i = 0; i < 16; ++i) local(i % 4, i / 4) = n.matrix[size_t(i)]; // column-major
  } else {
    Eigen::Affine3d a = Eigen::Affine3d::Identity();
    if (n.translation.size() == 3) a.translate(Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]));
    if (n.rotation.size() == 4) {
      Eigen::Quaterniond q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
      if (q.norm() > 0) a.rotate(q.normalized());
    }
    if (n.scale.size() == 3) a.scale(Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]));
    local = a.matrix();
  }
  if (!local.allFinite()) throw Error(name_ + ": node " + std::to_string(node) + " has a non-finite transform");
  const Eigen::Matrix4d world = parent * local;
  if (n.mesh >= 0) {
    if (size_t(n.mesh) >= model_.meshes.size()) throw Error(name_ + ": node " + std::to_string(node) + " refers to a missing mesh");
    const json* meshesJson = member(doc_, "meshes");
    const json& mj = (*meshesJson)[size_t(n.mesh)];
    const json* prims = member(mj, "primitives");
    const auto& primitives = model_.meshes[size_t(n.mesh)].primitives;
    for (size_t i = 0; i < primitives.size(); ++i)
      readPrimitive(primitives[i], prims && prims->is_array() && i < prims->size() ? (*prims)[i] : json::object(), world,
                    "mesh " + std::to_string(n.mesh) + " primitive " + std::to_string(i));
  }
  for (int child : n.children) visitNode(child, world, depth + 1);
  onPath_[size_t(node)] = 0;
}

Mesh GltfReader::read() {
  onPath_.assign(model_.nodes.size(), 0);
  if (!model_.scenes.empty()) {
    const size_t scene = model_.defaultScene >= 0 && size_t(model_.defaultScene) < model_.scenes.size() ? size_t(model_.defaultScene) : 0;
    for (int node : model_.scenes[scene].nodes) visitNode(node, Eigen::Matrix4d::Identity(), 0);
  } else {
    // No scene: every mesh once, untransformed (glTF allows libraries of meshes).
    const json* meshesJson = member(doc_, "meshes");
    for (size_t m = 0; m < model_.meshes.size(); ++m)
      for (size_t i = 0; i < model_.meshes[m].primitives.size(); ++i) {
        const json* prims = member((*meshesJson)[m], "primitives");
        readPrimitive(model_.meshes[m].primitives[i], prims && i < prims->size() ? (*prims)[i] : json::object(),
                      Eigen::Matrix4d::Identity(), "mesh " + std::to_string(m) + " primitive " + std::to_string(i));
      }
  }
  // Materials: glTF's list, plus a default one for primitives without a material.
  for (size_t i = 0; i < model_.materials.size(); ++i) mesh_.materials.push_back(material(i));
  if (needDefaultMaterial_) {
    Material d;
    d.name = "default";
    for (uint32_t& m : mesh_.faceMaterials)
      if (m == UINT32_MAX) m = uint32_t(mesh_.materials.size());
    mesh_.materials.push_back(d);
  }
  if (!anyUv_) mesh_.uvs.clear();
  if (!anyNormal_) mesh_.normals.clear();
  if (!allTangents_ || !anyUv_) mesh_.tangents.clear();
  bool anyTag = false;
  for (uint32_t t : mesh_.faceTags) anyTag |= t != 0;
  if (!anyTag) mesh_.faceTags.clear();
  weldPositions(mesh_);
  return std::move(mesh_);
}

// Extensions texfab reads; a file that requires any other is refused.
bool supportedExtension(const std::string& name) {
  return name == "KHR_draco_mesh_compression" || name == "KHR_texture_transform" || name == "KHR_mesh_quantization" ||
         name == "EXT_texture_webp";
}

// A GLB's JSON text and binary chunk.
struct GlbChunks {
  std::string json;
  std::optional<std::vector<uint8_t>> bin;
};

GlbChunks splitGlb(const std::string& name, const std::vector<uint8_t>& bytes) {
  if (bytes.size() < 20) throw Error(name + ": truncated GLB header");
  if (le32(bytes.data() + 4) != 2) throw Error(name + ": GLB version " + std::to_string(le32(bytes.data() + 4)) + " (expected 2)");
  const uint64_t length = le32(bytes.data() + 8);
  if (length > bytes.size()) throw Error(name + ": truncated GLB (header says " + std::to_string(length) + " bytes, file has " +
                                         std::to_string(bytes.size()) + ")");
  GlbChunks chunks;
  uint64_t at = 12;
  while (at + 8 <= length) {
    const uint64_t chunkLength = le32(bytes.data() + at);
    const uint32_t type = le32(bytes.data() + at + 4);
    if (at + 8 + chunkLength > length) throw Error(name + ": GLB chunk overruns the file");
    const uint8_t* chunk = bytes.data() + at + 8;
    if (at == 12) {
      if (type != kGlbChunkJson) throw Error(name + ": GLB does not start with a JSON chunk");
      chunks.json.assign(reinterpret_cast<const char*>(chunk), chunkLength);
    } else if (type == kGlbChunkBin && !chunks.bin) {
      chunks.bin.emplace(chunk, chunk + chunkLength);
    }
    at += 8 + ((chunkLength + 3) & ~uint64_t(3));
  }
  if (chunks.json.empty()) throw Error(name + ": GLB has no JSON chunk");
  return chunks;
}

// Version, required extensions, references: all before tinygltf reads a byte of any buffer.
void checkDocument(const fs::path& path, const json& doc) {
  const std::string name = path.string();
  const json* asset = member(doc, "asset");
  const json* version = asset ? member(*asset, "version") : nullptr;
  if (!version || !version->is_string() || version->get<std::string>().rfind("2.", 0) != 0)
    throw Error(name + ": not a glTF 2.0 file (asset.version missing or not 2.x)");
  if (const json* required = member(doc, "extensionsRequired"); required && required->is_array())
    for (const json& e : *required)
      if (!e.is_string() || !supportedExtension(e.get<std::string>()))
        throw Error(name + ": requires the glTF extension " + (e.is_string() ? e.get<std::string>() : "?") +
                    ", which texfab does not support");
  for (const char* list : {"buffers", "images"})
    if (const json* items = member(doc, list); items && items->is_array())
      for (const json& item : *items)
        if (const json* uri = member(item, "uri"); uri && uri->is_string() && !isDataUri(uri->get<std::string>()))
          (void)resolveModelReference(path, uri->get<std::string>(), true);
}

// The document tinygltf reads: no images (decoded by texfab), and no "indices" on Draco-compressed
// primitives (tinygltf 2.7 insists that index accessors have a buffer view, which those
// legitimately lack: the Draco stream has them).
std::string loaderDocument(json doc) {
  doc.erase("images");
  if (json* meshes = doc.contains("meshes") ? &doc["meshes"] : nullptr; meshes && meshes->is_array())
    for (json& m : *meshes)
      if (m.is_object() && m.contains("primitives") && m["primitives"].is_array())
        for (json& p : m["primitives"])
          if (const json* ext = member(p, "extensions"); ext && member(*ext, "KHR_draco_mesh_compression")) p.erase("indices");
  return doc.dump();
}

tinygltf::Model loadModel(const fs::path& path, const std::string& document, bool glb,
                          const std::optional<std::vector<uint8_t>>& bin) {
  tinygltf::TinyGLTF loader;
  FsContext context{path.parent_path().empty() ? fs::path(".") : path.parent_path()};
  loader.SetFsCallbacks(tinygltf::FsCallbacks{&fsFileExists, &fsExpand, &fsRead, &fsWrite, &context});
  loader.SetImageLoader(&noImageLoader, nullptr);
  loader.SetStoreOriginalJSONForExtrasAndExtensions(false);
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  if (glb) {
    const std::string packed = packGlb(document, bin ? &*bin : nullptr, path.string());
    ok = loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(packed.data()),
                                     uint32_t(packed.size()), context.folder.string());
  } else {
    ok = loader.LoadASCIIFromString(&model, &err, &warn, document.c_str(), uint32_t(document.size()), context.folder.string());
  }
  if (!ok) throw Error(path.string() + ": " + firstLine(err));
  return model;
}

} // namespace

Mesh readGltf(const fs::path& path) {
  const std::vector<uint8_t> bytes = readFileBytes(path, uint64_t(2) << 30);
  const bool glb = bytes.size() >= 4 && le32(bytes.data()) == kGlbMagic;
  const GlbChunks chunks = glb ? splitGlb(path.string(), bytes)
                         : GlbChunks{std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()), std::nullopt};
  const json doc = json::parse(chunks.json, nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) throw Error(path.string() + ": not valid glTF JSON");
  checkDocument(path, doc);
  const tinygltf::Model model = loadModel(path, loaderDocument(doc), glb, chunks.bin);
  const json noImages = json::array();
  const json* images = member(doc, "images");
  GltfReader reader(path, model, doc, images ? *images : noImages);
  return reader.read();
}

} // namespace texfab::geometry::detail
