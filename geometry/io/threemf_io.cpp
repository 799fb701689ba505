// SPDX-License-Identifier: GPL-3.0-or-later
// 3MF through Debian's lib3mf 1.8.1 (its C interface, NMR_DLLInterfaces.h): the core mesh and the
// Materials and Properties extension (3MF Consortium, version 1.0: <m:texture2d> and
// <m:texture2dgroup> with per-corner <m:tex2coord>, and <basematerials> for plain colours).
//
// Writing: one mesh object with one build item; each material with a base colour texture becomes
// a texture2d (its image as a PNG attachment under /3D/Textures/, its colour factor multiplied in,
// KHR_texture_transform applied to the UVs) and its triangles carry their corners' UVs; the other
// materials become one basematerials group (name and display colour). Coordinates are millimetres
// (the model unit times MeshWriteOptions::millimetresPerUnit), the model turned so that its up axis
// is 3MF's build direction (+z). lib3mf 1.8 writes its archive with
// Zip64 fields on every entry and a date of 1980-00-00, which assimp (5.2) refuses: the archive is
// re-packed with libzip (plain entries, deflated, dated 1980-01-01). Reading takes every mesh
// object of every build item (with its transform), its texture coordinates and textures, and
// base materials as plain colours.
#include "core/error.h"
#include "core/image_io.h"
#include "geometry/io/mesh_formats.h"

#include <Model/COM/NMR_DLLInterfaces.h>
#include <zip.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>

namespace texfab::geometry::detail {
namespace fs = std::filesystem;

namespace {

using namespace NMR;

// Owns one lib3mf instance.
struct Handle {
  PLib3MFBase* p = nullptr;
  Handle() = default;
  explicit Handle(PLib3MFBase* instance) : p(instance) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : p(o.p) { o.p = nullptr; }
  ~Handle() {
    if (p) lib3mf_release(p);
  }
  PLib3MFBase** out() { return &p; }
};

// Throws texfab::Error naming `where` with lib3mf's last error when `result` is not LIB3MF_OK.
void check(LIB3MFRESULT result, PLib3MFBase* instance, const std::string& where) {
  if (result == LIB3MF_OK) return;
  DWORD code = 0;
  LPCSTR message = nullptr;
  if (instance) lib3mf_getlasterror(instance, &code, &message);
  throw Error(where + ": " + (message && *message ? std::string(message) : "lib3mf error " + std::to_string(result)));
}

// The image times a colour factor, in linear light (textures hold sRGB).
Image tinted(const Image& image, const Eigen::Vector4f& factor) {
  if (factor == Eigen::Vector4f(1, 1, 1, 1)) return image;
  auto toLinear = [](float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); };
  auto toSrgb = [](float c) { return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f; };
  Image out = image;
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < out.channels; ++c) {
        float& v = out.at(x, y, c);
        v = c == 3 || (out.channels == 2 && c == 1) ? v * factor[3] : toSrgb(toLinear(v) * factor[std::min(c, 2)]);
      }
  return out;
}

std::string textureId(size_t m) { return "/3D/Textures/texture_" + std::to_string(m) + ".png"; }

uint8_t byteOf(float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); }

// The texture of material m as a texture2d resource; returns its id.
DWORD addTexture(PLib3MFModel* model, const Material& material, size_t m, const std::string& where) {
  const std::vector<uint8_t> png = encodePng(tinted(*material.baseColorTexture.image, material.baseColorFactor));
  Handle attachment, texture;
  std::string uri = textureId(m);
  std::string relation = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dtexture";
  check(lib3mf_model_addattachmentutf8(model, uri.data(), relation.data(), attachment.out()), model, where);
  check(lib3mf_attachment_readfrombuffer(attachment.p, const_cast<BYTE*>(png.data()), png.size()), attachment.p, where);
  check(lib3mf_model_addtexture2dfromattachment(model, attachment.p, texture.out()), model, where);
  check(lib3mf_texture2d_setcontenttype(texture.p, MODELTEXTURETYPE_PNG), texture.p, where);
  check(lib3mf_texture2d_settilestyleuv(texture.p, MODELTEXTURETILESTYLE_WRAP, MODELTEXTURETILESTYLE_WRAP), texture.p, where);
  DWORD id = 0;
  check(lib3mf_resource_getresourceid(texture.p, &id), texture.p, where);
  return id;
}

