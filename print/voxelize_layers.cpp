// SPDX-License-Identifier: GPL-3.0-or-later
// Based on: the scanline polygon fill with the non-zero winding rule (e.g. Foley et al.,
//   "Computer Graphics: Principles and Practice", 2nd ed., §3.6), applied to the contours that a
//   plane cuts from a closed triangle mesh (as slicers do), with half-open rules for vertices on the
//   plane and segment ends on a row in place of epsilons; the distance from a point to a triangle
//   as the union of its slab and its edge capsules (Ericson, "Real-Time Collision Detection",
//   §5.1.5 gives the closest-point form).
#include "print/voxelize_layers.h"

#include "core/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>

namespace texfab::print {

namespace {

constexpr int kChunkLayers = 16;  // layers sharing one list of candidate triangles

using Vec3 = Eigen::Vector3d;

struct Bounds {
  double xmin, xmax, ymin, ymax, zmin, zmax;
};

// Where a row's scanline enters and leaves the solid (mm): both points lie on the surface.
struct Run {
  double enter, leave;
};

// A segment of the layer's contour crossing a row of voxel centres.
struct Crossing {
  int32_t row;  // grid row index (y), not image row
  int8_t winding;
  double x;     // mm from the grid's origin
};

// The first voxel index whose centre ((i + 0.5) * pitch) is at or beyond `coordinate`.
int64_t ceilIndex(double coordinate, double pitch) { return int64_t(std::ceil(coordinate / pitch - 0.5)); }

// The point where edge (p, q) meets the plane z, computed from the two positions in lexicographic
// order, so both triangles of the edge get the same bits.
Vec3 cutEdge(const Vec3& p, const Vec3& q, double z) {
  const bool ordered = std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
  const Vec3& a = ordered ? p : q;
  const Vec3& b = ordered ? q : p;
  const double t = (z - a.z()) / (b.z() - a.z());
  return {a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y()), z};
}

// ---- shell geometry ------------------------------------------------------------------------------

// A triangle prepared for distance queries along rows (lines parallel to x): unit edge directions
// and lengths, unit normal, in-plane edge normals pointing inwards, and the reciprocals the
// interval computations divide by.
struct TriangleFrame {
  Vec3 v[3], d[3], inward[3], normal;
  double length[3];
  double invDx[3], invA[3];    // 1 / d.x (0 if d.x = 0), 1 / (1 - d.x^2) (0 if an edge runs along x)
  double invNx, invInwardX[3]; // the same for the slab's planes
  bool flat;                   // zero area: no slab, only the capsules

  TriangleFrame(const Vec3& a, const Vec3& b, const Vec3& c) : v{a, b, c} {
    auto inverse = [](double x) { return x != 0 ? 1.0 / x : 0.0; };
    const Vec3 n = (b - a).cross(c - a);
    flat = !(n.norm() > 0);
    normal = flat ? Vec3::Zero() : Vec3(n.normalized());
    invNx = inverse(normal.x());
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = v[(k + 1) % 3] - v[k];
      length[k] = e.norm();
      d[k] = length[k] > 0 ? Vec3(e / length[k]) : Vec3::Zero();
      inward[k] = normal.cross(d[k]);
      invDx[k] = inverse(d[k].x());
      const double across = 1 - d[k].x() * d[k].x();
      invA[k] = across > 1e-12 ? 1.0 / across : 0.0;
      invInwardX[k] = inverse(inward[k].x());
    }
  }
};

// The hull of intervals added to it (empty ones ignored).
struct Hull {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double a, double b) {
    if (!(a < b)) return;
    lo = std::min(lo, a);
    hi = std::max(hi, b);
  }
};

// Narrows [lo, hi] to the x where lower < alpha * x + beta < upper (invAlpha = 1 / alpha, or 0
// when alpha is 0).
void clipLinear(double alpha, double invAlpha, double beta, double lower, double upper, double& lo, double& hi) {
  if (alpha == 0) {
    if (!(beta > lower && beta < upper)) hi = lo - 1;
    return;
  }
  double a = (lower - beta) * invAlpha, b = (upper - beta) * invAlpha;
  if (a > b) std::swap(a, b);
  lo = std::max(lo, a);
  hi = std::min(hi, b);
}

