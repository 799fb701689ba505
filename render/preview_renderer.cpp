// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/preview_renderer.h"

#include "core/error.h"
#include "core/hash.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "render/material_mips.h"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <set>
#include <span>
#include <tuple>

namespace texfab::render {

using Eigen::Vector2f;
using Eigen::Vector3f;
using Eigen::Vector4f;

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Counter-based random numbers in [0, 1): a pure function of (pixel, sample, dimension).
float hashUnit(uint32_t x, uint32_t y, uint32_t s, uint32_t d) {
  return float(counterHash(x, y, s, d) >> 8) * (1.0f / 16777216.0f);
}

// A lobe of a normal distribution in world space: its axis, sharpness κ, weight and mean cosine
// to its axis (the length of its normals' mean, 1 for a single normal).
struct WorldLobe {
  Vector3f axis;
  float sharpness, weight, length;
};

// The most lobes a footprint gathers: 4 texels of 2 levels, 8 lobes each.
constexpr int kMaxFootprintLobes = 2 * 4 * 8;

// Adds to `lobes` the normal distribution under a footprint of mip level `lod` > 0 around texture
// coordinates `uv` (wrapping; v up): the texels of the two levels around `lod`, weighted as
// trilinear filtering weighs them (Han et al. shade the 8 texels and interpolate; their lobes
// together are that distribution). Below level 1 the finer side is the bilinear mapped normal
// `mapped`, one sharp lobe. `frame` is (tangent, bitangent, normal).
void addLobes(std::array<WorldLobe, kMaxFootprintLobes>& lobes, int& count, const NdfMipChain& chain, const Vector2f& uv, float lod,
              float normalScale, const std::array<Vector3f, 3>& frame, const Vector3f& mapped) {
  const int top = int(chain.levels.size()) - 1;
  const int fine = std::min(int(std::floor(lod)), top), coarse = std::min(fine + 1, top);
  const float f = fine == coarse ? 0.0f : lod - std::floor(lod);
  const auto add = [&](int level, float weight) {
    if (!(weight > 0)) return;
    if (level == 0) {
      if (mapped.squaredNorm() > 1e-12f) lobes[size_t(count++)] = {mapped.normalized(), kMaxVmfSharpness, weight, 1.0f};
      return;
    }
    const NdfLevel& l = chain.levels[size_t(level)];
    const float fx = (uv.x() - std::floor(uv.x())) * float(l.width) - 0.5f;
    const float fy = (1 - (uv.y() - std::floor(uv.y()))) * float(l.height) - 0.5f;
    const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
    const float sx = fx - float(x0), sy = fy - float(y0);
    for (int k = 0; k < 4; ++k) {
      const int dx = k & 1, dy = k >> 1;
      const float w = weight * (dx ? sx : 1 - sx) * (dy ? sy : 1 - sy);
      if (!(w > 0)) continue;
      const int x = ((x0 + dx) % l.width + l.width) % l.width, y = ((y0 + dy) % l.height + l.height) % l.height;
      for (const VmfLobe& lobe : l.texel(x, y)) {
        if (!(lobe.weight > 0)) continue;
        const Vector3f a = lobe.axis();
        const Vector3f world = normalScale * a.x() * frame[0] + normalScale * a.y() * frame[1] + a.z() * frame[2];
        if (world.squaredNorm() > 1e-12f)
          lobes[size_t(count++)] = {world.normalized(), lobe.sharpness(), w * lobe.weight, std::min(lobe.mean.norm(), 1.0f)};
      }
    }
  };
  add(fine, 1 - f);
  add(coarse, f);
}

// An orthonormal basis around n.
void basis(const Vector3f& n, Vector3f& t, Vector3f& b) {
  t = std::abs(n.x()) < 0.9f ? Vector3f::UnitX().cross(n).normalized() : Vector3f::UnitY().cross(n).normalized();
  b = n.cross(t);
}

} // namespace