// The zip archive `archive` written again to `file` with libzip: the same entries in the same order,
// deflated, without Zip64 fields (under 4 GiB), dated 1980-01-01 00:00.
void repackZip(const std::vector<BYTE>& archive, const fs::path& file, const std::string& where) {
  zip_error_t error;
  zip_error_init(&error);
  zip_source_t* source = zip_source_buffer_create(archive.data(), archive.size(), 0, &error);
  zip_t* in = source ? zip_open_from_source(source, ZIP_RDONLY, &error) : nullptr;
  if (!in) {
    if (source) zip_source_free(source);
    const std::string why = zip_error_strerror(&error);
    zip_error_fini(&error);
    throw Error(where + ": cannot read lib3mf's archive: " + why);
  }
  std::vector<std::pair<std::string, std::vector<uint8_t>>> entries;
  for (zip_int64_t i = 0, n = zip_get_num_entries(in, 0); i < n; ++i) {
    zip_stat_t st;
    zip_file_t* f = zip_stat_index(in, zip_uint64_t(i), 0, &st) == 0 ? zip_fopen_index(in, zip_uint64_t(i), 0) : nullptr;
    if (!f) {
      zip_discard(in);
      throw Error(where + ": cannot read lib3mf's archive entry " + std::to_string(i));
    }
    std::vector<uint8_t> data(size_t(st.size));
    const zip_int64_t got = zip_fread(f, data.data(), data.size());
    zip_fclose(f);
    if (got != zip_int64_t(data.size())) {
      zip_discard(in);
      throw Error(where + ": cannot read lib3mf's archive entry " + st.name);
    }
    entries.emplace_back(st.name, std::move(data));
  }
  zip_discard(in);

  int code = 0;
  zip_t* out = zip_open(file.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
  if (!out) throw Error(where + ": cannot create the file (libzip error " + std::to_string(code) + ")");
  for (const auto& [name, data] : entries) {
    zip_source_t* s = zip_source_buffer(out, data.data(), data.size(), 0);
    const zip_int64_t index = s ? zip_file_add(out, name.c_str(), s, ZIP_FL_ENC_UTF_8) : -1;
    if (index < 0) {
      if (s) zip_source_free(s);
      zip_discard(out);
      throw Error(where + ": cannot add " + name + " to the archive");
    }
    zip_set_file_compression(out, zip_uint64_t(index), ZIP_CM_DEFLATE, 0);
    zip_file_set_dostime(out, zip_uint64_t(index), 0, (1 << 5) | 1, 0);  // 1980-01-01 00:00
  }
  if (zip_close(out) != 0) {
    const std::string why = zip_strerror(out);
    zip_discard(out);
    throw Error(where + ": cannot write the file: " + why);
  }
}

} // namespace

