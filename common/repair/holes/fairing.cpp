#include "common/repair/holes/fairing.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>

namespace meshmend::holes {

namespace {

// Cotangents of the angles at a, b and c (0 for a degenerate triangle).
std::array<double, 3> cotangents(const Point3& a, const Point3& b, const Point3& c) {
  auto cot = [](const Point3& u, const Point3& v) {
    const double s = (u ^ v).Norm();
    return s > 0 ? (u * v) / s : 0.0;
  };
  return {cot(b - a, c - a), cot(c - b, a - b), cot(a - c, b - c)};
}

Eigen::Vector3d toEigen(const Point3& p) {
  return {p[0], p[1], p[2]};
}

double wendland(double r) {
  const double s = 1 - r;
  const double s2 = s * s;
  return s2 * s2 * (4 * r + 1);
}

using Sparse = Eigen::SparseMatrix<double>;
using Solver = Eigen::SimplicialLDLT<Sparse, Eigen::Lower>;

// The lower triangle of a symmetric pattern over `size` unknowns, from
// the pairs (row >= column) it holds (repeats allowed): bucketed by
// column, each column's distinct rows then sorted. `slots`, if given, gets
// where each pair is in the values.
Sparse lowerPattern(std::size_t size, const std::vector<std::pair<int, int>>& pairs,
                    std::vector<int>* slots = nullptr) {
  std::vector<int> start(size + 1, 0);
  for (const auto& [row, column] : pairs) ++start[std::size_t(column) + 1];
  for (std::size_t c = 0; c < size; ++c) start[c + 1] += start[c];
  std::vector<int> byColumn(pairs.size());  // pair indices, bucketed by column
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t p = 0; p < pairs.size(); ++p)
      byColumn[std::size_t(fill[std::size_t(pairs[p].second)]++)] = int(p);
  }
  Sparse m(static_cast<Eigen::Index>(size), static_cast<Eigen::Index>(size));
  m.resizeNonZeros(Eigen::Index(pairs.size()));
  int* outer = m.outerIndexPtr();
  int* inner = m.innerIndexPtr();
  if (slots) slots->assign(pairs.size(), 0);
  std::vector<int> at(size, -1);  // a row's slot in the column at hand
  int count = 0;
  outer[0] = 0;
  for (std::size_t c = 0; c < size; ++c) {
    int* const first = inner + count;
    int* last = first;
    for (int k = start[c]; k < start[c + 1]; ++k) {
      const int row = pairs[std::size_t(byColumn[std::size_t(k)])].first;
      if (at[std::size_t(row)] < 0) at[std::size_t(row)] = 0, *last++ = row;
    }
    std::sort(first, last);
    for (int* r = first; r != last; ++r) at[std::size_t(*r)] = int(r - inner);
    if (slots)
      for (int k = start[c]; k < start[c + 1]; ++k) {
        const int p = byColumn[std::size_t(k)];
        (*slots)[std::size_t(p)] = at[std::size_t(pairs[std::size_t(p)].first)];
      }
    for (int* r = first; r != last; ++r) at[std::size_t(*r)] = -1;
    count = int(last - inner);
    outer[c + 1] = count;
  }
  m.resizeNonZeros(count);
  std::fill(m.valuePtr(), m.valuePtr() + count, 0.0);
  return m;
}

// Where entry (row, column), row >= column, is in the values of a compressed lower pattern.
int slotOf(const Sparse& m, int row, int column) {
  const int* begin = m.innerIndexPtr() + m.outerIndexPtr()[column];
  const int* end = m.innerIndexPtr() + m.outerIndexPtr()[column + 1];
  return int(std::lower_bound(begin, end, row) - m.innerIndexPtr());
}

}  // namespace

// ---- Laplacian rows -------------------------------------------------------------

void LaplacianRow::add(int key, double omega) {
  for (auto& [k, w] : weights)
    if (k == key) {
      w += omega;
      return;
    }
  weights.push_back({key, omega});
}

void LaplacianRow::finish(double floor) {
  total = 0;
  for (auto& [k, w] : weights) total += (w = std::max(w, floor));
}

