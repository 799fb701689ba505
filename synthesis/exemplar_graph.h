// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Exemplar graphs: several exemplars at different scales, joined by edges that say which exemplar
// details which, and their analysis for multiscale synthesis (synthesize_graph.h).
//
// Based on:
//   C. Han, E. Risser, R. Ramamoorthi, E. Grinspun. Multiscale texture synthesis. SIGGRAPH 2008;
//     C. Han, PhD thesis, Columbia 2011, ch. 4 (the exemplar graph) and §5.2 (Gaussian stacks,
//     admissible candidates, k-coherence across exemplars, the superexemplar's packed levels).
// Notes: ../shared/notes/han-multiscale-notes.md §2-3; docs/exemplar-graphs.md.
//
// The analysis packs every Gaussian-stack level of every exemplar into one atlas (the thesis'
// §5.4 packing, u' = m e + u, in two dimensions): level k of node i is the m x m tile at
// (k m, i m). A synthesis coordinate is a packed atlas coordinate (coord_map.h), so it names an
// exemplar, a stack level and a position at once, the thesis' pointer (i, k, u).
//
// Deviations from the thesis, on purpose:
//   * appearance vectors as in texfab's single-exemplar analysis (exemplar_analysis.h: Gaussian-
//     weighted 5x5 neighborhoods at the level's spacing, 8-D PCA, int8), with one PCA basis for
//     the whole graph instead of one per synthesis level, so that every pair of levels compares in
//     one space; k-nearest candidates among those vectors, not among full neighborhoods;
//   * candidates: the texel itself (where admissible), then the best of each admissible level in
//     turn, so that every edge offers a way down at every level (the thesis keeps the K = 2 best
//     over all admissible levels, which a self-similar exemplar fills with its own texels);
//   * an edge admits only its destination's levels of 8 texels per side or more (minEntryLevel);
//   * the finest level of an exemplar with no outgoing edge (a leaf) is admissible to itself, so
//     that its texture can be synthesized down to its own pixels; beyond them it is magnified;
//   * an edge's region (the thesis' edges detail a whole exemplar) restricts it to the texels of its
//     source inside the region, at every stack level; a finest-level texel that no edge covers
//     stays, as a leaf's does;
//   * exemplars are toroidal (coordinates wrap in their tile), square, all of one power-of-two
//     side m, as the thesis assumes for exposition (withOneSide magnifies smaller ones to it);
//   * inconsistency correction (§5.3) with the thesis' constant RGB offsets b, fitted per candidate
//     as the mean 5x5 difference; k-nearest candidates are chosen without them, as in the thesis.

#include "core/context.h"
#include "core/image.h"
#include "synthesis/analysis_cache.h"
#include "synthesis/exemplar_analysis.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace texfab::synthesis {

/// An edge (i, j, r) of the thesis: a pixel of exemplar `from` spans 2^octaves pixels of exemplar
/// `to`; `to` details `from` at that scale. from == to makes a self-similar (infinitely zoomable)
/// exemplar.
struct GraphEdge {
  GraphEdge() = default;
  GraphEdge(int from_, int to_, int octaves_, std::vector<uint8_t> region_ = {})
      : from(from_), to(to_), octaves(octaves_), region(std::move(region_)) {}

  int from = 0;
  int to = 0;
  int octaves = 1;  ///< r >= 1: the scale ratio is 2^r
  /// The region of `from` this edge details: side x side flags, row-major, 1 = in; empty: all of it.
  std::vector<uint8_t> region;

  /// Whether pixel (x, y) of `from` (an exemplar `side` pixels wide) is in the region.
  bool covers(int x, int y, int side) const { return region.empty() || region[size_t(y) * size_t(side) + size_t(x)]; }
};

/// Largest side of a graph exemplar, and largest r of an edge.
inline constexpr int kMaxGraphExemplarSide = 512;
inline constexpr int kMaxGraphEdgeOctaves = 12;
/// Smallest side: 8 pixels, so that every level has a few distinct texels.
inline constexpr int kMinGraphExemplarSide = 8;
/// Most exemplars in a graph (GraphAnalysis::moves holds a bit per node).
inline constexpr int kMaxGraphNodes = 32;