void write3mf(const Mesh& mesh, const fs::path& path, const fs::path& tmp, const Eigen::Matrix3d& toBuild) {
  const std::string where = path.string();
  Handle model, object, properties, group, writer, item;
  check(lib3mf_createmodel(model.out()), nullptr, where);
  check(lib3mf_model_setunit(model.p, MODELUNIT_MILLIMETER), model.p, where);
  check(lib3mf_model_addmeshobject(model.p, object.out()), model.p, where);
  std::vector<MODELMESHVERTEX> vertices(mesh.positions.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Eigen::Vector3d p = toBuild * mesh.positions[i].cast<double>();
    for (int k = 0; k < 3; ++k) vertices[i].m_fPosition[k] = float(p[k]);
  }
  std::vector<MODELMESHTRIANGLE> triangles(mesh.triangleCount());
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) triangles[t].m_nIndices[k] = mesh.triangles[t][size_t(k)];
  check(lib3mf_meshobject_setgeometry(object.p, vertices.data(), DWORD(vertices.size()), triangles.data(),
                                      DWORD(triangles.size())),
        object.p, where);
  // Properties: a texture2d per textured material, one basematerials group for the others.
  std::map<size_t, DWORD> textures, colors;
  DWORD groupId = 0;
  for (size_t m = 0; m < mesh.materials.size(); ++m) {
    const Material& material = mesh.materials[m];
    if (material.baseColorTexture && mesh.hasUvs()) {
      textures[m] = addTexture(model.p, material, m, where);
      continue;
    }
    if (!group.p) {
      check(lib3mf_model_addbasematerialgroup(model.p, group.out()), model.p, where);
      check(lib3mf_resource_getresourceid(group.p, &groupId), group.p, where);
    }
    const Eigen::Vector4f& c = material.baseColorFactor;
    auto srgb = [](float v) { return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f; };
    DWORD index = 0;
    check(lib3mf_basematerial_addmaterialutf8(group.p, material.name.empty() ? "material" : material.name.c_str(),
                                              byteOf(srgb(c[0])), byteOf(srgb(c[1])), byteOf(srgb(c[2])), &index),
          group.p, where);
    colors[m] = index;
  }
  if (!mesh.materials.empty()) {
    check(lib3mf_meshobject_createpropertyhandler(object.p, properties.out()), object.p, where);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
      const size_t m = mesh.materialOf(t);
      if (auto it = textures.find(m); it != textures.end()) {
        MODELMESHTEXTURE2D uv{};
        uv.m_nTextureID = it->second;
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector2f p = mesh.materials[m].baseColorTexture.apply(mesh.uvs[3 * t + size_t(k)]);
          uv.m_fU[k] = p.x();
          uv.m_fV[k] = p.y();
        }
        check(lib3mf_propertyhandler_settexture(properties.p, DWORD(t), &uv), properties.p, where);
      } else {
        check(lib3mf_propertyhandler_setbasematerial(properties.p, DWORD(t), groupId, colors.at(m)), properties.p, where);
      }
    }
    // 3MF wants an object whose triangles have properties to name a default one: the first
    // triangle's (its first corner's UV for a texture).
    Handle defaults;
    check(lib3mf_object_createdefaultpropertyhandler(object.p, defaults.out()), object.p, where);
    const size_t m0 = mesh.materialOf(0);
    if (auto it = textures.find(m0); it != textures.end()) {
      const Eigen::Vector2f p = mesh.materials[m0].baseColorTexture.apply(mesh.uvs[0]);
      check(lib3mf_defaultpropertyhandler_settexture(defaults.p, it->second, p.x(), p.y()), defaults.p, where);
    } else {
      check(lib3mf_defaultpropertyhandler_setbasematerial(defaults.p, groupId, colors.at(m0)), defaults.p, where);
    }
  }
  check(lib3mf_model_addbuilditem(model.p, object.p, nullptr, item.out()), model.p, where);
  check(lib3mf_model_querywriter(model.p, "3mf", writer.out()), model.p, where);
  ULONG64 size = 0;
  check(lib3mf_writer_getstreamsize(writer.p, &size), writer.p, where);
  std::vector<BYTE> archive(static_cast<size_t>(size));
  check(lib3mf_writer_writetobuffer(writer.p, archive.data(), size), writer.p, where);
  repackZip(archive, tmp, where);
}

} // namespace texfab::geometry::detail

