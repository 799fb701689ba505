// SPDX-License-Identifier: GPL-3.0-or-later
#include "geometry/fracture/plane_arrangement.h"

#include "core/error.h"

#include <algorithm>
#include <numeric>
#include <unordered_map>

namespace texfab::geometry {
namespace {

struct Polygon {
  std::vector<uint32_t> loop;  // convex; counter-clockwise seen from `outer`
  int32_t inner = -1;
  int32_t outer = -1;
  int32_t plane = -1;
};

// The box, split plane by plane; cells are convex polyhedra bounded by shared polygons.
class Splitter {
public:
  explicit Splitter(const Eigen::AlignedBox3d& box) : tolerance_(1e-10 * box.diagonal().norm()) {
    for (uint32_t k = 0; k < 8; ++k)
      vertices_.push_back({k & 1 ? box.max().x() : box.min().x(), k & 2 ? box.max().y() : box.min().y(),
                           k & 4 ? box.max().z() : box.min().z()});
    // Corner loops counter-clockwise seen from outside: -x, +x, -y, +y, -z, +z.
    for (const auto& loop : {std::vector<uint32_t>{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}})
      faces_.push_back({loop, 0, -1, -1});
    sides_.emplace_back();
  }

  void split(const CutPlane& plane, int32_t index) {
    measure(plane);
    const size_t cells = sides_.size();
    markCrossed(cells);
    chords_.assign(cells, {});
    edgePoints_.clear();
    std::vector<Polygon> next;
    for (const Polygon& f : faces_) splitFace(f, next);
    for (size_t c = 0; c < cells; ++c)
      if (crossed(int32_t(c))) next.push_back({section(int32_t(c)), int32_t(c), front_[c], index});
    faces_ = std::move(next);
  }

  PlaneArrangement finish() && {
    std::vector<int32_t> order(sides_.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {  // every cell has a side per plane
      const auto &x = sides_[size_t(a)], &y = sides_[size_t(b)];
      const auto differ = std::mismatch(x.begin(), x.end(), y.begin());
      return differ.first != x.end() && *differ.first < *differ.second;
    });
    std::vector<int32_t> rank(order.size());
    for (size_t i = 0; i < order.size(); ++i) rank[size_t(order[i])] = int32_t(i);
    PlaneArrangement a;
    a.complex.cells = int(sides_.size());
    a.complex.vertices = std::move(vertices_);
    for (const Polygon& f : faces_) {
      if (f.loop.size() < 3) continue;
      CellFace face{{}, rank[size_t(f.inner)], f.outer < 0 ? -1 : rank[size_t(f.outer)]};
      if (f.loop.size() == 3) {
        face.triangles.push_back({f.loop[0], f.loop[1], f.loop[2]});
      } else {
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (uint32_t v : f.loop) centre += a.complex.vertices[v];
        const auto c = uint32_t(a.complex.vertices.size());
        a.complex.vertices.push_back(centre / double(f.loop.size()));
        for (size_t i = 0; i < f.loop.size(); ++i) face.triangles.push_back({c, f.loop[i], f.loop[(i + 1) % f.loop.size()]});
      }
      a.complex.faces.push_back(std::move(face));
      a.planeOf.push_back(f.plane);
    }
    return a;
  }

private:
  bool crossed(int32_t c) const { return c >= 0 && front_[size_t(c)] != c; }
  int32_t frontOf(int32_t c) const { return c < 0 ? c : front_[size_t(c)]; }

  void measure(const CutPlane& plane) {
    const Eigen::Vector3d n = plane.normal.normalized();
    distance_.resize(vertices_.size());
    sign_.resize(vertices_.size());
    for (size_t v = 0; v < vertices_.size(); ++v) {
      distance_[v] = (vertices_[v] - plane.point).dot(n);
      sign_[v] = int8_t(distance_[v] > tolerance_ ? 1 : distance_[v] < -tolerance_ ? -1 : 0);
    }
  }

  // Cells with corners on both sides get a new cell for their front part; every cell records its side.
  void markCrossed(size_t cells) {
    std::vector<uint8_t> behind(cells, 0), ahead(cells, 0);
    for (const Polygon& f : faces_)
      for (uint32_t v : f.loop)
        for (int32_t c : {f.inner, f.outer})
          if (c >= 0) {
            behind[size_t(c)] |= sign_[v] < 0;
            ahead[size_t(c)] |= sign_[v] > 0;
          }
    front_.resize(cells);
    for (size_t c = 0; c < cells; ++c) {
      front_[c] = int32_t(c);
      if (behind[c] && ahead[c]) {
        front_[c] = int32_t(sides_.size());
        std::vector<uint8_t> sides = sides_[c];
        sides.push_back(1);
        sides_.push_back(std::move(sides));
      }
      sides_[c].push_back(behind[c] ? 0 : ahead[c]);
    }
  }