/// A companion map of every exemplar of a graph (normal, roughness, height), resolved through the
/// synthesized coordinates like the colours (graphMapAtlas).
struct GraphMap {
  std::string name;            ///< one of kGraphMapNames
  std::vector<Image> perNode;  ///< node i's map, the size of its exemplar
};
inline constexpr const char* kGraphMapNames[] = {"normal", "roughness", "height"};

struct ExemplarGraph {
  std::vector<std::string> names;  ///< one per node, for messages
  std::vector<Image> exemplars;    ///< node i's exemplar; node 0 is the root (the coarsest)
  std::vector<GraphEdge> edges;
  std::vector<GraphMap> maps;      ///< companion maps (each for every node), none by default
  /// Thesis §5.3's inconsistency correction: a finer exemplar takes on the colours of the coarser
  /// one it details (a colour offset per candidate in another exemplar, carried per texel). False:
  /// every exemplar shows its own colours.
  bool coarseColors = true;
  /// How many pixels of exemplars[0] one pixel of the root as the user gave it spans (a power of
  /// two): more than 1 where withOneSide magnified the root. Zooms and texture scales given in root
  /// pixels are multiplied by it.
  int rootMagnification = 1;
  /// log2(rootMagnification): octaves to take from a zoom given in root pixels as given.
  int rootOctaves() const;

  /// The map named `name`, or null.
  const GraphMap* map(const std::string& name) const;

  int side() const { return exemplars.empty() ? 0 : exemplars.front().width; }
  /// Throws texfab::Error, naming the node or edge, unless: at least one node; every exemplar
  /// square, of one power-of-two side in [kMinGraphExemplarSide, kMaxGraphExemplarSide], finite;
  /// at most kMaxGraphNodes;
  /// edges between existing nodes with 1 <= octaves <= kMaxGraphEdgeOctaves, no edge twice, a
  /// region (where given) of side² flags with at least one set; every node reachable from the root;
  /// maps of known names, each once, with a finite image of its exemplar's size for every node.
  void validate() const;
  /// The finest synthesis level any output texel can need: the deepest path's total octaves plus
  /// the exemplars' levels; -1 when a cycle makes the texture infinitely deep.
  int deepestLevel() const;
};

/// `graph` with exemplars of different sizes magnified to the largest side M, so that a graph may
/// mix sizes (the thesis assumes one size for exposition): exemplar i, m_i pixels wide, is
/// magnified M / m_i times (each pixel a plane with its central differences' slopes, wrapping, so
/// that every block averages to its pixel; its companion maps too, normals renormalized; the
/// regions of its edges by nearest pixel), and every edge's octaves change by the log2 of the
/// ratio of its ends' magnifications, so that every pixel keeps its size; rootMagnification records
/// the root's. Magnification adds no detail: a magnified exemplar's finest levels are smooth, as a
/// leaf's are beyond its pixels. Exemplars that are not square with a power-of-two side in
/// [kMinGraphExemplarSide, kMaxGraphExemplarSide] are left for validate() to name. Throws
/// texfab::Error, naming the edge, where an edge would no longer lead to a finer scale.
ExemplarGraph withOneSide(ExemplarGraph graph);

struct GraphAnalysisOptions {
  int candidatesPerLevel = 2;  ///< best matches kept from each admissible level; 1..4
  float minSpread = 0.05f;     ///< candidates from one level lie at least max(2, minSpread * m) apart
  /// An edge leads only to destination levels with at least 2^minEntryLevel texels per side (the
  /// thesis admits any level >= 0): coarser ones are a few blurred texels that cannot hold the
  /// source's structure at that scale, and texels that entered them showed flat blobs.
  int minEntryLevel = 3;
  void validate() const;
};

/// Transfer offsets (GraphAnalysis::transfers, synthesis' per-texel R) are integers in units of
/// 1/kTransferOne of a colour value.
inline constexpr int kTransferOne = 4096;
/// GraphAnalysis::transferAppearance's fixed point: 2^-kTransferAppearanceBits appearance units.
inline constexpr int kTransferAppearanceBits = 16;

