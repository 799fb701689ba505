// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/embree_scene.h"

#include "core/error.h"
#include "core/parallel.h"
#include "geometry/mesh_connectivity.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <string>

namespace texfab::geometry {

namespace {

// The first Embree error of a device, recorded by its error callback.
struct DeviceErrors {
  std::mutex mutex;
  std::string first;
};

void errorCallback(void* user, RTCError code, const char* message) {
  auto* errors = static_cast<DeviceErrors*>(user);
  std::lock_guard lock(errors->mutex);
  if (errors->first.empty()) errors->first = "Embree error " + std::to_string(int(code)) + ": " + (message ? message : "");
}

// Inside test: counts distinct triangles crossed along a ray (filter rejects every hit so that
// traversal goes on to the far end).
struct CountingContext {
  RTCIntersectContext context;
  uint32_t hits[64];
  uint32_t count = 0;
  bool overflow = false;
};

void countingFilter(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<CountingContext*>(args->context);
  const uint32_t prim = RTCHitN_primID(args->hit, args->N, 0);
  args->valid[0] = 0;  // reject: keep traversing
  for (uint32_t i = 0; i < ctx->count; ++i)
    if (ctx->hits[i] == prim) return;  // the same triangle seen twice (spatial splits)
  if (ctx->count < 64) ctx->hits[ctx->count++] = prim;
  else ctx->overflow = true;
}

struct PointQueryData {
  const std::vector<Eigen::Vector3f>* positions;
  const std::vector<std::array<uint32_t, 3>>* triangles;
  SurfacePoint* best;
};

bool pointQueryCallback(RTCPointQueryFunctionArguments* args) {
  auto* data = static_cast<PointQueryData*>(args->userPtr);
  const auto& tri = (*data->triangles)[args->primID];
  const Eigen::Vector3f p(args->query->x, args->query->y, args->query->z);
  Eigen::Vector2f uv;
  const Eigen::Vector3f q = closestPointOnTriangle(p, (*data->positions)[tri[0]], (*data->positions)[tri[1]],
                                                   (*data->positions)[tri[2]], uv);
  const float d = (q - p).norm();
  // The nearest triangle, ties to the smaller index: Embree's traversal order follows its BVH,
  // which follows the instruction set it picked at run time (the CPU), and a point nearest to a
  // shared vertex or edge is as near to every triangle around it. The radius stays just above the
  // best distance so that every triangle at that distance is still visited.
  const SurfacePoint& best = *data->best;
  const bool nearer = best.found ? d < best.distance || (d == best.distance && args->primID < best.triangle)
                                 : d < args->query->radius;
  if (!nearer) return false;
  *data->best = {q, args->primID, uv, d, true};
  args->query->radius = std::nextafter(d, std::numeric_limits<float>::infinity());
  return true;  // the query radius shrank
}

RTCRayHit toEmbree(const Ray& ray) {
  RTCRayHit rh{};
  rh.ray.org_x = ray.origin.x();
  rh.ray.org_y = ray.origin.y();
  rh.ray.org_z = ray.origin.z();
  rh.ray.dir_x = ray.direction.x();
  rh.ray.dir_y = ray.direction.y();
  rh.ray.dir_z = ray.direction.z();
  rh.ray.tnear = ray.tnear;
  rh.ray.tfar = ray.tfar;
  rh.ray.mask = 0xFFFFFFFF;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

} // namespace

struct EmbreeScene::Impl {
  SceneOptions options;
  std::unique_ptr<DeviceErrors> errors = std::make_unique<DeviceErrors>();
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
  BoundingBox box;
  bool watertight = false;
  std::vector<Eigen::Vector3f> insideDirections;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const char* what) {
    std::lock_guard lock(errors->mutex);
    if (!errors->first.empty()) throw Error(std::string(what) + ": " + errors->first);
  }
};

EmbreeScene::EmbreeScene(const Mesh& mesh, const SceneOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  if (options.insideRays < 1 || options.insideRays % 2 == 0)
    throw Error("SceneOptions::insideRays must be odd and positive, got " + std::to_string(options.insideRays));
  validateMesh(mesh, "Embree scene");
  s.options = options;
  s.positions = mesh.positions;
  s.triangles = mesh.triangles;
  s.box = boundingBox(mesh);
  s.watertight = computeConnectivity(mesh).watertight;
  s.device = rtcNewDevice(nullptr);
  if (!s.device) throw Error("cannot create an Embree device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  rtcSetDeviceErrorFunction(s.device, &errorCallback, s.errors.get());
  s.scene = rtcNewScene(s.device);
  rtcSetSceneBuildQuality(s.scene, options.highQuality ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM);
  rtcSetSceneFlags(s.scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
  RTCGeometry geometry = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), s.positions.size()));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(uint32_t), s.triangles.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geometry);
    s.check("Embree scene");
    throw Error("Embree scene: cannot allocate geometry buffers");
  }
  for (size_t i = 0; i < s.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) vertices[3 * i + size_t(k)] = s.positions[i][k];
  for (size_t t = 0; t < s.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) indices[3 * t + size_t(k)] = s.triangles[t][size_t(k)];
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(s.scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(s.scene);
  s.check("Embree scene build");
  // Inside-test directions: a fixed spiral of unit vectors, none axis-aligned (axis-aligned rays
  // hit the edges of axis-aligned models far more often than chance).
  for (int i = 0; i < options.insideRays; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / options.insideRays * 0.98;
    const double phi = 2.399963229728653 * i + 0.3;  // golden angle
    const double r = std::sqrt(1.0 - z * z);
    s.insideDirections.emplace_back(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
  }
}

EmbreeScene::~EmbreeScene() = default;
EmbreeScene::EmbreeScene(EmbreeScene&&) noexcept = default;
EmbreeScene& EmbreeScene::operator=(EmbreeScene&&) noexcept = default;

RayHit EmbreeScene::intersect(const Ray& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = toEmbree(ray);
  rtcIntersect1(impl_->scene, &context, &rh);
  RayHit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.hit = true;
  hit.triangle = rh.hit.primID;
  hit.barycentric = Eigen::Vector2f(rh.hit.u, rh.hit.v);
  hit.distance = rh.ray.tfar;
  hit.geometricNormal = Eigen::Vector3f(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  return hit;
}

bool EmbreeScene::occluded(const Ray& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r = toEmbree(ray).ray;
  rtcOccluded1(impl_->scene, &context, &r);
  return r.tfar < 0;  // Embree sets tfar = -inf on a hit
}

std::vector<RayHit> EmbreeScene::intersect(std::span<const Ray> rays, const Context& ctx) const {
  std::vector<RayHit> hits(rays.size());
  parallelFor(0, int(rays.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) hits[size_t(i)] = intersect(rays[size_t(i)]);
  }, 256);
  return hits;
}

bool EmbreeScene::watertight() const { return impl_->watertight; }

bool EmbreeScene::inside(const Eigen::Vector3f& point) const {
  if (!impl_->watertight)
    throw Error("inside/outside test on an open mesh (it has boundary edges): the mesh has no inside");
  int votes = 0;
  for (const Eigen::Vector3f& d : impl_->insideDirections) {
    CountingContext ctx;
    rtcInitIntersectContext(&ctx.context);
    ctx.context.filter = &countingFilter;
    RTCRayHit rh = toEmbree(Ray{point, d, 0.0f, std::numeric_limits<float>::infinity()});
    rtcIntersect1(impl_->scene, &ctx.context, &rh);
    votes += (ctx.count % 2 == 1) ? 1 : 0;
  }
  return 2 * votes > int(impl_->insideDirections.size());
}

std::vector<uint8_t> EmbreeScene::inside(std::span<const Eigen::Vector3f> points, const Context& ctx) const {
  if (!impl_->watertight)
    throw Error("inside/outside test on an open mesh (it has boundary edges): the mesh has no inside");
  std::vector<uint8_t> out(points.size());
  parallelFor(0, int(points.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) out[size_t(i)] = inside(points[size_t(i)]) ? 1 : 0;
  }, 256);
  return out;
}

