// The linearised step of the enforcement (Aycheh & Kyung's Gauss-Newton
// iteration): one row per vertex–face or edge–edge element of the active
// pairs, and the minimum-norm displacement that brings every row to the goal.
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/repair/clearance/detail.h"

namespace meshmend::clearance_detail {

namespace {

// One vertex–face or edge–edge distance, by its four vertices: kind 0 =
// vertex v[0] against face (v[1], v[2], v[3]); kind 1 = edge (v[0], v[1])
// against edge (v[2], v[3]), each edge's smaller index first, the smaller edge first.
struct Element {
  std::array<int, 4> v;
  int kind;
  bool operator<(const Element& o) const { return kind != o.kind ? kind < o.kind : v < o.v; }
  bool operator==(const Element& o) const { return kind == o.kind && v == o.v; }
};

// A linearised distance: d + Σ_i w[i] (n · Δx_{v[i]}). The gradient comes from
// the closest points (envelope theorem): moving a corner moves the closest
// point by its weight, along the direction between the closest points.
struct Row {
  Element e;
  double d;
  Point3 n;
  double w[4];
};

bool evaluate(const std::vector<Point3>& P, const Element& e, Row& row) {
  row.e = e;
  Point3 a, b;
  if (e.kind == 0) {
    const PointTriangle x = pointTriangle(P[e.v[0]], P[e.v[1]], P[e.v[2]], P[e.v[3]]);
    a = P[e.v[0]];
    b = x.point;
    row.w[0] = 1;
    for (int i = 0; i < 3; ++i) row.w[i + 1] = -x.w[i];
    row.d = x.distance;
  } else {
    const SegmentSegment x = segmentSegment(P[e.v[0]], P[e.v[1]], P[e.v[2]], P[e.v[3]]);
    a = x.pa;
    b = x.pb;
    row.w[0] = 1 - x.s;
    row.w[1] = x.s;
    row.w[2] = -(1 - x.t);
    row.w[3] = -x.t;
    row.d = x.distance;
  }
  if (!(row.d > 0)) return false;
  row.n = (a - b) / row.d;
  return true;
}

// The elements of face pair (f, g) closer than `below`.
void elementsOf(const Soup& soup, const std::vector<Point3>& P, std::uint32_t f, std::uint32_t g,
                double below, std::vector<Element>& out) {
  const Triangle &a = soup.triangles[f], &b = soup.triangles[g];
  for (int i = 0; i < 3; ++i) {
    if (pointTriangle(P[a[i]], P[b[0]], P[b[1]], P[b[2]]).distance < below)
      out.push_back({{a[i], b[0], b[1], b[2]}, 0});
    if (pointTriangle(P[b[i]], P[a[0]], P[a[1]], P[a[2]]).distance < below)
      out.push_back({{b[i], a[0], a[1], a[2]}, 0});
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      int a0 = a[i], a1 = a[(i + 1) % 3], b0 = b[j], b1 = b[(j + 1) % 3];
      if (segmentSegment(P[a0], P[a1], P[b0], P[b1]).distance >= below) continue;
      if (a0 > a1) std::swap(a0, a1);
      if (b0 > b1) std::swap(b0, b1);
      if (std::make_pair(b0, b1) < std::make_pair(a0, a1)) {
        std::swap(a0, b0);
        std::swap(a1, b1);
      }
      out.push_back({{a0, a1, b0, b1}, 1});
    }
}

using SparseRows = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// The minimum-norm step Δ with d_k + J_k Δ ≥ goal for every row (the
// linearised problem, a quadratic programme with inequalities: rows already
// beyond the goal only stop the step from pushing them below it).
//
// First Hildreth's method (coordinate ascent on the dual, Δ = Jᵀ y, y ≥ 0)
// finds which rows bind; it handles repeated rows (a vertex–face and an
// edge–edge distance meeting at the same points) and more rows than moved
// coordinates. Then the step is solved exactly for the binding rows W with
// a sparse solve, Δ = (J_Wᵀ J_W + λI)⁻¹ J_Wᵀ (goal - d_W): for a small λ the
// minimum-norm solution J_Wᵀ (J_W J_Wᵀ)⁻¹ (goal - d_W), in the form whose
// size is the moved coordinates (J_W J_Wᵀ is singular when rows repeat). The
// solved step is kept if it satisfies every row, else Hildreth's.
Eigen::VectorXd minimumNormStep(const SparseRows& J, const Eigen::VectorXd& d, double goal,
                                double tolerance) {
  const int m = int(J.rows());
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(J.cols());
  Eigen::VectorXd y = Eigen::VectorXd::Zero(m);
  std::vector<double> norm2(m, 0);
  for (int k = 0; k < m; ++k)
    for (SparseRows::InnerIterator it(J, k); it; ++it) norm2[k] += it.value() * it.value();
  std::vector<int> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return d[a] < d[b]; });
  for (int sweep = 0; sweep < 400; ++sweep) {
    double worst = 0;
    for (int k : order) {
      if (!(norm2[k] > 0)) continue;
      double predicted = d[k];
      for (SparseRows::InnerIterator it(J, k); it; ++it) predicted += it.value() * delta[it.col()];
      const double shortfall = goal - predicted;
      if (y[k] == 0 && shortfall <= 0) continue;
      const double next = std::max(0.0, y[k] + shortfall / norm2[k]);
      const double change = next - y[k];
      if (change == 0) continue;
      y[k] = next;
      for (SparseRows::InnerIterator it(J, k); it; ++it) delta[it.col()] += change * it.value();
      worst = std::max(worst, std::abs(shortfall));
    }
    if (worst < 100 * tolerance) break;  // enough to tell the binding rows
  }

