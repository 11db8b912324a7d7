#include "common/exact/retriangulate.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "common/base/errors.h"
#include "common/exact/predicates.h"

namespace meshmend {

namespace {

using Edge = std::pair<int, int>;  // undirected: first < second

Edge key(int a, int b) {
  return a < b ? Edge{a, b} : Edge{b, a};
}

// Compares two smallestAngleMeasures of triangles on the four points
// `quad` (the two ways to split a quadrilateral): +1 when `after` is
// certainly the larger, -1 when certainly the smaller, 0 when the rounded
// positions cannot tell (the four points on one circle, or nearly: grids,
// regular polygons, CAD faces). The measure's error is bounded from the
// points' error boxes: moving a corner by d turns an angle by at most
// d / (the shortest side), and the measure (a squared sine) by at most twice that.
int compareMeasures(double before, double after, const std::array<const ExactPoint*, 4>& quad) {
  const double difference = after - before, scale = std::max(after, before);
  if (std::abs(difference) > 1e-3 * scale) return difference > 0 ? 1 : -1;  // far from a tie
  double error = 0, reach = 0, shortest = INFINITY;
  for (int i = 0; i < 4; ++i) {
    const Point3& a = quad[i]->approx();
    error = std::max(error, quad[i]->error());
    reach = std::max({reach, std::abs(a[0]), std::abs(a[1]), std::abs(a[2])});
    for (int j = i + 1; j < 4; ++j) shortest = std::min(shortest, (quad[j]->approx() - a).Norm());
  }
  error += reach * 1e-15;  // the rounding of the differences the measure takes
  const double bound = 1e-12 * scale + 16 * error / shortest;
  if (std::abs(difference) > bound) return difference > 0 ? 1 : -1;
  return 0;
}

// One re-triangulation at a time; its storage is kept for the next patch
// (retriangulate() holds one per thread), so that a patch in steady state
// allocates only its output.
class Retriangulator {
 public:
  RetriangulatedPatch run(const PatchInput& in) {
    reset(in);
    return triangulate(in);
  }

 private:
  void reset(const PatchInput& in) {
    V_.clear();
    edges_.clear();
    lines_.clear();
    T_.clear();
    constrained_.clear();
    lineEnds_.clear();
    if (!exactOrientations_.empty()) exactOrientations_ = {};  // (clear() would keep its buckets)
    exactEvaluations_ = 0;
    maxExactEvaluations_ = in.max_exact_evaluations;
    normalKnown_ = false;
    // Room for every vertex and triangle a few constraints make, without
    // moving the points (each copy of an ExactPoint is a reference count).
    const std::size_t vertices = 3 + in.points.size() + in.segments.size();
    V_.reserve(vertices);
    edges_.reserve(vertices);
    lines_.reserve(vertices);
    T_.reserve(2 * vertices);
    for (int i = 0; i < 3; ++i) add(in.corners[i], std::uint8_t((1 << i) | (1 << ((i + 2) % 3))));
    chooseProjection();
    kept_[0] = (axis_ + 1) % 3;
    kept_[1] = (axis_ + 2) % 3;
    T_.push_back({0, 1, 2});
  }

  RetriangulatedPatch triangulate(const PatchInput& in) {
    RetriangulatedPatch out;
    out.vertex_of_input.reserve(3 + in.points.size());
    out.vertex_of_input = {0, 1, 2};
    if (!in.on_edges.empty() && in.on_edges.size() != in.points.size())
      throw InvalidInputError("retriangulate: on_edges must have one entry per point");
    for (std::size_t i = 0; i < in.points.size(); ++i)
      out.vertex_of_input.push_back(
          insertPoint(in.points[i], in.on_edges.empty() ? 0 : in.on_edges[i]));
    const int inputs = int(out.vertex_of_input.size());
    for (const auto& s : in.segments) {
      if (s[0] < 0 || s[0] >= inputs || s[1] < 0 || s[1] >= inputs)
        throw InvalidInputError("retriangulate: segment refers to a point that does not exist");
      const int a = out.vertex_of_input[s[0]], b = out.vertex_of_input[s[1]];
      if (a == b) continue;  // a point, inserted already
      lineEnds_.push_back({a, b});
      lines_[a].add(int(lineEnds_.size()) - 1);
      lines_[b].add(int(lineEnds_.size()) - 1);
    }
    for (std::size_t s = 0; s < lineEnds_.size(); ++s)
      insertSegment(lineEnds_[s].first, lineEnds_[s].second, int(s));
    if (in.improve) improve();
    out.vertices = std::move(V_);
    out.triangles = T_;
    std::sort(constrained_.begin(), constrained_.end());
    out.constrained_edges.reserve(constrained_.size());
    for (const auto& piece : constrained_)
      out.constrained_edges.push_back({piece.edge.first, piece.edge.second});
    out.exact_evaluations = exactEvaluations_;
    return out;
  }

