// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/repair/remesh_volume.h"

#include "core/error.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <mutex>

namespace texfab::geometry {

Mesh remeshVolume(const Mesh& mesh, const RemeshVolumeOptions& o, const Context& ctx) {
  if (o.resolution < 16 || o.resolution > 4096) throw Error("the remeshing resolution must be 16 to 4096 voxels");
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });
  const BoundingBox box = boundingBox(mesh);
  const double voxel = double((box.max - box.min).maxCoeff()) / o.resolution;
  if (!(voxel > 0)) throw Error("the model has no extent to remesh");

  std::vector<openvdb::Vec3s> points;
  points.reserve(mesh.positions.size());
  for (const Eigen::Vector3f& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);

  std::vector<openvdb::Vec3s> outPoints;
  std::vector<openvdb::Vec4I> quads;
  tbb::task_arena arena(ctx.threads > 0 ? ctx.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    const openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(voxel);
    const openvdb::FloatGrid::Ptr distance = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles);
    openvdb::tools::volumeToMesh(*distance, outPoints, quads, 0.0);
  });
  if (quads.empty()) throw Error("the model encloses no volume (is it open?)");

  Mesh out;
  out.positions.reserve(outPoints.size());
  for (const openvdb::Vec3s& p : outPoints) out.positions.emplace_back(p.x(), p.y(), p.z());
  out.triangles.reserve(2 * quads.size());
  for (const openvdb::Vec4I& q : quads) {
    // OpenVDB's quads face inward; split along the shorter diagonal.
    const auto at = [&](int k) { return out.positions[q[k]]; };
    if ((at(0) - at(2)).squaredNorm() <= (at(1) - at(3)).squaredNorm()) {
      out.triangles.push_back({q[0], q[2], q[1]});
      out.triangles.push_back({q[0], q[3], q[2]});
    } else {
      out.triangles.push_back({q[1], q[3], q[2]});
      out.triangles.push_back({q[1], q[0], q[3]});
    }
  }
  return out;
}

} // namespace texfab::geometry
