// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: C. Han et al. Multiscale texture synthesis. SIGGRAPH 2008; C. Han, PhD thesis, 2011,
//           ch. 4 and §5.2 (admissible candidates 𝒜(E_k^i), k-coherence across exemplars).
#include "synthesis/exemplar_graph.h"

#include "core/error.h"
#include "core/files.h"
#include "core/hash.h"
#include "core/parallel.h"
#include "synthesis/appearance_space.h"
#include "synthesis/binary_io.h"
#include "synthesis/coord_map.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <climits>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>

namespace texfab::synthesis {

using namespace detail;

namespace {

constexpr int kSearchNeighbors = 12;  // nearest sites examined per admissible level
constexpr uint32_t kGraphCacheMagic = 0x47584654;  // "TFXG"
constexpr uint32_t kGraphCacheVersion = 7;         // bump whenever the graph analysis changes

// Atlas coordinate x (tiles of m pixels) moved by d, wrapped in its tile.
int inTile(int x, int d, int m) { return x - x % m + ((x % m + d) % m + m) % m; }

// RGB of any exemplar: grey (1 or 2 channels) replicated, alpha dropped.
Image rgbOf(const Image& image) {
  Image out(image.width, image.height, 3, image.format);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float* p = image.pixel(x, y);
      float* o = out.pixel(x, y);
      for (int c = 0; c < 3; ++c) o[c] = p[image.channels >= 3 ? c : 0];
    }
  return out;
}

struct Tile {
  int node = 0, level = 0;
  bool operator==(const Tile&) const = default;
};

bool isLeaf(const ExemplarGraph& g, int node) {
  return std::none_of(g.edges.begin(), g.edges.end(), [&](const GraphEdge& e) { return e.from == node; });
}

// 𝒜(E_k^i): the levels a texel of level k of node i may move to (thesis §5.2.1.2), itself first
// where it may stay; the finest level of a node that has edges out is never one (a leaf's is, to
// itself: see the header), nor an edge's destination level coarser than minEntryLevel.
std::vector<Tile> admissible(const ExemplarGraph& g, int levels, Tile from, int minEntryLevel) {
  const int finest = levels - 1;
  std::vector<Tile> out;
  if (from.level < finest || isLeaf(g, from.node)) out.push_back(from);
  for (const GraphEdge& e : g.edges) {
    const Tile t{e.to, from.level - e.octaves};
    if (e.from != from.node || t.level < std::min(minEntryLevel, finest) || (t.level == finest && !isLeaf(g, e.to)))
      continue;
    if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(t);
  }
  return out;
}

// Appearance vectors of every atlas texel in one PCA space (see the header's deviations): the
// basis and the quantization scale from a regular sample of about kExactAnalysisPixels
// neighborhoods over all tiles, every texel projected by fixed-order sums. Also the projection's
// response to a uniform RGB offset (GraphAnalysis::transferAppearance).
void appearanceOf(const std::vector<std::vector<Image>>& stacks, GraphAnalysis& a, const Context& ctx) {
  const int m = a.side, tiles = a.nodes * a.levels;
  const int dims = (2 * kPatchRadius + 1) * (2 * kPatchRadius + 1) * 3;
  const std::vector<float> weights = patchWeights();
  const int step = std::max(1, int(std::ceil(std::sqrt(double(tiles) * m * m / double(kExactAnalysisPixels)))));
  const int perSide = (m + step - 1) / step;
  Eigen::MatrixXf raw(int64_t(tiles) * perSide * perSide, dims);
  std::vector<float> patch(static_cast<size_t>(dims));
  int64_t row = 0;
  for (int i = 0; i < a.nodes; ++i)
    for (int k = 0; k < a.levels; ++k)
      for (int y = 0; y < m; y += step)
        for (int x = 0; x < m; x += step, ++row) {
          patchOf(stacks[size_t(i)][size_t(k)], x, y, a.spacing(k), ExemplarWrap::Tile, weights.data(), patch.data());
          for (int d = 0; d < dims; ++d) raw(row, d) = patch[size_t(d)];
        }
  Eigen::RowVectorXf mean;
  const Eigen::MatrixXf basis = principalBasis(raw, mean);
  const float maxAbs = (raw * basis).cwiseAbs().maxCoeff();
  const float scale = maxAbs > 0 ? 127.0f / maxAbs : 0.0f;
  raw.resize(0, 0);
  const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> b = basis;
  for (int c = 0; c < 3; ++c)
    for (int d = 0; d < kAppearanceDims; ++d) {
      double response = 0;  // of a unit offset of channel c: every sample's weighted value moves
      for (size_t s = 0; s < weights.size(); ++s) response += double(weights[s]) * b(int(s) * 3 + c, d);
      a.transferAppearance[size_t(d * 3 + c)] =
          int32_t(std::lrint(response * scale * double(1 << kTransferAppearanceBits) / kTransferOne));
    }

  const int aw = a.atlasWidth();
  std::vector<int8_t> out(size_t(aw) * size_t(a.atlasHeight()) * kAppearanceDims);
  parallelFor(0, a.atlasHeight(), ctx, [&](int y0, int y1) {
    std::vector<float> p(static_cast<size_t>(dims));
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < aw; ++x) {
        const int node = y / m, level = x / m;
        patchOf(stacks[size_t(node)][size_t(level)], x % m, y % m, a.spacing(level), ExemplarWrap::Tile,
                weights.data(), p.data());
        projectPatch(p.data(), dims, mean, b.data(), scale, &out[(size_t(y) * aw + x) * kAppearanceDims]);
      }
  }, 4);
  a.appearance = std::move(out);
}

