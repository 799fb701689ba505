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

#include "geometry/mesh.h"

#include <filesystem>
#include <string>

namespace texfab::geometry {

enum class MeshFormat { Obj, Ply, Off, Stl, Gltf, Glb, ThreeMf };

/// The format of `path` from its extension; throws texfab::Error for an unknown one.
MeshFormat meshFormatOf(const std::filesystem::path& path);

/// Human-readable names: "OBJ", "PLY", ...
const char* meshFormatName(MeshFormat format);

/// Reads a mesh. Texture images of OBJ and glTF materials are decoded.
Mesh readMesh(const std::filesystem::path& path);

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
};

/// Writes `mesh`. What each format keeps:
///  - glTF/GLB: everything (per-corner attributes, PBR materials, textures embedded as PNG);
///    one primitive per material; face tags are written as the primitive's `extras`.
///  - OBJ: positions, per-corner UVs and normals, materials as MTL (Kd, d, Pr, Pm, map_Kd,
///    norm, map_Pr via PNGs written next to the OBJ, named <stem>_<material>_<kind>.png).
///  - PLY: positions, per-vertex normals (averaged), per-corner UVs as the face property
///    `texcoord` (MeshLab's convention), per-face material index as `material_index`.
///  - 3MF: positions and triangles; textured materials as texture2d (image times colour factor)
///    with per-corner UVs, plain materials as base materials (display colour). Normals, tangents,
///    other maps and PBR factors are not in 3MF's core or Materials extension.
///  - OFF, STL: positions and triangles only.
void writeMesh(const Mesh& mesh, const std::filesystem::path& path, const MeshWriteOptions& options = {});

} // namespace texfab::geometry