PreviewRenderer::PreviewRenderer(const geometry::Mesh& mesh) : mesh_(mesh), scene_(mesh) {
  if (mesh.hasNormals()) {
    normals_ = mesh.normals;
  } else {
    geometry::Mesh shape;
    shape.positions = mesh.positions;
    shape.triangles = mesh.triangles;
    geometry::computeSmoothNormals(shape);
    normals_ = std::move(shape.normals);
  }
  bool normalMapped = false;  // or anisotropic: either needs tangents
  for (const geometry::Material& m : mesh.materials) normalMapped |= m.normalTexture || m.anisotropy;
  if (mesh.hasTangents()) {
    tangents_ = mesh.tangents;
  } else if (normalMapped && mesh.hasUvs()) {
    geometry::Mesh shape;
    shape.positions = mesh.positions;
    shape.triangles = mesh.triangles;
    shape.uvs = mesh.uvs;
    shape.normals = normals_;
    geometry::computeTangents(shape);
    tangents_ = std::move(shape.tangents);
  }
  std::map<const Image*, MipPyramid> cache;
  auto pyramid = [&](const geometry::Texture& t, bool srgb) -> MipPyramid {
    if (!t || !mesh.hasUvs()) return {};
    auto it = cache.find(t.image.get());
    if (it == cache.end())
      it = cache.emplace(t.image.get(), t.mips ? mipPyramidOf(*t.mips, srgb) : buildMipPyramid(*t.image, srgb)).first;
    return it->second;
  };
  for (const geometry::Material& m : mesh.materials)
    maps_.push_back({pyramid(m.baseColorTexture, true), pyramid(m.metallicRoughnessTexture, false),
                     pyramid(m.normalTexture, false), m.anisotropy ? pyramid(m.anisotropy.texture, false) : MipPyramid{},
                     {}});
  if (mesh.hasUvs()) {
    uvDensity_.resize(mesh.triangleCount());
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
      const float world = (mesh.corner(t, 1) - mesh.corner(t, 0)).cross(mesh.corner(t, 2) - mesh.corner(t, 0)).norm();
      const Vector2f a = mesh.uvs[3 * t + 1] - mesh.uvs[3 * t], b = mesh.uvs[3 * t + 2] - mesh.uvs[3 * t];
      const float uv = std::abs(a.x() * b.y() - a.y() * b.x());
      uvDensity_[t] = world > 0 ? std::sqrt(uv / world) : 0.0f;
    }
  }
}

PreviewRenderer::~PreviewRenderer() = default;

namespace {

// Whether filtering a material's normal map can show: not on a rough dielectric (metallic 0,
// roughness >= 0.7 everywhere), whose highlight is too broad and too weak (4 % reflectance) for
// the spread of its normals to change it visibly.
bool highlightNeedsFiltering(const geometry::Material& m, const MipPyramid& metallicRoughness) {
  float metallic = m.metallicFactor, roughness = m.roughnessFactor;
  if (!metallicRoughness.empty()) {
    const Image& level = metallicRoughness.levels[0];
    float minRoughness = 1, maxMetallic = 0;
    for (int y = 0; y < level.height; ++y)
      for (int x = 0; x < level.width; ++x)
        minRoughness = std::min(minRoughness, level.at(x, y, 1)), maxMetallic = std::max(maxMetallic, level.at(x, y, 2));
    metallic *= maxMetallic, roughness *= minRoughness;
  }
  return metallic > 0 || roughness < 0.7f;
}

} // namespace

void PreviewRenderer::filterNormalMaps(const RenderOptions& o, const Context& ctx) const {
  std::call_once(filtered_, [&] {
    std::map<const Image*, std::shared_ptr<const NdfMipChain>> distributions;
    for (size_t i = 0; i < maps_.size(); ++i) {
      const geometry::Texture& t = mesh_.materials[i].normalTexture;
      if (maps_[i].normal.empty() || t.image->channels < 3) continue;
      if (!highlightNeedsFiltering(mesh_.materials[i], maps_[i].metallicRoughness)) continue;
      auto it = distributions.find(t.image.get());
      if (it == distributions.end())
        it = distributions.emplace(t.image.get(), std::make_shared<const NdfMipChain>(filterNormalMap(*t.image, {}, o.normalMapCache, ctx))).first;
      maps_[i].normalDistribution = it->second;
    }
  });
}

Vector3f frontFor(const Vector3f& up) {
  const Vector3f u = up.normalized();
  if (std::abs(u.z()) > 0.9f) return Vector3f(0, u.z() > 0 ? -1.0f : 1.0f, 0);
  return (Vector3f::UnitZ() - u.z() * u).normalized();
}