// Each texel's 4 diagonal appearance vectors at its level's spacing, wrapped in its tile.
std::vector<int8_t> neighborhoodsOf(const GraphAnalysis& a) {
  const int m = a.side, aw = a.atlasWidth();
  std::vector<int8_t> out(size_t(aw) * size_t(a.atlasHeight()) * kNeighborhoodDims);
  for (int y = 0; y < a.atlasHeight(); ++y)
    for (int x = 0; x < aw; ++x) {
      const int h = a.spacing(x / m);
      for (int i = 0; i < kNeighborhoodSamples; ++i) {
        const int sx = inTile(x, kDiagonalX[i] * h, m), sy = inTile(y, kDiagonalY[i] * h, m);
        std::memcpy(&out[(size_t(y) * aw + x) * kNeighborhoodDims + size_t(i) * kAppearanceDims],
                    &a.appearance[(size_t(sy) * aw + sx) * kAppearanceDims], kAppearanceDims);
      }
    }
  return out;
}

// One admissible level's search structure: its texels on a grid of stride min(h_l, m/8) (a
// coarse level sees texels closer than h_l as one feature; cf. coherenceCandidates).
struct LevelSearch {
  Tile tile;
  int stride = 1;
  AppearanceCloud cloud;
  std::vector<uint32_t> sites;  // packed atlas coordinates
  std::unique_ptr<AppearanceTree> tree;

  LevelSearch(const GraphAnalysis& a, Tile t) : tile(t) {
    const int m = a.side;
    stride = std::max(1, std::min(a.spacing(t.level), m / 8));
    for (int y = 0; y < m; y += stride)
      for (int x = 0; x < m; x += stride) {
        const int ax = t.level * m + x, ay = t.node * m + y;
        sites.push_back(packCoord(uint32_t(ax), uint32_t(ay)));
        const int8_t* v = &a.appearance[(size_t(ay) * a.atlasWidth() + ax) * kAppearanceDims];
        cloud.points.insert(cloud.points.end(), v, v + kAppearanceDims);
      }
    tree = std::make_unique<AppearanceTree>(kAppearanceDims, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  }
};

// Squared distance between two texels of one tile, toroidal.
int64_t tileDistance2(uint32_t a, uint32_t b, int m) {
  return pixelDistance2(int(coordU(a)) % m, int(coordV(a)) % m, int(coordU(b)) % m, int(coordV(b)) % m, m, m,
                        ExemplarWrap::Tile);
}

// Whether an edge from tile `from` to tile `to` covers pixel (x, y) of its source.
bool edgeCovers(const ExemplarGraph& g, Tile from, Tile to, int x, int y, int m) {
  return std::any_of(g.edges.begin(), g.edges.end(), [&](const GraphEdge& e) {
    return e.from == from.node && e.to == to.node && from.level - e.octaves == to.level && e.covers(x, y, m);
  });
}

// Each atlas texel's candidates: itself where it may stay, then the candidatesPerLevel best of each
// admissible level whose edge covers it (exact k-nearest in appearance space, spread apart),
// missing slots repeating the first.
std::vector<uint32_t> candidatesOf(const ExemplarGraph& graph, const GraphAnalysis& a,
                                   const std::vector<std::vector<Tile>>& admissibleOf, const GraphAnalysisOptions& options,
                                   const Context& ctx) {
  const int m = a.side, aw = a.atlasWidth();
  std::vector<std::unique_ptr<LevelSearch>> searches(size_t(a.nodes * a.levels));
  for (const auto& set : admissibleOf)
    for (const Tile& t : set)
      if (!searches[size_t(t.node * a.levels + t.level)])
        searches[size_t(t.node * a.levels + t.level)] = std::make_unique<LevelSearch>(a, t);

  const int64_t spread = std::max<int64_t>(2, std::lrint(options.minSpread * float(m)));
  std::vector<uint32_t> candidates(size_t(aw) * size_t(a.atlasHeight()) * size_t(a.k), 0);
  parallelFor(0, a.atlasHeight(), ctx, [&](int y0, int y1) {
    std::vector<uint32_t> index(kSearchNeighbors);
    std::vector<float> dist(kSearchNeighbors), point(kAppearanceDims);
    std::vector<std::pair<float, uint32_t>> ranked;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < aw; ++x) {
        const int tile = (y / m) * a.levels + x / m;
        const uint32_t self = packCoord(uint32_t(x), uint32_t(y));
        const int8_t* v = &a.appearance[(size_t(y) * aw + x) * kAppearanceDims];
        for (int d = 0; d < kAppearanceDims; ++d) point[size_t(d)] = v[d];
        uint32_t* slot = &candidates[(size_t(y) * aw + x) * size_t(a.k)];
        int taken = 0;
        if (a.selfAdmissible[size_t(y) * aw + x]) slot[taken++] = self;
        for (const Tile& t : admissibleOf[size_t(tile)]) {
          if (!(t == Tile{y / m, x / m}) && !edgeCovers(graph, {y / m, x / m}, t, x % m, y % m, m)) continue;
          const LevelSearch& s = *searches[size_t(t.node * a.levels + t.level)];
          const size_t found = s.tree->knnSearch(point.data(), std::min(s.sites.size(), size_t(kSearchNeighbors)),
                                                 index.data(), dist.data());
          ranked.clear();
          for (size_t f = 0; f < found; ++f) ranked.emplace_back(dist[f], s.sites[index[f]]);
          std::sort(ranked.begin(), ranked.end());  // distance, then coordinate: a fixed order for ties
          const int first = taken;
          const int64_t apart2 = std::max<int64_t>(spread, s.stride) * std::max<int64_t>(spread, s.stride);
          for (const auto& [d, c] : ranked) {
            if (taken - first == options.candidatesPerLevel) break;
            bool apart = true;  // from the texel itself and from this level's other picks
            if (t == Tile{y / m, x / m}) apart = tileDistance2(c, self, m) >= apart2;
            for (int o = first; o < taken && apart; ++o) apart = tileDistance2(c, slot[o], m) >= apart2;
            if (apart) slot[taken++] = c;
          }
        }
        if (taken == 0) slot[taken++] = self;
        for (int o = taken; o < a.k; ++o) slot[o] = slot[0];  // missing slots repeat the first
      }
  }, 1);
  return candidates;
}