  int add(const ExactPoint& p, std::uint8_t edges = 0) {
    V_.push_back(p);
    edges_.push_back(edges);
    lines_.emplace_back();
    return int(V_.size()) - 1;
  }

  // Drop the axis along which the triangle's normal is largest (and
  // non-zero), so that the projection keeps every orientation.
  void chooseProjection() {
    if (V_[0].isInputPoint() && V_[1].isInputPoint() && V_[2].isInputPoint()) {
      const Point3 &a = V_[0].approx(), &b = V_[1].approx(), &c = V_[2].approx();
      axis_ = projectionAxis(a, b, c);
      if (axis_ < 0) throw InvalidInputError("retriangulate: the triangle is degenerate");
      sign_ = orient2dDropping(a, b, c, axis_);
      return;
    }
    std::array<mpq_class, 3> n;
    const RationalPoint &p = V_[0].exact(), &q = V_[1].exact(), &r = V_[2].exact();
    for (int k = 0; k < 3; ++k) {
      const int u = (k + 1) % 3, v = (k + 2) % 3;
      n[k] = (q.x[u] - p.x[u]) * (r.x[v] - p.x[v]) - (q.x[v] - p.x[v]) * (r.x[u] - p.x[u]);
    }
    axis_ = -1;
    for (int k = 0; k < 3; ++k)
      if (sgn(n[k]) != 0 && (axis_ < 0 || abs(n[k]) > abs(n[axis_]))) axis_ = k;
    if (axis_ < 0) throw InvalidInputError("retriangulate: the triangle is degenerate");
    sign_ = sgn(n[axis_]);
  }

  // Orientation of (a, b, c) in the projection, exactly, relative to the
  // input triangle: positive = same turn as the input.
  mpq_class orientValue(int a, int b, int c) const {
    countExactEvaluation();
    const mpq_class r = orient2dValue(V_[a].exact(), V_[b].exact(), V_[c].exact(), axis_);
    return sign_ > 0 ? r : mpq_class(-r);
  }
  int orient(int a, int b, int c) const {
    if (edges_[a] & edges_[b] & edges_[c]) return 0;           // on one edge of the input triangle
    if (lines_[a].sharedWith(lines_[b], lines_[c])) return 0;  // on one input segment
    int sign = certifiedOrient(a, b, c);
    if (sign == kUndecided) sign = orient2dDroppingFiltered(V_[a], V_[b], V_[c], axis_);
    return sign_ * (sign != kUndecided ? sign : exactOrient(a, b, c));
  }

  // The sign of the projected orientation of (a, b, c) where the rounded
  // positions certify it, else kUndecided: a bound on the error by forward
  // analysis, a few operations where the interval filter
  // (orient2dDroppingFiltered) takes many. With u = 2^-53 and m the largest
  // rounded difference, each difference is within e = (the three points'
  // errors) + u m of the exact one, so the products' difference is within
  // 4 m e + 2 e^2, and rounding the determinant adds at most
  // 2u (|l| + |r|) (1 + u). The bound is computed with twice that last term
  // and widened by (1 + 2^-40) for its own rounding, plus 2^-1000 for
  // underflow; large or non-finite values are left to the interval filter.
  int certifiedOrient(int a, int b, int c) const {
    const int x = kept_[0], y = kept_[1];
    const Point3 &pa = V_[a].approx(), &pb = V_[b].approx(), &pc = V_[c].approx();
    const double x1 = pb[x] - pa[x], y1 = pb[y] - pa[y], x2 = pc[x] - pa[x], y2 = pc[y] - pa[y];
    const double m =
        std::max(std::max(std::fabs(x1), std::fabs(y1)), std::max(std::fabs(x2), std::fabs(y2)));
    if (!(m < 1e100)) return kUndecided;
    const double l = x1 * y2, r = y1 * x2, d = l - r;
    const double e = V_[a].error() + V_[b].error() + V_[c].error() + 0x1p-53 * m;
    const double bound =
        (4 * m * e + 2 * e * e + 0x1p-51 * (std::fabs(l) + std::fabs(r))) * (1 + 0x1p-40) +
        0x1p-1000;
    if (d > bound) return 1;
    if (-d > bound) return -1;
    return kUndecided;
  }