TriangleWeights triangleWeights(const Point3& a, const Point3& b, const Point3& c) {
  TriangleWeights w{cotangents(a, b, c), {0, 0, 0}};
  const double area = ((b - a) ^ (c - a)).Norm() / 2;
  const std::array<Point3, 3> p{a, b, c};
  for (int k = 0; k < 3; ++k)
    if (w.cot[k] < 0) {  // obtuse at k
      for (int m = 0; m < 3; ++m) w.area[m] = m == k ? area / 2 : area / 4;
      return w;
    }
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3, l = (k + 2) % 3;
    w.area[k] =
        ((p[l] - p[k]).SquaredNorm() * w.cot[j] + (p[j] - p[k]).SquaredNorm() * w.cot[l]) / 8;
  }
  return w;
}

void addTriangleToRow(LaplacianRow& row, const std::array<int, 3>& k, const TriangleWeights& w,
                      int corner) {
  const int j = (corner + 1) % 3, l = (corner + 2) % 3;
  row.add(k[j], w.cot[l]);
  row.add(k[l], w.cot[j]);
  row.area += w.area[corner];
}

// ---- Curvature regression -----------------------------------------------------

bool CurvatureModel::fit(const std::vector<Point3>& positions,
                         const std::vector<double>& curvatures, const Point3& centre, double scale,
                         double gamma) {
  const std::size_t n = positions.size();
  if (n < 4 || !(scale > 0)) return false;
  centre_ = centre;
  scale_ = scale;
  inverseSupport_ = 1 / 2.5;
  centres_.clear();
  std::vector<double> y;
  for (std::size_t i = 0; i < n; ++i) {
    centres_.push_back(toEigen((positions[i] - centre) / scale));
    y.push_back(curvatures[i] * scale);
  }
  Eigen::MatrixXd K(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    K(Eigen::Index(i), Eigen::Index(i)) = 1 + 1 / gamma;
    for (std::size_t j = i + 1; j < n; ++j) {
      const double r = (centres_[i] - centres_[j]).norm() * inverseSupport_;
      K(Eigen::Index(i), Eigen::Index(j)) = K(Eigen::Index(j), Eigen::Index(i)) =
          r < 1 ? wendland(r) : 0.0;
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(K);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::VectorXd eta = llt.solve(Eigen::VectorXd::Ones(Eigen::Index(n)));
  const Eigen::VectorXd nu =
      llt.solve(Eigen::Map<const Eigen::VectorXd>(y.data(), Eigen::Index(n)));
  const double s = eta.sum();
  if (!(std::abs(s) > 0)) return false;
  bias_ = nu.sum() / s;
  alpha_ = nu - bias_ * eta;
  std::vector<double> seen = y;
  std::sort(seen.begin(), seen.end());
  low_ = seen[seen.size() / 20] / scale;
  high_ = seen[seen.size() - 1 - seen.size() / 20] / scale;
  return alpha_.allFinite() && std::isfinite(bias_);
}

double CurvatureModel::predict(const Point3& p) const {
  const Eigen::Vector3d x = toEigen((p - centre_) / scale_);
  double f = bias_;
  for (std::size_t i = 0; i < centres_.size(); ++i) {
    const double d2 = (x - centres_[i]).squaredNorm() * inverseSupport_ * inverseSupport_;
    if (d2 < 1) f += alpha_[Eigen::Index(i)] * wendland(std::sqrt(d2));
  }
  return std::clamp(f / scale_, low_, high_);
}

// ---- The least-squares system ---------------------------------------------------

// Least squares over the rows: sum_r A_r |(L x)_r - delta_r|^2 over the new
// vertices (unknowns), with (L x)_r = (1 / 2 A_r) sum_j omega_rj (x_j - x_r)
// the cotangent Laplacian (Eq. 1-3 with Eq. 4's area): the sum discretises
// the integral of |Laplacian|^2 whatever the local triangle size.
struct Fairing::System {
  // Row r's entries are [start[r], start[r + 1]): a key and its
  // coefficient, omega_rj times the row's weight; the row's own vertex first.
  std::vector<int> start, key;
  std::vector<double> coefficient;
  // The pairs of a row's entries (i, j) over unknowns whose product adds
  // to A^T A, and the slot in its values where it does (found once).
  std::vector<std::array<int, 3>> products;
  Sparse normal;                  // A^T A, lower triangle
  Eigen::MatrixXd fixedPart;      // rows x 3: the fixed vertices' contribution
  Eigen::VectorXd rowWeight;      // 1 / (2 sqrt(A_r))
  std::vector<double> rowLength;  // sum_j |omega_rj|: turns a row's residual into a length
  Solver solver;                  // its ordering and symbolic analysis are the pattern's: made once
};

Fairing::Fairing(const Patch& patch, const Rim& rim) : patch_(patch), rim_(rim) {
  for (std::size_t v = patch.n; v < patch.size(); ++v) rows_.push_back(int(v));
  for (std::size_t k = 0; k < patch.n; ++k)
    if (rim.hasRow[k]) rows_.push_back(int(k));
}

Fairing::~Fairing() = default;

std::vector<TriangleWeights> Fairing::weightsAt(const std::vector<Point3>& x) const {
  std::vector<TriangleWeights> w(patch_.triangles.size());
  for (std::size_t t = 0; t < patch_.triangles.size(); ++t) {
    const Triangle& tri = patch_.triangles[t];
    w[t] = triangleWeights(x[std::size_t(tri[0])], x[std::size_t(tri[1])], x[std::size_t(tri[2])]);
  }
  return w;
}

void Fairing::rowOf(int v, const std::vector<TriangleWeights>& weights, LaplacianRow& row,
                    double floor) const {
  row.weights.clear();
  row.area = 0;
  if (std::size_t(v) < patch_.n && rim_.hasRow[std::size_t(v)]) {
    const LaplacianRow& outside = rim_.outside[std::size_t(v)];
    row.weights.assign(outside.weights.begin(), outside.weights.end());
    row.area = outside.area;
  }
  for (int t : patch_.around[std::size_t(v)]) {
    const Triangle& tri = patch_.triangles[std::size_t(t)];
    int corner = 0;
    while (tri[corner] != v) ++corner;
    addTriangleToRow(row, {tri[0], tri[1], tri[2]}, weights[std::size_t(t)], corner);
  }
  row.finish(floor);
}

void Fairing::assemble(const std::vector<Point3>& x, const std::vector<TriangleWeights>& weights) {
  System& sys = *system_;
  const std::size_t unknowns = patch_.size() - patch_.n;
  const int first = int(patch_.n);
  const bool symbolic = sys.start.empty();
  sys.fixedPart = Eigen::MatrixXd::Zero(Eigen::Index(rows_.size()), 3);
  sys.rowLength.assign(rows_.size(), 0);
  sys.rowWeight.resize(Eigen::Index(rows_.size()));
  if (symbolic) sys.start.assign(1, 0);
  LaplacianRow row;
  std::size_t at = 0;
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    const int v = rows_[r];
    rowOf(v, weights, row);
    const double weight = row.area > 0 ? 1 / (2 * std::sqrt(row.area)) : 1.0;
    sys.rowWeight[Eigen::Index(r)] = weight;
    auto put = [&](int key, double coefficient) {
      coefficient *= weight;
      if (symbolic) {
        sys.key.push_back(key);
        sys.coefficient.push_back(coefficient);
      } else {
        sys.coefficient[at] = coefficient;  // the same keys in the same order
      }
      ++at;
      if (key < first) {
        const Point3 p = fixedPosition(key, x);
        for (int d = 0; d < 3; ++d) sys.fixedPart(Eigen::Index(r), d) += coefficient * p[d];
      }
    };
    put(v, -row.total);
    for (const auto& [key, w] : row.weights) {
      put(key, w);
      sys.rowLength[r] += std::abs(w);
    }
    if (symbolic) sys.start.push_back(int(sys.key.size()));
  }
  if (symbolic) {
    // The pattern of A^T A: every pair of unknowns that share a row; each
    // product of two of a row's coefficients adds to that pair's entry.
    std::vector<std::pair<int, int>> pairs;
    std::vector<int> unknown;  // a row's entries on unknowns
    for (std::size_t r = 0; r < rows_.size(); ++r) {
      unknown.clear();
      for (int i = sys.start[r]; i < sys.start[r + 1]; ++i)
        if (sys.key[std::size_t(i)] >= first) unknown.push_back(i);
      for (int i : unknown)
        for (int j : unknown) {
          const int a = sys.key[std::size_t(i)], b = sys.key[std::size_t(j)];
          if (b < a) continue;
          pairs.push_back({b - first, a - first});
          sys.products.push_back({i, j, 0});
        }
    }
    std::vector<int> slots;
    sys.normal = lowerPattern(unknowns, pairs, &slots);
    for (std::size_t p = 0; p < slots.size(); ++p) sys.products[p][2] = slots[p];
  }
  double* values = sys.normal.valuePtr();
  std::fill(values, values + sys.normal.nonZeros(), 0.0);
  for (const auto& [i, j, slot] : sys.products)
    values[slot] += sys.coefficient[std::size_t(i)] * sys.coefficient[std::size_t(j)];
}

Eigen::MatrixXd Fairing::rightHandSide(const Eigen::MatrixXd& delta) const {
  const System& sys = *system_;
  const int first = int(patch_.n);
  // The rows' targets less what the fixed vertices give, weighted as the rows.
  const Eigen::MatrixXd target = sys.rowWeight.asDiagonal() * delta - sys.fixedPart;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(Eigen::Index(patch_.size() - patch_.n), 3);
  for (std::size_t r = 0; r < rows_.size(); ++r)
    for (int i = sys.start[r]; i < sys.start[r + 1]; ++i)
      if (sys.key[std::size_t(i)] >= first)
        rhs.row(sys.key[std::size_t(i)] - first) +=
            sys.coefficient[std::size_t(i)] * target.row(Eigen::Index(r));
  return rhs;
}

double Fairing::solve(const Eigen::MatrixXd& delta, std::vector<Point3>& x) const {
  const System& sys = *system_;
  const int first = int(patch_.n);
  const std::size_t unknowns = patch_.size() - patch_.n;
  const Eigen::MatrixXd sol = sys.solver.solve(rightHandSide(delta));
  if (sys.solver.info() != Eigen::Success || !sol.allFinite()) return -1;
  for (std::size_t v = 0; v < unknowns; ++v)
    for (int d = 0; d < 3; ++d) x[patch_.n + v][d] = sol(Eigen::Index(v), d);
  // The RMS residual of the rows, as a length.
  const Eigen::MatrixXd target = sys.rowWeight.asDiagonal() * delta - sys.fixedPart;
  double sum = 0;
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    Eigen::RowVector3d residual = -target.row(Eigen::Index(r));
    for (int i = sys.start[r]; i < sys.start[r + 1]; ++i)
      if (sys.key[std::size_t(i)] >= first)
        residual += sys.coefficient[std::size_t(i)] * sol.row(sys.key[std::size_t(i)] - first);
    const double length = sys.rowLength[r] * sys.rowWeight[Eigen::Index(r)];
    if (length > 0) sum += residual.squaredNorm() / (length * length);
  }
  return std::sqrt(sum / double(std::max<std::size_t>(1, rows_.size())));
}