// Thesis §5.3's offset b per candidate slot: the mean of (texel - candidate) over their 5x5
// neighbourhoods at their levels' spacings, in the colours texels show (GraphAnalysis::colors: the
// offsets correct what is seen), in fixed-order float sums; 0 within an exemplar.
// Empty when every offset is 0.
std::vector<int16_t> transfersOf(const GraphAnalysis& a, const Context& ctx) {
  const int m = a.side, aw = a.atlasWidth();
  const auto colour = [&](int ax, int ay, int dx, int dy) { return a.colors.pixel(inTile(ax, dx, m), inTile(ay, dy, m)); };
  std::vector<int16_t> transfers(a.candidates.size() * 3, 0);
  std::atomic<bool> any = false;
  parallelFor(0, a.atlasHeight(), ctx, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < aw; ++x)
        for (int o = 0; o < a.k; ++o) {
          const size_t slot = (size_t(y) * aw + x) * size_t(a.k) + size_t(o);
          const uint32_t c = a.candidates[slot];
          const int cx = int(coordU(c)), cy = int(coordV(c));
          if (cy / m == y / m) continue;
          const int h = a.spacing(x / m), hc = a.spacing(cx / m);
          float sum[3] = {};
          for (int dy = -kPatchRadius; dy <= kPatchRadius; ++dy)
            for (int dx = -kPatchRadius; dx <= kPatchRadius; ++dx) {
              const float* p = colour(x, y, dx * h, dy * h);
              const float* q = colour(cx, cy, dx * hc, dy * hc);
              for (int ch = 0; ch < 3; ++ch) sum[ch] += p[ch] - q[ch];
            }
          constexpr int samples = (2 * kPatchRadius + 1) * (2 * kPatchRadius + 1);
          for (int ch = 0; ch < 3; ++ch) {
            const long b = std::clamp(std::lrint(sum[ch] / samples * kTransferOne), -32767L, 32767L);
            transfers[slot * 3 + size_t(ch)] = int16_t(b);
            if (b != 0) any = true;
          }
        }
  }, 4);
  if (!any) transfers.clear();
  return transfers;
}

} // namespace

void GraphAnalysisOptions::validate() const {
  if (candidatesPerLevel < 1 || candidatesPerLevel > 4) throw Error("graph candidates per level must be 1 to 4");
  if (!(minSpread >= 0.0f && minSpread <= 0.5f)) throw Error("graph candidate spread must be in [0, 0.5]");
  if (minEntryLevel < 0 || minEntryLevel > 9) throw Error("graph entry level must be 0 to 9");
}