  // The vertex where the plane crosses edge (a, b), made once for all faces along the edge.
  uint32_t edgePoint(uint32_t a, uint32_t b) {
    if (a > b) std::swap(a, b);
    const auto [it, inserted] = edgePoints_.emplace(uint64_t(a) << 32 | b, uint32_t(vertices_.size()));
    if (inserted) {
      const double t = distance_[a] / (distance_[a] - distance_[b]);
      const Eigen::Vector3d p = vertices_[a] + t * (vertices_[b] - vertices_[a]);
      vertices_.push_back(p);
      distance_.push_back(0);
      sign_.push_back(0);
    }
    return it->second;
  }

  void splitFace(const Polygon& f, std::vector<Polygon>& out) {
    const bool behind = std::any_of(f.loop.begin(), f.loop.end(), [&](uint32_t v) { return sign_[v] < 0; });
    const bool ahead = std::any_of(f.loop.begin(), f.loop.end(), [&](uint32_t v) { return sign_[v] > 0; });
    if (!behind || !ahead) {  // on one side, or in the plane (then neither of its cells is crossed)
      if (!ahead) addChords(f);
      out.push_back(ahead ? Polygon{f.loop, frontOf(f.inner), frontOf(f.outer), f.plane} : f);
      return;
    }
    Polygon back{{}, f.inner, f.outer, f.plane}, front{{}, frontOf(f.inner), frontOf(f.outer), f.plane};
    for (size_t i = 0; i < f.loop.size(); ++i) {
      const uint32_t a = f.loop[i], b = f.loop[(i + 1) % f.loop.size()];
      if (sign_[a] <= 0) back.loop.push_back(a);
      if (sign_[a] >= 0) front.loop.push_back(a);
      if (sign_[a] * sign_[b] < 0) {
        const uint32_t p = edgePoint(a, b);
        back.loop.push_back(p);
        front.loop.push_back(p);
      }
    }
    addChords(back);
    out.push_back(std::move(back));
    out.push_back(std::move(front));
  }

  // Edges in the plane of a face's part behind it, directed counter-clockwise seen from outside
  // the crossed cells it bounds: the outline of their sections, reversed.
  void addChords(const Polygon& f) {
    if (f.loop.size() < 3) return;
    for (size_t i = 0; i < f.loop.size(); ++i) {
      const uint32_t a = f.loop[i], b = f.loop[(i + 1) % f.loop.size()];
      if (sign_[a] != 0 || sign_[b] != 0) continue;
      if (crossed(f.inner)) chords_[size_t(f.inner)].push_back({a, b});
      if (crossed(f.outer)) chords_[size_t(f.outer)].push_back({b, a});
    }
  }

  // The section of crossed cell c, counter-clockwise seen from its front part.
  std::vector<uint32_t> section(int32_t c) const {
    std::unordered_map<uint32_t, uint32_t> next;
    for (const auto& [a, b] : chords_[size_t(c)])
      if (!next.emplace(b, a).second) throw Error("internal: a cell's section by a cutting plane is not one loop");
    std::vector<uint32_t> loop;
    if (next.empty()) throw Error("internal: a crossed cell has no section");
    uint32_t v = std::min_element(next.begin(), next.end())->first;
    do {
      loop.push_back(v);
      const auto it = next.find(v);
      if (it == next.end() || loop.size() > next.size()) throw Error("internal: a cell's section by a cutting plane is not one loop");
      v = it->second;
    } while (v != loop.front());
    if (loop.size() != next.size()) throw Error("internal: a cell's section by a cutting plane is not one loop");
    return loop;
  }

  double tolerance_;
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Polygon> faces_;
  std::vector<std::vector<uint8_t>> sides_;  // per cell: 0 behind or 1 in front of each plane so far
  // Per split:
  std::vector<double> distance_;
  std::vector<int8_t> sign_;
  std::vector<int32_t> front_;  // per cell: the cell of its front part (itself when not crossed)
  std::vector<std::vector<std::array<uint32_t, 2>>> chords_;
  std::unordered_map<uint64_t, uint32_t> edgePoints_;
};

} // namespace

void validatePlane(const CutPlane& plane) {
  if (!plane.point.allFinite() || !plane.normal.allFinite()) throw Error("a cutting plane is not finite");
  if (!(plane.normal.squaredNorm() > 0)) throw Error("a cutting plane has a zero normal");
}

PlaneArrangement planeArrangement(std::span<const CutPlane> planes, const Eigen::AlignedBox3d& bounds) {
  Splitter s(bounds);
  for (size_t k = 0; k < planes.size(); ++k) {
    validatePlane(planes[k]);
    s.split(planes[k], int32_t(k));
  }
  return std::move(s).finish();
}

} // namespace texfab::geometry
