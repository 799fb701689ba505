// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/fracture/fracture_mesh.h"

#include "core/error.h"
#include "core/hash.h"
#include "geometry/embree_scene.h"
#include "geometry/fracture/measure_solid.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

namespace texfab::geometry {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Candidate k: uniform in the box, or around the impact point.
Eigen::Vector3d candidate(const FractureOptions& o, const BoundingBox& box, uint64_t k) {
  auto u = [&](uint32_t purpose) { return unitInterval(counterHash(o.seed, uint32_t(k), purpose)); };
  if (!o.impact) {
    const Eigen::Vector3d lo = box.min.cast<double>(), hi = box.max.cast<double>();
    return lo + Eigen::Vector3d(u(0), u(1), u(2)).cwiseProduct(hi - lo);
  }
  const double z = 2 * u(0) - 1, phi = 2 * kPi * u(1), s = std::sqrt(std::max(0.0, 1 - z * z));
  const double r = 0.5 * box.diagonal() * u(2) * u(2);
  return *o.impact + r * Eigen::Vector3d(s * std::cos(phi), s * std::sin(phi), z);
}

// The first `pieces` candidates inside the model, drawn in batches (inside tests in parallel).
std::vector<Eigen::Vector3d> sampleSites(const Mesh& solid, const FractureOptions& o, const Context& ctx, size_t& drawn) {
  const EmbreeScene scene(solid);
  const BoundingBox box = boundingBox(solid);
  const size_t batch = std::max<size_t>(256, 4 * size_t(o.pieces)), limit = 200 * size_t(o.pieces) + 100000;
  std::vector<Eigen::Vector3d> sites;
  for (drawn = 0; sites.size() < size_t(o.pieces) && drawn < limit; drawn += batch) {
    std::vector<Eigen::Vector3f> points(batch);
    std::vector<Eigen::Vector3d> exact(batch);
    for (size_t i = 0; i < batch; ++i) {
      exact[i] = candidate(o, box, drawn + i);
      points[i] = exact[i].cast<float>();
      exact[i] = points[i].cast<double>();  // what was tested
    }
    const std::vector<uint8_t> inside = scene.inside(points, ctx);
    for (size_t i = 0; i < batch && sites.size() < size_t(o.pieces); ++i)
      if (inside[i]) sites.push_back(exact[i]);
  }
  if (sites.size() < size_t(o.pieces))
    throw Error("the model holds only " + std::to_string(sites.size()) + " of the " + std::to_string(o.pieces) +
                " sites asked for (" + std::to_string(drawn) + " points drawn): ask for fewer pieces" +
                (o.impact ? " or move the impact point onto the model" : ""));
  return sites;
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[size_t(x)] != x) x = parent[size_t(x)] = parent[size_t(parent[size_t(x)])];
    return x;
  }
};

// The cell across each crack of a one-cell piece, with the crack's area.
std::map<int, double> neighbours(const CellPiece& piece, const CellComplex& cells) {
  std::map<int, double> area;
  const Mesh& m = piece.mesh;
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    if (piece.cutFace[t] < 0) continue;
    const CellFace& f = cells.faces[size_t(piece.cutFace[t])];
    const int other = f.inner == piece.cells.front() ? f.outer : f.inner;
    if (other >= 0) area[other] += 0.5 * double((m.corner(t, 1) - m.corner(t, 0)).cross(m.corner(t, 2) - m.corner(t, 0)).norm());
  }
  return area;
}