  // The exact orientation of three vertices the rounded values leave open
  // (points on one curve are often exactly collinear), computed once per
  // vertex triple: the segment insertion and the flips ask for the same
  // triples in every order.
  int exactOrient(int a, int b, int c) const {
    std::array<int, 3> key{a, b, c};
    int parity = 1;  // sorting the triple by swaps: each swap turns the orientation
    if (key[0] > key[1]) std::swap(key[0], key[1]), parity = -parity;
    if (key[1] > key[2]) std::swap(key[1], key[2]), parity = -parity;
    if (key[0] > key[1]) std::swap(key[0], key[1]), parity = -parity;
    const std::uint64_t packed =
        (std::uint64_t(key[0]) << 42) | (std::uint64_t(key[1]) << 21) | std::uint64_t(key[2]);
    const bool packable = key[2] < (1 << 21);  // else not remembered
    if (packable) {
      const auto known = exactOrientations_.find(packed);
      if (known != exactOrientations_.end()) return parity * known->second;
    }
    countExactEvaluation();
    const int sign =
        sgn(orient2dValue(V_[key[0]].exact(), V_[key[1]].exact(), V_[key[2]].exact(), axis_));
    if (packable) exactOrientations_.emplace(packed, sign);
    return parity * sign;
  }

  // Is p visibly off the triangle's plane (from the rounded values)? The
  // triple product det[b - a, c - a, p - a] of the rounded differences
  // against a bound on its error: with m the largest difference and e the
  // points' errors plus u m (u = 2^-53) the largest error of one, each of
  // its six terms is within (m + e)^3 - m^3 = e (3 m^2 + 3 m e + e^2) of
  // the exact one, and evaluating it rounds by less than 2^-45 m^3. The
  // bound is widened by (1 + 2^-40) for its own rounding, plus 2^-1000 for
  // underflow; large or non-finite values are not checked.
  bool visiblyOffPlane(const ExactPoint& p) {
    const Point3& a = V_[0].approx();
    if (!normalKnown_) {
      const Point3 e1 = V_[1].approx() - a, e2 = V_[2].approx() - a;
      normal_ = e1 ^ e2;
      cornerDifference_ = std::max(largest(e1), largest(e2));
      normalKnown_ = true;
    }
    const Point3 e3 = p.approx() - a;
    const double m = std::max(cornerDifference_, largest(e3));
    if (!(m < 1e90)) return false;
    const double e =
        V_[0].error() + std::max({V_[1].error(), V_[2].error(), p.error()}) + 0x1p-53 * m;
    const double bound =
        (6 * e * (3 * m * m + 3 * m * e + e * e) + 0x1p-45 * m * m * m) * (1 + 0x1p-40) + 0x1p-1000;
    return std::fabs(normal_ * e3) > bound;
  }
  static double largest(const Point3& d) {
    return std::max({std::fabs(d[0]), std::fabs(d[1]), std::fabs(d[2])});
  }

  // Index of the triangle holding directed edge a->b, or -1.
  int triangleWith(int a, int b) const {
    for (std::size_t t = 0; t < T_.size(); ++t)
      for (int i = 0; i < 3; ++i)
        if (T_[t][i] == a && T_[t][(i + 1) % 3] == b) return int(t);
    return -1;
  }