/// What graph synthesis reads: the packed stack levels and their tables.
struct GraphAnalysis {
  int side = 0;        ///< m
  int levels = 0;      ///< L + 1 stack levels per exemplar
  int nodes = 0;
  int k = 0;           ///< candidates per atlas texel
  int entryLevel = 0;  ///< the coarsest level an edge leads to (GraphAnalysisOptions::minEntryLevel)
  /// What texels show, levels*m x nodes*m, RGB: tile (k, i) holds exemplar i averaged over the
  /// footprint of a level-k texel (a box h_k wide), not the blurrier Gaussian stack it is matched by.
  Image colors;
  std::vector<int8_t> appearance;    ///< per atlas texel, kAppearanceDims
  std::vector<int8_t> neighborhood;  ///< per atlas texel, kNeighborhoodDims (diagonals at the level's spacing)
  std::vector<uint32_t> candidates;  ///< per atlas texel, k packed atlas coordinates
  /// Thesis §5.3's transfer functions, per atlas texel and candidate slot (k * 3, RGB): the offset b
  /// that takes the candidate's colours to the texel's, the mean difference of their 5x5
  /// neighbourhoods at their levels' spacings (0 within an exemplar). Empty when every b is 0 or
  /// correction is off (ExemplarGraph::coarseColors).
  std::vector<int16_t> transfers;
  /// How an RGB offset moves appearance vectors: row d, column c is the change of dimension d per
  /// transfer unit of channel c, in 2^-kTransferAppearanceBits (the appearance projection is linear
  /// in the patch's colours).
  std::array<int32_t, kAppearanceDims * 3> transferAppearance{};
  /// Per atlas texel: may a texel keep its level while synthesis goes finer (every level but the
  /// finest; at the finest, texels of a leaf and texels no edge's region covers).
  std::vector<uint8_t> selfAdmissible;
  /// Per atlas texel: bit j set where a texel pointing there may take a candidate in node j: its own
  /// node, and the destinations of the edges that cover it (thesis §5.2.1.2: candidates lie in the
  /// texel's admissible set, whichever neighbour offers them).
  std::vector<uint32_t> moves;
  /// Per node: the octaves from the root along the shallowest path of edges (the root's 0), so
  /// that a pixel of node i spans 2^-depth[i] root pixels.
  std::vector<int32_t> depth;
  uint64_t key = 0;

  int atlasWidth() const { return side * levels; }
  int atlasHeight() const { return side * nodes; }
  int finestLevel() const { return levels - 1; }
  /// h_k = 2^(L-k), in pixels of the level's own exemplar.
  int spacing(int level) const { return 1 << (finestLevel() - level); }
};

/// Analyses `graph` (validated first). Pure: a function of the exemplars, the edges and the
/// options. Reports the stages "stacks", "appearance" and "candidates" through ctx.
GraphAnalysis analyzeGraph(const ExemplarGraph& graph, const GraphAnalysisOptions& options = {},
                           const Context& ctx = {});

/// A companion map packed as GraphAnalysis::colors packs the colours (level k of node i is the m x m
/// tile at (k m, i m), node i's map averaged over a level-k footprint), with the map's channels: what a
/// synthesized coordinate reads (applyCoords, sampleSurfaceGraph), so that the map follows the
/// colours through every exemplar and level.
Image graphMapAtlas(const GraphMap& map);
/// graphMapAtlas of the graph's map `name`, or nothing where the graph gives none.
std::optional<Image> graphMapAtlas(const ExemplarGraph& graph, const std::string& name);

/// The cache key of (graph, options).
uint64_t graphAnalysisKey(const ExemplarGraph& graph, const GraphAnalysisOptions& options);

/// analyzeGraph through the analysis cache (`<key>.graph` in cache.dir): read when present and
/// valid (a damaged or foreign file is recomputed, never trusted), else analysed and stored, the
/// cache then pruned. `cached` (optional) tells which. Reports one "analysis" stage.
GraphAnalysis analyzeGraph(const ExemplarGraph& graph, const GraphAnalysisOptions& options,
                           const AnalysisCacheSettings& cache, const Context& ctx, bool* cached = nullptr);

/// Writes / reads one cached graph analysis; readGraphAnalysis returns nothing for a missing,
/// foreign or damaged file.
void writeGraphAnalysis(const GraphAnalysis& analysis, const std::filesystem::path& path);
std::optional<GraphAnalysis> readGraphAnalysis(const std::filesystem::path& path, uint64_t expectedKey);

/// Peak memory of analyzeGraph, in bytes (an upper bound).
double graphAnalysisMemoryBytes(int nodes, int side);

} // namespace texfab::synthesis
