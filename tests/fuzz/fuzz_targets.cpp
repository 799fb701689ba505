// SPDX-License-Identifier: GPL-3.0-or-later
#include "tests/fuzz/fuzz_targets.h"

#include "core/error.h"
#include "core/image_io.h"
#include "geometry/io/mesh_io.h"
#include "print/icc_profile.h"
#include "print/print_materials.h"
#include "print/slice_writer.h"
#include "synthesis/coord_map.h"
#include "synthesis/exemplar_analysis.h"
#include "synthesis/exemplar_graph.h"
#include "synthesis/graph_file.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/solid_tiles.h"
#include "tests/geometry/test_meshes.h"
#include "tests/print/icc_test_profiles.h"

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

namespace texfab::fuzz {
namespace {

namespace fs = std::filesystem;
using Bytes = std::span<const uint8_t>;

// ---- the scratch folder and files -----------------------------------------------------------

// One scratch folder per process (in memory where /dev/shm exists), removed at exit.
class Scratch {
public:
  Scratch() {
    const fs::path base = fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    path_ = base / ("texfab-fuzz-" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

private:
  fs::path path_;
};

const fs::path& scratch() {
  static const Scratch dir;
  return dir.path();
}

void writeFile(const fs::path& path, Bytes bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
}

void writeFile(const fs::path& path, std::string_view text) {
  writeFile(path, Bytes(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

std::vector<uint8_t> readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The input as a scratch file named `name`.
fs::path inputFile(Bytes input, const std::string& name) {
  const fs::path path = scratch() / name;
  writeFile(path, input);
  return path;
}

[[noreturn]] void contractBroken(const std::string& what) {
  std::fprintf(stderr, "fuzz: a reader accepted an input and broke its contract: %s\n", what.c_str());
  std::abort();
}

// Runs `read`; texfab::Error is a refusal, everything else escapes to the fuzzer.
// Runs `read`: true when it returns, false when it refuses with texfab::Error; everything else
// escapes to the fuzzer.
template <class Read>
bool refusalsAllowed(Read&& read) {
  try {
    read();
    return true;
  } catch (const Error&) {
    return false;
  }
}

void checkImage(const Image& image, const std::string& what) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != size_t(image.width) * size_t(image.height) * size_t(image.channels))
    contractBroken(what + ": an image whose pixels do not match its size");
}

// ---- seeds --------------------------------------------------------------------------------

const fs::path kModels = fs::path(TEXFAB_SOURCE_DIR) / "models";

// A small CGAL model of each format that has one in the repository.
void copySeed(const fs::path& source, const fs::path& folder) {
  if (fs::exists(source)) fs::copy_file(source, folder / source.filename(), fs::copy_options::overwrite_existing);
}

// Calls `write(path)` for a file `name` in a fresh scratch folder; returns the bytes of that file,
// then of each of `sideFiles` the writer put beside it (an OBJ's MTL).
std::vector<std::vector<uint8_t>> writtenFiles(const std::string& name, const std::function<void(const fs::path&)>& write,
                                               std::initializer_list<const char*> sideFiles = {}) {
  const fs::path dir = scratch() / "seed";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write(dir / name);
  std::vector<std::vector<uint8_t>> files{readFile(dir / name)};
  for (const char* side : sideFiles) files.push_back(readFile(dir / side));
  fs::remove_all(dir);
  return files;
}

// `mesh` (by default the textured cube: two materials, one textured; UVs, normals, face tags) as a
// file of `extension` written with `options`: its bytes.
std::vector<uint8_t> meshSeed(const std::string& extension, const geometry::MeshWriteOptions& options = {},
                              const geometry::Mesh& mesh = test::texturedCube()) {
  return writtenFiles("fuzz" + extension, [&](const fs::path& path) { geometry::writeMesh(mesh, path, options); })[0];
}

// The textured cube with KHR_materials_anisotropy: a strength, a rotation and a texture with a KTX2
// chain of its own (KHR_texture_basisu).
geometry::Mesh anisotropicCube() {
  geometry::Mesh cube = test::texturedCube();
  geometry::Material::Anisotropy& a = cube.materials[0].anisotropy;
  a.strength = 0.5f;
  a.rotation = 0.75f;
  a.texture.image = test::gradientImage(8, 8);
  auto mips = std::make_shared<std::vector<Image>>();
  for (int side : {8, 4, 2, 1}) mips->push_back(*test::gradientImage(side, side));
  a.texture.mips = std::move(mips);
  return cube;
}

// Targets that read several formats take the format's index as their input's first byte.
std::vector<uint8_t> withFormatByte(size_t format, std::vector<uint8_t> bytes) {
  bytes.insert(bytes.begin(), uint8_t(format));
  return bytes;
}

void writeSeed(const fs::path& folder, const std::string& name, Bytes bytes) { writeFile(folder / name, bytes); }

// ---- meshes -------------------------------------------------------------------------------

bool readMeshFile(const fs::path& path) {
  return refusalsAllowed([&] {
    const geometry::Mesh mesh = geometry::readMesh(path);
    try {
      geometry::validateMesh(mesh, path.string());
    } catch (const Error& e) {
      contractBroken(std::string("readMesh returned a mesh validateMesh refuses: ") + e.what());
    }
  });
}

template <const char* kExtension>
bool runMesh(Bytes input) {
  return readMeshFile(inputFile(input, std::string("fuzz") + kExtension));
}

// An OBJ input is the OBJ, optionally followed by kMtlMarker and the MTL that `mtllib fuzz.mtl`
// names: both files are fuzzed together.
constexpr std::string_view kMtlMarker = "\n#texfab-fuzz-mtl\n";

bool runObj(Bytes input) {
  const std::string_view text(reinterpret_cast<const char*>(input.data()), input.size());
  const size_t marker = text.find(kMtlMarker);
  const fs::path mtl = scratch() / "fuzz.mtl";
  if (marker == std::string_view::npos) fs::remove(mtl);
  else writeFile(mtl, text.substr(marker + kMtlMarker.size()));
  return readMeshFile(inputFile(input.first(std::min(marker, input.size())), "fuzz.obj"));
}

void seedObj(const fs::path& folder) {
  const auto files = writtenFiles("fuzz.obj", [](const fs::path& path) { geometry::writeMesh(test::texturedCube(), path); },
                                  {"fuzz.mtl"});
  const std::vector<uint8_t>& obj = files[0];
  const std::vector<uint8_t>& mtl = files[1];
  std::vector<uint8_t> joined = obj;
  joined.insert(joined.end(), kMtlMarker.begin(), kMtlMarker.end());
  joined.insert(joined.end(), mtl.begin(), mtl.end());
  writeSeed(folder, "cube_mtl.obj", joined);
  writeSeed(folder, "cube.obj", obj);
  writeFile(folder / "polygons.obj", std::string_view("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\nvt 0 0\nvt 1 1\n"
                                                      "vn 0 0 1\nf 1/1/1 2/2/1 3/1/1 4/2/1\nf -5 -4 -1\nf 2 3 5\n"
                                                      "usemtl x\ng part\nf 3 4 5\nf 4 1 5\n"));
}

void seedPly(const fs::path& folder) {
  geometry::MeshWriteOptions ascii;
  ascii.binary = false;
  writeSeed(folder, "cube_binary.ply", meshSeed(".ply"));
  writeSeed(folder, "cube_ascii.ply", meshSeed(".ply", ascii));
  copySeed(kModels / "cgal" / "colored_tetra.ply", folder);
}

void seedOff(const fs::path& folder) {
  writeSeed(folder, "cube.off", meshSeed(".off"));
  copySeed(kModels / "cgal" / "corner.off", folder);
}

void seedStl(const fs::path& folder) {
  geometry::MeshWriteOptions ascii;
  ascii.binary = false;
  writeSeed(folder, "cube_binary.stl", meshSeed(".stl"));
  writeSeed(folder, "cube_ascii.stl", meshSeed(".stl", ascii));
}

void seedGltf(const fs::path& folder) {
  geometry::MeshWriteOptions embed;
  embed.embed = true;
  writeSeed(folder, "cube.gltf", meshSeed(".gltf", embed));
}

void seedGlb(const fs::path& folder) {
  geometry::MeshWriteOptions draco;
  draco.draco = true;
  writeSeed(folder, "cube.glb", meshSeed(".glb"));
  writeSeed(folder, "cube_draco.glb", meshSeed(".glb", draco));
  writeSeed(folder, "cube_anisotropy.glb", meshSeed(".glb", {}, anisotropicCube()));
}

void seed3mf(const fs::path& folder) { writeSeed(folder, "cube.3mf", meshSeed(".3mf")); }

// ---- images -------------------------------------------------------------------------------

// A small exemplar crop, written in `extension` and read back as bytes.
std::vector<uint8_t> imageSeed(const std::string& extension, PixelFormat format = PixelFormat::UInt8, int channels = 3) {
  Image image = *test::gradientImage(12, 10, channels);
  image.format = format;
  return writtenFiles("seed" + extension, [&](const fs::path& path) { writeImage(image, path); })[0];
}

bool runImageMemory(Bytes input) {
  return refusalsAllowed([&] { checkImage(decodeImage(input, "fuzz"), "decodeImage"); });
}

void seedImageMemory(const fs::path& folder) {
  writeSeed(folder, "rgb.png", imageSeed(".png"));
  writeSeed(folder, "rgba16.png", imageSeed(".png", PixelFormat::UInt16, 4));
  writeSeed(folder, "rgb.jpg", imageSeed(".jpg"));
  writeSeed(folder, "rgba.webp", imageSeed(".webp", PixelFormat::UInt8, 4));
}

// readImage picks the reader from the extension: the first byte of the input chooses it.
constexpr std::array<const char*, 8> kImageExtensions = {".png", ".jpg", ".tif", ".exr", ".tga", ".webp", ".hdr", ".bmp"};

bool runImageFile(Bytes input) {
  if (input.empty()) return false;
  const std::string extension = kImageExtensions[input[0] % kImageExtensions.size()];
  return refusalsAllowed([&] { checkImage(readImage(inputFile(input.subspan(1), "fuzz" + extension)), "readImage"); });
}

void seedImageFile(const fs::path& folder) {
  for (size_t i = 0; i < kImageExtensions.size(); ++i) {
    const std::string extension = kImageExtensions[i];
    const PixelFormat format = extension == ".exr" || extension == ".hdr" ? PixelFormat::Float : PixelFormat::UInt8;
    writeSeed(folder, "image" + extension, withFormatByte(i, imageSeed(extension, format)));
  }
}

// GIMP pattern, version 1 (core/image_io.cpp): six big-endian words, a name, the pixels.
bool runPattern(Bytes input) {
  return refusalsAllowed([&] { checkImage(decodePat(input, "fuzz.pat"), "decodePat"); });
}

void seedPattern(const fs::path& folder) {
  for (uint32_t depth : {1u, 3u, 4u}) {
    const uint32_t width = 6, height = 5;
    const std::string name = "texfab seed";
    const uint32_t header = uint32_t(24 + name.size() + 1);
    std::vector<uint8_t> bytes;
    for (uint32_t word : {header, 1u, width, height, depth})
      for (int shift = 24; shift >= 0; shift -= 8) bytes.push_back(uint8_t(word >> shift));
    bytes.insert(bytes.end(), {'G', 'P', 'A', 'T'});
    bytes.insert(bytes.end(), name.begin(), name.end());
    bytes.push_back(0);
    for (uint32_t i = 0; i < width * height * depth; ++i) bytes.push_back(uint8_t(i * 37));
    writeSeed(folder, "pattern" + std::to_string(depth) + ".pat", bytes);
  }
}

// Coordinate maps (written by synth --coords, read by stats --coords): 16-bit PNG/TIFF or EXR.
constexpr std::array<const char*, 3> kCoordExtensions = {".exr", ".png", ".tif"};

bool runCoordMap(Bytes input) {
  if (input.empty()) return false;
  const std::string extension = kCoordExtensions[input[0] % kCoordExtensions.size()];
  return refusalsAllowed([&] {
    const synthesis::CoordMap map = synthesis::readCoordMap(inputFile(input.subspan(1), "coords" + extension), 64, 48);
    if (map.coords.size() != size_t(map.width) * size_t(map.height)) contractBroken("readCoordMap: size mismatch");
  });
}

void seedCoordMap(const fs::path& folder) {
  synthesis::CoordMap map;
  map.width = 9;
  map.height = 7;
  map.exemplarWidth = 64;
  map.exemplarHeight = 48;
  for (int i = 0; i < map.width * map.height; ++i) map.coords.push_back(synthesis::packCoord(uint32_t(i % 64), uint32_t(i % 48)));
  for (size_t i = 0; i < kCoordExtensions.size(); ++i) {
    const std::string name = std::string("coords") + kCoordExtensions[i];
    writeSeed(folder, name,
              withFormatByte(i, writtenFiles(name, [&](const fs::path& path) { synthesis::writeCoordMap(map, path); })[0]));
  }
}

// ---- print: materials, slice manifests, ICC profiles ---------------------------------------

bool runMaterials(Bytes input) {
  return refusalsAllowed([&] { print::readPrintMaterials(inputFile(input, "materials.json")); });
}

void seedMaterials(const fs::path& folder) {
  writeFile(folder / "list.json", std::string_view(R"([{"name": "White", "color": "#ffffff"}, {"name": "Black", "color": [0, 0, 0]}])"));
  writeFile(folder / "object.json", std::string_view(R"({"materials": [{"name": "Slate", "lab": [50.0, 10.5, -20.25]},
    {"name": "Clear", "color": "#E0F0F0", "opacity": 0}, {"name": "Magenta", "color": "#FF00FF", "opacity": 1}]})"));
}

// A slice folder whose manifest is the input, next to one layer file, merged as `texfab merge-slices` does
// (the manifest read, its shard checked, its files verified against their checksums).
bool runManifest(Bytes input) {
  const fs::path shard = scratch() / "shard", output = scratch() / "merged";
  fs::create_directories(shard);
  writeFile(shard / "slices.json", input);
  writeFile(shard / "slice_00000.png", std::string_view("layer"));
  const bool merged = refusalsAllowed([&] {
    print::readSliceManifest(shard);
    const fs::path shards[] = {shard};
    print::mergeSliceFolders(shards, output, true);
  });
  fs::remove_all(output);
  return merged;
}

void seedManifest(const fs::path& folder) {
  const std::string layer = "layer";
  const std::string sha = print::sha256Hex(Bytes(reinterpret_cast<const uint8_t*>(layer.data()), layer.size()));
  writeFile(folder / "slices.json",
            std::string(R"({"format": "texfab-slices", "version": 1, "print": {"dpi": [600, 300], "layer_mm": 0.027},
  "layers": {"first": 0, "count": 1, "total": 1},
  "files": [{"layer": 0, "file": "slice_00000.png", "bytes": 5, "sha256": ")") + sha + "\"}]}");
}

bool runIcc(Bytes input) {
  return refusalsAllowed([&] {
    const print::IccProfile profile(inputFile(input, "fuzz.icc"));
    const print::Lab lab = profile.reproduced({0.8, 0.4, 0.2});
    profile.roundTrip(lab);
  });
}

void seedIcc(const fs::path& folder) {
  test::writeRgbProfile(folder / "srgb_like.icc", 0.0);
  test::writeRgbProfile(folder / "narrow_output.icc", 0.3, cmsSigOutputClass);
}

// ---- the analysis cache ---------------------------------------------------------------------

// A cache reader returns nothing for a damaged or foreign file (it is recomputed, never trusted).
template <class Read>
bool cacheLoads(Read&& read) {
  bool loaded = false;
  refusalsAllowed([&] { loaded = read(); });
  return loaded;
}

// Cache files carry the key of what they hold; the seeds are written with this one.
constexpr uint64_t kSeedKey = 0x7465786661622121ull;

Image seedExemplar() { return *test::gradientImage(16, 16); }

bool runAnalysisCache(Bytes input) {
  return cacheLoads([&] { return synthesis::readAnalysis(inputFile(input, "fuzz.analysis"), kSeedKey).has_value(); });
}

void seedAnalysisCache(const fs::path& folder) {
  synthesis::AnalysisOptions options;
  synthesis::ExemplarAnalysis analysis = synthesis::analyzeExemplar(seedExemplar(), options);
  analysis.key = kSeedKey;
  synthesis::writeAnalysis(analysis, folder / "gradient.analysis");
}

synthesis::SolidAnalysis seedSolidAnalysis() {
  const Image e = seedExemplar();
  synthesis::SolidAnalysis analysis = synthesis::analyzeSolid(e, e, e, {});
  analysis.key = kSeedKey;
  return analysis;
}

bool runSolidCache(Bytes input) {
  return cacheLoads([&] { return synthesis::readSolidAnalysis(inputFile(input, "fuzz.solid"), kSeedKey).has_value(); });
}

void seedSolidCache(const fs::path& folder) { synthesis::writeSolidAnalysis(seedSolidAnalysis(), folder / "gradient.solid"); }

bool runTilesCache(Bytes input) {
  return cacheLoads([&] { return synthesis::readSolidTiles(inputFile(input, "fuzz.tiles"), kSeedKey).has_value(); });
}

void seedTilesCache(const fs::path& folder) {
  synthesis::SolidTileOptions options;
  options.tileSide = 8;
  options.iterations = options.finestIterations = 1;
  synthesis::SolidTileSet tiles = synthesis::buildSolidTiles(seedSolidAnalysis(), options);
  tiles.key = kSeedKey;
  synthesis::writeSolidTiles(tiles, folder / "gradient.tiles");
}

bool runGraphCache(Bytes input) {
  return cacheLoads([&] { return synthesis::readGraphAnalysis(inputFile(input, "fuzz.graph"), kSeedKey).has_value(); });
}

void seedGraphCache(const fs::path& folder) {
  synthesis::ExemplarGraph graph;
  graph.names = {"gradient", "detail"};
  graph.exemplars = {seedExemplar(), seedExemplar()};
  graph.edges = {{0, 1, 1}};
  synthesis::GraphAnalysis analysis = synthesis::analyzeGraph(graph);
  analysis.key = kSeedKey;
  synthesis::writeGraphAnalysis(analysis, folder / "gradient.graph");
}

// Graph files (synth --graph): JSON naming two 16x16 exemplars and a mask beside it (in the
// scratch folder, written once), edges with scales and regions.
bool runGraphFile(Bytes input) {
  static const bool images = [] {
    writeImage(seedExemplar(), scratch() / "a.png");
    writeImage(seedExemplar(), scratch() / "b.png");
    Image mask(16, 16, 1);
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 8; ++x) mask.at(x, y, 0) = 1.0f;
    writeImage(mask, scratch() / "mask.png");
    return true;
  }();
  (void)images;
  return refusalsAllowed([&] { synthesis::readExemplarGraph(inputFile(input, "graph.json")); });
}

void seedGraphFile(const fs::path& folder) {
  writeFile(folder / "two.json", std::string_view(R"({"exemplars": [{"name": "a", "image": "a.png"},
    {"name": "b", "image": "b.png"}], "root": "a", "edges": [{"from": "a", "to": "b", "scale": 2}]})"));
  writeFile(folder / "regions.json", std::string_view(R"({"exemplars": [{"name": "a", "image": "a.png"},
    {"name": "b", "image": "b.png"}], "edges": [{"from": "a", "to": "b", "scale": 2, "region": [-3, 4, 8, 16]},
    {"from": "a", "to": "a", "scale": 2, "region": "mask.png"}]})"));
  writeFile(folder / "maps.json", std::string_view(R"({"exemplars": [{"name": "a", "image": "a.png",
    "maps": {"normal": "b.png", "height": "mask.png"}}, {"name": "b", "image": "b.png",
    "maps": {"normal": "a.png", "height": "a.png"}}], "edges": [{"from": "a", "to": "b", "scale": 2}]})"));
}

constexpr char kOff[] = ".off", kPly[] = ".ply", kStl[] = ".stl", kGltf[] = ".gltf", kGlb[] = ".glb", k3mf[] = ".3mf";

constexpr FuzzTarget kTargets[] = {
    {"mesh_obj", "readMesh: OBJ with its MTL", runObj, seedObj},
    {"mesh_ply", "readMesh: PLY (ASCII, binary)", runMesh<kPly>, seedPly},
    {"mesh_off", "readMesh: OFF", runMesh<kOff>, seedOff},
    {"mesh_stl", "readMesh: STL (ASCII, binary)", runMesh<kStl>, seedStl},
    {"mesh_gltf", "readMesh: glTF (tinygltf, embedded buffers and images)", runMesh<kGltf>, seedGltf},
    {"mesh_glb", "readMesh: GLB (tinygltf, Draco, embedded images)", runMesh<kGlb>, seedGlb},
    {"mesh_3mf", "readMesh: 3MF (lib3mf)", runMesh<k3mf>, seed3mf},
    {"image_memory", "decodeImage: PNG, JPEG, WebP in memory (OpenImageIO)", runImageMemory, seedImageMemory},
    {"image_file", "readImage: every extension texfab reads (OpenImageIO)", runImageFile, seedImageFile},
    {"pattern", "decodePat: GIMP patterns", runPattern, seedPattern},
    {"coord_map", "readCoordMap: stats --coords (EXR, 16-bit PNG/TIFF)", runCoordMap, seedCoordMap},
    {"materials", "readPrintMaterials: slice --materials JSON", runMaterials, seedMaterials},
    {"manifest", "readSliceManifest + mergeSliceFolders: merge-slices", runManifest, seedManifest},
    {"icc", "IccProfile: slice --icc-profile (LittleCMS)", runIcc, seedIcc},
    {"analysis_cache", "readAnalysis: the 2-D analysis cache", runAnalysisCache, seedAnalysisCache},
    {"solid_cache", "readSolidAnalysis: the solid analysis cache", runSolidCache, seedSolidCache},
    {"tiles_cache", "readSolidTiles: the solid tiles cache", runTilesCache, seedTilesCache},
    {"graph_cache", "readGraphAnalysis: the exemplar graph analysis cache", runGraphCache, seedGraphCache},
    {"graph_file", "readExemplarGraph: synth/texture --graph JSON with regions", runGraphFile, seedGraphFile},
};

} // namespace

std::span<const FuzzTarget> fuzzTargets() { return kTargets; }

const FuzzTarget* findFuzzTarget(std::string_view name) {
  for (const FuzzTarget& t : kTargets)
    if (name == t.name) return &t;
  return nullptr;
}

} // namespace texfab::fuzz
