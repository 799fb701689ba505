// SPDX-License-Identifier: GPL-3.0-or-later
// texfab info: what a model contains (size, topology, UVs, materials, textures); with --devices,
// the Vulkan devices the synthesis kernels can run on.
#include "apps/texfab/cli.h"
#include "apps/texfab/command.h"
#include "geometry/io/mesh_io.h"
#include "geometry/mesh_connectivity.h"
#include "synthesis/backend.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace texfab::cli {

namespace {

struct InfoArgs {
  std::string model;
  bool devices = false;
  bool json = false;
};

void printDevices(bool json) {
  const std::vector<synthesis::vulkan::DeviceInfo> devices = synthesis::vulkanDevices();
  if (json) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& d : devices)
      j.push_back({{"index", d.index}, {"name", d.name}, {"type", d.type}, {"driver", d.driver},
                   {"vulkan", d.apiVersion}, {"memory_bytes", d.memoryBytes}, {"max_binding_bytes", d.maxRangeBytes},
                   {"usable", d.unusable.empty()}, {"unusable_because", d.unusable}});
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (devices.empty()) {
    std::printf("no Vulkan device found (%s)\n", synthesis::vulkanBuilt()
                                                     ? "no Vulkan loader or driver; the CPU backend runs everything"
                                                     : "this texfab was built without the Vulkan backend");
    return;
  }
  for (const auto& d : devices) {
    std::printf("[%d] %s\n", d.index, d.name.c_str());
    std::printf("    type      %s\n    driver    %s\n    Vulkan    %s\n    memory    %.1f GiB (binding range %.0f MiB)\n",
                d.type.c_str(), d.driver.c_str(), d.apiVersion.c_str(), double(d.memoryBytes) / double(1 << 30),
                double(d.maxRangeBytes) / double(1 << 20));
    if (!d.unusable.empty()) std::printf("    unusable  %s\n", d.unusable.c_str());
  }
}

nlohmann::json describeTexture(const geometry::Texture& t) {
  if (!t) return nullptr;
  nlohmann::json j = {{"width", t.image->width}, {"height", t.image->height}, {"channels", t.image->channels}};
  if (!t.name.empty()) j["name"] = t.name;
  if (t.encodedMips) j["mip_chain"] = {{"format", "ktx2"}, {"bytes", t.encodedMips->size()}};
  if (t.hasTransform())
    j["transform"] = {{"offset", {t.offset.x(), t.offset.y()}}, {"scale", {t.scale.x(), t.scale.y()}}, {"rotation", t.rotation}};
  return j;
}