namespace texfab::geometry::detail {

namespace {

using namespace NMR;

// The image of texture2d `id`, decoded.
std::shared_ptr<const Image> readTexture(PLib3MFModel* model, DWORD id, const std::string& where) {
  Handle texture, attachment;
  check(lib3mf_model_gettexture2dbyid(model, id, texture.out()), model, where);
  check(lib3mf_texture2d_getattachment(texture.p, attachment.out()), texture.p, where);
  ULONG64 size = 0;
  check(lib3mf_attachment_getstreamsize(attachment.p, &size), attachment.p, where);
  if (size > (uint64_t(1) << 31)) throw Error(where + ": texture " + std::to_string(id) + " is too large");
  std::vector<uint8_t> bytes(size);
  check(lib3mf_attachment_writetobuffer(attachment.p, bytes.data(), size), attachment.p, where);
  return std::make_shared<const Image>(decodeImage(bytes, where + " texture " + std::to_string(id)));
}

// Appends mesh object `object` placed by `transform` to `mesh`, its triangles' textures and base
// materials as materials (shared through `materialOf`, keyed by texture id or (group, index)).
void appendObject(PLib3MFModel* model, PLib3MFModelMeshObject* object, const MODELTRANSFORM* transform, Mesh& mesh,
                  std::map<std::pair<DWORD, DWORD>, uint32_t>& materialOf, const std::string& where) {
  DWORD nv = 0, nt = 0;
  check(lib3mf_meshobject_getvertexcount(object, &nv), object, where);
  check(lib3mf_meshobject_gettrianglecount(object, &nt), object, where);
  std::vector<MODELMESHVERTEX> vertices(nv);
  std::vector<MODELMESHTRIANGLE> triangles(nt);
  if (nv) check(lib3mf_meshobject_getvertices(object, vertices.data(), nv, nullptr), object, where);
  if (nt) check(lib3mf_meshobject_gettriangleindices(object, triangles.data(), nt, nullptr), object, where);
  const uint32_t base = uint32_t(mesh.positions.size());
  for (const MODELMESHVERTEX& v : vertices) {
    Eigen::Vector3f p(v.m_fPosition[0], v.m_fPosition[1], v.m_fPosition[2]);
    if (transform) {  // 3MF's matrices are row vectors times a 4x3 matrix
      Eigen::Vector3f q;
      for (int c = 0; c < 3; ++c) q[c] = p.x() * transform->m_fFields[c][0] + p.y() * transform->m_fFields[c][1] +
                                         p.z() * transform->m_fFields[c][2] + transform->m_fFields[c][3];
      p = q;
    }
    mesh.positions.push_back(p);
  }
  Handle properties;
  check(lib3mf_meshobject_createpropertyhandler(object, properties.out()), object, where);
  for (DWORD t = 0; t < nt; ++t) {
    const auto& i = triangles[t].m_nIndices;
    if (i[0] >= nv || i[1] >= nv || i[2] >= nv) throw Error(where + ": triangle " + std::to_string(t) + " indexes a missing vertex");
    mesh.triangles.push_back({base + i[0], base + i[1], base + i[2]});
    MODELMESHTEXTURE2D uv{};
    DWORD group = 0, index = 0;
    std::pair<DWORD, DWORD> key{0, 0};
    if (lib3mf_propertyhandler_gettexture(properties.p, t, &uv) == LIB3MF_OK && uv.m_nTextureID != 0) key = {uv.m_nTextureID, UINT32_MAX};
    else if (lib3mf_propertyhandler_getbasematerial(properties.p, t, &group, &index) == LIB3MF_OK && group != 0) key = {group, index};
    for (int k = 0; k < 3; ++k) mesh.uvs.push_back(key.second == UINT32_MAX ? Eigen::Vector2f(uv.m_fU[k], uv.m_fV[k]) : Eigen::Vector2f(0, 0));
    auto [it, added] = materialOf.emplace(key, uint32_t(mesh.materials.size()));
    if (added) {
      Material m;
      m.metallicFactor = 0.0f;
      if (key.second == UINT32_MAX) {
        m.name = "texture" + std::to_string(key.first);
        m.baseColorTexture.image = readTexture(model, key.first, where);
      } else if (key.first != 0) {
        Handle materials;
        check(lib3mf_model_getbasematerialbyid(model, key.first, materials.out()), model, where);
        BYTE rgba[4] = {255, 255, 255, 255};
        check(lib3mf_basematerial_getdisplaycolor(materials.p, key.second, &rgba[0], &rgba[1], &rgba[2], &rgba[3]), materials.p, where);
        auto linear = [](BYTE b) { const float c = b / 255.0f; return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); };
        m.name = "material" + std::to_string(key.first) + "_" + std::to_string(key.second);
        m.baseColorFactor = {linear(rgba[0]), linear(rgba[1]), linear(rgba[2]), rgba[3] / 255.0f};
      } else {
        m.name = "default";
      }
      mesh.materials.push_back(m);
    }
    mesh.faceMaterials.push_back(it->second);
  }
}

// lib3mf 1.8 allocates and clears each archive entry's stated size before inflating it: an entry
// that states more than deflate can expand its compressed bytes to (1032 times), or more compressed
// bytes than the archive holds, is refused first.
void checkEntrySizes(const fs::path& path, const std::string& where) {
  std::error_code error;
  const uint64_t fileSize = fs::file_size(path, error);
  int code = 0;
  zip_t* archive = zip_open(path.c_str(), ZIP_RDONLY, &code);
  if (!archive || error) {
    if (archive) zip_discard(archive);
    return;  // lib3mf says what is wrong with it
  }
  for (zip_int64_t i = 0, n = zip_get_num_entries(archive, 0); i < n; ++i) {
    zip_stat_t st;
    if (zip_stat_index(archive, zip_uint64_t(i), 0, &st) != 0) continue;
    const bool known = (st.valid & ZIP_STAT_SIZE) && (st.valid & ZIP_STAT_COMP_SIZE);
    std::string problem;
    if (known && st.comp_size > fileSize)
      problem = std::to_string(st.comp_size) + " compressed bytes, more than the archive's " + std::to_string(fileSize);
    else if (known && st.size > 1032 * st.comp_size + 1024)
      problem = std::to_string(st.size) + " bytes, more than its " + std::to_string(st.comp_size) +
                " compressed bytes can hold";
    if (!problem.empty()) {
      const std::string name = st.name ? st.name : "?";
      zip_discard(archive);
      throw Error(where + ": corrupt 3MF: archive entry '" + name + "' states " + problem);
    }
  }
  zip_discard(archive);
}

} // namespace

