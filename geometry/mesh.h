// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// texfab's one mesh type: an indexed triangle mesh in plain structure-of-arrays form.
//
// Positions are shared by the triangles that use them (index-based, so connectivity is explicit).
// UVs, normals and tangents are stored per *corner* (3 per triangle, corner c = 3*t + k), so a UV
// seam or a crease is just two corners of one vertex that disagree; each attribute array is either
// empty (absent) or holds exactly 3 * triangleCount() entries. Materials follow glTF 2.0's PBR
// metallic-roughness model. Halfedge structures (OpenMesh, CGAL) are built from this type inside
// the algorithms that need them and converted back at their boundary.

#include "core/image.h"
#include "core/image_io.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace texfab::geometry {

/// A texture of a material: the decoded image (shared, since several materials or meshes may use
/// one picture) plus the UV transform of glTF's KHR_texture_transform, applied as
/// uv' = offset + R(rotation) * (scale ∘ uv) in glTF's v-down UV space (apply() converts).
struct Texture {
  std::shared_ptr<const Image> image; ///< null when the material has no such texture
  std::string name;                   ///< a file name hint for writers ("marble.png"); may be empty
  Eigen::Vector2f offset{0.0f, 0.0f};
  Eigen::Vector2f scale{1.0f, 1.0f};
  float rotation = 0.0f; ///< radians, counter-clockwise in UV space as glTF defines it
  /// The PNG, JPEG or WebP file `image` was decoded from, when it was read from one: writers keep
  /// these bytes instead of re-encoding (MeshWriteOptions::textures). Describes `image`: code that
  /// replaces `image` resets it.
  std::shared_ptr<const EncodedImage> encoded;
  /// A MIP chain of the texture's own, for viewers that can take one: levels[0] has `image`'s
  /// size and each next level halves each side (rounding down, at least 1) down to 1x1. The glTF
  /// writers add it as a KTX2 image (KHR_texture_basisu, UASTC) beside `image`, which stays the
  /// fallback; null: viewers make their own MIPs. Describes `image`: code that replaces `image`
  /// resets it.
  std::shared_ptr<const std::vector<Image>> mips;
  /// The KTX2 file such a chain was read from (a glTF's KHR_texture_basisu image): writers carry
  /// these bytes along when `mips` is null. Describes `image`: code that replaces `image` resets it.
  std::shared_ptr<const std::vector<uint8_t>> encodedMips;

  explicit operator bool() const { return image != nullptr; }
  bool hasTransform() const { return offset != Eigen::Vector2f(0, 0) || scale != Eigen::Vector2f(1, 1) || rotation != 0; }
  /// The transformed UV (both in the mesh's v-up convention).
  Eigen::Vector2f apply(const Eigen::Vector2f& uv) const;
};

/// glTF 2.0 PBR metallic-roughness material. Factors multiply the textures (or stand alone).
/// Base colour textures hold sRGB-encoded colour; the others hold linear data.
struct Material {
  std::string name;
  Eigen::Vector4f baseColorFactor{1.0f, 1.0f, 1.0f, 1.0f}; ///< linear RGBA
  float metallicFactor = 1.0f;  ///< glTF's default; OBJ/PLY imports set 0
  float roughnessFactor = 1.0f;
  float normalScale = 1.0f;
  bool doubleSided = false;
  /// Alpha blending (glTF alphaMode BLEND; OBJ d < 1). When false the material is opaque and the
  /// alpha of the factor and texture is ignored, as glTF's default OPAQUE mode says.
  bool blend = false;
  Texture baseColorTexture;
  Texture metallicRoughnessTexture; ///< G = roughness, B = metallic (glTF)
  Texture normalTexture;            ///< tangent-space normal map (+Y up, OpenGL convention)
  /// KHR_materials_anisotropy: along a direction of the tangent plane the specular lobe widens
  /// from α = roughness² to α_t = mix(α, 1, strength²); across it α stays.
  struct Anisotropy {
    float strength = 0.0f;  ///< multiplies the texture's B; 0: isotropic
    float rotation = 0.0f;  ///< radians, counter-clockwise from the tangent, applied to the direction
    Texture texture;        ///< RG: the direction in tangent space, [-1, 1] stored as [0, 1]; B: strength
    explicit operator bool() const { return strength > 0; }
  } anisotropy;

