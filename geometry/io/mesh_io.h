// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Reading and writing meshes. The format follows the file extension (case-insensitive):
//   .obj (+ .mtl and its textures)   .ply (ascii / binary)   .off   .stl (ascii / binary)
//   .gltf / .glb (glTF 2.0; KHR_draco_mesh_compression and KHR_texture_transform read)
//   .3mf (core + Materials and Properties: texture2d with per-corner UVs, base materials)
// Readers triangulate polygons, apply glTF node transforms, and validate the result
// (validateMesh): bad input throws texfab::Error with a one-line message naming the file.
// References inside a model (MTL files, textures, glTF buffers and images) must stay inside the
// model's folder: "..", absolute paths and URI schemes other than data: are refused.
// Writers write every file to a temporary name first and rename at the end, so a failure leaves
// no partial output.

#include "core/context.h"
#include "geometry/mesh.h"

#include <filesystem>
#include <span>
#include <string>

namespace texfab::geometry {

enum class MeshFormat { Obj, Ply, Off, Stl, Gltf, Glb, ThreeMf };

/// The format of `path` from its extension; throws texfab::Error for an unknown one.
MeshFormat meshFormatOf(const std::filesystem::path& path);

/// Human-readable names: "OBJ", "PLY", ...
const char* meshFormatName(MeshFormat format);

/// Whether the format carries materials with textures (glTF, GLB, OBJ+MTL; 3MF: the base colour
/// only); PLY, OFF and STL do not.
bool meshFormatCarriesTextures(MeshFormat format);

/// Whether the format is glTF (.gltf or .glb).
inline bool meshFormatIsGltf(MeshFormat format) { return format == MeshFormat::Gltf || format == MeshFormat::Glb; }

/// Reads a mesh. Texture images of OBJ and glTF materials are decoded (and their file bytes kept:
/// Texture::encoded). An OBJ whose .mtl or texture file is missing loads with plain materials and
/// a warning through ctx, as other OBJ readers do.
Mesh readMesh(const std::filesystem::path& path, const Context& ctx = {});

/// How writers store texture images.
enum class TextureEncoding {
  Keep,  ///< an image read from a PNG, JPEG or WebP file keeps its bytes; any other image is PNG
  Png,   ///< lossless (8-bit)
  Jpeg,  ///< lossy, no alpha; `textureQuality`
  Webp,  ///< lossy; glTF through EXT_texture_webp (required by the file); `textureQuality`
};

struct MeshWriteOptions {
  /// Binary PLY / STL (default); false writes ASCII.
  bool binary = true;
  /// glTF/GLB only: compress geometry with KHR_draco_mesh_compression (required extension).
  bool draco = false;
  /// Draco quantization bits for positions, UVs, normals and tangents, and compression level
  /// 0 (fast) .. 10 (small).
  int dracoPositionBits = 14;
  int dracoUvBits = 12;
  int dracoNormalBits = 10;
  int dracoLevel = 7;
  /// glTF/GLB: compute tangents when the mesh has UVs and a normal map but no tangents.
  bool computeMissingTangents = true;
  /// Texture images (glTF, GLB, OBJ): see TextureEncoding.
  TextureEncoding textures = TextureEncoding::Keep;
  int textureQuality = 90;  ///< JPEG and WebP quality, 1 (small) .. 100 (best)
  /// .gltf: buffers and images as data URIs inside the file; false (default) writes them beside
  /// it (<stem>.bin, <stem>_<n>.png, ...).
  bool embed = false;
  /// 3MF (whose coordinates are millimetres): the length of one model unit in mm; 0 = from
  /// heightMm. (0, 1e6] otherwise.
  double millimetresPerUnit = 0;
  /// 3MF, when millimetresPerUnit is 0: the model's extent along `up` in mm; 0 = one unit is 1 mm.
  double heightMm = 0;
  /// The model's up axis (non-zero). 3MF builds along +z: the model is turned so that `up` points
  /// there, and stands in a slicer as it does in texfab's previews.
  Eigen::Vector3f up{0, 0, 1};
};

/// The rotation that turns `up` to +z (the shortest; a half turn about x for -z).
Eigen::Matrix3d upToZ(const Eigen::Vector3f& up);

/// The length of one model unit in mm that a 3MF of `mesh` gets with `options` (see above). Throws
/// texfab::Error when heightMm is asked of a model with no extent along `up`.
double millimetresPerUnit(const Mesh& mesh, const MeshWriteOptions& options);

/// Writes `mesh`. What each format keeps:
///  - glTF/GLB: everything (per-corner attributes, PBR materials, textures); one primitive per
///    material; face tags are written as the primitive's `extras`. A mesh without materials gets
///    a plain dielectric one (metallic 0, roughness 0.5), not glTF's default metal.
///  - OBJ: positions, UVs and normals (each distinct value written once; normals computed when the
///    mesh has none), materials as MTL (Kd, d, Pr, Pm, map_Kd; the normal map as map_Bump, bump
///    and norm; map_Pr) with images next to the OBJ, named <stem>_<material>_<kind>.<ext>.
///  - PLY: positions, per-vertex normals (averaged), per-corner UVs as the face property
///    `texcoord` (MeshLab's convention), per-face material index as `material_index`.
///  - 3MF: positions and triangles; textured materials as texture2d (image times colour factor)
///    with per-corner UVs, plain materials as base materials (display colour). Normals, tangents,
///    other maps and PBR factors are not in 3MF's core or Materials extension.
///  - OFF, STL: positions and triangles only.
void writeMesh(const Mesh& mesh, const std::filesystem::path& path, const MeshWriteOptions& options = {});

/// One part of a scene: a mesh placed at `translation` (a glTF node with a mesh of its own).
struct SceneNode {
  std::string name;
  Mesh mesh;  ///< positions relative to the node
  Eigen::Vector3f translation{0.0f, 0.0f, 0.0f};
};

/// Writes meshes as one glTF 2.0 scene (.glb or .gltf): a named node and mesh per entry, in order,
/// with the MeshWriteOptions of writeMesh. Materials equal in every field (the same texture images
/// included) are written once and shared.
void writeScene(std::span<const SceneNode> nodes, const std::filesystem::path& path, const MeshWriteOptions& options = {});

} // namespace texfab::geometry