namespace {

// Where the camera looks (a point on the view's axis) and how far from it it stands so that
// every vertex the triangles use projects inside the view shrunk by `margin`, centred (tanX, tanY:
// tangents of the half fields of view); never closer than the bounding sphere of radius `radius`
// around `center`.
struct Framing {
  Vector3f target;
  float distance = 0;
};

Framing frameVertices(const geometry::Mesh& mesh, const Vector3f& center, const Vector3f& forward, const Vector3f& right,
                      const Vector3f& up, float tanX, float tanY, float margin, float radius) {
  std::vector<char> used(mesh.positions.size(), 0);
  for (const auto& t : mesh.triangles)
    for (uint32_t v : t) used[v] = 1;
  Framing f{center, 0};
  // The distance that fits the vertices about the target, then the target moved to the centre of
  // their projection (perspective makes it asymmetric), twice.
  for (int pass = 0; pass < 3; ++pass) {
    float distance = 0;
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      if (!used[v]) continue;
      const Vector3f p = mesh.positions[v] - f.target;
      const float depth = p.dot(forward);
      distance = std::max({distance, margin * std::abs(p.dot(right)) / tanX - depth,
                           margin * std::abs(p.dot(up)) / tanY - depth});
    }
    f.distance = std::max(distance, 1.05f * radius + (f.target - center).norm());
    if (pass == 2) break;
    float x0 = std::numeric_limits<float>::max(), x1 = -x0, y0 = x0, y1 = -x0;
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      if (!used[v]) continue;
      const Vector3f p = mesh.positions[v] - f.target;
      const float depth = f.distance + p.dot(forward);
      x0 = std::min(x0, p.dot(right) / depth), x1 = std::max(x1, p.dot(right) / depth);
      y0 = std::min(y0, p.dot(up) / depth), y1 = std::max(y1, p.dot(up) / depth);
    }
    if (x1 < x0) break;  // no vertices
    f.target += f.distance * (0.5f * (x0 + x1) * right + 0.5f * (y0 + y1) * up);
  }
  return f;
}

} // namespace

struct PreviewRenderer::View {
  const RenderOptions& o;
  Vector3f eye, forward, right, up, modelUp, light;
  float tanHalf = 0, aspect = 0, distance = 0, radius = 0;
  int strata = 1, spp = 1;
  float pixelSpread = 0; ///< radians per pixel at the centre
  float lodBias = 0;     ///< each sample covers 1/spp of the pixel
  float eps = 0;         ///< shadow and AO ray offset
  uint32_t aoStride = 1; ///< coprime with the AO rays per pixel, to decorrelate the two AO strata
  Vector3f background;   ///< linear

  View(const RenderOptions& options, const geometry::Mesh& mesh, const geometry::BoundingBox& box) : o(options) {
    const Vector3f center = box.center();
    radius = std::max(0.5f * box.diagonal(), 1e-6f);
    const float az = o.azimuthDegrees * kPi / 180, el = o.elevationDegrees * kPi / 180;
    modelUp = o.up.normalized();
    const Vector3f front = frontFor(modelUp), side = modelUp.cross(front);
    const Vector3f toCamera = std::cos(el) * (std::sin(az) * side + std::cos(az) * front) + std::sin(el) * modelUp;
    tanHalf = std::tan(0.5f * o.fovYDegrees * kPi / 180);
    aspect = float(o.width) / float(o.height);
    forward = -toCamera;
    right = forward.cross(modelUp).normalized();
    up = right.cross(forward);
    const Framing framing = frameVertices(mesh, center, forward, right, up, tanHalf * aspect, tanHalf, o.margin, radius);
    distance = framing.distance;
    eye = framing.target + distance * toCamera;
    // Key light from the camera's upper left, a little behind it; sky light from the model's up.
    light = (toCamera + 0.9f * up - 0.6f * right).normalized();
    strata = std::max(1, int(std::sqrt(float(o.samplesPerPixel))));
    spp = strata * strata;
    pixelSpread = 2.0f * tanHalf / float(o.height);
    lodBias = -0.5f * std::log2(float(spp));
    eps = 1e-4f * radius;
    const uint32_t aoCount = uint32_t(std::max(1, spp * std::max(o.aoSamples, 0)));
    aoStride = uint32_t(std::max(1.0, std::round(0.618 * aoCount)));
    while (std::gcd(aoStride, aoCount) != 1) ++aoStride;
    background = Vector3f(srgbToLinear(o.background.x()), srgbToLinear(o.background.y()), srgbToLinear(o.background.z()));
  }
};