namespace {

// `image` magnified `factor` times per side, each pixel a plane through its value with the
// central differences' slopes (wrapping: graph exemplars are toroidal): smooth, and every
// factor x factor block averages to the pixel it came from, so that a texel of the magnified
// exemplar's level that spans a pixel as given shows that pixel's value.
Image magnified(const Image& image, int factor) {
  Image out(image.width * factor, image.height * factor, image.channels);
  out.format = PixelFormat::Float;  // values between the 8-bit levels
  const auto at = [&](int x, int y, int c) {
    return image.at((x + image.width) % image.width, (y + image.height) % image.height, c);
  };
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < image.channels; ++c) {
        const float value = at(x, y, c), dx = 0.5f * (at(x + 1, y, c) - at(x - 1, y, c)),
                    dy = 0.5f * (at(x, y + 1, c) - at(x, y - 1, c));
        for (int j = 0; j < factor; ++j)
          for (int i = 0; i < factor; ++i) {
            // The sub-pixel's centre, -1/2 .. 1/2 across the pixel.
            const float sx = float(2 * i + 1 - factor) / float(2 * factor), sy = float(2 * j + 1 - factor) / float(2 * factor);
            out.at(x * factor + i, y * factor + j, c) = value + sx * dx + sy * dy;
          }
      }
  return out;
}

// A magnified normal map's normals made unit again (stored as (n + 1) / 2).
void renormalize(Image& normals) {
  if (normals.channels < 3) return;
  for (int y = 0; y < normals.height; ++y)
    for (int x = 0; x < normals.width; ++x) {
      float* p = normals.pixel(x, y);
      const float nx = 2 * p[0] - 1, ny = 2 * p[1] - 1, nz = 2 * p[2] - 1;
      const float length = std::sqrt(nx * nx + ny * ny + nz * nz);
      if (length > 0) p[0] = 0.5f * (nx / length + 1), p[1] = 0.5f * (ny / length + 1), p[2] = 0.5f * (nz / length + 1);
    }
}

// An exemplar validate() accepts the shape of; the others are left for it to name.
bool squarePowerOfTwo(const Image& e) {
  return e.width == e.height && std::has_single_bit(unsigned(e.width)) && e.width >= kMinGraphExemplarSide &&
         e.width <= kMaxGraphExemplarSide;
}

} // namespace

ExemplarGraph withOneSide(ExemplarGraph graph) {
  int side = 0;
  for (const Image& e : graph.exemplars)
    if (squarePowerOfTwo(e)) side = std::max(side, e.width);
  std::vector<int> octaves(graph.exemplars.size(), 0);  // each exemplar's magnification
  for (size_t i = 0; i < graph.exemplars.size(); ++i) {
    Image& e = graph.exemplars[i];
    if (!squarePowerOfTwo(e) || e.width == side) continue;
    const int factor = side / e.width;
    octaves[i] = std::countr_zero(unsigned(factor));
    for (GraphMap& map : graph.maps)
      if (i < map.perNode.size() && map.perNode[i].width == e.width && map.perNode[i].height == e.height) {
        map.perNode[i] = magnified(map.perNode[i], factor);
        if (map.name == "normal") renormalize(map.perNode[i]);
      }
    for (GraphEdge& edge : graph.edges)
      if (edge.from == int(i) && edge.region.size() == size_t(e.width) * size_t(e.width)) {
        std::vector<uint8_t> region(size_t(side) * size_t(side));
        for (int y = 0; y < side; ++y)
          for (int x = 0; x < side; ++x) region[size_t(y) * size_t(side) + size_t(x)] = edge.covers(x / factor, y / factor, e.width);
        edge.region = std::move(region);
      }
    e = magnified(e, factor);
  }
  for (GraphEdge& edge : graph.edges) {
    if (edge.from < 0 || edge.to < 0 || size_t(edge.from) >= octaves.size() || size_t(edge.to) >= octaves.size()) continue;
    const int given = edge.octaves;
    edge.octaves += octaves[size_t(edge.to)] - octaves[size_t(edge.from)];
    if (given >= 1 && edge.octaves < 1) {  // m_to / scale > m_from / 2
      const int from = side >> octaves[size_t(edge.from)], to = side >> octaves[size_t(edge.to)];
      const auto sized = [&](int node, int m) {
        return "'" + graph.names[size_t(node)] + "' (" + std::to_string(m) + "x" + std::to_string(m) + ")";
      };
      throw Error("edge " + sized(edge.from, from) + " -> " + sized(edge.to, to) + ": at scale " +
                  std::to_string(int64_t(1) << given) + " the second spans " + std::to_string(to >> given) +
                  " pixels of the first; exemplars of different sizes can be joined only where the finer spans at "
                  "most half of the coarser (here a scale of at least " + std::to_string(2 * to / from) + ")");
    }
  }
  if (!octaves.empty()) graph.rootMagnification = 1 << octaves[0];
  return graph;
}