  /// Every texture slot (some may be empty): base colour, metallic-roughness, normal, anisotropy.
  std::array<Texture*, 4> textures() { return {&baseColorTexture, &metallicRoughnessTexture, &normalTexture, &anisotropy.texture}; }
  std::array<const Texture*, 4> textures() const {
    return {&baseColorTexture, &metallicRoughnessTexture, &normalTexture, &anisotropy.texture};
  }
};

struct Mesh {
  std::vector<Eigen::Vector3f> positions;       ///< #V
  std::vector<std::array<uint32_t, 3>> triangles; ///< #T, counter-clockwise seen from outside
  std::vector<Eigen::Vector2f> uvs;             ///< 3 * #T or empty; v up (OpenGL), as in OBJ
  std::vector<Eigen::Vector3f> normals;         ///< 3 * #T or empty; unit length
  std::vector<Eigen::Vector4f> tangents;        ///< 3 * #T or empty; xyz unit, w = ±1 handedness
  std::vector<Material> materials;              ///< may be empty (a default material is implied)
  std::vector<uint32_t> faceMaterials;          ///< #T or empty (all 0); indexes `materials`
  std::vector<uint32_t> faceTags;               ///< #T or empty (all 0); e.g. 1 = cut face

  size_t vertexCount() const { return positions.size(); }
  size_t triangleCount() const { return triangles.size(); }
  bool hasUvs() const { return !uvs.empty(); }
  bool hasNormals() const { return !normals.empty(); }
  bool hasTangents() const { return !tangents.empty(); }
  uint32_t materialOf(size_t t) const { return faceMaterials.empty() ? 0 : faceMaterials[t]; }
  uint32_t tagOf(size_t t) const { return faceTags.empty() ? 0 : faceTags[t]; }
  Eigen::Vector3f corner(size_t t, int k) const { return positions[triangles[t][size_t(k)]]; }
};

/// Axis-aligned bounding box of the positions used by triangles (empty box when none).
struct BoundingBox {
  Eigen::Vector3f min{0, 0, 0};
  Eigen::Vector3f max{0, 0, 0};
  Eigen::Vector3f center() const { return 0.5f * (min + max); }
  float diagonal() const { return (max - min).norm(); }
};
BoundingBox boundingBox(const Mesh& mesh);

/// Sum of the triangles' areas, in double precision.
double surfaceArea(const Mesh& mesh);

/// Throws texfab::Error (message prefixed by `name`) unless the mesh is well formed: at least one
/// triangle, finite coordinates, indices in range, attribute arrays of the right sizes, material
/// ids in range (an empty material list allows id 0 only).
void validateMesh(const Mesh& mesh, const std::string& name);

/// Unit geometric normal of triangle t (zero for a degenerate triangle).
Eigen::Vector3f faceNormal(const Mesh& mesh, size_t t);

/// Centroid of triangle t, in double precision.
inline Eigen::Vector3d triangleCentroid(const Mesh& mesh, size_t t) {
  return (mesh.corner(t, 0).cast<double>() + mesh.corner(t, 1).cast<double>() + mesh.corner(t, 2).cast<double>()) / 3.0;
}

/// Fills `mesh.normals`: each corner gets the area-weighted average of the normals of the
/// triangles around its vertex that meet its own triangle at less than `creaseDegrees` (so a cube
/// keeps sharp edges and a sphere is smooth). 180 = smooth everywhere.
void computeSmoothNormals(Mesh& mesh, float creaseDegrees = 60.0f);

/// Fills `mesh.tangents` from UVs and normals (per-corner, accumulated per (vertex, uv, normal)
/// corner group, Gram-Schmidt orthogonalized against the normal; w gives the bitangent's side so
/// that B = w * cross(N, T)) [Lengyel 2001, "Computing Tangent Space Basis Vectors"].
/// Requires UVs and normals; no-op without UVs.
void computeTangents(Mesh& mesh);

/// Merges vertices whose positions are exactly equal (per-corner attributes are kept, so seams
/// stay seams). Formats with per-vertex attributes (glTF) split vertices along UV seams; welding
/// restores the connectivity the surface has.
void weldPositions(Mesh& mesh);

/// Reverses the winding of triangle t: corners 1 and 2 swap, with their UVs, normals and tangents;
/// a normal that then points against its triangle is negated.
void flipTriangle(Mesh& mesh, size_t t);

/// Removes vertices no triangle uses; the rest are renumbered in order of first use.
void removeUnusedVertices(Mesh& mesh);

} // namespace texfab::geometry
