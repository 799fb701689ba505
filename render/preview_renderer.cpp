// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/preview_renderer.h"

#include "render/image/error.h"
#include "render/image/image_io.h"
#include "render/image/parallel.h"

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <numbers>
#include <numeric>

namespace texfab::render {

using Eigen::Vector2f;
using Eigen::Vector3f;
using Eigen::Vector4f;

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Counter-based random numbers: a pure function of (pixel, sample, dimension).
float hashUnit(uint32_t x, uint32_t y, uint32_t s, uint32_t d) {
  uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ s * 0xcb1ab31fu ^ d * 0x165667b1u;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return float(h >> 8) * (1.0f / 16777216.0f);
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
  bool normalMapped = false;
  for (const geometry::Material& m : mesh.materials) normalMapped |= bool(m.normalTexture);
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
    if (it == cache.end()) it = cache.emplace(t.image.get(), buildMipPyramid(*t.image, srgb)).first;
    return it->second;
  };
  for (const geometry::Material& m : mesh.materials)
    maps_.push_back({pyramid(m.baseColorTexture, true), pyramid(m.metallicRoughnessTexture, false), pyramid(m.normalTexture, false)});
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

Image PreviewRenderer::render(const RenderOptions& o, const Context& ctx) const {
  if (o.width < 1 || o.height < 1 || o.width > kMaxImageSide || o.height > kMaxImageSide)
    throw Error("render: image size out of range");
  if (o.samplesPerPixel < 1 || o.samplesPerPixel > 4096) throw Error("render: samples per pixel must be 1..4096");
  if (!(o.elevationDegrees > -90 && o.elevationDegrees < 90)) throw Error("render: elevation must be in (-90, 90) degrees");
  if (!(o.fovYDegrees > 1 && o.fovYDegrees < 170)) throw Error("render: field of view must be in (1, 170) degrees");
  const geometry::BoundingBox& box = scene_.bounds();
  const Vector3f center = box.center();
  const float radius = std::max(0.5f * box.diagonal(), 1e-6f);
  const float az = o.azimuthDegrees * kPi / 180, el = o.elevationDegrees * kPi / 180;
  const Vector3f toCamera(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  const float tanHalf = std::tan(0.5f * o.fovYDegrees * kPi / 180);
  const float aspect = float(o.width) / float(o.height);
  // Fit the bounding sphere in the narrower field of view.
  const float fitTan = std::min(tanHalf, tanHalf * aspect);
  const float distance = o.margin * radius / std::sin(std::atan(fitTan));
  const Vector3f eye = center + distance * toCamera;
  const Vector3f forward = -toCamera;
  const Vector3f right = forward.cross(Vector3f::UnitY()).normalized();
  const Vector3f up = right.cross(forward);
  // Key light from the camera's upper left, a little behind it; sky light from +Y.
  const Vector3f light = (toCamera + 0.9f * up - 0.6f * right).normalized();
  const Vector3f keyColor(2.6f, 2.5f, 2.35f), skyColor(0.55f, 0.6f, 0.7f), groundColor(0.25f, 0.22f, 0.2f);
  const int strata = std::max(1, int(std::sqrt(float(o.samplesPerPixel))));
  const int spp = strata * strata;
  const float pixelSpread = 2.0f * tanHalf / float(o.height);  // radians per pixel at the centre
  const float lodBias = -0.5f * std::log2(float(spp));           // each sample covers 1/spp of the pixel
  const float eps = 1e-4f * radius;
  // A stride coprime with the number of AO rays per pixel, to decorrelate the two AO strata.
  const uint32_t aoCount = uint32_t(std::max(1, spp * std::max(o.aoSamples, 0)));
  uint32_t aoStride = uint32_t(std::max(1.0, std::round(0.618 * aoCount)));
  while (std::gcd(aoStride, aoCount) != 1) ++aoStride;
  const Vector3f bg(srgbToLinear(o.background.x()), srgbToLinear(o.background.y()), srgbToLinear(o.background.z()));

  Image out(o.width, o.height, o.transparentBackground ? 4 : 3, PixelFormat::UInt8);
  parallelFor(0, o.height, ctx, [&](int y0, int y1) {
    for (int py = y0; py < y1; ++py)
      for (int px = 0; px < o.width; ++px) {
        Vector3f sum = Vector3f::Zero();
        float coverage = 0;
        for (int s = 0; s < spp; ++s) {
          const float jx = (float(s % strata) + hashUnit(uint32_t(px), uint32_t(py), uint32_t(s), 0)) / float(strata);
          const float jy = (float(s / strata) + hashUnit(uint32_t(px), uint32_t(py), uint32_t(s), 1)) / float(strata);
          const float sx = (2.0f * (float(px) + jx) / float(o.width) - 1.0f) * tanHalf * aspect;
          const float sy = (1.0f - 2.0f * (float(py) + jy) / float(o.height)) * tanHalf;
          const Vector3f dir = (forward + sx * right + sy * up).normalized();
          const geometry::RayHit hit = scene_.intersect({eye, dir, 0.0f, std::numeric_limits<float>::infinity()});
          if (!hit.hit) {
            if (!o.transparentBackground) sum += bg;
            continue;
          }
          coverage += 1;
          const size_t t = hit.triangle;
          const float u = hit.barycentric.x(), v = hit.barycentric.y(), w = 1 - u - v;
          const Vector3f p = eye + hit.distance * dir;
          Vector3f ng = hit.geometricNormal.normalized();
          Vector3f n = w * normals_[3 * t] + u * normals_[3 * t + 1] + v * normals_[3 * t + 2];
          n = n.squaredNorm() > 0 ? Vector3f(n.normalized()) : ng;
          // Preview is double-sided: face the viewer.
          if (ng.dot(dir) > 0) {
            ng = -ng;
            if (n.dot(ng) < 0) n = -n;
          }
          const uint32_t mi = mesh_.materialOf(t);
          const geometry::Material fallback = [] {
            geometry::Material m;
            m.baseColorFactor = Vector4f(0.8f, 0.8f, 0.8f, 1.0f);
            m.metallicFactor = 0.0f;
            m.roughnessFactor = 0.6f;
            return m;
          }();
          const geometry::Material& material = mi < mesh_.materials.size() ? mesh_.materials[mi] : fallback;
          Vector4f base = material.baseColorFactor;
          float metallic = material.metallicFactor, roughness = material.roughnessFactor;
          if (mesh_.hasUvs() && mi < maps_.size()) {
            const MaterialMaps& maps = maps_[mi];
            const Vector2f uv = w * mesh_.uvs[3 * t] + u * mesh_.uvs[3 * t + 1] + v * mesh_.uvs[3 * t + 2];
            // Footprint of this sample on the surface (ray differential of a pinhole camera),
            // widened by the grazing angle, converted to texels.
            const float cosTheta = std::max(std::abs(ng.dot(dir)), 0.05f);
            const float footprint = hit.distance * pixelSpread / std::sqrt(cosTheta);
            auto lookup = [&](const MipPyramid& pyramid, const geometry::Texture& texture) -> Vector4f {
              const Image& level0 = pyramid.levels[0];
              const float texels = footprint * uvDensity_[t] * std::sqrt(float(level0.width) * float(level0.height)) *
                                   std::sqrt(std::abs(texture.scale.x() * texture.scale.y()));
              const float lod = std::log2(std::max(texels, 1e-8f)) + lodBias;
              const Vector2f tuv = texture.apply(uv);
              return sampleTrilinear(pyramid, tuv.x(), tuv.y(), lod);
            };
            if (!maps.baseColor.empty()) base = base.cwiseProduct(lookup(maps.baseColor, material.baseColorTexture));
            if (!maps.metallicRoughness.empty()) {
              const Vector4f mr = lookup(maps.metallicRoughness, material.metallicRoughnessTexture);
              roughness *= mr.y();
              metallic *= mr.z();
            }
            if (!maps.normal.empty() && !tangents_.empty()) {
              const Vector4f tc = w * tangents_[3 * t] + u * tangents_[3 * t + 1] + v * tangents_[3 * t + 2];
              Vector3f tangent = tc.head<3>() - n * n.dot(tc.head<3>());
              if (tangent.squaredNorm() > 1e-12f) {
                tangent.normalize();
                const Vector3f bitangent = (tangents_[3 * t].w() < 0 ? -1.0f : 1.0f) * n.cross(tangent);
                const Vector4f m = lookup(maps.normal, material.normalTexture);
                const Vector3f local(material.normalScale * (2 * m.x() - 1), material.normalScale * (2 * m.y() - 1), 2 * m.z() - 1);
                const Vector3f mapped = local.x() * tangent + local.y() * bitangent + local.z() * n;
                if (mapped.squaredNorm() > 1e-12f) n = mapped.normalized();
              }
            }
          }
          const Vector3f albedo = base.head<3>().cwiseMax(0.0f);
          roughness = std::clamp(roughness, 0.05f, 1.0f);
          metallic = std::clamp(metallic, 0.0f, 1.0f);
          const Vector3f diffuse = (1 - metallic) * albedo;
          const Vector3f f0 = Vector3f::Constant(0.04f) * (1 - metallic) + metallic * albedo;
          const Vector3f offset = p + eps * ng;
          Vector3f color = Vector3f::Zero();
          // Key light: Lambert + normalized Blinn-Phong, shadowed.
          const float nl = n.dot(light);
          if (nl > 0 && ng.dot(light) > -0.2f) {
            const bool lit = !o.shadows || !scene_.occluded({offset, light, 0.0f, 4.0f * radius + distance});
            if (lit) {
              const Vector3f h = (light - dir).normalized();
              const float alpha = roughness * roughness;
              const float shininess = std::max(2.0f / (alpha * alpha) - 2.0f, 1.0f);
              const float spec = (shininess + 8) / (8 * kPi) * std::pow(std::max(n.dot(h), 0.0f), shininess);
              color += keyColor.cwiseProduct(0.32f * diffuse + 0.32f * spec * f0) * nl;
            }
          }
          // Sky light with ambient occlusion (cosine-weighted hemisphere rays).
          Vector3f ambient = Vector3f::Zero();
          if (o.aoSamples > 0) {
            Vector3f ta, tb;
            basis(n, ta, tb);
            for (int a = 0; a < o.aoSamples; ++a) {
              // Stratified over the pixel's AO rays: two shuffled 1-D strata (a rotation and a
              // coprime stride are permutations), jittered within the stratum.
              const uint32_t index = uint32_t(s * o.aoSamples + a), count = uint32_t(spp * o.aoSamples);
              const uint32_t shift1 = uint32_t(hashUnit(uint32_t(px), uint32_t(py), 0, 4) * float(count));
              const uint32_t shift2 = uint32_t(hashUnit(uint32_t(px), uint32_t(py), 0, 5) * float(count));
              const float r1 = (float((index + shift1) % count) + hashUnit(uint32_t(px), uint32_t(py), index, 2)) / float(count);
              const float r2 =
                  (float((index * aoStride + shift2) % count) + hashUnit(uint32_t(px), uint32_t(py), index, 3)) / float(count);
              const float rr = std::sqrt(r1), phi = 2 * kPi * r2;
              Vector3f d = rr * std::cos(phi) * ta + rr * std::sin(phi) * tb + std::sqrt(std::max(0.0f, 1 - r1)) * n;
              if (d.dot(ng) <= 0) d -= 2 * d.dot(ng) * ng;
              if (!scene_.occluded({offset, d, 0.0f, 0.6f * radius})) {
                const float k = 0.5f * (d.y() + 1);
                ambient += k * skyColor + (1 - k) * groundColor;
              }
            }
            ambient /= float(o.aoSamples);
          } else {
            const float k = 0.5f * (n.y() + 1);
            ambient = k * skyColor + (1 - k) * groundColor;
          }
          color += ambient.cwiseProduct(diffuse + 0.25f * f0);
          // Soft highlight roll-off (Reinhard-style), on the shaded surface only.
          color = color.cwiseQuotient(Vector3f::Ones() + 0.15f * color);
          // Blend partially transparent materials with the background.
          const float opacity = material.blend ? std::clamp(base.w(), 0.0f, 1.0f) : 1.0f;
          if (opacity < 1 && !o.transparentBackground) color = opacity * color + (1 - opacity) * bg;
          else if (opacity < 1) coverage -= 1 - opacity, color *= opacity;
          sum += color;
        }
        float* dst = out.pixel(px, py);
        if (o.transparentBackground) {
          const float a = coverage / float(spp);
          // Colour un-premultiplied by coverage, so edges do not darken when composited.
          const Vector3f c = coverage > 0 ? Vector3f(sum / coverage) : Vector3f::Zero();
          for (int k = 0; k < 3; ++k) dst[k] = linearToSrgb(c[k]);
          dst[3] = a;
        } else {
          const Vector3f c = sum / float(spp);
          for (int k = 0; k < 3; ++k) dst[k] = linearToSrgb(c[k]);
        }
        // Quantize now, so the image holds exactly the 8-bit values written.
        for (int k = 0; k < out.channels; ++k) dst[k] = std::round(std::clamp(dst[k], 0.0f, 1.0f) * 255.0f) / 255.0f;
      }
  });
  return out;
}

} // namespace texfab::render