// The x interval of the line (x, y, z) within distance s of the triangle (open; empty: lo >= hi).
// The triangle swept by a ball is convex and is the union of its slab (points projecting into the
// triangle, |height| < s) and the capsules around its edges, so the interval is the hull of theirs.
Hull nearInterval(const TriangleFrame& f, double y, double z, double s) {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  Hull hull;
  const double s2 = s * s;
  for (int k = 0; k < 3; ++k) {
    const Vec3& v = f.v[k];
    const double eta = y - v.y(), zeta = z - v.z();
    if (const double q = s2 - eta * eta - zeta * zeta; q > 0) hull.add(v.x() - std::sqrt(q), v.x() + std::sqrt(q));
    if (f.length[k] == 0) continue;
    // Cylinder around the edge's line: A tau^2 - 2 dx m tau + C < 0 with tau = x - v.x, clipped to
    // the slab 0 < dx tau + m < length.
    const Vec3& d = f.d[k];
    const double m = d.y() * eta + d.z() * zeta;
    const double c = eta * eta + zeta * zeta - m * m - s2;
    double lo = -kInfinity, hi = kInfinity;
    if (f.invA[k] > 0) {
      const double disc = d.x() * d.x() * m * m - (1 - d.x() * d.x()) * c;
      if (disc <= 0) continue;
      const double root = std::sqrt(disc);
      lo = (d.x() * m - root) * f.invA[k];
      hi = (d.x() * m + root) * f.invA[k];
    } else if (c >= 0) {
      continue;
    }
    clipLinear(d.x(), f.invDx[k], m, 0, f.length[k], lo, hi);
    hull.add(v.x() + lo, v.x() + hi);
  }
  if (!f.flat) {
    const Vec3& n = f.normal;
    double lo = -kInfinity, hi = kInfinity;
    const Vec3& a = f.v[0];
    clipLinear(n.x(), f.invNx, n.y() * (y - a.y()) + n.z() * (z - a.z()) - n.x() * a.x(), -s, s, lo, hi);
    for (int k = 0; k < 3 && lo < hi; ++k) {
      const Vec3 &e = f.inward[k], &v = f.v[k];
      clipLinear(e.x(), f.invInwardX[k], e.y() * (y - v.y()) + e.z() * (z - v.z()) - e.x() * v.x(), 0, kInfinity, lo, hi);
    }
    hull.add(lo, hi);
  }
  return hull;
}

// Bit rows: one bit per voxel of a row.
void setBits(uint64_t* row, int64_t begin, int64_t end) {
  for (int64_t i = begin; i < end;) {
    const int64_t word = i >> 6, bit = i & 63, n = std::min<int64_t>(64 - bit, end - i);
    row[word] |= (n == 64 ? ~uint64_t(0) : ((uint64_t(1) << n) - 1)) << bit;
    i += n;
  }
}

// The first index in [from, to) whose bit equals `value`, or `to`.
int64_t nextBit(const uint64_t* row, int64_t from, int64_t to, bool value) {
  for (int64_t i = from; i < to;) {
    const int64_t word = i >> 6, bit = i & 63;
    uint64_t w = (value ? row[word] : ~row[word]) >> bit;
    if (w) return std::min(to, i + int64_t(__builtin_ctzll(w)));
    i += 64 - bit;
  }
  return to;
}

} // namespace

struct LayerVoxelizer::Impl {
  PrintGrid grid;
  VoxelizeOptions options;
  VoxelizerReport report;
  std::vector<Vec3> positions;                   // mm, relative to the grid origin, welded
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<Bounds> bounds;                    // per triangle
  std::vector<std::vector<uint32_t>> chunks;     // per chunk of layers: triangles within shellMm of it

  double rowY(int64_t j) const { return (double(j) + 0.5) * grid.pitchMm.y(); }
  double layerZ(int layer) const { return (double(layer) + 0.5) * grid.pitchMm.z(); }

  void load(const geometry::Mesh& mesh);
  void checkClosed() const;
  void buildChunks();

  void cutLayer(std::span<const uint32_t> candidates, double z, std::vector<Crossing>& out) const;
  void cutTriangle(const std::array<uint32_t, 3>& t, double z, std::vector<Crossing>& out) const;
  LayerSpans fill(std::vector<Crossing>& crossings, int layer, std::vector<Run>& runs) const;
  void markRunEnds(const LayerSpans& inside, const std::vector<Run>& runs, std::vector<uint64_t>& bits, int64_t words) const;
  void markShell(std::span<const uint32_t> candidates, double z, const LayerSpans& inside, const std::vector<Run>& runs,
                 std::vector<uint64_t>& bits, int64_t words) const;
  static void splitSpans(LayerSpans& spans, const std::vector<uint64_t>& bits, int64_t words);
};

// ---- setup ---------------------------------------------------------------------------------------

void VoxelizeOptions::validate() const {
  if (!(shellMm > 0 && shellMm <= 1e4)) {
    std::ostringstream s;
    s << "shell thickness must be in (0, 10000] mm, got " << shellMm;
    throw Error(s.str());
  }
}

