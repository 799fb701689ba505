// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/graph_file.h"

#include "core/error.h"
#include "core/image_io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <fstream>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <map>
#include <type_traits>

namespace texfab::synthesis {

namespace {

using nlohmann::json;

void onlyKeys(const json& object, std::initializer_list<const char*> keys, const std::string& where) {
  for (const auto& item : object.items())
    if (std::none_of(keys.begin(), keys.end(), [&](const char* k) { return item.key() == k; }))
      throw Error(where + ": unknown field '" + item.key() + "'");
}

// object[key], which must be there and be a T (std::string, double or json for an array).
template <class T> T get(const json& object, const char* key, const std::string& where) {
  if (!object.contains(key)) throw Error(where + ": missing \"" + key + "\"");
  const json& v = object.at(key);
  bool ok = v.is_array();
  if constexpr (std::is_same_v<T, std::string>) ok = v.is_string();
  if constexpr (std::is_same_v<T, double>) ok = v.is_number();
  if (!ok) throw Error(where + ": \"" + key + "\" has the wrong type");
  return v.get<T>();
}

// An edge's "region" as side x side flags: [x, y, width, height] in pixels of the source
// (wrapping, as exemplars tile), or a mask image of the source's size (first channel >= 0.5: in).
std::vector<uint8_t> regionOf(const json& value, int side, const std::filesystem::path& folder,
                              const std::string& where) {
  std::vector<uint8_t> region(size_t(side) * size_t(side), 0);
  if (value.is_string()) {
    const Image mask = readImage(folder / value.get<std::string>());
    if (mask.width != side || mask.height != side)
      throw Error(where + ": region mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                  ", its exemplar " + std::to_string(side) + "x" + std::to_string(side));
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) region[size_t(y) * side + x] = mask.at(x, y, 0) >= 0.5f;
    return region;
  }
  const bool rectangle = value.is_array() && value.size() == 4 &&
                         std::all_of(value.begin(), value.end(), [](const json& v) { return v.is_number_integer(); });
  if (!rectangle) throw Error(where + ": \"region\" must be [x, y, width, height] in pixels or a mask image");
  const auto r = value.get<std::vector<int64_t>>();
  if (r[2] < 1 || r[3] < 1 || r[2] > side || r[3] > side)
    throw Error(where + ": region width and height must be 1 to " + std::to_string(side));
  if (std::llabs(r[0]) > (int64_t(1) << 30) || std::llabs(r[1]) > (int64_t(1) << 30))
    throw Error(where + ": region x and y must be within +-2^30");
  for (int64_t y = r[1]; y < r[1] + r[3]; ++y)
    for (int64_t x = r[0]; x < r[0] + r[2]; ++x)
      region[size_t(((y % side) + side) % side) * side + size_t(((x % side) + side) % side)] = 1;
  return region;
}

// An exemplar's "maps": {"normal": "n.png", ...} (kGraphMapNames).
std::map<std::string, std::string> mapsOf(const json& exemplar, const std::string& where) {
  std::map<std::string, std::string> files;
  if (!exemplar.contains("maps")) return files;
  const json& maps = exemplar.at("maps");
  if (!maps.is_object()) throw Error(where + ": \"maps\" must be {\"normal\": image, \"roughness\": ..., \"height\": ...}");
  onlyKeys(maps, {"normal", "roughness", "height"}, where + ": maps");
  for (const auto& item : maps.items()) files[item.key()] = get<std::string>(maps, item.key().c_str(), where + ": maps");
  return files;
}

// The graph's maps: each one every exemplar gives, read relative to `folder`.
std::vector<GraphMap> readMaps(const std::vector<std::map<std::string, std::string>>& files,
                               const std::vector<std::string>& names, const std::filesystem::path& folder,
                               const std::string& file) {
  std::vector<GraphMap> maps;
  for (const char* name : kGraphMapNames) {
    const auto has = [&](const std::map<std::string, std::string>& f) { return f.count(name) > 0; };
    if (std::none_of(files.begin(), files.end(), has)) continue;
    GraphMap map{name, {}};
    for (size_t i = 0; i < files.size(); ++i) {
      if (!has(files[i]))
        throw Error(file + ": exemplar '" + names[i] + "' has no " + name +
                    " map while others have one: give it for every exemplar or for none");
      map.perNode.push_back(readImage(folder / files[i].at(name)));
    }
    maps.push_back(std::move(map));
  }
  return maps;
}

} // namespace

ExemplarGraph readExemplarGraph(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) throw Error(file + ": cannot open the graph file");
  json doc;
  try {
    doc = json::parse(in);
  } catch (const json::exception& e) {
    throw Error(file + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (!doc.is_object()) throw Error(file + ": expected an object with \"exemplars\" and \"edges\"");
  onlyKeys(doc, {"exemplars", "edges", "root", "colors"}, file);

  ExemplarGraph graph;
  if (doc.contains("colors")) {
    const std::string colors = get<std::string>(doc, "colors", file);
    if (colors != "coarse" && colors != "own")
      throw Error(file + ": colors '" + colors + "' must be 'coarse' (finer exemplars take the coarser ones' colours) or 'own'");
    graph.coarseColors = colors == "coarse";
  }
  std::vector<std::string> images;
  std::vector<std::map<std::string, std::string>> mapFiles;  // per exemplar: map name -> image
  for (const json& e : get<json>(doc, "exemplars", file)) {
    const std::string where = file + ": exemplar " + std::to_string(graph.names.size() + 1);
    if (!e.is_object()) throw Error(where + ": expected {\"name\": ..., \"image\": ...}");
    onlyKeys(e, {"name", "image", "maps"}, where);
    const std::string name = get<std::string>(e, "name", where);
    if (std::find(graph.names.begin(), graph.names.end(), name) != graph.names.end())
      throw Error(file + ": exemplar '" + name + "' is named twice");
    graph.names.push_back(name);
    images.push_back(get<std::string>(e, "image", where));
    mapFiles.push_back(mapsOf(e, where));
  }
  if (graph.names.empty()) throw Error(file + ": \"exemplars\" is empty");
  auto indexOf = [&](const std::string& name, const std::string& where) {
    const auto it = std::find(graph.names.begin(), graph.names.end(), name);
    if (it == graph.names.end()) throw Error(where + ": no exemplar is named '" + name + "'");
    return int(it - graph.names.begin());
  };
  if (doc.contains("root")) {
    const int root = indexOf(get<std::string>(doc, "root", file), file + ": root");
    std::rotate(graph.names.begin(), graph.names.begin() + root, graph.names.begin() + root + 1);
    std::rotate(images.begin(), images.begin() + root, images.begin() + root + 1);
    std::rotate(mapFiles.begin(), mapFiles.begin() + root, mapFiles.begin() + root + 1);
  }
  std::vector<std::pair<size_t, json>> regions;  // filled once the exemplars' side is known
  if (doc.contains("edges")) {
    for (const json& e : get<json>(doc, "edges", file)) {
      const std::string where = file + ": edge " + std::to_string(graph.edges.size() + 1);
      if (!e.is_object()) throw Error(where + ": expected {\"from\": ..., \"to\": ..., \"scale\": ...}");
      onlyKeys(e, {"from", "to", "scale", "region"}, where);
      if (e.contains("region")) regions.emplace_back(graph.edges.size(), e.at("region"));
      const double scale = get<double>(e, "scale", where);
      if (!(scale > 1) || scale > 1e6 || scale != std::floor(scale) || !std::has_single_bit(uint64_t(scale)))
        throw Error(where + ": scale " + e.at("scale").dump() + " must be a power of two greater than 1 (2, 4, 8, ...)");
      graph.edges.push_back({indexOf(get<std::string>(e, "from", where), where),
                             indexOf(get<std::string>(e, "to", where), where),
                             std::countr_zero(uint64_t(scale))});
    }
  }
  const std::filesystem::path folder = path.parent_path();
  for (const std::string& image : images) graph.exemplars.push_back(readImage(folder / image));  // absolute: as is
  graph.maps = readMaps(mapFiles, graph.names, folder, file);
  for (const auto& [edge, region] : regions)
    graph.edges[edge].region = regionOf(region, graph.exemplars[size_t(graph.edges[edge].from)].width, folder,
                                        file + ": edge " + std::to_string(edge + 1));
  try {
    graph = withOneSide(std::move(graph));
    graph.validate();
  } catch (const Error& e) {
    throw Error(file + ": " + e.what());
  }
  return graph;
}

} // namespace texfab::synthesis
