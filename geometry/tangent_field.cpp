// SPDX-License-Identifier: GPL-3.0-or-later
// Smooth tangent fields by a sparse linear solve over a discrete connection:
//  - F. Knöppel, K. Crane, U. Pinkall, P. Schröder, "Globally Optimal Direction Fields",
//    SIGGRAPH 2013 (complex representation in per-vertex frames, parallel transport across edges,
//    smoothness + alignment energy; n-direction fields as z^n).
//  - G. Taubin, "Estimating the Tensor of Curvature of a Surface from a Polyhedral
//    Approximation", ICCV 1995 (per-vertex principal directions for the curvature option).
#include "geometry/tangent_field.h"

#include "core/error.h"

#include <Eigen/Eigenvalues>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <complex>
#include <queue>

namespace texfab::geometry {

void TangentFieldOptions::validate() const {
  if (!(smoothness > 0) || !std::isfinite(smoothness)) throw Error("tangent field smoothness must be > 0");
  if (kind == TangentFieldKind::Direction && !(direction.norm() > 0) )
    throw Error("tangent field direction must be a non-zero vector");
  if (!direction.allFinite()) throw Error("tangent field direction must be finite");
}

namespace {

using Complex = std::complex<double>;

double wrapAngle(double a) {
  a = std::fmod(a + M_PI, 2 * M_PI);
  if (a < 0) a += 2 * M_PI;
  return a - M_PI;
}

} // namespace

Eigen::Vector3f TangentField::at(const Mesh& mesh, size_t t, float b1, float b2) const {
  const auto& tri = mesh.triangles[t];
  Eigen::Vector3f v = (1 - b1 - b2) * tangents[tri[0]] + b1 * tangents[tri[1]] + b2 * tangents[tri[2]];
  Eigen::Vector3f n = (mesh.corner(t, 1) - mesh.corner(t, 0)).cross(mesh.corner(t, 2) - mesh.corner(t, 0));
  if (n.squaredNorm() > 0) n.normalize();
  v -= n * n.dot(v);
  if (v.squaredNorm() < 1e-20f) { // the field cancels here (a singularity): any tangent
    v = (mesh.corner(t, 1) - mesh.corner(t, 0));
    v -= n * n.dot(v);
  }
  return v.squaredNorm() > 0 ? Eigen::Vector3f(v.normalized()) : Eigen::Vector3f(1, 0, 0);
}

namespace {

/// Per-vertex unit normals (area-weighted; +z where undefined), tangent frames (e1, e2 = n × e1)
/// and areas (a third of the incident triangles' areas).
struct VertexFrames {
  std::vector<Eigen::Vector3d> n, e1, e2;
  std::vector<double> area;
  double meanArea = 1; ///< over used vertices

