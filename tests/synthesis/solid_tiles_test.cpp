// SPDX-License-Identifier: GPL-3.0-or-later
// Solid texture tiles (solid_tiles.h): the layout (every voxel one element, faces shared by
// construction), determinism of the optimization and of evaluation (threads, subsets, order), the
// seam across tile faces, slice quality against lazy synthesis and a shuffled image, the cache,
// and bad input.
#include "core/error.h"
#include "core/hash.h"
#include "procedural_solids.h"
#include "solid_test_support.h"
#include "synthesis/coord_map.h"
#include "synthesis/quality_measures.h"
#include "synthesis/solid_analysis.h"
#include "synthesis/solid_tile_measures.h"
#include "synthesis/solid_tiles.h"
#include "synthesis/synthesize_solid.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

namespace texfab::synthesis {
namespace {

using test::boxVoxels;
using test::marble;

namespace fs = std::filesystem;
using test::TempDir;

const SolidAnalysis& analysis64() {
  static const SolidAnalysis a = [] {
    const Image e = marble(64, 8, 8);
    return analyzeSolid(e, e, e, {}, Context{.threads = 2});
  }();
  return a;
}

SolidTileOptions smallOptions() {
  SolidTileOptions o;
  o.tileSide = 8;
  o.iterations = 2;
  o.finestIterations = 2;
  return o;
}

// Tiles of 16 voxels (two levels: 8, then 16), the optimization on 64^3 arrangements: a few seconds.
SolidTileOptions options16() {
  SolidTileOptions o;
  o.tileSide = 16;
  return o;
}

const SolidTileSet& tiles64() {
  static const SolidTileSet t = buildSolidTiles(analysis64(), options16(), Context{.threads = 2});
  return t;
}

TEST(SolidTileLayout, EveryVoxelIsOneElementAndEveryElementIsReachable) {
  for (const int variants : {2, 3}) {
    const SolidTileLayout layout(8, variants);
    const size_t tiles = size_t(std::pow(variants, 6));
    EXPECT_EQ(layout.elements, 2u + 6u * 7 + 3u * size_t(variants) * 49 + tiles * 343);
    std::vector<int> seen(layout.elements, 0);
    for (uint32_t tile = 0; tile < tiles; ++tile)  // every tile, edge and corner variant of a cell
      for (uint32_t edges = 0; edges < 16; ++edges)
        for (int z = 0; z < 8; ++z)
          for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
              const size_t e = layout.element(x, y, z, tile | edges << 10);
              ASSERT_LT(e, layout.elements);
              ++seen[e];
            }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 0), 0) << variants << " variants";
  }
}

TEST(SolidTileLayout, NeighbouringCellsShareTheirFace) {
  // Faces match by construction: the face plane x = 8 belongs to cell 1 (its start), and cell 0
  // (whose end it is) chose its interior by that face's variant.
  for (const uint32_t variants : {2u, 3u}) {
    const SolidTileLayout layout(8, int(variants));
    auto variant = [&](int kind, int64_t x, int64_t y, int64_t z) {
      const uint32_t h = voxelHash(5, 0, int32_t(x), int32_t(y), int32_t(z), uint32_t(kind));
      return kind < 3 ? h % variants : h & 1u;
    };
    for (int64_t y = 0; y < 8; ++y) {
      const uint32_t left = layout.cellCode(0, y, 0, variant) & 1023u;
      const uint32_t right = layout.cellCode(1, y, 0, variant) & 1023u;
      EXPECT_EQ((left / variants) % variants, right % variants);  // one's end face is the other's start
    }
  }
}

TEST(SolidTileLayout, NegativePositionsFallInTheirOwnCells) {
  const SolidTileLayout layout(4);
  auto zero = [](int, int64_t, int64_t, int64_t) { return 0u; };
  // -4 is a face plane (local 0) of cell -1; -1 is local 3 of cell -1.
  EXPECT_LT(layout.element(-4, 1, 1, zero), layout.interiors);
  EXPECT_GE(layout.element(-1, 1, 1, zero), layout.interiors);
  EXPECT_EQ(layout.element(-3, -3, -3, zero), layout.element(1, 1, 1, zero));
}

TEST(SolidTiles, OptimizationIsTheSameOnOneAndTwoThreads) {
  const SolidTileSet one = buildSolidTiles(analysis64(), smallOptions(), Context{.threads = 1});
  const SolidTileSet two = buildSolidTiles(analysis64(), smallOptions(), Context{.threads = 2});
  ASSERT_EQ(one.elements.size(), one.layout.elements);
  EXPECT_TRUE(one.elements == two.elements);
  for (const Triple& t : one.elements)
    for (uint32_t c : t) ASSERT_TRUE(coordU(c) < 64u && coordV(c) < 64u);
  // Through a second level too (upsampling, the faces carried into both sides of each).
  const SolidTileSet upsampled = buildSolidTiles(analysis64(), options16(), Context{.threads = 1});
  EXPECT_TRUE(upsampled.elements == tiles64().elements);
}

