#include "common/retriangulate.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "common/errors.h"
#include "common/predicates.h"

namespace meshmend {

namespace {

using Edge = std::pair<int, int>;  // undirected: first < second

Edge key(int a, int b) {
  return a < b ? Edge{a, b} : Edge{b, a};
}

class Retriangulator {
 public:
  explicit Retriangulator(const PatchInput& in) {
    // Room for every vertex and triangle a few constraints make, without
    // moving the points (each copy of an ExactPoint is a reference count).
    const std::size_t vertices = 3 + in.points.size() + in.segments.size();
    V_.reserve(vertices);
    edges_.reserve(vertices);
    lines_.reserve(vertices);
    T_.reserve(2 * vertices);
    for (int i = 0; i < 3; ++i) add(in.corners[i], std::uint8_t((1 << i) | (1 << ((i + 2) % 3))));
    chooseProjection();
    T_.push_back({0, 1, 2});
  }

  Patch run(const PatchInput& in) {
    Patch out;
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
    out.triangles = std::move(T_);
    for (const auto& piece : constrained_)
      out.constrained_edges.push_back({piece.first.first, piece.first.second});
    return out;
  }

 private:
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
    const mpq_class r = orient2dValue(V_[a].exact(), V_[b].exact(), V_[c].exact(), axis_);
    return sign_ > 0 ? r : mpq_class(-r);
  }
  int orient(int a, int b, int c) const {
    if (edges_[a] & edges_[b] & edges_[c]) return 0;           // on one edge of the input triangle
    if (lines_[a].sharedWith(lines_[b], lines_[c])) return 0;  // on one input segment
    const int sign = orient2dDroppingFiltered(V_[a], V_[b], V_[c], axis_);
    return sign_ * (sign != kUndecided ? sign : exactOrient(a, b, c));
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
    const int sign =
        sgn(orient2dValue(V_[key[0]].exact(), V_[key[1]].exact(), V_[key[2]].exact(), axis_));
    if (packable) exactOrientations_.emplace(packed, sign);
    return parity * sign;
  }

  // Is p visibly off the triangle's plane (from the rounded values)?
  bool visiblyOffPlane(const ExactPoint& p) const {
    const Interval3 a = intervalOf(V_[0]), b = intervalOf(V_[1]), c = intervalOf(V_[2]);
    const Interval3 d = intervalOf(p);
    Interval e1[3], e2[3], e3[3];
    for (int k = 0; k < 3; ++k) {
      e1[k] = b[k] - a[k];
      e2[k] = c[k] - a[k];
      e3[k] = d[k] - a[k];
    }
    const Interval det = e1[0] * (e2[1] * e3[2] - e2[2] * e3[1]) -
                         e1[1] * (e2[0] * e3[2] - e2[2] * e3[0]) +
                         e1[2] * (e2[0] * e3[1] - e2[1] * e3[0]);
    return det.positive() || det.negative();
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
    const auto piece = constrained_.find(key(a, b));
    if (piece != constrained_.end()) {
      const int support = piece->second;
      constrained_.erase(piece);
      constrained_.emplace(key(a, q), support);
      constrained_.emplace(key(q, b), support);
    }
  }

  // Is vertex v strictly inside segment (a, b)? (collinear checked by caller)
  bool between(int a, int b, int v) const {
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
      constrained_.emplace(key(a, b), support);
      return;
    }
    // The edges the segment crosses in both interiors.
    auto crosses = [&](int u, int w) {
      return u != a && u != b && w != a && w != b && orient(a, b, u) * orient(a, b, w) < 0 &&
             orient(u, w, a) * orient(u, w, b) < 0;
    };
    std::vector<Edge> queue;  // first in, first out from `next`
    std::size_t next = 0;
    for (const auto& tri : T_)
      for (int i = 0; i < 3; ++i) {
        const int u = tri[i], w = tri[(i + 1) % 3];
        if (u < w && crosses(u, w)) queue.push_back({u, w});
      }
    if (queue.empty()) throw InvalidInputError("retriangulate: a constraint leaves the triangle");
    for (const Edge& e : queue) {
      const auto other = constrained_.find(e);
      if (other == constrained_.end()) continue;
      // Two constraints cross: insert their crossing point, computed from
      // the end points of the two input segments they lie on, not from the
      // pieces, whose ends may be earlier crossings with far longer numbers
      // (the same point, at many times the cost where dozens of curves cross
      // in one face).
      const Edge line = lineEnds_[support], across = lineEnds_[other->second];
      const mpq_class oa = orientValue(across.first, across.second, line.first);
      const mpq_class ob = orientValue(across.first, across.second, line.second);
      const mpq_class t = oa / (oa - ob);
      RationalPoint x;
      const RationalPoint &A = V_[line.first].exact(), &B = V_[line.second].exact();
      for (int k = 0; k < 3; ++k) x.x[k] = A.x[k] + t * (B.x[k] - A.x[k]);
      const int q = add(ExactPoint(x));
      lines_[q].add(support);
      lines_[q].add(other->second);
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
    constrained_.emplace(key(a, b), support);
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

  // A measure increasing with the smallest angle of triangle (a, b, c), from
  // the rounded positions: the squared sine of that angle, opposite the
  // shortest side (at most 60°, where the sine still grows with the angle).
  double minAngle(int a, int b, int c) const {
    const Point3 &pa = V_[a].approx(), &pb = V_[b].approx(), &pc = V_[c].approx();
    const double ab = (pb - pa).SquaredNorm(), bc = (pc - pb).SquaredNorm(),
                 ca = (pa - pc).SquaredNorm();
    const double cross = ((pb - pa) ^ (pc - pa)).SquaredNorm();  // 4 × area²
    // sin² at the apex opposite the shortest side = 4 area² / (product of the two others).
    const double others = ab <= bc && ab <= ca ? bc * ca : bc <= ca ? ab * ca : ab * bc;
    return others > 0 ? cross / others : 0;
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
          if (after > before * (1 + 1e-9) && flipIfConvex(u, w)) changed = true;
        }
      if (!changed) return;
    }
  }

  std::vector<ExactPoint> V_;
  std::vector<std::uint8_t> edges_;  // per vertex: edges of the input triangle it lies on (bits)
  std::vector<std::array<int, 3>> T_;
  // The constrained edges, each with the number of the input segment it is
  // a piece of.
  std::map<Edge, int> constrained_;
  // The input segments' end points, and for each vertex the input segments
  // it lies on, exactly (end points, crossings, vertices found on a
  // segment): three points on one segment are collinear without asking the
  // numbers, which cannot tell that from "almost" (the exact rational
  // orientation is the slow path, and points on one curve ask it often).
  struct Lines {
    std::array<int, 4> id;
    int n = 0;  // a vertex on more segments keeps the first four: the rest are computed
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
  std::vector<Lines> lines_;
  int axis_ = 2, sign_ = 1;
  mutable std::unordered_map<std::uint64_t, int> exactOrientations_;  // sorted triple -> sign
};

}  // namespace

Patch retriangulate(const PatchInput& input) {
  return Retriangulator(input).run(input);
}

}  // namespace meshmend