int ExemplarGraph::rootOctaves() const { return std::countr_zero(unsigned(rootMagnification)); }

void ExemplarGraph::validate() const {
  if (exemplars.empty()) throw Error("exemplar graph: no exemplars");
  if (names.size() != exemplars.size()) throw Error("exemplar graph: one name per exemplar");
  if (exemplars.size() > size_t(kMaxGraphNodes))
    throw Error("exemplar graph: " + std::to_string(exemplars.size()) + " exemplars, at most " +
                std::to_string(kMaxGraphNodes));
  const int m = side();
  for (size_t i = 0; i < exemplars.size(); ++i) {
    const Image& e = exemplars[i];
    const std::string what = "exemplar '" + names[i] + "'";
    if (e.width != e.height || !std::has_single_bit(unsigned(e.width)) || e.width < kMinGraphExemplarSide ||
        e.width > kMaxGraphExemplarSide)
      throw Error(what + " is " + std::to_string(e.width) + "x" + std::to_string(e.height) +
                  ": graph exemplars must be square, with a power-of-two side from " +
                  std::to_string(kMinGraphExemplarSide) + " to " + std::to_string(kMaxGraphExemplarSide));
    if (e.width != m)
      throw Error(what + " is " + std::to_string(e.width) + " pixels wide, the root '" + names[0] + "' " +
                  std::to_string(m) + ": every exemplar of a graph has the same size");
    if (e.channels < 1 || e.pixels.size() != size_t(e.width) * e.height * e.channels) throw Error(what + " has no pixels");
    if (!std::all_of(e.pixels.begin(), e.pixels.end(), [](float v) { return std::isfinite(v); }))
      throw Error(what + " holds values that are not finite numbers");
  }
  const int levels = std::countr_zero(unsigned(m));  // L
  for (size_t n = 0; n < edges.size(); ++n) {
    const GraphEdge& e = edges[n];
    const int nodes = int(exemplars.size());
    if (e.from < 0 || e.from >= nodes || e.to < 0 || e.to >= nodes)
      throw Error("exemplar graph: edge " + std::to_string(n + 1) + " joins an exemplar that does not exist");
    const std::string what = "edge '" + names[size_t(e.from)] + "' -> '" + names[size_t(e.to)] + "'";
    if (e.octaves < 1)
      throw Error(what + ": its scale ratio must be greater than 1 (a power of two: 2, 4, 8, ...)");
    if (e.octaves > std::min(levels, kMaxGraphEdgeOctaves))
      throw Error(what + ": scale ratio " + std::to_string(int64_t(1) << std::min(e.octaves, 40)) +
                  " is more than the exemplars' " + std::to_string(m) +
                  " pixels: the whole destination would fit in one pixel of the source");
    for (size_t o = 0; o < n; ++o)
      if (edges[o].from == e.from && edges[o].to == e.to && edges[o].octaves == e.octaves)
        throw Error(what + " is given twice");
    if (!e.region.empty() && e.region.size() != size_t(m) * size_t(m))
      throw Error(what + ": its region must have the exemplars' " + std::to_string(m) + "x" + std::to_string(m) + " pixels");
    if (!e.region.empty() && std::none_of(e.region.begin(), e.region.end(), [](uint8_t v) { return v != 0; }))
      throw Error(what + ": its region is empty");
  }
  for (size_t j = 0; j < maps.size(); ++j) {
    const GraphMap& map = maps[j];
    if (std::none_of(std::begin(kGraphMapNames), std::end(kGraphMapNames), [&](const char* n) { return map.name == n; }))
      throw Error("exemplar graph: unknown map '" + map.name + "' (normal, roughness or height)");
    for (size_t o = 0; o < j; ++o)
      if (maps[o].name == map.name) throw Error("exemplar graph: the " + map.name + " map is given twice");
    if (map.perNode.size() != exemplars.size())
      throw Error("exemplar graph: the " + map.name + " map must be given for every exemplar");
    for (size_t i = 0; i < exemplars.size(); ++i) {
      const Image& image = map.perNode[i];
      const std::string what = "the " + map.name + " map of exemplar '" + names[i] + "'";
      if (image.width != m || image.height != m || image.channels < 1)
        throw Error(what + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    ", its exemplar " + std::to_string(m) + "x" + std::to_string(m));
      if (!std::all_of(image.pixels.begin(), image.pixels.end(), [](float v) { return std::isfinite(v); }))
        throw Error(what + " holds values that are not finite numbers");
    }
  }
  std::vector<char> reached(exemplars.size(), 0);
  std::vector<int> todo{0};
  reached[0] = 1;
  while (!todo.empty()) {
    const int n = todo.back();
    todo.pop_back();
    for (const GraphEdge& e : edges)
      if (e.from == n && !reached[size_t(e.to)]) reached[size_t(e.to)] = 1, todo.push_back(e.to);
  }
  for (size_t i = 0; i < exemplars.size(); ++i)
    if (!reached[i]) throw Error("exemplar '" + names[i] + "' is not reached from the root '" + names[0] + "' by any edge");
}