// Merges pieces under the minimum volume into the neighbour sharing the most crack area, smallest
// first; returns the merged groups (cells by root).
int mergeSlivers(const Mesh& solid, const CellComplex& cells, std::vector<CellPiece>& pieces, const FractureOptions& o,
                 double modelVolume, const Context& ctx, IntersectCellsReport& report) {
  const double threshold = o.minVolume * modelVolume;
  const size_t n = pieces.size();  // one per cell
  std::vector<double> volume(n);
  for (size_t c = 0; c < n; ++c) volume[c] = measureSolid(pieces[c].mesh).volume;
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return volume[size_t(a)] < volume[size_t(b)]; });
  UnionFind groups(n);
  std::vector<double> groupVolume = volume;
  std::vector<std::vector<int>> members(n);
  for (size_t c = 0; c < n; ++c) members[c] = {int(c)};
  int merged = 0;
  for (int c : order) {
    const int root = groups.find(c);
    if (groupVolume[size_t(root)] >= threshold || pieces[size_t(c)].mesh.triangles.empty()) continue;
    std::map<int, double> shared;  // neighbouring group -> crack area, over the group's cells
    for (int d : members[size_t(root)])
      for (const auto& [cell, area] : neighbours(pieces[size_t(d)], cells))
        if (groups.find(cell) != root) shared[groups.find(cell)] += area;
    if (shared.empty()) continue;
    const int into = std::max_element(shared.begin(), shared.end(), [](const auto& a, const auto& b) { return a.second < b.second; })->first;
    groups.parent[size_t(root)] = into;
    groupVolume[size_t(into)] += groupVolume[size_t(root)];
    members[size_t(into)].insert(members[size_t(into)].end(), members[size_t(root)].begin(), members[size_t(root)].end());
    ++merged;
  }
  if (!merged) return 0;
  std::map<int, std::vector<int>> byRoot;
  for (size_t c = 0; c < n; ++c) byRoot[groups.find(int(c))].push_back(int(c));
  std::vector<std::vector<int>> mergedGroups;
  for (auto& [root, members] : byRoot)
    if (members.size() > 1) mergedGroups.push_back(members);
  std::vector<CellPiece> rebuilt = intersectCells(solid, cells, mergedGroups, o.cut, ctx, &report);
  std::vector<CellPiece> out;
  size_t next = 0;
  for (auto& [root, members] : byRoot)  // ordered by root; re-sorted by first cell below
    out.push_back(members.size() > 1 ? std::move(rebuilt[next++]) : std::move(pieces[size_t(members.front())]));
  std::sort(out.begin(), out.end(), [](const CellPiece& a, const CellPiece& b) { return a.cells.front() < b.cells.front(); });
  pieces = std::move(out);
  return merged;
}

} // namespace

void FractureOptions::validate() const {
  if (pieces < 1 || pieces > kMaxFracturePieces)
    throw Error("pieces must be in [1, " + std::to_string(kMaxFracturePieces) + "], got " + std::to_string(pieces));
  if (!(roughness >= 0 && roughness <= 0.25)) throw Error("roughness must be in [0, 0.25]");
  if (!(minVolume >= 0 && minVolume < 0.5)) throw Error("min volume must be a fraction of the model's volume in [0, 0.5)");
  if (impact && !impact->allFinite()) throw Error("the impact point must be finite");
}

FractureResult fractureMesh(const Mesh& solid, const FractureOptions& o, const Context& ctx) {
  o.validate();
  FractureResult r;
  Stage sitesStage(ctx, "sites");
  r.sites = sampleSites(solid, o, ctx, r.report.candidates);
  r.report.sites = int(r.sites.size());
  sitesStage.finish(std::to_string(r.sites.size()) + " sites inside the model");

  Stage cellsStage(ctx, "cells");
  const BoundingBox box = boundingBox(solid);
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.01 * box.diagonal() + 1e-6);
  const Eigen::AlignedBox3d bounds(box.min.cast<double>() - margin, box.max.cast<double>() + margin);
  r.cells = voronoiCells(r.sites, bounds, {o.roughness, o.seed}, &r.report.cells);
  cellsStage.finish(std::to_string(r.report.cells.faces) + " cell faces");

  std::vector<std::vector<int>> groups(r.sites.size());
  for (size_t c = 0; c < groups.size(); ++c) groups[c] = {int(c)};
  r.pieces = intersectCells(solid, r.cells, groups, o.cut, ctx, &r.report.intersect);
  r.report.modelVolume = measureSolid(solid).volume;
  if (o.minVolume > 0) {
    Stage mergeStage(ctx, "merge");
    r.report.merged = mergeSlivers(solid, r.cells, r.pieces, o, r.report.modelVolume, ctx.nested(), r.report.intersect);
    mergeStage.finish(std::to_string(r.report.merged) + " pieces merged");
  }
  std::erase_if(r.pieces, [](const CellPiece& p) { return p.mesh.triangles.empty(); });
  return r;
}

} // namespace texfab::geometry