struct PreviewRenderer::Surface {
  Vector3f p, ng, n; ///< position, geometric and shading normals (facing the viewer)
  const geometry::Material* material = nullptr;
  Vector4f base;     ///< base colour (linear) and alpha, textures applied
  float metallic = 0, roughness = 0;
  /// KHR_materials_anisotropy: the lobe widens along `tangent` (unit, across n) to
  /// α_t = mix(α, 1, anisotropy²); 0: isotropic.
  float anisotropy = 0;
  Vector3f tangent = Vector3f::Zero();
  /// Where a normal map is minified: the normal distribution under the sample's footprint, as
  /// lobes in world space (those of the two nearest NDF levels, weighted), for the highlight.
  std::array<WorldLobe, kMaxFootprintLobes> lobes;
  int lobeCount = 0;
};

namespace {

const geometry::Material& fallbackMaterial() {
  static const geometry::Material m = [] {
    geometry::Material f;
    f.baseColorFactor = Vector4f(0.8f, 0.8f, 0.8f, 1.0f);
    f.metallicFactor = 0.0f;
    f.roughnessFactor = 0.6f;
    return f;
  }();
  return m;
}

const Vector3f kKeyColor(2.6f, 2.5f, 2.35f), kSkyColor(0.55f, 0.6f, 0.7f), kGroundColor(0.25f, 0.22f, 0.2f);

// The environment's radiance toward direction d: the sky above, the ground below, blended linearly
// in d's height. Linear in d, so over any distribution of directions its mean is its value at
// their mean vector.
Vector3f environment(const Vector3f& d, const Vector3f& up) {
  const float k = 0.5f * (d.dot(up) + 1);
  return k * kSkyColor + (1 - k) * kGroundColor;
}

} // namespace

double renderMemoryBytes(const geometry::Mesh& mesh, const RenderOptions& options) {
  constexpr double kPyramid = 4.0 / 3.0;                   // a MIP chain over its base level
  constexpr double kPerTriangle = 4 + 3 * (12 + 16) + 96;  // uv density, corner normals and tangents, BVH
  double bytes = double(options.width) * options.height * 4 * sizeof(float) +
                 kPerTriangle * double(mesh.triangleCount());
  std::set<const Image*> seen;
  for (const geometry::Material& m : mesh.materials)
    for (const geometry::Texture* t : m.textures()) {
      if (!*t || !seen.insert(t->image.get()).second) continue;
      const double texels = double(t->image->width) * t->image->height;
      bytes += kPyramid * texels * 4 * sizeof(float);
      // Fitted lobes: one per texel at level 0, then 8.
      if (t == &m.normalTexture && options.normalMapFiltering == NormalMapFiltering::Lobes)
        bytes += texels * sizeof(VmfLobe) * (1 + FilterNormalMapOptions{}.lobes * (kPyramid - 1));
    }
  return bytes;
}

Image PreviewRenderer::render(const RenderOptions& o, const Context& ctx) const {
  if (o.width < 1 || o.height < 1 || o.width > kMaxImageSide || o.height > kMaxImageSide)
    throw Error("render: image size out of range");
  if (o.samplesPerPixel < 1 || o.samplesPerPixel > 4096) throw Error("render: samples per pixel must be 1..4096");
  if (!(o.elevationDegrees > -90 && o.elevationDegrees < 90)) throw Error("render: elevation must be in (-90, 90) degrees");
  if (!(o.fovYDegrees > 1 && o.fovYDegrees < 170)) throw Error("render: field of view must be in (1, 170) degrees");
  if (!(o.up.allFinite() && o.up.norm() > 0)) throw Error("render: the up direction must be a non-zero vector");
  if (!(o.margin > 0.01f && o.margin < 100)) throw Error("render: margin must be in (0.01, 100)");
  if (o.normalMapFiltering == NormalMapFiltering::Lobes) filterNormalMaps(o, ctx);
  const View view(o, mesh_, scene_.bounds());
  Image out(o.width, o.height, o.transparentBackground ? 4 : 3, PixelFormat::UInt8);
  parallelFor(0, o.height, ctx, [&](int y0, int y1) {
    for (int py = y0; py < y1; ++py)
      for (int px = 0; px < o.width; ++px) {
        Vector3f sum = Vector3f::Zero();
        float coverage = 0;
        for (int s = 0; s < view.spp; ++s) addSample(view, px, py, s, sum, coverage);
        // The surface's mean radiance, its highlights rolled off (Reinhard-style): after the pixel's
        // samples are averaged, so that the pixel is the tone of the light it receives, as filtered
        // shading (a normal map's lobes) computes it.
        Vector3f c = coverage > 0 ? Vector3f(sum / coverage) : Vector3f::Zero();
        c = c.cwiseQuotient(Vector3f::Ones() + 0.15f * c);
        const float a = coverage / float(view.spp);
        float* dst = out.pixel(px, py);
        // Transparent: colour un-premultiplied by coverage, so edges do not darken when composited.
        if (!o.transparentBackground) c = a * c + (1 - a) * view.background;
        for (int k = 0; k < 3; ++k) dst[k] = linearToSrgb(c[k]);
        if (o.transparentBackground) dst[3] = a;
        // Quantize now, so the image holds exactly the 8-bit values written.
        for (int k = 0; k < out.channels; ++k) dst[k] = std::round(std::clamp(dst[k], 0.0f, 1.0f) * 255.0f) / 255.0f;
      }
  });
  return out;
}