int ExemplarGraph::deepestLevel() const {
  // Longest path (in octaves) from the root; a node on the current path seen again is a cycle.
  std::vector<int> memo(exemplars.size(), -2), onPath(exemplars.size(), 0);
  std::function<int(int)> depth = [&](int n) -> int {
    if (onPath[size_t(n)]) return -1;
    if (memo[size_t(n)] != -2) return memo[size_t(n)];
    onPath[size_t(n)] = 1;
    int best = 0;
    for (const GraphEdge& e : edges) {
      if (e.from != n) continue;
      const int d = depth(e.to);
      if (d < 0) return onPath[size_t(n)] = 0, memo[size_t(n)] = -1;
      best = std::max(best, e.octaves + d);
    }
    onPath[size_t(n)] = 0;
    return memo[size_t(n)] = best;
  };
  const int d = depth(0);
  return d < 0 ? -1 : d + std::countr_zero(unsigned(side()));
}

double graphAnalysisMemoryBytes(int nodes, int side) {
  const double levels = std::countr_zero(unsigned(side)) + 1;
  const double texels = double(nodes) * levels * side * side;
  // stacks and colour atlas (RGB floats twice), appearance, neighborhoods, candidates (at most
  // 1 + 4 per admissible level, a few levels), the search trees.
  return texels * (2 * 3 * sizeof(float) + kAppearanceDims + kNeighborhoodDims + 4 * 17 + 2 * kAppearanceDims * 4) +
         double(kExactAnalysisPixels) * 75 * sizeof(float) * 2;
}

namespace {

// Octaves from the root to each node along the shallowest path (Bellman-Ford: edges are few, all
// of positive length).
std::vector<int32_t> shallowestDepths(const ExemplarGraph& graph) {
  std::vector<int32_t> depth(graph.exemplars.size(), INT32_MAX);
  depth[0] = 0;
  for (size_t round = 0; round < graph.exemplars.size(); ++round)
    for (const GraphEdge& e : graph.edges)
      if (depth[size_t(e.from)] != INT32_MAX)
        depth[size_t(e.to)] = std::min(depth[size_t(e.to)], depth[size_t(e.from)] + e.octaves);
  return depth;
}

} // namespace

const GraphMap* ExemplarGraph::map(const std::string& name) const {
  for (const GraphMap& m : maps)
    if (m.name == name) return &m;
  return nullptr;
}

namespace {

// What a texel at level k shows: the image averaged over its footprint, a box h_k = 2^(L-k) pixels
// wide centred on it (h_k + 1 taps, 1/2 at the two ends), toroidal, separable. The
// Gaussian stack's level k, which synthesis matches, is blurred twice as far (binomial passes at
// 1 .. h_k / 2: sigma about 0.58 h_k against the box's 0.29 h_k); shown, it made every zoom
// blurrier than the next and read as a scale jump. Running sums in double, in a fixed order.
std::vector<Image> footprintStack(const Image& image) {
  const int m = image.width, levels = std::countr_zero(unsigned(m)) + 1, channels = image.channels;
  // One pass along x or y, h even: out = (the sum of the h + 1 values centred on i, less half of
  // the two end values) / h.
  const auto pass = [&](const Image& in, int h, bool alongX) {
    Image out(m, m, channels, in.format);
    const int half = h / 2;
    const auto at = [&](int line, int i, int c) {
      const int j = ((i % m) + m) % m;
      return double(alongX ? in.at(j, line, c) : in.at(line, j, c));
    };
    for (int line = 0; line < m; ++line)
      for (int c = 0; c < channels; ++c) {
        double sum = 0;  // of the h + 1 values centred on i
        for (int o = -half; o <= half; ++o) sum += at(line, o, c);
        for (int i = 0; i < m; ++i) {
          const double ends = 0.5 * (at(line, i - half, c) + at(line, i + half, c));
          (alongX ? out.at(i, line, c) : out.at(line, i, c)) = float((sum - ends) / h);
          sum += at(line, i + half + 1, c) - at(line, i - half, c);
        }
      }
    return out;
  };
  std::vector<Image> stack;
  for (int k = 0; k < levels; ++k) {
    const int h = 1 << (levels - 1 - k);
    stack.push_back(h == 1 ? image : pass(pass(image, h, true), h, false));
  }
  return stack;
}

// Level k of stacks[i] into the m x m tile at (k m, i m).
Image packStacks(const std::vector<std::vector<Image>>& stacks) {
  const Image& first = stacks.front().front();
  const int m = first.width, levels = int(stacks.front().size()), channels = first.channels;
  Image atlas(m * levels, m * int(stacks.size()), channels);
  for (size_t i = 0; i < stacks.size(); ++i)
    for (int k = 0; k < levels; ++k)
      for (int y = 0; y < m; ++y)
        std::memcpy(atlas.pixel(k * m, int(i) * m + y), stacks[i][size_t(k)].pixel(0, y), size_t(m) * channels * sizeof(float));
  return atlas;
}

} // namespace