bool Fairing::firstBiharmonic(std::vector<Point3>& x, double& residual, bool fromShape) {
  residual = 0;
  if (patch_.size() == patch_.n) return true;  // nothing to place
  const Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(Eigen::Index(rows_.size()), 3);
  // First weights: the patch in its domain, or where x has it.
  std::vector<Point3> inDomain(patch_.size());
  for (std::size_t v = 0; v < patch_.size(); ++v)
    inDomain[v] = Point3(patch_.uv[v].x, patch_.uv[v].y, 0);
  system_ = std::make_unique<System>();
  assemble(x, weightsAt(fromShape ? x : inDomain));
  System& sys = *system_;
  sys.solver.analyzePattern(sys.normal);
  sys.solver.factorize(sys.normal);
  if (sys.solver.info() != Eigen::Success) return false;
  residual = solve(zero, x);
  return residual >= 0;
}

bool Fairing::reweightBiharmonic(std::vector<Point3>& x, double& residual) {
  if (patch_.size() == patch_.n) return true;  // nothing to place
  // The weights of each shape in turn: the same pattern and ordering, the
  // numbers factorised again.
  System& sys = *system_;
  const Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(Eigen::Index(rows_.size()), 3);
  for (int pass = 0; pass < kReweightings; ++pass) {
    assemble(x, weightsAt(x));
    sys.solver.factorize(sys.normal);
    if (sys.solver.info() != Eigen::Success) return false;
    residual = solve(zero, x);
    if (residual < 0) return false;
  }
  return true;
}