// Sample s of pixel (px, py): a stratified, jittered camera ray (one sample: through the pixel's
// centre, where a filtered texture lookup is meant), shaded where it hits. Adds the surface's
// radiance times its opacity to `sum`, and its opacity to `coverage`.
void PreviewRenderer::addSample(const View& view, int px, int py, int s, Vector3f& sum, float& coverage) const {
  const RenderOptions& o = view.o;
  const auto jitter = [&](int stratum, uint32_t dimension) {
    return view.spp == 1 ? 0.5f : (float(stratum) + hashUnit(uint32_t(px), uint32_t(py), uint32_t(s), dimension)) / float(view.strata);
  };
  const float jx = jitter(s % view.strata, 0), jy = jitter(s / view.strata, 1);
  const float sx = (2.0f * (float(px) + jx) / float(o.width) - 1.0f) * view.tanHalf * view.aspect;
  const float sy = (1.0f - 2.0f * (float(py) + jy) / float(o.height)) * view.tanHalf;
  const Vector3f dir = (view.forward + sx * view.right + sy * view.up).normalized();
  const geometry::RayHit hit = scene_.intersect({view.eye, dir, 0.0f, std::numeric_limits<float>::infinity()});
  if (!hit.hit) return;
  const Surface surface = surfaceAt(view, hit, dir);
  const float opacity = surface.material->blend ? std::clamp(surface.base.w(), 0.0f, 1.0f) : 1.0f;
  sum += opacity * lightSurface(view, surface, dir, px, py, s);
  coverage += opacity;
}

namespace {

// KHR_materials_anisotropy at a point of tangent frame (tangent, bitangent, shading normal n), given
// its texture's texel (when it has one): the direction in which the lobe widens (the texel's RG, a
// tangent-space direction, turned by the rotation, taken across n) and the strength (its B times
// the material's). Strength 0: isotropic.
std::pair<Vector3f, float> anisotropyAt(const geometry::Material::Anisotropy& a, const std::optional<Vector4f>& texel,
                                        const std::array<Vector3f, 3>& frame) {
  const Vector2f d = texel ? Vector2f(2 * texel->x() - 1, 2 * texel->y() - 1) : Vector2f(1, 0);
  const float strength = std::min(a.strength * (texel ? texel->z() : 1.0f), 1.0f);
  const float c = std::cos(a.rotation), s = std::sin(a.rotation);
  Vector3f along = (c * d.x() - s * d.y()) * frame[0] + (s * d.x() + c * d.y()) * frame[1];
  along -= frame[2] * frame[2].dot(along);
  if (along.squaredNorm() < 1e-12f || !(strength > 0)) return {Vector3f::Zero(), 0.0f};
  return {along.normalized(), strength};
}

} // namespace