Mesh read3mf(const fs::path& path) {
  const std::string where = path.string();
  checkEntrySizes(path, where);
  Handle model, reader, items;
  check(lib3mf_createmodel(model.out()), nullptr, where);
  check(lib3mf_model_queryreader(model.p, "3mf", reader.out()), model.p, where);
  check(lib3mf_reader_readfromfileutf8(reader.p, path.c_str()), reader.p, where);
  check(lib3mf_model_getbuilditems(model.p, items.out()), model.p, where);
  Mesh mesh;
  std::map<std::pair<DWORD, DWORD>, uint32_t> materialOf;
  for (BOOL more = false; lib3mf_builditemiterator_movenext(items.p, &more) == LIB3MF_OK && more;) {
    Handle item, object;
    check(lib3mf_builditemiterator_getcurrent(items.p, item.out()), items.p, where);
    check(lib3mf_builditem_getobjectresource(item.p, object.out()), item.p, where);
    BOOL isMesh = false, hasTransform = false;
    check(lib3mf_object_ismeshobject(object.p, &isMesh), object.p, where);
    if (!isMesh) throw Error(where + ": components objects are not read, only meshes");
    MODELTRANSFORM transform{};
    check(lib3mf_builditem_hasobjecttransform(item.p, &hasTransform), item.p, where);
    if (hasTransform) check(lib3mf_builditem_getobjecttransform(item.p, &transform), item.p, where);
    appendObject(model.p, object.p, hasTransform ? &transform : nullptr, mesh, materialOf, where);
  }
  if (mesh.triangles.empty()) throw Error(where + ": no mesh in the build");
  const bool textured = std::any_of(mesh.materials.begin(), mesh.materials.end(), [](const Material& m) { return bool(m.baseColorTexture); });
  if (!textured) mesh.uvs.clear();
  if (mesh.materials.size() == 1 && mesh.materials[0].name == "default") mesh.materials.clear(), mesh.faceMaterials.clear();
  return mesh;
}

} // namespace texfab::geometry::detail