Image graphMapAtlas(const GraphMap& map) {
  std::vector<std::vector<Image>> stacks;
  for (const Image& image : map.perNode) stacks.push_back(footprintStack(image));
  return packStacks(stacks);
}

std::optional<Image> graphMapAtlas(const ExemplarGraph& graph, const std::string& name) {
  if (const GraphMap* map = graph.map(name)) return graphMapAtlas(*map);
  return std::nullopt;
}

GraphAnalysis analyzeGraph(const ExemplarGraph& graph, const GraphAnalysisOptions& options, const Context& ctx) {
  graph.validate();
  options.validate();
  GraphAnalysis a;
  a.side = graph.side();
  a.levels = std::countr_zero(unsigned(a.side)) + 1;
  a.nodes = int(graph.exemplars.size());
  a.entryLevel = std::min(options.minEntryLevel, a.finestLevel());
  for (const GraphEdge& e : graph.edges)
    if (e.octaves + a.entryLevel > a.finestLevel())
      throw Error("edge '" + graph.names[size_t(e.from)] + "' -> '" + graph.names[size_t(e.to)] + "': a scale of " +
                  std::to_string(1 << e.octaves) + " leaves fewer than " + std::to_string(1 << a.entryLevel) +
                  " texels of '" + graph.names[size_t(e.to)] + "' per side at the finest level of '" +
                  graph.names[size_t(e.from)] + "': use exemplars of at least " +
                  std::to_string(1 << (e.octaves + a.entryLevel)) + " pixels or a smaller scale");
  const int m = a.side, aw = a.atlasWidth();

  Stage stacks(ctx, "stacks");
  std::vector<std::vector<Image>> stack;
  std::vector<std::vector<Image>> shown;
  for (int i = 0; i < a.nodes; ++i) {
    const Image rgb = rgbOf(graph.exemplars[size_t(i)]);
    stack.push_back(gaussianStack(rgb, ExemplarWrap::Tile));
    shown.push_back(footprintStack(rgb));
  }
  a.colors = packStacks(shown);
  stacks.finish();

  Stage appearance(ctx, "appearance");
  appearanceOf(stack, a, appearance.inner());
  a.neighborhood = neighborhoodsOf(a);
  appearance.finish();

  Stage candidates(ctx, "candidates");
  std::vector<std::vector<Tile>> admissibleOf(size_t(a.nodes * a.levels));
  size_t widest = 1;
  a.selfAdmissible.assign(size_t(aw) * size_t(a.atlasHeight()), 1);
  a.moves.assign(a.selfAdmissible.size(), 0);
  for (int i = 0; i < a.nodes; ++i)
    for (int k = 0; k < a.levels; ++k) {
      auto& set = admissibleOf[size_t(i * a.levels + k)] = admissible(graph, a.levels, {i, k}, options.minEntryLevel);
      widest = std::max(widest, set.size());
      for (int y = 0; y < m; ++y)
        for (int x = 0; x < m; ++x) {
          uint32_t& moves = a.moves[size_t(i * m + y) * aw + size_t(k * m + x)];
          moves = 1u << i;
          for (const Tile& t : set)
            if (edgeCovers(graph, {i, k}, t, x, y, m)) moves |= 1u << t.node;
        }
      if (!set.empty() && set.front() == Tile{i, k}) continue;
      // The finest level of a node with edges out: its texels no edge covers stay, as a leaf's.
      for (int y = 0; y < m; ++y)
        for (int x = 0; x < m; ++x)
          a.selfAdmissible[size_t(i * m + y) * aw + size_t(k * m + x)] = std::none_of(
              graph.edges.begin(), graph.edges.end(), [&](const GraphEdge& e) { return e.from == i && e.covers(x, y, m); });
    }
  a.k = 1 + options.candidatesPerLevel * int(widest);
  a.candidates = candidatesOf(graph, a, admissibleOf, options, ctx);
  if (graph.coarseColors) a.transfers = transfersOf(a, ctx);
  candidates.finish();

  a.depth = shallowestDepths(graph);
  a.key = graphAnalysisKey(graph, options);
  return a;
}

