// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Internal to geometry/: one reader/writer pair per format (obj_io.cpp, ply_io.cpp, off_io.cpp,
// stl_io.cpp, gltf_read.cpp, gltf_write.cpp, threemf_io.cpp) behind readMesh/writeMesh, plus shared
// helpers.
// Readers may return meshes that validateMesh has not checked yet; readMesh validates.

#include "geometry/io/mesh_io.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace texfab::geometry::detail {

Mesh readObj(const std::filesystem::path& path, const Context& ctx);  ///< warns through ctx
Mesh readPly(const std::filesystem::path& path);
Mesh readOff(const std::filesystem::path& path);
Mesh readStl(const std::filesystem::path& path);
Mesh readGltf(const std::filesystem::path& path); ///< .gltf and .glb
Mesh read3mf(const std::filesystem::path& path);   ///< lib3mf inside threemf_io.cpp only

/// Writers write to `tmp` (and commit any side files themselves, after the main file is complete
/// in `tmp`); the caller renames `tmp` onto `path`.
void writeObj(const Mesh& mesh, const std::filesystem::path& path, const std::filesystem::path& tmp,
              const MeshWriteOptions& options,
              std::vector<std::pair<std::filesystem::path, std::filesystem::path>>& sideFiles);
void writePly(const Mesh& mesh, const std::filesystem::path& tmp, bool binary);
void writeOff(const Mesh& mesh, const std::filesystem::path& tmp);
void writeStl(const Mesh& mesh, const std::filesystem::path& tmp, bool binary);
void writeGltf(const Mesh& mesh, const std::filesystem::path& path, const std::filesystem::path& tmp, bool binary,
               const MeshWriteOptions& options,
               std::vector<std::pair<std::filesystem::path, std::filesystem::path>>& sideFiles);
/// Several meshes as one glTF scene (writeScene).
void writeGltfScene(std::span<const SceneNode> nodes, const std::filesystem::path& path, const std::filesystem::path& tmp,
                    bool binary, const MeshWriteOptions& options,
                    std::vector<std::pair<std::filesystem::path, std::filesystem::path>>& sideFiles);

/// A texture's image as the writers store it: its file's bytes when options.textures is Keep and
/// it has them, else encoded in the requested format (Keep: PNG).
EncodedImage storedImage(const Texture& texture, const MeshWriteOptions& options);
/// 3MF in millimetres, built along +z: each position p is written as `toBuild` p.
void write3mf(const Mesh& mesh, const std::filesystem::path& path, const std::filesystem::path& tmp,
              const Eigen::Matrix3d& toBuild);

/// The whole file; throws texfab::Error naming it when it cannot be read or exceeds `maxBytes`.
std::vector<uint8_t> readFileBytes(const std::filesystem::path& path, uint64_t maxBytes = uint64_t(4) << 30);
/// Writes bytes to `path` (no rename), throwing texfab::Error naming `shownAs` on failure.
void writeFileBytes(const std::filesystem::path& path, std::string_view bytes, const std::filesystem::path& shownAs);

/// Line-oriented text cursor shared by the ASCII readers (OBJ, MTL, PLY, OFF, STL).
class TextCursor {
public:
  TextCursor(const char* begin, const char* end) : p_(begin), end_(end) {}
  bool atEnd() const { return p_ >= end_; }
  /// Next line without its terminator (handles \n, \r\n, \r); advances the line counter.
  std::string_view nextLine();
  size_t lineNumber() const { return line_; }

private:
  const char* p_;
  const char* end_;
  size_t line_ = 0;
};

/// A material of an OBJ or PLY file: a dielectric (metallic 0, roughness 0.8) unless the file
/// says otherwise.
Material importedMaterial(std::string name = {});
/// A corner normal as a file gives it: unit length, or triangle t's own normal where it is zero.
/// Throws texfab::Error naming `path` when it is NaN or infinite.
Eigen::Vector3f importedNormal(const Eigen::Vector3f& n, const Mesh& mesh, size_t t, const std::filesystem::path& path);

/// Splits on spaces/tabs.
std::vector<std::string_view> splitWords(std::string_view line);
/// Strict number parsing; false on garbage or overflow.
bool parseFloat(std::string_view word, float& value);
bool parseInt(std::string_view word, long long& value);

} // namespace texfab::geometry::detail

namespace texfab::geometry::detail {

/// GLB container constants (glTF 2.0 §4.4).
inline constexpr uint32_t kGlbMagic = 0x46546C67, kGlbChunkJson = 0x4E4F534A, kGlbChunkBin = 0x004E4942;

/// A GLB file: the 12-byte header, the JSON chunk (padded with spaces) and, unless `bin` is null,
/// the binary chunk (padded with zeros). Throws texfab::Error naming `shownAs` when it would
/// exceed the format's 4 GiB.
std::string packGlb(std::string_view json, const std::vector<uint8_t>* bin, const std::string& shownAs);

/// One glTF primitive's vertex data, per vertex (glTF layout), used for Draco coding.
struct VertexArrays {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector2f> uvs;      ///< glTF convention (v down); empty if absent
  std::vector<Eigen::Vector3f> normals;  ///< empty if absent
  std::vector<Eigen::Vector4f> tangents; ///< empty if absent
  std::vector<uint32_t> indices;         ///< 3 per triangle
};

/// Draco attribute unique ids of an encoded primitive (-1 = absent), as the glTF extension lists.
struct DracoAttributeIds {
  int position = -1, uv = -1, normal = -1, tangent = -1;
};

/// Encodes a primitive with Draco (edgebreaker); returns the bytes and the attribute ids.
std::vector<uint8_t> encodeDraco(const VertexArrays& vertices, const MeshWriteOptions& options, DracoAttributeIds& ids);

/// Decodes a Draco-compressed glTF primitive; `name` names errors. Attributes whose id is -1 are
/// not read; normals are renormalized and tangent w snapped to ±1.
VertexArrays decodeDraco(const uint8_t* data, size_t size, const DracoAttributeIds& ids, const std::string& name);

} // namespace texfab::geometry::detail

namespace texfab::geometry::detail {

/// Triangulates one polygon given by vertex positions, returning corner triples (indices into
/// `corners`). Ear clipping in the polygon's best-fit plane (Newell normal), so concave faces
/// come out right; polygons of more than 64 corners, and those ear clipping cannot finish
/// (self-intersecting), fall back to a fan.
std::vector<std::array<uint32_t, 3>> triangulatePolygon(const std::vector<Eigen::Vector3f>& corners);

} // namespace texfab::geometry::detail