  double angleIn(size_t v, const Eigen::Vector3d& d) const { return std::atan2(d.dot(e2[v]), d.dot(e1[v])); }
  /// The transport angle from vertex i to j: the angle of a vector at j = the angle at i + rho.
  double transport(const Mesh& mesh, uint32_t i, uint32_t j) const {
    const Eigen::Vector3d d = (mesh.positions[j] - mesh.positions[i]).cast<double>();
    return angleIn(j, d) - angleIn(i, d);
  }
};

VertexFrames vertexFrames(const Mesh& mesh) {
  const size_t nv = mesh.vertexCount(), nt = mesh.triangleCount();
  VertexFrames f;
  f.area.assign(nv, 0.0);
  f.n.assign(nv, Eigen::Vector3d::Zero());
  for (size_t t = 0; t < nt; ++t) {
    const Eigen::Vector3d a = mesh.corner(t, 0).cast<double>(), b = mesh.corner(t, 1).cast<double>(),
                          c = mesh.corner(t, 2).cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) {
      f.n[mesh.triangles[t][size_t(k)]] += n;
      f.area[mesh.triangles[t][size_t(k)]] += n.norm() / 6;
    }
  }
  double meanArea = 0;
  size_t used = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (f.n[v].squaredNorm() > 0) f.n[v].normalize(), ++used;
    else f.n[v] = Eigen::Vector3d::UnitZ();
    meanArea += f.area[v];
  }
  meanArea = used ? meanArea / double(used) : 1.0;
  f.meanArea = meanArea > 0 ? meanArea : 1;
  f.e1.resize(nv), f.e2.resize(nv);
  for (size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3d& n = f.n[v];
    const Eigen::Vector3d axis = std::abs(n.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    f.e1[v] = (axis - n * n.dot(axis)).normalized();
    f.e2[v] = n.cross(f.e1[v]);
  }
  return f;
}

/// An undirected edge (i < j) with its transport angle from i to j.
struct Edge {
  uint32_t i, j;
  double rho;
};

std::vector<Edge> connectionEdges(const Mesh& mesh, const VertexFrames& frames) {
  std::vector<std::pair<uint32_t, uint32_t>> keys;
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = mesh.triangles[t][size_t(k)], b = mesh.triangles[t][size_t((k + 1) % 3)];
      if (a == b) continue;
      keys.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<Edge> edges;
  edges.reserve(keys.size());
  for (auto [i, j] : keys) edges.push_back({i, j, frames.transport(mesh, i, j)});
  return edges;
}

/// A user direction in each vertex frame (complex; magnitude = confidence).
std::vector<Complex> directionTargets(const Eigen::Vector3f& direction, const VertexFrames& frames) {
  const Eigen::Vector3d dir = direction.cast<double>().normalized();
  std::vector<Complex> target(frames.n.size());
  for (size_t v = 0; v < target.size(); ++v) target[v] = Complex(dir.dot(frames.e1[v]), dir.dot(frames.e2[v]));
  return target;
}

/// The minimum-curvature direction of Taubin's tensor M = Σ w_ij κ_ij T_ij T_ijᵀ (its eigenvectors
/// in the tangent plane are the principal directions), raised to `power` (a line field doubles the
/// angle), weighted by the anisotropy, normalized to a mean confidence of 1.
std::vector<Complex> curvatureTargets(const Mesh& mesh, const VertexFrames& frames, const std::vector<Edge>& edges,
                                      int power) {
  const size_t nv = frames.n.size();
  const auto& N = frames.n;
  std::vector<Complex> target(nv, Complex(0, 0));
  std::vector<Eigen::Matrix3d> M(nv, Eigen::Matrix3d::Zero());
  std::vector<double> wsum(nv, 0.0);
  for (const Edge& e : edges)
    for (int side = 0; side < 2; ++side) {
      const uint32_t i = side ? e.j : e.i, j = side ? e.i : e.j;
      const Eigen::Vector3d d = (mesh.positions[j] - mesh.positions[i]).cast<double>();
      const double len2 = d.squaredNorm();
      if (!(len2 > 0)) continue;
      const double kappa = 2 * N[i].dot(-d) / len2;
      Eigen::Vector3d T = d - N[i] * N[i].dot(d);
      if (T.squaredNorm() <= 0) continue;
      T.normalize();
      const double w = std::sqrt(len2);
      M[i] += w * kappa * T * T.transpose();
      wsum[i] += w;
    }
  for (size_t v = 0; v < nv; ++v) {
    if (!(wsum[v] > 0)) continue;
    const Eigen::Vector3d &e1 = frames.e1[v], &e2 = frames.e2[v];
    Eigen::Matrix2d m;
    const Eigen::Matrix3d Mv = M[v] / wsum[v];
    m << e1.dot(Mv * e1), e1.dot(Mv * e2), e2.dot(Mv * e1), e2.dot(Mv * e2);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(m);
    const Eigen::Vector2d ev = es.eigenvalues();
    // Eigenvalue of the tensor is proportional to curvature; minimum |curvature| direction.
    const int idx = std::abs(ev(0)) <= std::abs(ev(1)) ? 0 : 1;
    const Eigen::Vector2d dir = es.eigenvectors().col(idx);
    const double anis = std::abs(std::abs(ev(0)) - std::abs(ev(1)));
    target[v] = std::pow(Complex(dir.x(), dir.y()), power) * anis;
  }
  double mean = 0;
  for (const Complex& z : target) mean += std::abs(z);
  mean /= double(std::max<size_t>(nv, 1));
  if (mean > 0)
    for (Complex& z : target) z /= mean;
  return target;
}

/// Minimizes Σ_edges |z_j - r_ij z_i|² + λ Σ_i (a_i / ā) |z_i - d_i|² (λ = 1 / smoothness) over
/// the complex z_i, r_ij the transport raised to `power`.
Eigen::VectorX<Complex> solveField(const VertexFrames& frames, const std::vector<Edge>& edges,
                                   const std::vector<Complex>& target, int power, double smoothness) {
  const size_t nv = frames.n.size();
  const double lambda = 1.0 / smoothness;
  std::vector<Eigen::Triplet<Complex>> trip;
  trip.reserve(4 * edges.size() + nv);
  std::vector<double> diag(nv, 0.0);
  for (const Edge& e : edges) {
    const Complex r = std::polar(1.0, power * e.rho);
    diag[e.i] += 1, diag[e.j] += 1;
    trip.emplace_back(e.j, e.i, -r);
    trip.emplace_back(e.i, e.j, -std::conj(r));
  }
  const Eigen::Index n = Eigen::Index(nv);
  Eigen::VectorX<Complex> rhs(n);
  for (size_t v = 0; v < nv; ++v) {
    const double w = lambda * frames.area[v] / frames.meanArea + 1e-9;
    trip.emplace_back(v, v, Complex(diag[v] + w, 0));
    rhs(Eigen::Index(v)) = w * target[v];
  }
  Eigen::SparseMatrix<Complex> A(n, n);
  A.setFromTriplets(trip.begin(), trip.end());
  // The system is a connection Laplacian plus a diagonal of about 1 per vertex: well conditioned,
  // so conjugate gradients converge in a few dozen iterations (a direct factorization fills in
  // badly beyond ~100K vertices). Sequential, hence deterministic.
  Eigen::ConjugateGradient<Eigen::SparseMatrix<Complex>, Eigen::Lower | Eigen::Upper> solver;
  solver.setTolerance(1e-8);
  solver.setMaxIterations(2000);
  solver.compute(A);
  Eigen::VectorX<Complex> z = rhs;
  if (solver.info() == Eigen::Success) z = solver.solveWithGuess(rhs, target.empty() ? rhs : Eigen::Map<const Eigen::VectorX<Complex>>(target.data(), n).eval());
  if (!z.allFinite()) z = rhs;
  return z;
}

/// A line field's angles (the roots of z) with signs made consistent along a breadth-first walk of
/// each connected component.
void orientLineField(const std::vector<Edge>& edges, std::vector<double>& angle) {
  const size_t nv = angle.size();
  std::vector<std::vector<std::pair<uint32_t, double>>> nbr(nv);
  for (const Edge& e : edges) nbr[e.i].push_back({e.j, e.rho}), nbr[e.j].push_back({e.i, -e.rho});
  std::vector<uint8_t> seen(nv, 0);
  for (size_t s = 0; s < nv; ++s) {
    if (seen[s]) continue;
    seen[s] = 1;
    std::queue<uint32_t> q;
    q.push(uint32_t(s));
    while (!q.empty()) {
      const uint32_t i = q.front();
      q.pop();
      for (auto [j, rho] : nbr[i]) {
        if (seen[j]) continue;
        seen[j] = 1;
        if (std::abs(wrapAngle(angle[j] - (angle[i] + rho))) > M_PI / 2) angle[j] += M_PI;
        q.push(j);
      }
    }
  }
}

/// Singularities: the turning of the (power-)field around each triangle, corrected by the
/// holonomy. The holonomy of a flat-enough triangle is the angle defect; the field's index is the
/// turn plus that defect over 2π (per power).
void findSingularities(const Mesh& mesh, const VertexFrames& frames, const std::vector<double>& angle, int power,
                       TangentField& field) {
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    double turn = 0, holonomy = 0;
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = mesh.triangles[t][size_t(k)], j = mesh.triangles[t][size_t((k + 1) % 3)];
      if (i == j) ok = false;
      const double rho = frames.transport(mesh, i, j);
      holonomy += rho;
      turn += wrapAngle(power * (angle[j] - angle[i] - rho));
    }
    if (!ok) continue;
    const double defect = wrapAngle(holonomy);
    const double idx = std::round((turn + power * defect) / (2 * M_PI));
    if (idx != 0) {
      field.singularTriangles.push_back(uint32_t(t));
      field.singularIndex.push_back(float(idx / power));
    }
  }
}

} // namespace