void runInfo(const InfoArgs& args) {
  using namespace geometry;
  if (args.devices) return printDevices(args.json);
  const Run run("info", {});  // warnings of the reader go to stderr
  const Mesh mesh = readMesh(args.model, run.ctx());
  const MeshConnectivity topo = computeConnectivity(mesh);
  const BoundingBox box = boundingBox(mesh);
  nlohmann::json j;
  j["file"] = args.model;
  j["format"] = meshFormatName(meshFormatOf(args.model));
  j["vertices"] = topo.usedVertices;
  j["triangles"] = mesh.triangleCount();
  j["bounding_box"] = {{"min", {box.min.x(), box.min.y(), box.min.z()}}, {"max", {box.max.x(), box.max.y(), box.max.z()}}};
  j["components"] = topo.components;
  j["edges"] = topo.edges.size();
  j["boundary_edges"] = topo.boundaryEdges;
  j["non_manifold_edges"] = topo.nonManifoldEdges;
  j["non_manifold_vertices"] = topo.nonManifoldVertices;
  j["inconsistently_oriented_edges"] = topo.inconsistentEdges;
  j["degenerate_triangles"] = topo.degenerateTriangles;
  j["closed"] = topo.closed;
  j["manifold"] = topo.manifold;
  j["oriented"] = topo.oriented;
  j["genus"] = topo.genus ? nlohmann::json(*topo.genus) : nlohmann::json(nullptr);
  j["uvs"] = mesh.hasUvs();
  j["normals"] = mesh.hasNormals();
  j["tangents"] = mesh.hasTangents();
  nlohmann::json materials = nlohmann::json::array();
  std::vector<size_t> uses(std::max<size_t>(1, mesh.materials.size()), 0);
  for (size_t t = 0; t < mesh.triangleCount(); ++t) ++uses[mesh.materialOf(t)];
  for (size_t i = 0; i < mesh.materials.size(); ++i) {
    const Material& m = mesh.materials[i];
    materials.push_back({{"name", m.name},
                         {"triangles", uses[i]},
                         {"base_color_factor", {m.baseColorFactor.x(), m.baseColorFactor.y(), m.baseColorFactor.z(), m.baseColorFactor.w()}},
                         {"metallic", m.metallicFactor},
                         {"roughness", m.roughnessFactor},
                         {"base_color_texture", describeTexture(m.baseColorTexture)},
                         {"metallic_roughness_texture", describeTexture(m.metallicRoughnessTexture)},
                         {"normal_texture", describeTexture(m.normalTexture)}});
    if (m.anisotropy)
      materials.back()["anisotropy"] = {{"strength", m.anisotropy.strength},
                                        {"rotation", m.anisotropy.rotation},
                                        {"texture", describeTexture(m.anisotropy.texture)}};
  }
  j["materials"] = materials;
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("%s (%s)\n", args.model.c_str(), j["format"].get<std::string>().c_str());
  std::printf("  vertices        %zu\n  triangles       %zu\n", topo.usedVertices, mesh.triangleCount());
  std::printf("  bounding box    [%g %g %g] .. [%g %g %g]\n", double(box.min.x()), double(box.min.y()), double(box.min.z()),
              double(box.max.x()), double(box.max.y()), double(box.max.z()));
  std::printf("  components      %zu\n", topo.components);
  std::printf("  closed          %s (%zu boundary edges)\n", topo.closed ? "yes" : "no", topo.boundaryEdges);
  std::printf("  manifold        %s (%zu non-manifold edges, %zu non-manifold vertices)\n", topo.manifold ? "yes" : "no",
              topo.nonManifoldEdges, topo.nonManifoldVertices);
  std::printf("  oriented        %s (%zu inconsistently oriented edges)\n", topo.oriented ? "yes" : "no",
              topo.inconsistentEdges);
  if (topo.genus) std::printf("  genus           %lld\n", *topo.genus);
  else std::printf("  genus           n/a (not a closed, oriented manifold)\n");
  std::printf("  UVs             %s\n  normals         %s\n  tangents        %s\n", mesh.hasUvs() ? "yes" : "no",
              mesh.hasNormals() ? "yes" : "no", mesh.hasTangents() ? "yes" : "no");
  std::printf("  materials       %zu\n", mesh.materials.size());
  for (size_t i = 0; i < mesh.materials.size(); ++i) {
    const Material& m = mesh.materials[i];
    std::printf("    [%zu] %s: %zu triangles, base color (%.3g %.3g %.3g %.3g), metallic %.3g, roughness %.3g\n", i,
                m.name.empty() ? "(unnamed)" : m.name.c_str(), uses[i], double(m.baseColorFactor.x()),
                double(m.baseColorFactor.y()), double(m.baseColorFactor.z()), double(m.baseColorFactor.w()),
                double(m.metallicFactor), double(m.roughnessFactor));
    auto texture = [](const char* what, const Texture& t) {
      if (t)
        std::printf("        %-18s %dx%d, %d channels%s%s%s\n", what, t.image->width, t.image->height, t.image->channels,
                    t.name.empty() ? "" : ", ", t.name.c_str(),
                    t.encodedMips ? ", and its own MIP chain (KTX2, KHR_texture_basisu)" : "");
    };
    texture("base color", m.baseColorTexture);
    texture("metallic-roughness", m.metallicRoughnessTexture);
    texture("normal", m.normalTexture);
    if (m.anisotropy) {
      std::printf("        %-18s strength %.3g, rotation %.3g rad (KHR_materials_anisotropy)\n", "anisotropy",
                  double(m.anisotropy.strength), double(m.anisotropy.rotation));
      texture("anisotropy map", m.anisotropy.texture);
    }
  }
}

} // namespace

Command addInfoCommand(CLI::App& root) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* app = root.add_subcommand("info", "Describe a model: size, bounding box, components, closed/manifold, genus, "
                                              "UVs, materials and textures");
  CLI::Option* model = app->add_option("model", args->model, "Model (.obj, .ply, .off, .stl, .gltf, .glb)");
  app->add_flag("--devices", args->devices, "List the Vulkan devices (--backend vulkan, --device N) instead")
      ->excludes(model);
  app->add_flag("--json", args->json, "Print JSON instead of text");
  app->parse_complete_callback([args] {
    if (args->model.empty() && !args->devices) throw CLI::RequiredError("a model (or --devices)");
  });
  return {app, [args] { runInfo(*args); }};
}

} // namespace texfab::cli