  int insertPoint(const ExactPoint& p, std::uint8_t edges) {
    for (std::size_t v = 0; v < V_.size(); ++v)
      if (samePoint(p, V_[v])) return int(v);
    if (visiblyOffPlane(p))
      throw InvalidInputError("retriangulate: a point does not lie in the triangle's plane");
    for (int k = 0; k < 3; ++k)
      if (edges & (1 << k)) {
        const int q = insertOnEdge(p, k);
        if (q >= 0) return q;
      }
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
        const int a = tri[zeroEdge], b = tri[(zeroEdge + 1) % 3];
        edges_[q] |= edges_[a] & edges_[b];  // on an edge of the input triangle too
        splitEdge(a, b, q);
      }
      return q;
    }
    throw InvalidInputError("retriangulate: a point does not lie on the triangle");
  }

  // Inserts p, known to lie inside edge k of the input triangle, between its
  // neighbours along that edge; -1 when they are not joined by an edge (a
  // point on the edge arrived without saying so), for the general insertion.
  int insertOnEdge(const ExactPoint& p, int k) {
    const int c0 = k, c1 = (k + 1) % 3;
    int axis = 0;  // a coordinate that changes monotonically along the edge
    for (int a = 1; a < 3; ++a)
      if (std::fabs(V_[c1].approx()[a] - V_[c0].approx()[a]) >
          std::fabs(V_[c1].approx()[axis] - V_[c0].approx()[axis]))
        axis = a;
    const int direction = compareCoordinate(V_[c1], V_[c0], axis);
    int before = c0, after = c1;
    for (int v = 3; v < int(V_.size()); ++v) {
      if (!(edges_[v] & (1 << k))) continue;
      const int side = compareCoordinate(V_[v], p, axis) * direction;
      if (side < 0 && compareCoordinate(V_[v], V_[before], axis) * direction > 0) before = v;
      if (side > 0 && compareCoordinate(V_[v], V_[after], axis) * direction < 0) after = v;
    }
    if (triangleWith(before, after) < 0 && triangleWith(after, before) < 0) return -1;
    const int q = add(p, std::uint8_t(1 << k));
    splitEdge(before, after, q);
    return q;
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
    const int piece = constrainedIndex(key(a, b));
    if (piece >= 0) {
      const int support = constrained_[piece].support;
      constrained_[piece] = constrained_.back();
      constrained_.pop_back();
      constrain(key(a, q), support);
      constrain(key(q, b), support);
    }
  }

  // Is v beyond a and b in some coordinate by more than the points' errors
  // and the rounding of this test (the bounding box of the rounded values,
  // widened), so that between() need not compare exactly?
  bool clearlyOutside(int a, int b, int v) const {
    const Point3 &pa = V_[a].approx(), &pb = V_[b].approx(), &pv = V_[v].approx();
    const double errors = V_[a].error() + V_[b].error() + V_[v].error();
    for (int k = 0; k < 3; ++k) {
      const double lo = std::min(pa[k], pb[k]), hi = std::max(pa[k], pb[k]);
      const double slack =
          (errors + 0x1p-50 * (std::fabs(lo) + std::fabs(hi) + std::fabs(pv[k]))) * (1 + 0x1p-40) +
          0x1p-1000;
      if (pv[k] + slack < lo || pv[k] - slack > hi) return true;
    }
    return false;
  }

  int constrainedIndex(const Edge& e) const {
    for (std::size_t i = 0; i < constrained_.size(); ++i)
      if (constrained_[i].edge == e) return int(i);
    return -1;
  }
  // Marks e as a piece of input segment `support` (a piece known already keeps
  // its first).
  void constrain(const Edge& e, int support) {
    if (constrainedIndex(e) < 0) constrained_.push_back({e, support});
  }

  // Is vertex v strictly inside segment (a, b)? (collinear checked by caller)
  bool between(int a, int b, int v) const {
    if (clearlyOutside(a, b, v)) return false;
    for (int k = 0; k < 3; ++k)
      if (compareCoordinate(V_[v], V_[a], k) * compareCoordinate(V_[b], V_[v], k) < 0) return false;
    return !samePoint(V_[a], V_[v]) && !samePoint(V_[b], V_[v]);
  }