TEST(SolidTiles, EvaluationIsAPureFunctionOfPosition) {
  const SolidTileSet& t = tiles64();
  const VoxelBox box{-21, 37, -5, 40, 30, 20};
  std::vector<Triple> fromBox(size_t(box.count()));
  evaluateSolidTilesBox(t, 3, box, fromBox, Context{.threads = 2});
  // The same voxels in reverse order, one thread, as a list; and a sub-box.
  std::vector<Voxel> voxels = boxVoxels(box);
  std::reverse(voxels.begin(), voxels.end());
  std::vector<Triple> fromList(voxels.size());
  evaluateSolidTiles(t, 3, voxels, fromList, Context{.threads = 1});
  std::reverse(fromList.begin(), fromList.end());
  EXPECT_TRUE(fromBox == fromList);
  const VoxelBox sub{-3, 40, 0, 7, 5, 3};
  std::vector<Triple> fromSub(size_t(sub.count()));
  evaluateSolidTilesBox(t, 3, sub, fromSub);
  size_t i = 0;
  for (int z = 0; z < sub.nz; ++z)
    for (int y = 0; y < sub.ny; ++y)
      for (int x = 0; x < sub.nx; ++x, ++i) {
        const size_t j = (size_t(sub.z + z - box.z) * size_t(box.ny) + size_t(sub.y + y - box.y)) * size_t(box.nx) +
                         size_t(sub.x + x - box.x);
        ASSERT_EQ(fromSub[i], fromBox[j]);
      }
  // Another seed arranges the tiles differently.
  std::vector<Triple> seed4(size_t(box.count()));
  evaluateSolidTilesBox(t, 4, box, seed4);
  EXPECT_FALSE(seed4 == fromBox);
}

TEST(SolidTiles, SynthesizeSolidReadsTheTilesWithTheTilesMethod) {
  SolidAnalysis a = analysis64();
  SolidSynthesisOptions o;
  o.method = SolidMethod::Tiles;
  o.seed = 9;
  const VoxelBox box{5, 6, 7, 8, 8, 8};
  EXPECT_THROW(synthesizeSolidBox(a, box, o), Error);  // no tile set yet
  a.tiles = std::make_shared<const SolidTileSet>(tiles64());
  const SolidSynthesisResult r = synthesizeSolidBox(a, box, o);
  std::vector<Triple> expected(size_t(box.count()));
  evaluateSolidTilesBox(tiles64(), 9, box, expected);
  EXPECT_TRUE(r.triples == expected);
  EXPECT_EQ(synthesizeSolid(a, boxVoxels(box), o).triples, expected);
  EXPECT_EQ(r.voxelsSynthesized(), 0);
}

// A z = k slice, n x n, as colours: from the tile set (seed 1), or by lazy synthesis.
std::vector<Voxel> zSlice(int64_t k, int n) {
  std::vector<Voxel> voxels;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) voxels.push_back({x + 100, y + 200, k});
  return voxels;
}

Image colors(const std::vector<Triple>& triples, const Image& ex, int n) {
  std::vector<float> values;
  solidColors(triples, ex, ex, ex, values);
  Image im(n, n, solidColorChannels(ex, ex, ex));
  im.pixels = std::move(values);
  return im;
}

Image tileSlice(const SolidTileSet& t, const Image& ex, int64_t k, int n) {
  const std::vector<Voxel> voxels = zSlice(k, n);
  std::vector<Triple> triples(voxels.size());
  evaluateSolidTiles(t, 1, voxels, triples);
  return colors(triples, ex, n);
}

// The mean colour step into and out of a face plane over the same inside a tile, the largest over
// three axis-aligned slices of 8 x 8 tiles: faces are shared, so a face should look like any other
// plane.
double seamRatio(const SolidTileSet& t, const Image& ex) { return measureSolidTileLattice(t, ex, ex, ex).seamRatio; }

TEST(SolidTiles, NoSeamAcrossTileFaces) {
  const double ratio = seamRatio(tiles64(), marble(64, 8, 8));
  RecordProperty("seam_ratio", std::to_string(ratio));
  EXPECT_LT(ratio, 1.1) << "seam ratio " << ratio;  // the target
}

