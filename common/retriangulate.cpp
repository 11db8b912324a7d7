#include "common/retriangulate.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <set>

#include "common/errors.h"

namespace meshmend {

namespace {

using Edge = std::pair<int, int>;  // undirected: first < second

Edge key(int a, int b) {
  return a < b ? Edge{a, b} : Edge{b, a};
}

class Retriangulator {
 public:
  explicit Retriangulator(const PatchInput& in) {
    for (const RationalPoint& c : in.corners) add(c);
    chooseProjection();
    T_.push_back({0, 1, 2});
  }

  Patch run(const PatchInput& in) {
    Patch out;
    out.vertex_of_input = {0, 1, 2};
    for (const RationalPoint& p : in.points) out.vertex_of_input.push_back(insertPoint(p));
    const int inputs = int(out.vertex_of_input.size());
    for (const auto& s : in.segments) {
      if (s[0] < 0 || s[0] >= inputs || s[1] < 0 || s[1] >= inputs)
        throw InvalidInputError("retriangulate: segment refers to a point that does not exist");
      insertSegment(out.vertex_of_input[s[0]], out.vertex_of_input[s[1]]);
    }
    if (in.improve) improve();
    out.vertices = V_;
    out.triangles = T_;
    for (const Edge& e : constrained_) out.constrained_edges.push_back({e.first, e.second});
    return out;
  }

 private:
  int add(RationalPoint p) {
    for (mpq_class& c : p.x) c.canonicalize();  // GMP compares canonical fractions only
    V_.push_back(p);
    approx_.emplace_back(p.x[0].get_d(), p.x[1].get_d(), p.x[2].get_d());
    // How far each rounded coordinate may be from the exact one: nothing for
    // doubles, otherwise one unit in the last place (get_d truncates).
    double error = 0;
    for (int k = 0; k < 3; ++k)
      if (mpq_class(approx_.back()[k]) != p.x[k])
        error = std::max(error, std::fabs(approx_.back()[k]) * 0x1p-52 + 0x1p-1074);
    error_.push_back(error);
    return int(V_.size()) - 1;
  }

  // Drop the axis along which the triangle's exact normal is largest (and
  // non-zero), so that the projection keeps every orientation.
  void chooseProjection() {
    std::array<mpq_class, 3> n;
    for (int k = 0; k < 3; ++k) {
      const int u = (k + 1) % 3, v = (k + 2) % 3;
      n[k] = (V_[1].x[u] - V_[0].x[u]) * (V_[2].x[v] - V_[0].x[v]) -
             (V_[1].x[v] - V_[0].x[v]) * (V_[2].x[u] - V_[0].x[u]);
    }
    axis_ = -1;
    for (int k = 0; k < 3; ++k)
      if (sgn(n[k]) != 0 && (axis_ < 0 || abs(n[k]) > abs(n[axis_]))) axis_ = k;
    if (axis_ < 0) throw InvalidInputError("retriangulate: the triangle is degenerate");
    sign_ = sgn(n[axis_]);
  }

  // Orientation of (a, b, c) in the projection, exactly (value and sign),
  // relative to the input triangle: positive = same turn as the input.
  mpq_class orientValue(int a, int b, int c) const {
    const int u = (axis_ + 1) % 3, v = (axis_ + 2) % 3;
    const mpq_class r = (V_[b].x[u] - V_[a].x[u]) * (V_[c].x[v] - V_[a].x[v]) -
                        (V_[b].x[v] - V_[a].x[v]) * (V_[c].x[u] - V_[a].x[u]);
    return sign_ > 0 ? r : mpq_class(-r);
  }
  // The sign of orientValue, first from the rounded coordinates with a
  // rigorous bound on the error (input rounding and arithmetic), exactly
  // only when the bound cannot decide.
  int orient(int a, int b, int c) const {
    constexpr double eps = 0x1p-53;
    const int u = (axis_ + 1) % 3, v = (axis_ + 2) % 3;
    const Point3 &pa = approx_[a], &pb = approx_[b], &pc = approx_[c];
    const double ea = error_[a], eb = error_[b], ec = error_[c];
    const double x1 = pb[u] - pa[u], y1 = pc[v] - pa[v];
    const double x2 = pb[v] - pa[v], y2 = pc[u] - pa[u];
    const double ex1 = ea + eb + std::fabs(x1) * eps, ey1 = ea + ec + std::fabs(y1) * eps;
    const double ex2 = ea + eb + std::fabs(x2) * eps, ey2 = ea + ec + std::fabs(y2) * eps;
    const double l = x1 * y1, r = x2 * y2, det = l - r;
    const double el = std::fabs(x1) * ey1 + std::fabs(y1) * ex1 + ex1 * ey1 + std::fabs(l) * eps;
    const double er = std::fabs(x2) * ey2 + std::fabs(y2) * ex2 + ex2 * ey2 + std::fabs(r) * eps;
    const double bound = (el + er + std::fabs(det) * eps) * (1 + 8 * eps);
    if (std::isfinite(det) && std::isfinite(bound)) {
      if (det > bound) return sign_;
      if (-det > bound) return -sign_;
    }
    return sgn(orientValue(a, b, c));
  }