  // Inserts the constraint a-b, a piece of input segment number `support`.
  void insertSegment(int a, int b, int support) {
    if (a == b) return;
    // A vertex on the segment splits it.
    int nearest = -1;
    for (int v = 0; v < int(V_.size()); ++v) {
      // The coordinate comparisons first: they turn away most vertices
      // without the orientation, which is exact work for points on a line.
      if (v == a || v == b || !between(a, b, v) || orient(a, b, v) != 0) continue;
      if (nearest < 0 || between(a, nearest, v)) nearest = v;
    }
    if (nearest >= 0) {
      lines_[nearest].add(support);
      insertSegment(a, nearest, support);
      insertSegment(nearest, b, support);
      return;
    }
    if (triangleWith(a, b) >= 0 || triangleWith(b, a) >= 0) {
      constrain(key(a, b), support);
      return;
    }
    // The edges the segment crosses in both interiors. Each vertex's side of
    // a-b is asked once (no vertex is made until the crossings are known).
    side_.assign(V_.size(), kUnknownSide);
    auto sideOf = [&](int v) {
      if (side_[v] == kUnknownSide) side_[v] = std::int8_t(orient(a, b, v));
      return int(side_[v]);
    };
    auto crosses = [&](int u, int w) {
      return u != a && u != b && w != a && w != b && sideOf(u) * sideOf(w) < 0 &&
             orient(u, w, a) * orient(u, w, b) < 0;
    };
    std::vector<Edge>& queue = queue_;  // first in, first out from `next`
    queue.clear();
    std::size_t next = 0;
    for (const auto& tri : T_)
      for (int i = 0; i < 3; ++i) {
        const int u = tri[i], w = tri[(i + 1) % 3];
        if (u < w && crosses(u, w)) queue.push_back({u, w});
      }
    if (queue.empty()) throw InvalidInputError("retriangulate: a constraint leaves the triangle");
    for (std::size_t i = 0; i < queue.size(); ++i) {
      const Edge e = queue[i];  // (the recursion below reuses the queue)
      const int other = constrainedIndex(e);
      if (other < 0) continue;
      const int otherSupport = constrained_[other].support;
      // Two constraints cross: insert their crossing point, computed from
      // the end points of the two input segments they lie on, not from the
      // pieces, whose ends may be earlier crossings with far longer numbers
      // (the same point, at many times the cost where dozens of curves cross
      // in one face).
      const Edge line = lineEnds_[support], across = lineEnds_[otherSupport];
      const mpq_class oa = orientValue(across.first, across.second, line.first);
      const mpq_class ob = orientValue(across.first, across.second, line.second);
      const mpq_class t = oa / (oa - ob);
      RationalPoint x;
      const RationalPoint &A = V_[line.first].exact(), &B = V_[line.second].exact();
      for (int k = 0; k < 3; ++k) x.x[k] = A.x[k] + t * (B.x[k] - A.x[k]);
      const int q = add(ExactPoint(x));
      lines_[q].add(support);
      lines_[q].add(otherSupport);
      splitEdge(e.first, e.second, q);
      insertSegment(a, q, support);
      insertSegment(q, b, support);
      return;
    }
    // Sloan's edge recovery: flip crossing edges whose quadrilateral is
    // convex; a flipped edge that still crosses goes back in the queue.
    for (std::size_t guard = 0; next < queue.size(); ++guard) {
      if (guard > 100000)
        throw InvalidInputError("retriangulate: constraint recovery did not finish");
      const Edge e = queue[next++];
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
    constrain(key(a, b), support);
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

  // smallestAngleMeasure of triangle (a, b, c), from the rounded positions.
  // Computed from the smallest index on, so that every rotation of a
  // triangle gets the same value (improve keeps one per triangle).
  double minAngle(int a, int b, int c) const {
    if (b < a && b < c) {
      std::swap(a, b);  // (b, a, c)
      std::swap(b, c);  // (b, c, a)
    } else if (c < a && c < b) {
      std::swap(a, c);  // (c, b, a)
      std::swap(b, c);  // (c, a, b)
    }
    return smallestAngleMeasure(V_[a].approx(), V_[b].approx(), V_[c].approx());
  }

  // neighbour_[3 t + i]: the triangle across edge i of triangle t (from
  // corner i to i + 1), or -1 on the border.
  void findNeighbours() {
    const int n = int(T_.size());
    neighbour_.assign(3 * std::size_t(n), -1);
    // The sides listed by their first corner (a linked list per corner), so
    // that the side back is found among the few that leave the other end.
    firstSide_.assign(V_.size(), -1);
    sides_.resize(3 * std::size_t(n));
    for (int t = 0; t < n; ++t)
      for (int i = 0; i < 3; ++i) {
        int& first = firstSide_[T_[t][i]];
        sides_[3 * t + i] = {first, T_[t][(i + 1) % 3], t};
        first = 3 * t + i;
      }
    for (int t = 0; t < n; ++t)
      for (int i = 0; i < 3; ++i) {
        const int u = T_[t][i];
        for (int s = firstSide_[T_[t][(i + 1) % 3]]; s >= 0; s = sides_[s].next)
          if (sides_[s].end == u) {
            neighbour_[3 * t + i] = sides_[s].triangle;
            break;
          }
      }
  }

  // The sides of t, and the sides across from them, are to be looked at again.
  void unsettle(int t) {
    for (int k = 0; k < 3; ++k) {
      settled_[3 * t + k] = 0;
      const int across = neighbour_[3 * t + k];
      if (across < 0) continue;
      for (int m = 0; m < 3; ++m)
        if (neighbour_[3 * across + m] == t) settled_[3 * across + m] = 0;
    }
  }

  // Max-min angle flips on unconstrained interior edges, in passes over the
  // triangles' sides in order. The validity of each flip is decided
  // exactly; only the quality comparison is approximate. An edge that keeps
  // is settled until one of its two triangles changes: asking again would
  // give the same answer.
  void improve() {
    const int n = int(T_.size());
    quality_.resize(n);
    for (int t = 0; t < n; ++t) quality_[t] = minAngle(T_[t][0], T_[t][1], T_[t][2]);
    findNeighbours();
    settled_.assign(3 * std::size_t(n), 0);
    for (int pass = 0; pass < 50; ++pass) {
      bool changed = false;
      for (int t = 0; t < n; ++t)
        for (int i = 0; i < 3; ++i) {
          if (settled_[3 * t + i]) continue;
          const int u = T_[t][i], w = T_[t][(i + 1) % 3];
          const int other = neighbour_[3 * t + i];
          if (other < 0 || constrainedIndex(key(u, w)) >= 0) {
            settled_[3 * t + i] = 1;
            continue;
          }
          int j = 0;
          while (T_[other][j] != w) ++j;
          const int p = T_[t][(i + 2) % 3], q = T_[other][(j + 2) % 3];
          // (u, w, p) and (w, u, q) are the triangles; the flip makes
          // (p, q, w) and (q, p, u), if their quadrilateral is strictly convex.
          const double first = minAngle(p, q, w), second = minAngle(q, p, u);
          if (flipImproves(u, w, p, q, std::min(quality_[t], quality_[other]),
                           std::min(first, second)) &&
              orient(p, q, w) > 0 && orient(q, p, u) > 0) {
            flip(t, i, other, j);
            quality_[t] = first;
            quality_[other] = second;
            changed = true;
          } else {
            settled_[3 * t + i] = settled_[3 * other + j] = 1;
          }
        }
      if (!changed) return;
    }
  }

  // Does flipping edge (u, w) of triangles (u, w, p) and (w, u, q) to (p, q)
  // raise their smallest angle (from `before` to `after`, as measured)? Where
  // the measures cannot tell, the exact in-circle test does, and with the
  // four points on one circle the diagonal through the lexicographically
  // smallest of them is kept. Every answer is thus that of one triangulation
  // (Delaunay, its ties broken by a fixed perturbation), whatever the
  // triangulation the flips start from: faces of two meshes that overlap in
  // a plane re-triangulate their overlap alike, into the same faces.
  bool flipImproves(int u, int w, int p, int q, double before, double after) const {
    if (const int c = compareMeasures(before, after, {&V_[u], &V_[w], &V_[p], &V_[q]}))
      return c > 0;
    countExactEvaluation();
    if (const int in = inCircle(V_[u].exact(), V_[w].exact(), V_[p].exact(), V_[q].exact()))
      return in > 0;
    int smallest = u;
    for (int x : {w, p, q})
      if (compareLexicographic(V_[x], V_[smallest]) < 0) smallest = x;
    return smallest == p || smallest == q;
  }

  // Flips the edge between side i of t1 and side j of t2 (see improve),
  // keeping the neighbours.
  void flip(int t1, int i, int t2, int j) {
    const int u = T_[t1][i], w = T_[t1][(i + 1) % 3], p = T_[t1][(i + 2) % 3];
    const int q = T_[t2][(j + 2) % 3];
    const int wp = neighbour_[3 * t1 + (i + 1) % 3], pu = neighbour_[3 * t1 + (i + 2) % 3];
    const int uq = neighbour_[3 * t2 + (j + 1) % 3], qw = neighbour_[3 * t2 + (j + 2) % 3];
    T_[t1] = {p, q, w};
    T_[t2] = {q, p, u};
    const int n1[3] = {t2, qw, wp}, n2[3] = {t1, pu, uq};
    for (int k = 0; k < 3; ++k) {
      neighbour_[3 * t1 + k] = n1[k];
      neighbour_[3 * t2 + k] = n2[k];
    }
    // p-u now borders t2, q-w t1.
    for (int m = 0; pu >= 0 && m < 3; ++m)
      if (neighbour_[3 * pu + m] == t1) neighbour_[3 * pu + m] = t2;
    for (int m = 0; qw >= 0 && m < 3; ++m)
      if (neighbour_[3 * qw + m] == t2) neighbour_[3 * qw + m] = t1;
    unsettle(t1);
    unsettle(t2);
  }

  std::vector<ExactPoint> V_;
  std::vector<std::uint8_t> edges_;  // per vertex: edges of the input triangle it lies on (bits)
  std::vector<std::array<int, 3>> T_;
  // The constrained edges, each with the number of the input segment it is
  // a piece of.
  struct Constrained {
    Edge edge;
    int support;
    bool operator<(const Constrained& o) const { return edge < o.edge; }
  };
  std::vector<Constrained> constrained_;  // few: searched in order
  // The input segments' end points, and for each vertex the input segments
  // it lies on, exactly (end points, crossings, vertices found on a
  // segment): three points on one segment are collinear without asking the
  // numbers, which cannot tell that from "almost" (the exact rational
  // orientation is the slow path, and points on one curve ask it often).
  struct Lines {
    std::array<int, 4> id;
    // A vertex on more segments keeps the first four: the rest are computed.
    int n = 0;
    void add(int line) {
      if (n < 4 && !has(line)) id[n++] = line;
    }
    bool has(int line) const {
      return std::find(id.begin(), id.begin() + n, line) != id.begin() + n;
    }
    bool sharedWith(const Lines& b, const Lines& c) const {
      for (int i = 0; i < n; ++i)
        if (b.has(id[i]) && c.has(id[i])) return true;
      return false;
    }
  };
  std::vector<Edge> lineEnds_;
  // Scratch of insertSegment: the crossed edges to flip, each vertex's side
  // of the segment.
  std::vector<Edge> queue_;
  static constexpr std::int8_t kUnknownSide = 2;
  std::vector<std::int8_t> side_;
  // Scratch of improve: per triangle its quality and neighbours, per side
  // whether it is settled, and the sides listed by first corner.
  std::vector<double> quality_;
  std::vector<int> neighbour_, firstSide_;
  struct Side {
    int next;  // the next side from the same corner, or -1
    int end, triangle;
  };
  std::vector<Side> sides_;
  std::vector<std::uint8_t> settled_;
  std::vector<Lines> lines_;
  int axis_ = 2, sign_ = 1;
  std::array<int, 2> kept_{0, 1};  // the coordinates the projection keeps
  bool normalKnown_ = false;
  Point3 normal_;                // (corner 1 - corner 0) x (corner 2 - corner 0), rounded
  double cornerDifference_ = 0;  // the largest coordinate of those differences
  // Sorted triple -> sign; rare (only where the rounded values cannot tell).
  mutable std::unordered_map<std::uint64_t, int> exactOrientations_;
  mutable std::size_t exactEvaluations_ = 0;
  std::size_t maxExactEvaluations_ = 0;

  // Counts one rational evaluation (an orientation, an in-circle test)
  // against the patch's work bound.
  void countExactEvaluation() const {
    if (++exactEvaluations_ > maxExactEvaluations_ && maxExactEvaluations_ > 0)
      throw WorkLimitError(
          "the intersection curves meet in one face at points that need exact arithmetic for "
          "every decision (more than " +
          std::to_string(maxExactEvaluations_) +
          " exact evaluations): many sheets pass through nearly one point there, as the "
          "meridians of a spindle torus do near its axis");
  }
};

}  // namespace

namespace {

// The edge whose inside a point is known to lie in (a single bit), or -1.
int onlyEdge(std::uint8_t bits) {
  return bits == 1 ? 0 : bits == 2 ? 1 : bits == 4 ? 2 : -1;
}

// The most common patch where two surfaces cross: one segment between
// points known to lie inside two different edges of a proper triangle (the
// bits of on_edges are trusted, as everywhere). It cuts a corner off the
// triangle, and the rest is a convex quadrilateral (its corners are on the
// triangle's border, none at the corner cut off) with two ways to split it:
// the one the general path's insertions and max-min angle flips end with,
// so the triangles are the same. Every triangle is proper: no three of
// these points are collinear. False (and `out` untouched) when the input is
// not of that shape.
bool cutCorner(const PatchInput& in, RetriangulatedPatch& out) {
  if (!in.improve || in.points.size() != 2 || in.on_edges.size() != 2 || in.segments.size() != 1)
    return false;
  const std::array<int, 2> s = in.segments[0];
  if (!((s[0] == 3 && s[1] == 4) || (s[0] == 4 && s[1] == 3))) return false;
  const int e0 = onlyEdge(in.on_edges[0]), e1 = onlyEdge(in.on_edges[1]);
  if (e0 < 0 || e1 < 0 || e0 == e1) return false;
  // A degenerate triangle is the general path's to refuse.
  for (const ExactPoint& corner : in.corners)
    if (!corner.isInputPoint()) return false;
  if (collinear(in.corners[0].approx(), in.corners[1].approx(), in.corners[2].approx()))
    return false;
  // Around the border, in the triangle's orientation: corner a, p (inside
  // edge k, from a to c), corner c, q (inside edge k + 1), corner b.
  const int k = (e0 + 1) % 3 == e1 ? e0 : e1;
  const int p = k == e0 ? 3 : 4, q = 7 - p;
  const int a = k, c = (k + 1) % 3, b = (k + 2) % 3;
  auto at = [&](int i) -> const ExactPoint& { return i < 3 ? in.corners[i] : in.points[i - 3]; };
  // The diagonal the general path's flips end with: the one with the larger
  // smallest angle, where the measures tell (otherwise the general path
  // decides, exactly).
  auto measure = [&](int x, int y, int z) {
    if (y < x && y < z)
      std::swap(x, y), std::swap(y, z);
    else if (z < x && z < y)
      std::swap(x, z), std::swap(y, z);
    return smallestAngleMeasure(at(x).approx(), at(y).approx(), at(z).approx());
  };
  const double throughB = std::min(measure(a, p, b), measure(p, q, b));  // diagonal p-b
  const double throughA = std::min(measure(a, p, q), measure(a, q, b));  // diagonal a-q
  const int viaB = compareMeasures(throughA, throughB, {&at(a), &at(b), &at(p), &at(q)});
  if (viaB == 0) return false;
  out.vertices = {in.corners[0], in.corners[1], in.corners[2], in.points[0], in.points[1]};
  out.vertex_of_input = {0, 1, 2, 3, 4};
  out.triangles = {{p, c, q}};
  if (viaB > 0)
    out.triangles.insert(out.triangles.end(), {{a, p, b}, {p, q, b}});
  else
    out.triangles.insert(out.triangles.end(), {{a, p, q}, {a, q, b}});
  out.constrained_edges = {{3, 4}};
  return true;
}

}  // namespace

RetriangulatedPatch retriangulate(const PatchInput& input) {
  RetriangulatedPatch patch;
  if (cutCorner(input, patch)) return patch;
  thread_local Retriangulator workspace;
  return workspace.run(input);
}

}  // namespace meshmend