SurfacePoint EmbreeScene::closestPoint(const Eigen::Vector3f& point, float maxDistance) const {
  SurfacePoint best;
  PointQueryData data{&impl_->positions, &impl_->triangles, &best};
  RTCPointQuery query;
  query.x = point.x();
  query.y = point.y();
  query.z = point.z();
  query.radius = maxDistance;
  query.time = 0.0f;
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(impl_->scene, &query, &context, &pointQueryCallback, &data);
  return best;
}

std::vector<SurfacePoint> EmbreeScene::closestPoints(std::span<const Eigen::Vector3f> points, const Context& ctx) const {
  std::vector<SurfacePoint> out(points.size());
  parallelFor(0, int(points.size()), ctx, [&](int b, int e) {
    for (int i = b; i < e; ++i) out[size_t(i)] = closestPoint(points[size_t(i)]);
  }, 256);
  return out;
}

const BoundingBox& EmbreeScene::bounds() const { return impl_->box; }
size_t EmbreeScene::triangleCount() const { return impl_->triangles.size(); }

Eigen::Vector3f closestPointOnTriangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                                       const Eigen::Vector3f& c, Eigen::Vector2f& uv) {
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return uv = {0, 0}, a;
  const Eigen::Vector3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return uv = {1, 0}, b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const float v = d1 / (d1 - d3);
    return uv = {v, 0}, Eigen::Vector3f(a + v * ab);
  }
  const Eigen::Vector3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return uv = {0, 1}, c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const float w = d2 / (d2 - d6);
    return uv = {0, w}, Eigen::Vector3f(a + w * ac);
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return uv = {1 - w, w}, Eigen::Vector3f(b + w * (c - b));
  }
  const float denom = 1.0f / (va + vb + vc);
  const float v = vb * denom, w = vc * denom;
  if (!std::isfinite(v) || !std::isfinite(w)) return uv = {0, 0}, a;  // degenerate triangle
  return uv = {v, w}, Eigen::Vector3f(a + ab * v + ac * w);
}

} // namespace texfab::geometry