  bool samePoint(const RationalPoint& p, int v) const {
    return p.x[0] == V_[v].x[0] && p.x[1] == V_[v].x[1] && p.x[2] == V_[v].x[2];
  }

  // Index of the triangle holding directed edge a->b, or -1.
  int triangleWith(int a, int b) const {
    for (std::size_t t = 0; t < T_.size(); ++t)
      for (int i = 0; i < 3; ++i)
        if (T_[t][i] == a && T_[t][(i + 1) % 3] == b) return int(t);
    return -1;
  }

  int insertPoint(RationalPoint p) {
    for (mpq_class& c : p.x) c.canonicalize();
    for (std::size_t v = 0; v < V_.size(); ++v)
      if (samePoint(p, int(v))) return int(v);
    if (orient3d(V_[0], V_[1], V_[2], p) != 0)
      throw InvalidInputError("retriangulate: a point does not lie in the triangle's plane");
    const int q = add(p);
    for (std::size_t t = 0; t < T_.size(); ++t) {
      const std::array<int, 3> tri = T_[t];
      int o[3], zeros = 0, zeroEdge = -1;
      bool inside = true;
      for (int i = 0; i < 3; ++i) {
        o[i] = orient(tri[i], tri[(i + 1) % 3], q);
        if (o[i] < 0) inside = false;
        if (o[i] == 0) ++zeros, zeroEdge = i;
      }
      if (!inside) continue;
      if (zeros == 0) {
        T_[t] = {tri[0], tri[1], q};
        T_.push_back({tri[1], tri[2], q});
        T_.push_back({tri[2], tri[0], q});
      } else {
        splitEdge(tri[zeroEdge], tri[(zeroEdge + 1) % 3], q);
      }
      return q;
    }
    throw InvalidInputError("retriangulate: a point does not lie on the triangle");
  }

  // Splits edge (a, b) at q (q lies on it), in both triangles that hold it.
  void splitEdge(int a, int b, int q) {
    for (const auto& [x, y] : {Edge{a, b}, Edge{b, a}}) {
      const int t = triangleWith(x, y);
      if (t < 0) continue;
      const std::array<int, 3> tri = T_[t];
      int i = 0;
      while (tri[i] != x) ++i;
      const int c = tri[(i + 2) % 3];
      T_[t] = {x, q, c};
      T_.push_back({q, y, c});
    }
    if (constrained_.erase(key(a, b))) {
      constrained_.insert(key(a, q));
      constrained_.insert(key(q, b));
    }
  }

  // Is vertex v strictly inside segment (a, b)? (collinear checked by caller)
  bool between(int a, int b, int v) const {
    for (int k = 0; k < 3; ++k) {
      const int s1 = sgn(V_[v].x[k] - V_[a].x[k]), s2 = sgn(V_[b].x[k] - V_[v].x[k]);
      if (s1 * s2 < 0) return false;
    }
    return !samePoint(V_[a], v) && !samePoint(V_[b], v);
  }