uint64_t graphAnalysisKey(const ExemplarGraph& graph, const GraphAnalysisOptions& options) {
  Fnv1a hash;
  hash.add(kGraphCacheVersion);
  for (const Image& e : graph.exemplars) {
    hash.add(e.width);
    hash.add(e.channels);
    hash.add(e.pixels.data(), e.pixels.size() * sizeof(float));
  }
  for (const GraphEdge& e : graph.edges) {
    hash.add(e.from);
    hash.add(e.to);
    hash.add(e.octaves);
    hash.add(e.region.size());
    hash.add(e.region.data(), e.region.size());
  }
  hash.add(options.candidatesPerLevel);
  hash.add(options.minSpread);
  hash.add(options.minEntryLevel);
  hash.add(graph.coarseColors);
  return hash.h;
}

void writeGraphAnalysis(const GraphAnalysis& a, const std::filesystem::path& path) {
  writeFileAtomically(path, [&](std::ostream& out) {
    BinaryWriter w{out};
    w.value(kGraphCacheMagic);
    w.value(kGraphCacheVersion);
    w.value(a.key);
    w.value(a.side);
    w.value(a.nodes);
    w.value(a.k);
    w.value(a.entryLevel);
    w.vec(a.colors.pixels);
    w.vec(a.appearance);
    w.vec(a.neighborhood);
    w.vec(a.candidates);
    w.vec(a.transfers);
    w.value(a.transferAppearance);
    w.vec(a.selfAdmissible);
    w.vec(a.moves);
    w.vec(a.depth);
  });
}

std::optional<GraphAnalysis> readGraphAnalysis(const std::filesystem::path& path, uint64_t expectedKey) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  BinaryReader r{in};
  uint32_t magic = 0, version = 0;
  GraphAnalysis a;
  r.value(magic);
  r.value(version);
  r.value(a.key);
  r.value(a.side);
  r.value(a.nodes);
  r.value(a.k);
  r.value(a.entryLevel);
  if (!r.ok || magic != kGraphCacheMagic || version != kGraphCacheVersion || a.key != expectedKey ||
      a.side < kMinGraphExemplarSide || a.side > kMaxGraphExemplarSide || !std::has_single_bit(unsigned(a.side)) ||
      a.nodes < 1 || a.nodes > std::min(65535 / a.side, kMaxGraphNodes) || a.k < 1 || a.k > 1 + 4 * 64 || a.entryLevel < 0)
    return std::nullopt;
  a.levels = std::countr_zero(unsigned(a.side)) + 1;
  const size_t texels = size_t(a.atlasWidth()) * size_t(a.atlasHeight());
  a.colors = Image(a.atlasWidth(), a.atlasHeight(), 3);
  r.vec(a.colors.pixels, texels * 3);
  r.vec(a.appearance, texels * kAppearanceDims);
  r.vec(a.neighborhood, texels * kNeighborhoodDims);
  r.vec(a.candidates, texels * size_t(a.k));
  r.vec(a.transfers, {0, texels * size_t(a.k) * 3});  // empty without transfers
  r.value(a.transferAppearance);
  r.vec(a.selfAdmissible, texels);
  r.vec(a.moves, texels);
  r.vec(a.depth, size_t(a.nodes));
  if (!r.ok || in.peek() != std::ifstream::traits_type::eof()) return std::nullopt;
  if (a.depth[0] != 0) return std::nullopt;
  for (int32_t d : a.depth)
    if (d < 0 || d > kMaxGraphEdgeOctaves * a.nodes) return std::nullopt;
  for (uint32_t c : a.candidates)
    if (coordU(c) >= uint32_t(a.atlasWidth()) || coordV(c) >= uint32_t(a.atlasHeight())) return std::nullopt;
  return a;
}

GraphAnalysis analyzeGraph(const ExemplarGraph& graph, const GraphAnalysisOptions& options,
                           const AnalysisCacheSettings& cache, const Context& ctx, bool* cached) {
  graph.validate();
  options.validate();
  Stage stage(ctx, "analysis");
  bool fromCache = false;
  GraphAnalysis a = cache.dir ? loadOrCompute(*cache.dir, graphAnalysisKey(graph, options), ".graph",
                                              readGraphAnalysis, [&] { return analyzeGraph(graph, options, stage.inner()); },
                                              writeGraphAnalysis, &fromCache, ctx)
                              : analyzeGraph(graph, options, stage.inner());
  pruneCache(cache);
  stage.finish(fromCache ? "(cached)" : std::to_string(a.nodes) + " exemplars, " + std::to_string(a.levels) + " levels");
  if (cached) *cached = fromCache;
  return a;
}

} // namespace texfab::synthesis