// The hit's normals (double-sided: facing the viewer) and material, with its textures sampled at
// the mip level of the sample's footprint (a pinhole camera's ray differential, widened by the
// grazing angle) and the normal map applied.
PreviewRenderer::Surface PreviewRenderer::surfaceAt(const View& view, const geometry::RayHit& hit,
                                                    const Vector3f& dir) const {
  Surface f;
  const size_t t = hit.triangle;
  const float u = hit.barycentric.x(), v = hit.barycentric.y(), w = 1 - u - v;
  f.p = view.eye + hit.distance * dir;
  f.ng = hit.geometricNormal.normalized();
  Vector3f n = w * normals_[3 * t] + u * normals_[3 * t + 1] + v * normals_[3 * t + 2];
  n = n.squaredNorm() > 0 ? Vector3f(n.normalized()) : f.ng;
  if (f.ng.dot(dir) > 0) {
    f.ng = -f.ng;
    if (n.dot(f.ng) < 0) n = -n;
  }
  const uint32_t mi = mesh_.materialOf(t);
  const geometry::Material& material = mi < mesh_.materials.size() ? mesh_.materials[mi] : fallbackMaterial();
  f.material = &material;
  f.base = material.baseColorFactor;
  f.metallic = material.metallicFactor, f.roughness = material.roughnessFactor;
  if (mesh_.hasUvs() && mi < maps_.size()) {
    const MaterialMaps& maps = maps_[mi];
    const Vector2f uv = w * mesh_.uvs[3 * t] + u * mesh_.uvs[3 * t + 1] + v * mesh_.uvs[3 * t + 2];
    const float cosTheta = std::max(std::abs(f.ng.dot(dir)), 0.05f);
    const float footprint = hit.distance * view.pixelSpread / std::sqrt(cosTheta);
    auto lodOf = [&](const Image& level0, const geometry::Texture& texture) {
      const float texels = footprint * uvDensity_[t] * std::sqrt(float(level0.width) * float(level0.height)) *
                           std::sqrt(std::abs(texture.scale.x() * texture.scale.y()));
      return std::log2(std::max(texels, 1e-8f)) + view.lodBias;
    };
    auto lookup = [&](const MipPyramid& pyramid, const geometry::Texture& texture) -> Vector4f {
      const Vector2f tuv = texture.apply(uv);
      return sampleTrilinear(pyramid, tuv.x(), tuv.y(), lodOf(pyramid.levels[0], texture));
    };
    if (!maps.baseColor.empty()) f.base = f.base.cwiseProduct(lookup(maps.baseColor, material.baseColorTexture));
    if (!maps.metallicRoughness.empty()) {
      const Vector4f mr = lookup(maps.metallicRoughness, material.metallicRoughnessTexture);
      f.roughness *= mr.y();
      f.metallic *= mr.z();
    }
    if ((!maps.normal.empty() || material.anisotropy) && !tangents_.empty()) {
      const Vector4f tc = w * tangents_[3 * t] + u * tangents_[3 * t + 1] + v * tangents_[3 * t + 2];
      Vector3f tangent = tc.head<3>() - n * n.dot(tc.head<3>());
      if (tangent.squaredNorm() > 1e-12f) {
        tangent.normalize();
        const Vector3f bitangent = (tangents_[3 * t].w() < 0 ? -1.0f : 1.0f) * n.cross(tangent);
        if (!maps.normal.empty()) {
          const Vector4f m = lookup(maps.normal, material.normalTexture);
          const Vector3f local(material.normalScale * (2 * m.x() - 1), material.normalScale * (2 * m.y() - 1), 2 * m.z() - 1);
          const Vector3f mapped = local.x() * tangent + local.y() * bitangent + local.z() * n;
          const float lod = lodOf(maps.normal.levels[0], material.normalTexture);
          const NormalMapFiltering filtering = view.o.normalMapFiltering;
          if (lod > 0 && filtering == NormalMapFiltering::Lobes && maps.normalDistribution) {
            addLobes(f.lobes, f.lobeCount, *maps.normalDistribution, material.normalTexture.apply(uv), lod,
                     material.normalScale, {tangent, bitangent, n}, mapped);
          } else if (lod > 0 && filtering == NormalMapFiltering::Toksvig && mapped.squaredNorm() > 1e-12f) {
            // The mean normal's length |m| = κ / (κ + 1) for Toksvig's exponent |m|s / (|m| + s(1 - |m|)).
            const float length = std::min(Vector3f(2 * m.x() - 1, 2 * m.y() - 1, 2 * m.z() - 1).norm(), 1.0f);
            const float sharpness = std::min(length / std::max(1 - length, 1e-6f), kMaxVmfSharpness);
            f.lobes[0] = {mapped.normalized(), sharpness, 1.0f, length};
            f.lobeCount = 1;
          }
          if (mapped.squaredNorm() > 1e-12f) n = mapped.normalized();
        }
        if (material.anisotropy) {
          const auto texel = maps.anisotropy.empty() ? std::nullopt
                                                      : std::optional(lookup(maps.anisotropy, material.anisotropy.texture));
          std::tie(f.tangent, f.anisotropy) = anisotropyAt(material.anisotropy, texel, {tangent, bitangent, n});
        }
      }
    }
  }
  f.n = n;
  return f;
}