void LayerVoxelizer::Impl::load(const geometry::Mesh& mesh) {
  // Weld equal positions (STL and glTF split vertices) so that edges match by index.
  geometry::Mesh welded;
  welded.positions = mesh.positions;
  welded.triangles = mesh.triangles;
  geometry::weldPositions(welded);
  report.weldedVertices = mesh.positions.size() - welded.positions.size();
  report.triangles = welded.triangles.size();
  positions.resize(welded.positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    positions[i] = (grid.rotation * welded.positions[i].cast<double>() - grid.origin) * grid.mmPerUnit;
  triangles = std::move(welded.triangles);
  bounds.resize(triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Vec3 &a = positions[triangles[t][0]], &b = positions[triangles[t][1]], &c = positions[triangles[t][2]];
    bounds[t] = {std::min({a.x(), b.x(), c.x()}), std::max({a.x(), b.x(), c.x()}), std::min({a.y(), b.y(), c.y()}),
                 std::max({a.y(), b.y(), c.y()}), std::min({a.z(), b.z(), c.z()}), std::max({a.z(), b.z(), c.z()})};
  }
}

// Closed: every directed edge is matched by one running the other way, so the contours a plane
// cuts are closed and the winding number is defined everywhere.
void LayerVoxelizer::Impl::checkClosed() const {
  std::vector<std::pair<uint64_t, int>> edges;
  edges.reserve(3 * triangles.size());
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
      if (a != b) edges.push_back({uint64_t(std::min(a, b)) << 32 | std::max(a, b), a < b ? 1 : -1});
    }
  std::sort(edges.begin(), edges.end());
  size_t unmatched = 0, oddEdges = 0;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    int sum = 0;
    while (j < edges.size() && edges[j].first == edges[i].first) sum += edges[j++].second;
    unmatched += sum != 0;
    oddEdges += (j - i) % 2;
    i = j;
  }
  if (unmatched == 0) return;
  throw Error("the model is not closed: " + std::to_string(unmatched) + " edges are not matched by an edge running "
              "the other way (" + std::to_string(oddEdges) + " of them border a hole, the others flipped triangles); "
              "a print needs a closed surface");
}

void LayerVoxelizer::Impl::buildChunks() {
  const double s = options.shellMm, pz = grid.pitchMm.z();
  chunks.assign(size_t((grid.layers + kChunkLayers - 1) / kChunkLayers), {});
  for (size_t t = 0; t < triangles.size(); ++t) {
    // Layers whose centre plane lies within s of the triangle's z range.
    const int64_t first = std::max<int64_t>(0, ceilIndex(bounds[t].zmin - s, pz));
    const int64_t last = std::min<int64_t>(grid.layers - 1, ceilIndex(bounds[t].zmax + s, pz));
    for (int64_t c = first / kChunkLayers; c <= last / kChunkLayers && first <= last; ++c)
      chunks[size_t(c)].push_back(uint32_t(t));
  }
}

LayerVoxelizer::LayerVoxelizer(const geometry::Mesh& mesh, const PrintGrid& grid, const VoxelizeOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.validate();
  geometry::validateMesh(mesh, "voxelization");
  if (grid.width < 1 || grid.height < 1 || grid.layers < 1) throw Error("voxelization: empty print grid");
  impl_->grid = grid;
  impl_->options = options;
  impl_->load(mesh);
  impl_->checkClosed();
  impl_->buildChunks();
}

LayerVoxelizer::~LayerVoxelizer() = default;
LayerVoxelizer::LayerVoxelizer(LayerVoxelizer&&) noexcept = default;
LayerVoxelizer& LayerVoxelizer::operator=(LayerVoxelizer&&) noexcept = default;
const PrintGrid& LayerVoxelizer::grid() const { return impl_->grid; }
const VoxelizeOptions& LayerVoxelizer::options() const { return impl_->options; }
const VoxelizerReport& LayerVoxelizer::report() const { return impl_->report; }

int64_t LayerSpans::insideVoxels() const {
  int64_t n = 0;
  for (const VoxelSpan& s : spans) n += s.end - s.begin;
  return n;
}

int64_t LayerSpans::shellVoxels() const {
  int64_t n = 0;
  for (const VoxelSpan& s : spans) n += s.shell ? s.end - s.begin : 0;
  return n;
}

// ---- inside: contours and the winding rule -------------------------------------------------------