  std::vector<char> binding(m, 0);
  for (int k = 0; k < m; ++k) binding[k] = y[k] > 0;
  for (int round = 0; round < 4; ++round) {
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<double> r;
    for (int k = 0; k < m; ++k) {
      if (!binding[k]) continue;
      for (SparseRows::InnerIterator it(J, k); it; ++it)
        entries.emplace_back(int(r.size()), int(it.col()), it.value());
      r.push_back(goal - d[k]);
    }
    if (r.empty()) return delta;
    Eigen::SparseMatrix<double> JW(int(r.size()), J.cols());
    JW.setFromTriplets(entries.begin(), entries.end());
    Eigen::SparseMatrix<double> H = Eigen::SparseMatrix<double>(JW.transpose()) * JW;
    double largest = 0;
    for (int i = 0; i < H.rows(); ++i) largest = std::max(largest, H.coeff(i, i));
    // The ridge keeps the solve defined for coordinates no binding row moves
    // and in directions no row sees; small enough not to shorten the step.
    Eigen::SparseMatrix<double> ridge(H.rows(), H.cols());
    ridge.setIdentity();
    H += ridge * (1e-10 * std::max(largest, 1e-300));
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(H);
    if (solver.info() != Eigen::Success) return delta;
    const Eigen::VectorXd solved = solver.solve(
        Eigen::VectorXd(JW.transpose() * Eigen::Map<const Eigen::VectorXd>(r.data(), r.size())));
    const Eigen::VectorXd predicted = d + J * solved;
    bool short_ = false;
    for (int k = 0; k < m; ++k)
      if (norm2[k] > 0 && predicted[k] < goal - tolerance) {
        short_ = true;
        binding[k] = 1;  // a row Hildreth had not yet seen binding
      }
    if (!short_) return solved;
  }
  return delta;
}

// The rows of the active pairs' elements closer than targets.near, once
// each, without the rows whose vertices are all locked or capped; `column`
// numbers the vertices that may move. Sets `anyShort` when a movable row is
// below the goal.
std::vector<Row> activeRows(const Separation& s, std::vector<int>& column,
                            std::vector<int>& columnVertex, bool& anyShort) {
  std::vector<Element> elements;
  for (const NearPair& p : s.near) elementsOf(s.soup, s.P, p.f, p.g, s.targets.near, elements);
  std::sort(elements.begin(), elements.end());
  elements.erase(std::unique(elements.begin(), elements.end()), elements.end());
  std::vector<Row> rows;
  rows.reserve(elements.size());
  column.assign(s.P.size(), -1);
  columnVertex.clear();
  anyShort = false;
  auto free = [&](int v) { return !s.locked[v] && !s.capped[v]; };
  for (const Element& e : elements) {
    Row row;
    if (!evaluate(s.P, e, row)) continue;
    if (std::none_of(e.v.begin(), e.v.end(), free)) continue;  // nothing to solve for
    if (row.d < s.targets.goal) anyShort = true;
    for (int v : e.v)
      if (free(v) && column[v] < 0) {
        column[v] = int(columnVertex.size());
        columnVertex.push_back(v);
      }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

Step linearisedStep(Separation& s) {
  std::vector<int> column, columnVertex;
  bool anyShort = false;
  const std::vector<Row> rows = activeRows(s, column, columnVertex, anyShort);
  s.result.constraints_last = rows.size();
  Step step;
  if (!anyShort) {
    s.result.stop_reason = "locked";
    return step;
  }
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd d(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Row& r = rows[k];
    d[k] = r.d;
    for (int i = 0; i < 4; ++i) {
      const int c = column[r.e.v[i]];
      if (c < 0) continue;
      for (int a = 0; a < 3; ++a)
        if (r.w[i] * r.n[a] != 0) entries.emplace_back(int(k), 3 * c + a, r.w[i] * r.n[a]);
    }
  }
  SparseRows J(int(rows.size()), int(3 * columnVertex.size()));
  J.setFromTriplets(entries.begin(), entries.end());
  const double tau = s.options.tau, cap = s.options.max_displacement;
  const Eigen::VectorXd delta = minimumNormStep(J, d, s.targets.goal, 1e-6 * tau);

  // Within a trust radius of tau (conflicting rows can ask for far more
  // than any single pair needs), then within the cap.
  double largest = 0;
  for (std::size_t c = 0; c < columnVertex.size(); ++c)
    largest = std::max(largest, Point3(delta[3 * c], delta[3 * c + 1], delta[3 * c + 2]).Norm());
  const double scale = largest > tau ? tau / largest : 1.0;
  step.by.assign(s.P.size(), Point3(0, 0, 0));
  for (std::size_t c = 0; c < columnVertex.size(); ++c) {
    const int v = columnVertex[c];
    Point3 by(delta[3 * c] * scale, delta[3 * c + 1] * scale, delta[3 * c + 2] * scale);
    if (cap > 0) {
      const Point3 total = s.P[v] - s.P0[v] + by;
      const double len = total.Norm();
      if (len > cap) by = total * (cap / len) - (s.P[v] - s.P0[v]);
    }
    if (by.Norm() == 0) continue;
    step.by[v] = by;
    step.vertices.push_back(v);
  }
  return step;
}

}  // namespace meshmend::clearance_detail