TEST(SolidTiles, SeamAcrossTileFacesOfASmoothExemplarIsBounded) {
  // Clouds whose features are as wide as a tile, where a seam shows most. Upsampling a tile's last
  // voxels from its own interior gave 1.89 here, a visible grid; from the next face, 1.31. What
  // is left is a rougher band along the faces (docs/measurements.md#seams-at-the-tiles-faces): the
  // bound holds that gain, not yet the 1.1.
  const Image ex = test::ProceduralSolid("clouds").exemplar(64);
  const SolidAnalysis a = analyzeSolid(ex, ex, ex, {}, Context{.threads = 2});
  const double ratio = seamRatio(buildSolidTiles(a, options16(), Context{.threads = 2}), ex);
  RecordProperty("seam_ratio", std::to_string(ratio));
  EXPECT_LT(ratio, 1.45) << "seam ratio " << ratio;
}

TEST(SolidTiles, SlicesMatchTheExemplarAtLeastAsWellAsLazySynthesis) {
  const SolidTileSet& t = tiles64();
  const Image ex = marble(64, 8, 8);
  const int n = 128;
  const Image tiles = tileSlice(t, ex, 45, n);
  const Image lazy = colors(synthesizeSolid(analysis64(), zSlice(45, n), {}).triples, ex, n);
  const double fTiles = neighborhoodFidelity(tiles, ex), fLazy = neighborhoodFidelity(lazy, ex);
  const double cTiles = neighborhoodCompleteness(tiles, ex), cLazy = neighborhoodCompleteness(lazy, ex);
  const double kTiles = contrastRatio(tiles, ex), kLazy = contrastRatio(lazy, ex);
  const int period = t.layout.side;
  const double lTiles = shiftedSelfCorrelation(tiles, period, period);
  const double lLazy = shiftedSelfCorrelation(lazy, period, period);
  RecordProperty("fidelity", std::to_string(fTiles) + " (lazy " + std::to_string(fLazy) + ")");
  RecordProperty("completeness", std::to_string(cTiles) + " (lazy " + std::to_string(cLazy) + ")");
  RecordProperty("contrast", std::to_string(kTiles) + " (lazy " + std::to_string(kLazy) + ")");
  RecordProperty("lattice", std::to_string(lTiles) + " (lazy " + std::to_string(lLazy) + ")");
  EXPECT_LT(fTiles, fLazy);
  EXPECT_LT(cTiles, 1.1 * cLazy);
  EXPECT_GT(kTiles, 0.9 * kLazy);
  // The lattice: correlation at the tile period at most a little above that of a texture without one.
  EXPECT_LT(lTiles, lLazy + 0.3) << "tiles " << lTiles << ", lazy " << lLazy;
}

TEST(SolidTiles, CacheRoundTripsAndRefusesDamagedFiles) {
  const TempDir dir;
  const SolidTileOptions o = smallOptions();
  bool cached = true;
  const SolidTileSet built = buildSolidTilesCached(analysis64(), o, dir.path(), {}, &cached);
  EXPECT_FALSE(cached);
  const SolidTileSet read = buildSolidTilesCached(analysis64(), o, dir.path(), {}, &cached);
  EXPECT_TRUE(cached);
  EXPECT_TRUE(read.elements == built.elements);
  char name[40];
  std::snprintf(name, sizeof name, "%016llx.tiles", static_cast<unsigned long long>(built.key));
  const fs::path file = dir.path() / name;
  ASSERT_TRUE(fs::exists(file));
  EXPECT_FALSE(readSolidTiles(file, built.key + 1));  // another analysis or options
  fs::resize_file(file, fs::file_size(file) - 5);     // truncated
  EXPECT_FALSE(readSolidTiles(file, built.key));
  writeSolidTiles(built, file);
  {  // a coordinate outside the exemplar
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-4, std::ios::end);
    const uint32_t bad = packCoord(1000, 1000);
    f.write(reinterpret_cast<const char*>(&bad), sizeof bad);
  }
  EXPECT_FALSE(readSolidTiles(file, built.key));
  const SolidTileSet again = buildSolidTilesCached(analysis64(), o, dir.path(), {}, &cached);
  EXPECT_FALSE(cached);  // recomputed, never trusted
  EXPECT_TRUE(again.elements == built.elements);
}

TEST(SolidTiles, BadOptionsAreRefusedByName) {
  SolidTileOptions o;
  o.tileSide = 4;
  EXPECT_THROW(buildSolidTiles(analysis64(), o), Error);
  o = {};
  o.tileSide = 12;  // not a power of two
  try {
    buildSolidTiles(analysis64(), o);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tile side must be 8, 16, 32 or 64"), std::string::npos) << e.what();
  }
  o = {};
  o.faceVariants = 4;
  EXPECT_THROW(o.validate(), Error);
  o = {};
  o.arrangementCopies = 3;
  EXPECT_THROW(o.validate(), Error);
  o = {};
  o.histogramWeight = std::nanf("");
  EXPECT_THROW(o.validate(), Error);
}

} // namespace
} // namespace texfab::synthesis