void LayerVoxelizer::Impl::cutTriangle(const std::array<uint32_t, 3>& tri, double z, std::vector<Crossing>& out) const {
  const Vec3* v[3] = {&positions[tri[0]], &positions[tri[1]], &positions[tri[2]]};
  const bool above[3] = {v[0]->z() >= z, v[1]->z() >= z, v[2]->z() >= z};
  if (above[0] == above[1] && above[1] == above[2]) return;
  // Walking the triangle's boundary, edge down (above -> below) gives the segment's start B and
  // edge up its end A: with the triangle counter-clockwise seen from outside, the solid lies to
  // the left of B -> A seen from +z.
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    const int n = (k + 1) % 3;
    if (above[k] && !above[n]) from = cutEdge(*v[k], *v[n], z);
    if (!above[k] && above[n]) to = cutEdge(*v[k], *v[n], z);
  }
  // Rows whose centre y satisfies lo < y <= hi (a segment end on a row counts as above it).
  const double lo = std::min(from.y(), to.y()), hi = std::max(from.y(), to.y());
  const double py = grid.pitchMm.y();
  int64_t first = std::max<int64_t>(0, int64_t(std::floor(lo / py - 0.5)));
  while (first < grid.height && rowY(first) <= lo) ++first;
  const int8_t winding = to.y() > from.y() ? -1 : 1;  // leaving the solid when the segment runs up
  const double slope = (to.x() - from.x()) / (to.y() - from.y());
  for (int64_t j = first; j < grid.height && rowY(j) <= hi; ++j)
    out.push_back({int32_t(j), winding, from.x() + (rowY(j) - from.y()) * slope});
}

void LayerVoxelizer::Impl::cutLayer(std::span<const uint32_t> candidates, double z, std::vector<Crossing>& out) const {
  for (uint32_t t : candidates)
    if (bounds[t].zmin <= z && z <= bounds[t].zmax) cutTriangle(triangles[t], z, out);
}

// Inside spans per image row from the crossings (sorted here by row, then x), and for each span
// the run of the scanline it comes from.
LayerSpans LayerVoxelizer::Impl::fill(std::vector<Crossing>& crossings, int layer, std::vector<Run>& runs) const {
  std::sort(crossings.begin(), crossings.end(), [](const Crossing& a, const Crossing& b) {
    return a.row != b.row ? a.row > b.row : a.x != b.x ? a.x < b.x : a.winding < b.winding;  // image rows: top first
  });
  LayerSpans out;
  out.layer = layer;
  out.rowStart.assign(size_t(grid.height) + 1, 0);
  const double px = grid.pitchMm.x();
  size_t i = 0;
  for (int r = 0; r < grid.height; ++r) {
    out.rowStart[size_t(r)] = uint32_t(out.spans.size());
    const int32_t j = grid.height - 1 - r;
    int winding = 0;
    double start = 0;
    for (; i < crossings.size() && crossings[i].row == j; ++i) {
      const int before = winding;
      winding += crossings[i].winding;
      if (before == 0 && winding != 0) start = crossings[i].x;
      if (before != 0 && winding == 0) {
        const int64_t b = std::max<int64_t>(0, ceilIndex(start, px));
        const int64_t e = std::min<int64_t>(grid.width, ceilIndex(crossings[i].x, px));
        if (b < e) {
          out.spans.push_back({int32_t(b), int32_t(e), false});
          runs.push_back({start, crossings[i].x});
        }
      }
    }
  }
  out.rowStart[size_t(grid.height)] = uint32_t(out.spans.size());
  return out;
}

// ---- shell: voxels near the surface ----------------------------------------------------------------

// Voxels nearer than the shell to where their row enters or leaves the solid: those points lie on
// the surface, so these voxels are shell without looking at triangles.
void LayerVoxelizer::Impl::markRunEnds(const LayerSpans& inside, const std::vector<Run>& runs, std::vector<uint64_t>& bits,
                                       int64_t words) const {
  const double s = options.shellMm, px = grid.pitchMm.x();
  for (int r = 0; r < inside.rows(); ++r)
    for (uint32_t i = inside.rowStart[size_t(r)]; i < inside.rowStart[size_t(r) + 1]; ++i) {
      const VoxelSpan& span = inside.spans[i];
      uint64_t* row = bits.data() + size_t(r) * size_t(words);
      const int64_t enterEnd = std::min<int64_t>(span.end, ceilIndex(runs[i].enter + s, px));
      const int64_t leaveBegin = std::max<int64_t>(std::max<int64_t>(span.begin, enterEnd), ceilIndex(runs[i].leave - s, px));
      setBits(row, span.begin, enterEnd);
      setBits(row, leaveBegin, span.end);
    }
}