  void insertSegment(int a, int b) {
    if (a == b) return;
    // A vertex on the segment splits it.
    int nearest = -1;
    for (int v = 0; v < int(V_.size()); ++v) {
      if (v == a || v == b || orient(a, b, v) != 0 || !between(a, b, v)) continue;
      if (nearest < 0 || between(a, nearest, v)) nearest = v;
    }
    if (nearest >= 0) {
      insertSegment(a, nearest);
      insertSegment(nearest, b);
      return;
    }
    if (triangleWith(a, b) >= 0 || triangleWith(b, a) >= 0) {
      constrained_.insert(key(a, b));
      return;
    }
    // The edges the segment crosses in both interiors.
    auto crosses = [&](int u, int w) {
      return u != a && u != b && w != a && w != b && orient(a, b, u) * orient(a, b, w) < 0 &&
             orient(u, w, a) * orient(u, w, b) < 0;
    };
    std::deque<Edge> queue;
    for (const auto& tri : T_)
      for (int i = 0; i < 3; ++i) {
        const int u = tri[i], w = tri[(i + 1) % 3];
        if (u < w && crosses(u, w)) queue.push_back({u, w});
      }
    if (queue.empty()) throw InvalidInputError("retriangulate: a constraint leaves the triangle");
    for (const Edge& e : queue)
      if (constrained_.count(e)) {  // two constraints cross: insert their crossing point
        const mpq_class oa = orientValue(e.first, e.second, a);
        const mpq_class ob = orientValue(e.first, e.second, b);
        const mpq_class t = oa / (oa - ob);
        RationalPoint x;
        for (int k = 0; k < 3; ++k) x.x[k] = V_[a].x[k] + t * (V_[b].x[k] - V_[a].x[k]);
        const int q = add(x);
        splitEdge(e.first, e.second, q);
        insertSegment(a, q);
        insertSegment(q, b);
        return;
      }
    // Sloan's edge recovery: flip crossing edges whose quadrilateral is
    // convex; a flipped edge that still crosses goes back in the queue.
    for (std::size_t guard = 0; !queue.empty(); ++guard) {
      if (guard > 100000)
        throw InvalidInputError("retriangulate: constraint recovery did not finish");
      const Edge e = queue.front();
      queue.pop_front();
      Edge flipped;
      if (!flipIfConvex(e.first, e.second, &flipped)) {
        queue.push_back(e);
        continue;
      }
      if (crosses(flipped.first, flipped.second))
        queue.push_back(key(flipped.first, flipped.second));
    }
    if (triangleWith(a, b) < 0 && triangleWith(b, a) < 0)
      throw InvalidInputError("retriangulate: could not recover a constraint");
    constrained_.insert(key(a, b));
  }

  // Flips edge (u, w) if the two triangles around it form a strictly convex
  // quadrilateral. Returns whether it flipped.
  bool flipIfConvex(int u, int w, Edge* flipped = nullptr) {
    const int t1 = triangleWith(u, w), t2 = triangleWith(w, u);
    if (t1 < 0 || t2 < 0) return false;
    const int p = opposite(t1, u, w), q = opposite(t2, w, u);
    // (u, w, p) and (w, u, q) are the triangles; the new edge is p-q.
    if (orient(p, q, w) <= 0 || orient(q, p, u) <= 0) return false;
    T_[t1] = {p, q, w};
    T_[t2] = {q, p, u};
    if (flipped) *flipped = {p, q};
    return true;
  }

  int opposite(int t, int a, int b) const {
    for (int v : T_[t])
      if (v != a && v != b) return v;
    return -1;
  }

  // Smallest angle of triangle (a, b, c), from the rounded positions.
  double minAngle(int a, int b, int c) const {
    auto angle = [&](int p, int q, int r) {
      const Point3 u = approx_[q] - approx_[p], v = approx_[r] - approx_[p];
      return std::atan2((u ^ v).Norm(), u * v);
    };
    return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
  }

  // Max-min angle flips on unconstrained interior edges. The validity of each
  // flip is decided exactly; only the quality comparison is approximate.
  void improve() {
    for (int pass = 0; pass < 50; ++pass) {
      bool changed = false;
      for (std::size_t t = 0; t < T_.size(); ++t)
        for (int i = 0; i < 3; ++i) {
          const int u = T_[t][i], w = T_[t][(i + 1) % 3];
          if (constrained_.count(key(u, w))) continue;
          const int other = triangleWith(w, u);
          if (other < 0) continue;
          const int p = opposite(int(t), u, w), q = opposite(other, w, u);
          const double before = std::min(minAngle(u, w, p), minAngle(w, u, q));
          const double after = std::min(minAngle(p, q, w), minAngle(q, p, u));
          if (after > before + 1e-9 && flipIfConvex(u, w)) changed = true;
        }
      if (!changed) return;
    }
  }

  std::vector<RationalPoint> V_;
  std::vector<Point3> approx_;
  std::vector<double> error_;  // per vertex: bound on |rounded - exact| of each coordinate
  std::vector<std::array<int, 3>> T_;
  std::set<Edge> constrained_;
  int axis_ = 2, sign_ = 1;
};

}  // namespace

Patch retriangulate(const PatchInput& input) {
  return Retriangulator(input).run(input);
}

}  // namespace meshmend