std::pair<Point3, double> Fairing::normalAndArea(int v, const std::vector<Point3>& x) const {
  Point3 n(0, 0, 0);
  double area = 0;
  for (int t : patch_.around[std::size_t(v)]) {
    const Triangle& tri = patch_.triangles[std::size_t(t)];
    const Point3 a = (x[std::size_t(tri[1])] - x[std::size_t(tri[0])]) ^
                     (x[std::size_t(tri[2])] - x[std::size_t(tri[0])]);
    n += a;
    area += a.Norm() / 6;
  }
  if (std::size_t(v) < patch_.n) {
    n += rim_.outsideNormal[std::size_t(v)];
    area += rim_.outsideArea[std::size_t(v)];
  }
  const double twiceArea = n.Norm();  // faces around a vertex are nearly coplanar
  return {twiceArea > 0 ? n / twiceArea : n, area};
}

bool Fairing::regression(std::vector<Point3>& x, const CurvatureModel& model, double& residual,
                         bool fromShape) {
  if (!system_ && !biharmonic(x, residual, fromShape)) return false;
  if (patch_.size() == patch_.n) return true;
  std::vector<double> curvature(rows_.size());
  for (std::size_t r = 0; r < rows_.size(); ++r)
    curvature[r] = model.predict(x[std::size_t(rows_[r])]);
  Eigen::MatrixXd delta(Eigen::Index(rows_.size()), 3);
  for (int iteration = 0; iteration < 3; ++iteration) {
    for (std::size_t r = 0; r < rows_.size(); ++r) {
      const auto [n, area] = normalAndArea(rows_[r], x);
      const Point3 d = n * (-4 * area * curvature[r]);
      for (int k = 0; k < 3; ++k) delta(Eigen::Index(r), k) = d[k];
    }
    std::vector<Point3> trial = x;
    const double res = solve(delta, trial);
    if (res < 0) break;
    x = std::move(trial);
    residual = res;
  }
  return true;
}