// The other voxels of the shell: for each triangle within the shell distance of the layer, the
// interval of each row it reaches, where that row's voxels are farther than the shell from both
// ends of their run (markRunEnds did the rest). Rows and triangles that cannot reach such voxels
// are skipped by bounds first.
void LayerVoxelizer::Impl::markShell(std::span<const uint32_t> candidates, double z, const LayerSpans& inside,
                                     const std::vector<Run>& runs, std::vector<uint64_t>& bits, int64_t words) const {
  const double s = options.shellMm, px = grid.pitchMm.x(), py = grid.pitchMm.y();
  for (uint32_t t : candidates) {
    const Bounds& b = bounds[t];
    const double dz = std::max({0.0, b.zmin - z, z - b.zmax}), hz2 = s * s - dz * dz;
    if (hz2 <= 0) continue;
    const double hz = std::sqrt(hz2);
    const int64_t jFirst = std::max<int64_t>(0, ceilIndex(b.ymin - hz, py));
    const int64_t jLast = std::min<int64_t>(grid.height - 1, ceilIndex(b.ymax + hz, py));
    std::optional<TriangleFrame> frame;
    for (int64_t j = jFirst; j <= jLast; ++j) {
      const double y = rowY(j), dy = std::max({0.0, b.ymin - y, y - b.ymax}), h2 = hz2 - dy * dy;
      if (h2 <= 0) continue;
      const double h = std::sqrt(h2), reachLo = b.xmin - h, reachHi = b.xmax + h;
      const int r = grid.height - 1 - int(j);
      const uint32_t first = inside.rowStart[size_t(r)], last = inside.rowStart[size_t(r) + 1];
      bool reaches = false;
      for (uint32_t i = first; i < last && !reaches; ++i)
        reaches = runs[i].enter + s < reachHi && reachLo < runs[i].leave - s && runs[i].enter + s < runs[i].leave - s;
      if (!reaches) continue;
      if (!frame) frame.emplace(positions[triangles[t][0]], positions[triangles[t][1]], positions[triangles[t][2]]);
      const Hull near = nearInterval(*frame, y, z, s);
      if (!(near.lo < near.hi)) continue;
      for (uint32_t i = first; i < last; ++i) {
        const VoxelSpan& span = inside.spans[i];
        const int64_t lo = std::max<int64_t>(span.begin, ceilIndex(std::max(near.lo, runs[i].enter + s), px));
        const int64_t hi = std::min<int64_t>(span.end, ceilIndex(std::min(near.hi, runs[i].leave - s), px));
        if (lo < hi) setBits(bits.data() + size_t(r) * size_t(words), lo, hi);
      }
    }
  }
}

// Splits each inside span into shell and core runs by the bits; touching runs of one kind merge.
void LayerVoxelizer::Impl::splitSpans(LayerSpans& out, const std::vector<uint64_t>& bits, int64_t words) {
  std::vector<VoxelSpan> spans;
  spans.reserve(out.spans.size() * 3);
  for (int r = 0; r < out.rows(); ++r) {
    const uint64_t* row = bits.data() + size_t(r) * size_t(words);
    const size_t rowBegin = spans.size();
    for (const VoxelSpan& span : out.row(r))
      for (int64_t at = span.begin; at < span.end;) {
        const bool shell = (row[at >> 6] >> (at & 63)) & 1;
        const int64_t next = nextBit(row, at, span.end, !shell);
        if (spans.size() > rowBegin && spans.back().end == at && spans.back().shell == shell) spans.back().end = int32_t(next);
        else spans.push_back({int32_t(at), int32_t(next), shell});
        at = next;
      }
    out.rowStart[size_t(r)] = uint32_t(rowBegin);
  }
  out.rowStart[size_t(out.rows())] = uint32_t(spans.size());
  out.spans = std::move(spans);
}

LayerSpans LayerVoxelizer::voxelize(int layer) const {
  const Impl& s = *impl_;
  if (layer < 0 || layer >= s.grid.layers)
    throw Error("layer " + std::to_string(layer) + " is outside the print (0 to " + std::to_string(s.grid.layers - 1) + ")");
  const double z = s.layerZ(layer);
  const std::span<const uint32_t> candidates = s.chunks[size_t(layer / kChunkLayers)];
  std::vector<Crossing> crossings;
  s.cutLayer(candidates, z, crossings);
  std::vector<Run> runs;
  LayerSpans spans = s.fill(crossings, layer, runs);
  const int64_t words = (s.grid.width + 63) / 64;
  std::vector<uint64_t> bits(size_t(words) * size_t(s.grid.height), 0);
  s.markRunEnds(spans, runs, bits, words);
  s.markShell(candidates, z, spans, runs, bits, words);
  Impl::splitSpans(spans, bits, words);
  return spans;
}

} // namespace texfab::print
