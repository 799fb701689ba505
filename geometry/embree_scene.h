// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Ray casts, inside/outside tests and closest-point queries over a mesh, on an Embree BVH.
// Embree types stay in embree_scene.cpp; the scene owns its device (RAII) and reports Embree
// errors as texfab::Error. All queries are const and thread-safe; the batch versions spread the
// work over ctx.threads (0 = all cores) and return results in input order.

#include "core/context.h"
#include "geometry/mesh.h"

#include <Eigen/Core>

#include <limits>
#include <memory>
#include <span>
#include <vector>

namespace texfab::geometry {

struct Ray {
  Eigen::Vector3f origin{0, 0, 0};
  Eigen::Vector3f direction{0, 0, 1}; ///< need not be unit; distances are in units of |direction|
  float tnear = 0.0f;
  float tfar = std::numeric_limits<float>::infinity();
};

struct RayHit {
  bool hit = false;
  uint32_t triangle = 0;
  /// Weights of corners 1 and 2: point = (1-u-v) * c0 + u * c1 + v * c2.
  Eigen::Vector2f barycentric{0, 0};
  float distance = std::numeric_limits<float>::infinity(); ///< ray parameter t
  Eigen::Vector3f geometricNormal{0, 0, 0};               ///< unnormalized, (c1-c0) x (c2-c0)
};

struct SurfacePoint {
  Eigen::Vector3f point{0, 0, 0};
  uint32_t triangle = 0;
  Eigen::Vector2f barycentric{0, 0}; ///< as in RayHit
  float distance = std::numeric_limits<float>::infinity();
  bool found = false; ///< false when nothing lies within the query radius
};

struct SceneOptions {
  /// Rays cast per inside test; the majority of their parity votes decides. Odd, >= 1. Several
  /// rays make the answer robust to a ray grazing an edge or vertex.
  int insideRays = 5;
  /// BVH build quality: false = Embree's medium (fast build), true = high (faster rays).
  bool highQuality = false;
};

class EmbreeScene {
public:
  /// Builds the BVH over `mesh`'s triangles (positions are copied). Throws texfab::Error if
  /// Embree fails or the mesh is invalid.
  explicit EmbreeScene(const Mesh& mesh, const SceneOptions& options = {});
  ~EmbreeScene();
  EmbreeScene(EmbreeScene&&) noexcept;
  EmbreeScene& operator=(EmbreeScene&&) noexcept;
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  RayHit intersect(const Ray& ray) const;
  /// True when anything lies on the ray within [tnear, tfar] (shadow rays).
  bool occluded(const Ray& ray) const;
  std::vector<RayHit> intersect(std::span<const Ray> rays, const Context& ctx = {}) const;

  /// Whether inside/outside is defined: every edge has an even number of triangles.
  bool watertight() const;
  /// Ray-parity inside test with SceneOptions::insideRays rays (majority vote). Throws
  /// texfab::Error when the mesh is not watertight: an open mesh has no inside, and the test
  /// reports that rather than guess.
  bool inside(const Eigen::Vector3f& point) const;
  std::vector<uint8_t> inside(std::span<const Eigen::Vector3f> points, const Context& ctx = {}) const;

  /// Closest point of the surface to `point` within `maxDistance` (rtcPointQuery).
  SurfacePoint closestPoint(const Eigen::Vector3f& point,
                            float maxDistance = std::numeric_limits<float>::infinity()) const;
  std::vector<SurfacePoint> closestPoints(std::span<const Eigen::Vector3f> points, const Context& ctx = {}) const;

  const BoundingBox& bounds() const;
  size_t triangleCount() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Closest point on triangle (a, b, c) to p, with barycentrics (u, v) of b and c [Ericson 2005,
/// "Real-Time Collision Detection", §5.1.5].
Eigen::Vector3f closestPointOnTriangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                                       const Eigen::Vector3f& c, Eigen::Vector2f& uv);

} // namespace texfab::geometry