// A key light (Lambert + normalized Blinn-Phong, shadowed), a sky light with ambient occlusion
// (cosine-weighted hemisphere rays, stratified over the pixel's AO rays) and its glossy reflection.
Vector3f PreviewRenderer::lightSurface(const View& view, const Surface& f, const Vector3f& dir, int px, int py,
                                       int s) const {
  const RenderOptions& o = view.o;
  const Vector3f& n = f.n;
  const Vector3f albedo = f.base.head<3>().cwiseMax(0.0f);
  const float roughness = std::clamp(f.roughness, 0.05f, 1.0f);
  const float alpha = roughness * roughness, shininess = std::max(2.0f / (alpha * alpha) - 2.0f, 1.0f);  // Blinn-Phong
  const float alphaT = alpha + (1 - alpha) * f.anisotropy * f.anisotropy;  // along f.tangent
  const float metallic = std::clamp(f.metallic, 0.0f, 1.0f);
  const Vector3f diffuse = (1 - metallic) * albedo;
  const Vector3f f0 = Vector3f::Constant(0.04f) * (1 - metallic) + metallic * albedo;
  const Vector3f offset = f.p + view.eps * f.ng;
  // The mean cosine of the surface's normals with a direction: the normal's, or over the footprint's
  // normal distribution each lobe's mean normal's (exact for the fill and the sky, which are linear
  // in the normal, and for the key light where a lobe lies on its lit side).
  const std::span<const WorldLobe> lobes(f.lobes.data(), size_t(f.lobeCount));
  const auto cosine = [&](const Vector3f& d) {
    if (lobes.empty()) return std::max(0.0f, n.dot(d));
    float sum = 0;
    for (const WorldLobe& l : lobes) sum += l.weight * l.length * std::max(0.0f, l.axis.dot(d));
    return sum;
  };
  Vector3f color = Vector3f::Zero();
  const float nl = cosine(view.light);
  if (nl > 0 && f.ng.dot(view.light) > -0.2f) {
    const bool lit = !o.shadows || !scene_.occluded({offset, view.light, 0.0f, 4.0f * view.radius + view.distance});
    if (lit) {
      const Vector3f h = (view.light - dir).normalized();
      // The highlight of one normal at its own cosine, its specular lobe convolved with a vMF lobe
      // of sharpness κ (infinite: none; s' = κs / (κ + s), Han et al. 2007, Eq. 7.20, or in α,
      // widenedAlpha2): at the normal, or over the footprint's normal distribution, lobe by lobe.
      // With anisotropy, along t (f.tangent taken across the normal) α_t, across it α: Ashikhmin and
      // Shirley's exponents for Blinn-Phong, KHR_materials_anisotropy's GGX and visibility.
      const auto highlight = [&](const Vector3f& normal, float sharpness) -> Vector3f {
        const float cl = normal.dot(view.light);
        if (cl <= 0) return Vector3f::Zero();
        const float nh = std::max(normal.dot(h), 0.0f);
        Vector3f t = f.tangent - normal * normal.dot(f.tangent);
        const bool anisotropic = alphaT > alpha && t.squaredNorm() > 1e-12f;
        if (anisotropic) t.normalize();
        const Vector3f b = normal.cross(t);
        if (o.specular == SpecularModel::BlinnPhong) {
          const auto widened = [&](float a) {
            const float s0 = std::max(2.0f / (a * a) - 2.0f, 1.0f);
            return std::isinf(sharpness) ? s0 : convolvedExponent(sharpness, s0);
          };
          const float s = widened(alpha);
          if (!anisotropic) return f0 * ((s + 8) / (8 * kPi) * std::pow(nh, s) * cl);
          const float st = widened(alphaT), ht = h.dot(t), hb = h.dot(b);
          const float exponent = (st * ht * ht + s * hb * hb) / std::max(1 - nh * nh, 1e-12f);
          return f0 * (std::sqrt((st + 8) * (s + 8)) / (8 * kPi) * std::pow(nh, exponent) * cl);
        }
        const float a2 = float(widenedAlpha2(double(alpha) * alpha, 1.0 / double(sharpness)));
        const float nv = std::max(-normal.dot(dir), 1e-4f), vh = std::max(-h.dot(dir), 0.0f);
        const Vector3f fresnel = f0 + (Vector3f::Ones() - f0) * std::pow(1 - vh, 5.0f);
        if (!anisotropic) {
          const float d = nh * nh * (a2 - 1) + 1;
          const float visibility = 0.5f / (cl * std::sqrt(nv * nv * (1 - a2) + a2) + nv * std::sqrt(cl * cl * (1 - a2) + a2));
          return fresnel * (a2 / (kPi * d * d) * visibility * cl);
        }
        const float ab = std::sqrt(a2), at = std::sqrt(float(widenedAlpha2(double(alphaT) * alphaT, 1.0 / double(sharpness))));
        const float ht = h.dot(t) / at, hb = h.dot(b) / ab, d = ht * ht + hb * hb + nh * nh;
        const float vt = -dir.dot(t), vb = -dir.dot(b), lt = view.light.dot(t), lb = view.light.dot(b);
        const float visibility = 0.5f / (cl * std::sqrt(at * at * vt * vt + ab * ab * vb * vb + nv * nv) +
                                         nv * std::sqrt(at * at * lt * lt + ab * ab * lb * lb + cl * cl));
        return fresnel * (1 / (kPi * at * ab * d * d) * visibility * cl);
      };
      Vector3f specular = Vector3f::Zero();
      if (lobes.empty()) specular = highlight(n, std::numeric_limits<float>::infinity());
      for (const WorldLobe& l : lobes) specular += l.weight * highlight(l.axis, l.sharpness);
      color += kKeyColor.cwiseProduct(0.32f * diffuse * nl + 0.32f * specular);
    }
  }
  // A weak fill light from the camera, never shadowed: faces in deep gaps (the cut faces of
  // exploded pieces, the inside of a crack) keep their colour where the key and the sky do not reach.
  color += 0.1f * diffuse * cosine(-dir);
  Vector3f ambient = Vector3f::Zero();
  float open = 1;  // the share of the AO rays that find the hemisphere open
  if (o.aoSamples > 0) {
    Vector3f ta, tb;
    basis(n, ta, tb);
    int closed = 0;
    for (int a = 0; a < o.aoSamples; ++a) {
      // Two shuffled 1-D strata (a rotation and a coprime stride are permutations), jittered
      // within the stratum.
      const uint32_t index = uint32_t(s * o.aoSamples + a), count = uint32_t(view.spp * o.aoSamples);
      const uint32_t shift1 = uint32_t(hashUnit(uint32_t(px), uint32_t(py), 0, 4) * float(count));
      const uint32_t shift2 = uint32_t(hashUnit(uint32_t(px), uint32_t(py), 0, 5) * float(count));
      const float r1 = (float((index + shift1) % count) + hashUnit(uint32_t(px), uint32_t(py), index, 2)) / float(count);
      const float r2 =
          (float((index * view.aoStride + shift2) % count) + hashUnit(uint32_t(px), uint32_t(py), index, 3)) / float(count);
      const float rr = std::sqrt(r1), phi = 2 * kPi * r2;
      Vector3f d = rr * std::cos(phi) * ta + rr * std::sin(phi) * tb + std::sqrt(std::max(0.0f, 1 - r1)) * n;
      if (d.dot(f.ng) <= 0) d -= 2 * d.dot(f.ng) * f.ng;
      if (!scene_.occluded({offset, d, 0.0f, 0.6f * view.radius})) ambient += environment(d, view.modelUp);
      else closed += 1;
    }
    ambient /= float(o.aoSamples);
    open = 1 - float(closed) / float(o.aoSamples);
  } else {
    Vector3f mean = lobes.empty() ? n : Vector3f::Zero();  // the mean normal
    for (const WorldLobe& l : lobes) mean += l.weight * l.length * l.axis;
    ambient = environment(mean, view.modelUp);
  }
  // The environment's reflection (Han et al. 2007, §7.6.3, for a linear environment): its value at
  // the mean reflected direction, over the footprint's normal distribution where there is one,
  // shortened by the glossy lobe's spread (Blinn-Phong's s about the half vector is about Phong's
  // s/4 about the mirror direction, whose mean cosine is (s/4 + 1) / (s/4 + 2)), dimmed as the AO
  // rays find the hemisphere closed.
  Vector3f reflected = lobes.empty() ? Vector3f(dir - 2 * dir.dot(n) * n) : Vector3f::Zero();
  for (const WorldLobe& l : lobes) reflected += l.weight * meanReflection(dir, l.axis, l.sharpness, l.length);
  // An anisotropic lobe shortens it as the isotropic lobe of its mean α² would.
  const float meanShininess =
      alphaT > alpha ? std::max(4.0f / (alpha * alpha + alphaT * alphaT) - 2.0f, 1.0f) : shininess;
  reflected *= (meanShininess + 4) / (meanShininess + 8);
  color += ambient.cwiseProduct(diffuse) + open * environment(reflected, view.modelUp).cwiseProduct(f0);
  return color;
}

} // namespace texfab::render
