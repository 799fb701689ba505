// SPDX-License-Identifier: GPL-3.0-or-later
// Draco compression of glTF primitives (KHR_draco_mesh_compression).
#include "core/error.h"
#include "geometry/io/mesh_formats.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <cmath>

namespace texfab::geometry::detail {

namespace {

template <int N, class Vec>
int addAttribute(draco::Mesh& mesh, draco::GeometryAttribute::Type type, const std::vector<Vec>& values) {
  if (values.empty()) return -1;
  draco::GeometryAttribute ga;
  ga.Init(type, nullptr, N, draco::DT_FLOAT32, false, sizeof(float) * N, 0);
  const int id = mesh.AddAttribute(ga, true, uint32_t(values.size()));
  draco::PointAttribute* attribute = mesh.attribute(id);
  for (size_t i = 0; i < values.size(); ++i) attribute->SetAttributeValue(draco::AttributeValueIndex(uint32_t(i)), values[i].data());
  return int(attribute->unique_id());
}

template <int N>
bool readAttribute(const draco::Mesh& mesh, int uniqueId, std::vector<Eigen::Matrix<float, N, 1>>& out) {
  if (uniqueId < 0) return true;
  const draco::PointAttribute* attribute = mesh.GetAttributeByUniqueId(uint32_t(uniqueId));
  if (!attribute || attribute->num_components() != N) return false;
  out.resize(mesh.num_points());
  for (uint32_t p = 0; p < mesh.num_points(); ++p)
    if (!attribute->ConvertValue<float, N>(attribute->mapped_index(draco::PointIndex(p)), out[p].data())) return false;
  return true;
}

} // namespace

std::vector<uint8_t> encodeDraco(const VertexArrays& v, const MeshWriteOptions& options, DracoAttributeIds& ids) {
  draco::Mesh mesh;
  mesh.set_num_points(uint32_t(v.positions.size()));
  mesh.SetNumFaces(v.indices.size() / 3);
  for (size_t f = 0; f < v.indices.size() / 3; ++f)
    mesh.SetFace(draco::FaceIndex(uint32_t(f)), {draco::PointIndex(v.indices[3 * f]), draco::PointIndex(v.indices[3 * f + 1]),
                                                draco::PointIndex(v.indices[3 * f + 2])});
  ids.position = addAttribute<3>(mesh, draco::GeometryAttribute::POSITION, v.positions);
  ids.uv = addAttribute<2>(mesh, draco::GeometryAttribute::TEX_COORD, v.uvs);
  ids.normal = addAttribute<3>(mesh, draco::GeometryAttribute::NORMAL, v.normals);
  ids.tangent = addAttribute<4>(mesh, draco::GeometryAttribute::GENERIC, v.tangents);
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.dracoPositionBits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, options.dracoUvBits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, options.dracoNormalBits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::GENERIC, options.dracoNormalBits + 2);
  const int speed = 10 - std::clamp(options.dracoLevel, 0, 10);
  encoder.SetSpeedOptions(speed, speed);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &buffer);
  if (!status.ok()) throw Error(std::string("Draco encoding failed: ") + status.error_msg());
  return std::vector<uint8_t>(buffer.data(), buffer.data() + buffer.size());
}

VertexArrays decodeDraco(const uint8_t* data, size_t size, const DracoAttributeIds& ids, const std::string& name) {
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data), size);
  draco::Decoder decoder;
  auto result = decoder.DecodeMeshFromBuffer(&buffer);
  if (!result.ok()) throw Error(name + ": Draco decoding failed: " + result.status().error_msg_string());
  const std::unique_ptr<draco::Mesh> mesh = std::move(result).value();
  VertexArrays v;
  if (ids.position < 0) throw Error(name + ": Draco primitive has no POSITION attribute");
  if (!readAttribute<3>(*mesh, ids.position, v.positions) || !readAttribute<2>(*mesh, ids.uv, v.uvs) ||
      !readAttribute<3>(*mesh, ids.normal, v.normals) || !readAttribute<4>(*mesh, ids.tangent, v.tangents))
    throw Error(name + ": Draco data lacks an attribute the glTF extension names, or has the wrong size");
  v.indices.reserve(size_t(mesh->num_faces()) * 3);
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = mesh->face(f)[k].value();
      if (p >= mesh->num_points()) throw Error(name + ": Draco face index out of range");
      v.indices.push_back(p);
    }
  for (auto& n : v.normals)
    if (n.squaredNorm() > 0) n.normalize();
  for (auto& t : v.tangents) {
    Eigen::Vector3f xyz = t.head<3>();
    if (xyz.squaredNorm() > 0) xyz.normalize();
    t = Eigen::Vector4f(xyz.x(), xyz.y(), xyz.z(), t.w() < 0 ? -1.0f : 1.0f);
  }
  return v;
}

} // namespace texfab::geometry::detail