TangentField computeTangentField(const Mesh& mesh, const TangentFieldOptions& options) {
  options.validate();
  const size_t nv = mesh.vertexCount();
  const VertexFrames frames = vertexFrames(mesh);
  const std::vector<Edge> edges = connectionEdges(mesh, frames);
  const int power = options.kind == TangentFieldKind::Curvature ? 2 : 1;
  const std::vector<Complex> target = options.kind == TangentFieldKind::Direction
                                    ? directionTargets(options.direction, frames)
                                    : curvatureTargets(mesh, frames, edges, power);
  const Eigen::VectorX<Complex> z = solveField(frames, edges, target, power, options.smoothness);
  std::vector<double> angle(nv, 0.0);
  for (size_t v = 0; v < nv; ++v) angle[v] = std::arg(z(Eigen::Index(v))) / power;
  if (power == 2) orientLineField(edges, angle);

  TangentField field;
  field.normals.resize(nv);
  field.tangents.resize(nv);
  for (size_t v = 0; v < nv; ++v) {
    field.normals[v] = frames.n[v].cast<float>();
    field.tangents[v] = (std::cos(angle[v]) * frames.e1[v] + std::sin(angle[v]) * frames.e2[v]).cast<float>();
  }
  findSingularities(mesh, frames, angle, power, field);
  return field;
}

} // namespace texfab::geometry