// ---- The membrane -----------------------------------------------------------

bool Fairing::membrane(std::vector<Point3>& x, bool uniformWeights, double& residual) {
  const std::size_t n = patch_.n, unknowns = patch_.size() - n;
  residual = 0;
  if (unknowns == 0) return true;
  const int first = int(n);
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t r = 0; r < unknowns; ++r) {
    const int v = int(n + r);
    pairs.push_back({int(r), int(r)});
    for (int t : patch_.around[std::size_t(v)])
      for (int c : patch_.triangles[std::size_t(t)])
        if (c > v) pairs.push_back({c - first, int(r)});
  }
  Sparse matrix = lowerPattern(unknowns, pairs);
  double* values = matrix.valuePtr();
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(Eigen::Index(unknowns), 3);
  std::vector<TriangleWeights> weights;
  if (!uniformWeights) weights = weightsAt(x);
  LaplacianRow row;
  double diagonal = 0;
  for (std::size_t r = 0; r < unknowns; ++r) {
    const int v = int(n + r);
    if (uniformWeights) {
      row.weights.clear();
      for (int t : patch_.around[std::size_t(v)])
        for (int c : patch_.triangles[std::size_t(t)])
          if (c != v) row.add(c, 0.5);  // each neighbour on two faces around v: 1
      row.finish();
    } else {
      rowOf(v, weights, row, kPositiveWeightFloor);
    }
    values[slotOf(matrix, int(r), int(r))] = row.total;
    diagonal += row.total;
    for (const auto& [key, w] : row.weights) {
      if (key > v)
        values[slotOf(matrix, key - first, int(r))] -= w;
      else if (key < first)
        for (int d = 0; d < 3; ++d) rhs(Eigen::Index(r), d) += w * x[std::size_t(key)][d];
    }
  }
  Solver solver(matrix);
  if (solver.info() != Eigen::Success) return false;
  const Eigen::MatrixXd sol = solver.solve(rhs);
  if (solver.info() != Eigen::Success || !sol.allFinite()) return false;
  for (std::size_t v = n; v < patch_.size(); ++v)
    for (int d = 0; d < 3; ++d) x[v][d] = sol(Eigen::Index(v - n), d);
  const Eigen::MatrixXd res = matrix.selfadjointView<Eigen::Lower>() * sol - rhs;
  residual = std::sqrt(res.squaredNorm() / double(unknowns)) /
             std::max(1e-300, diagonal / double(unknowns));
  return true;
}

bool Fairing::harmonic(std::vector<Point3>& x, double& residual) {
  return membrane(x, false, residual);
}

bool Fairing::uniform(std::vector<Point3>& x) {
  double residual = 0;
  return membrane(x, true, residual);
}

}  // namespace meshmend::holes
