#include "common/exact/triangle_intersection.h"

#include <algorithm>

#include <gmpxx.h>

#include "common/exact/predicates.h"

namespace meshmend {

namespace {

// ---- 2-D tests on the projection that drops `axis` ---------------------------

// r is known to be collinear with p, q: is it within the closed segment?
bool onSegment(const Point3& p, const Point3& q, const Point3& r, int axis) {
  for (int k = 0; k < 3; ++k) {
    if (k == axis) continue;
    if (r[k] < std::min(p[k], q[k]) || r[k] > std::max(p[k], q[k])) return false;
  }
  return true;
}

bool segmentsIntersect2(const Point3& p, const Point3& q, const Point3& r, const Point3& s,
                        int axis) {
  const int o1 = orient2dDropping(p, q, r, axis), o2 = orient2dDropping(p, q, s, axis);
  const int o3 = orient2dDropping(r, s, p, axis), o4 = orient2dDropping(r, s, q, axis);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  return (o1 == 0 && onSegment(p, q, r, axis)) || (o2 == 0 && onSegment(p, q, s, axis)) ||
         (o3 == 0 && onSegment(r, s, p, axis)) || (o4 == 0 && onSegment(r, s, q, axis));
}

bool pointInTriangle2(const Point3& p, const TrianglePoints& t, int axis) {
  const int s = orient2dDropping(t[0], t[1], t[2], axis);
  for (int i = 0; i < 3; ++i)
    if (orient2dDropping(t[i], t[(i + 1) % 3], p, axis) * s < 0) return false;
  return true;
}

bool segmentIntersectsTriangle2(const Point3& p, const Point3& q, const TrianglePoints& t,
                                int axis) {
  if (pointInTriangle2(p, t, axis) || pointInTriangle2(q, t, axis)) return true;
  for (int i = 0; i < 3; ++i)
    if (segmentsIntersect2(p, q, t[i], t[(i + 1) % 3], axis)) return true;
  return false;
}

bool trianglesIntersect2(const TrianglePoints& a, const TrianglePoints& b, int axis) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segmentsIntersect2(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], axis)) return true;
  return pointInTriangle2(a[0], b, axis) || pointInTriangle2(b[0], a, axis);
}

// ---- 3-D ---------------------------------------------------------------------

// Does segment pq meet triangle t, given sp, sq = orient3d(t, p), orient3d(t, q)
// (not both of one strict sign)?
bool edgeMeetsTriangle(const Point3& p, const Point3& q, int sp, int sq, const TrianglePoints& t) {
  if (sp == 0 && sq == 0)
    return segmentIntersectsTriangle2(p, q, t, projectionAxis(t[0], t[1], t[2]));
  // The segment meets the plane in one point: is it inside the triangle?
  const int s1 = orient3d(p, q, t[0], t[1]);
  const int s2 = orient3d(p, q, t[1], t[2]);
  const int s3 = orient3d(p, q, t[2], t[0]);
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

bool strictlyOneSide(const int s[3]) {
  return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0);
}

// Two triangles a, b whose corners all lie strictly off the other's plane,
// neither all on one side (the common case where surfaces cross). Each meets
// the other's plane in a segment whose ends lie on the two edges at its
// corner alone on its side, and the order of the four ends along the
// planes' common line, direction d = n_a x n_b (n = (t1-t0) x (t2-t0)), is a
// sign of input points, so no point needs constructing to decide it:
//  - a's ends X1, X2 on the edges from its lone corner p to a[ia+1], a[ia+2]:
//    X2 - X1 has the sign of -side(p) along d;
//  - b's ends Y1, Y2 (lone corner u): Y2 - Y1 has the sign of side(u);
//  - X on the edge from p to x, Y on the edge from u to y: Y - X has the
//    sign of orient3d(p, x, u, y) side(p) side(u).
// (With X = p + s(x - p), Y = u + t(y - u), s, t in (0, 1), Y - X = τd:
// orient3d(p, x, u, y) = det[x-p, Y-p, y-u] = (τ/s) det[X-p, d, y-u]
// = (τ/s) (n_a·(y-u)) (n_b·(X-p)), as n_a·(X-p) = 0 (Binet-Cauchy); the two
// dot products have the signs -side(u) and -side(p). The first two follow
// from (X1-p) x (X2-p) = s1 s2 n_a and its twin for b in the same way.)
class CrossingOrder {
 public:
  struct End {
    std::uint8_t triangle, edge;  // the end lies on edge `edge` of triangle `triangle`
    const Point3 *from, *to;      // that edge from the lone corner to its other corner
  };

  // side as PlaneSides, all six non-zero, neither triangle strictly on one side.
  CrossingOrder(const TrianglePoints& a, const TrianglePoints& b, const PlaneSides& side) {
    const TrianglePoints* T[2] = {&a, &b};
    for (int t = 0; t < 2; ++t) {
      const int* s = side[t];
      const int lone = s[0] == s[1] ? 2 : s[0] == s[2] ? 1 : 0;
      sign_[t] = s[lone];
      const TrianglePoints& own = *T[t];
      const End first{std::uint8_t(t), std::uint8_t(lone), &own[lone], &own[(lone + 1) % 3]};
      const End second{std::uint8_t(t), std::uint8_t((lone + 2) % 3), &own[lone],
                       &own[(lone + 2) % 3]};
      // second - first along d: -side(p) for a, side(u) for b.
      const bool secondFirst = t == 0 ? sign_[0] > 0 : sign_[1] < 0;
      lo_[t] = secondFirst ? second : first;
      hi_[t] = secondFirst ? first : second;
    }
  }

  const End& lo(int t) const { return lo_[t]; }
  const End& hi(int t) const { return hi_[t]; }

  // Sign of y - x along d, for ends of different triangles.
  int compare(const End& x, const End& y) const {
    const End &ea = x.triangle == 0 ? x : y, &eb = x.triangle == 0 ? y : x;
    const int s = orient3d(*ea.from, *ea.to, *eb.from, *eb.to) * sign_[0] * sign_[1];
    return x.triangle == 0 ? s : -s;
  }

  // Do the closed segments overlap?
  bool overlap() const { return compare(lo_[0], hi_[1]) >= 0 && compare(lo_[1], hi_[0]) >= 0; }

 private:
  int sign_[2];  // side of each triangle's lone corner
  End lo_[2], hi_[2];
};

bool allOffPlane(const PlaneSides& side) {
  return side[0][0] != 0 && side[0][1] != 0 && side[0][2] != 0 && side[1][0] != 0 &&
         side[1][1] != 0 && side[1][2] != 0;
}

}  // namespace

bool segmentIntersectsTriangle(const Point3& p, const Point3& q, const TrianglePoints& t) {
  const int sp = orient3d(t[0], t[1], t[2], p), sq = orient3d(t[0], t[1], t[2], q);
  if (sp * sq > 0) return false;
  return edgeMeetsTriangle(p, q, sp, sq, t);
}

bool trianglesIntersect(const TrianglePoints& a, const TrianglePoints& b) {
  PlaneSides side;
  for (int j = 0; j < 3; ++j) side[1][j] = orient3d(a[0], a[1], a[2], b[j]);
  if (strictlyOneSide(side[1])) return false;
  for (int i = 0; i < 3; ++i) side[0][i] = orient3d(b[0], b[1], b[2], a[i]);
  return trianglesIntersect(a, b, side);
}

bool trianglesIntersect(const TrianglePoints& a, const TrianglePoints& b, const PlaneSides& side) {
  const int *sa = side[0], *sb = side[1];
  if (strictlyOneSide(sb) || strictlyOneSide(sa)) return false;
  if (sa[0] == 0 && sa[1] == 0 && sa[2] == 0)
    return trianglesIntersect2(a, b, projectionAxis(a[0], a[1], a[2]));
  if (allOffPlane(side)) return CrossingOrder(a, b, side).overlap();
  // Not coplanar: an end point of the common segment lies on an edge of one
  // triangle inside the other.
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (sa[i] * sa[j] <= 0 && edgeMeetsTriangle(a[i], a[j], sa[i], sa[j], b)) return true;
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (sb[i] * sb[j] <= 0 && edgeMeetsTriangle(b[i], b[j], sb[i], sb[j], a)) return true;
  }
  return false;
}

bool intersectBeyondShared(const TrianglePoints& a, const TrianglePoints& b, int shared, int ia,
                           int ib) {
  switch (shared) {
    case 0:
      return trianglesIntersect(a, b);
    case 1: {
      // A face whose edge opposite the shared corner lies strictly on one
      // side of the other's plane meets that plane only at the corner.
      const Point3 &a1 = a[(ia + 1) % 3], &a2 = a[(ia + 2) % 3];
      const Point3 &b1 = b[(ib + 1) % 3], &b2 = b[(ib + 2) % 3];
      if (orient3d(b[0], b[1], b[2], a1) * orient3d(b[0], b[1], b[2], a2) > 0 ||
          orient3d(a[0], a[1], a[2], b1) * orient3d(a[0], a[1], a[2], b2) > 0)
        return false;
      return segmentIntersectsTriangle(a1, a2, b) || segmentIntersectsTriangle(b1, b2, a);
    }
    case 2: {
      const Point3 &p = a[(ia + 1) % 3], &q = a[(ia + 2) % 3];
      if (orient3d(p, q, a[ia], b[ib]) != 0) return false;
      const int axis = projectionAxis(a[0], a[1], a[2]);
      return orient2dDropping(p, q, a[ia], axis) == orient2dDropping(p, q, b[ib], axis);
    }
    default:
      return true;
  }
}

const char* toString(ContactKind kind) {
  switch (kind) {
    case ContactKind::kNone:
      return "none";
    case ContactKind::kCrossing:
      return "crossing";
    case ContactKind::kTouchAtPoint:
      return "touch at a point";
    case ContactKind::kTouchAlongEdge:
      return "touch along an edge";
    case ContactKind::kCoplanarOverlap:
      return "coplanar overlap";
    case ContactKind::kCoplanarTouch:
      return "coplanar touch";
  }
  return "?";
}

// ---- exact classification ------------------------------------------------------

namespace {

// The ExactPoint a contact point's defining elements describe.
ExactPoint exactPointOf(const ContactPoint& c, const TrianglePoints& a, const TrianglePoints& b) {
  const TrianglePoints& own = c.triangle == 0 ? a : b;
  const TrianglePoints& other = c.triangle == 0 ? b : a;
  switch (c.kind) {
    case ContactPoint::Kind::kVertex:
      return ExactPoint(own[c.index]);
    case ContactPoint::Kind::kEdgeFace:
      return ExactPoint::edgePlane(own[c.index], own[(c.index + 1) % 3], other[0], other[1],
                                   other[2]);
    case ContactPoint::Kind::kEdgeEdge:
      break;
  }
  return ExactPoint::edgeLine(a[c.index], a[(c.index + 1) % 3], b[c.other_index],
                              b[(c.other_index + 1) % 3], projectionAxis(a[0], a[1], a[2]));
}

// Not coplanar, from rounded values: each triangle meets the other's plane
// in a segment (its points on an edge crossing the plane, or its corners in
// the plane), and the contact is the overlap of the two segments along the
// planes' common line, found by comparing positions along that line in
// interval arithmetic. Returns false when a comparison is too close to call
// (touching configurations, ties), leaving it to the exact classification.
bool classifyCrossing(const TrianglePoints& a, const TrianglePoints& b, const int side[2][3],
                      TriangleContact& contact) {
  const TrianglePoints* T[2] = {&a, &b};
  // Each triangle's plane serves twice: its normal gives the line's
  // direction, and the other's edges cross it (each corner evaluated once).
  const PlaneInterval plane[2] = {PlaneInterval(a[0], a[1], a[2]), PlaneInterval(b[0], b[1], b[2])};
  const Interval3 n[2] = {plane[0].normal(), plane[1].normal()};
  Interval3 d;  // direction of the common line
  for (int k = 0; k < 3; ++k)
    d[k] = n[0][(k + 1) % 3] * n[1][(k + 2) % 3] - n[0][(k + 2) % 3] * n[1][(k + 1) % 3];
  struct Candidate {
    ContactPoint tag;
    ExactPoint point;
    Interval key;  // position along d
  };
  Candidate part[2][2];
  int count[2] = {0, 0}, zeros[2] = {0, 0};
  for (int t = 0; t < 2; ++t) {
    const TrianglePoints &own = *T[t], &other = *T[1 - t];
    Interval cornerSide[3];
    bool evaluated[3] = {false, false, false};
    auto sideOf = [&](int i) -> const Interval& {
      if (!evaluated[i]) cornerSide[i] = plane[1 - t](own[i]), evaluated[i] = true;
      return cornerSide[i];
    };
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      const int si = side[t][i], sj = side[t][j];
      if (si != 0 && si * sj >= 0) continue;
      if (count[t] == 2) return false;  // cannot happen for crossing triangles
      Candidate& c = part[t][count[t]++];
      c.tag.triangle = std::uint8_t(t);
      c.tag.index = std::uint8_t(i);
      if (si == 0) {
        c.tag.kind = ContactPoint::Kind::kVertex;
        ++zeros[t];
        c.point = ExactPoint(own[i]);
      } else {
        c.tag.kind = ContactPoint::Kind::kEdgeFace;
        c.point = ExactPoint::edgePlane(own[i], own[j], other[0], other[1], other[2], sideOf(i),
                                        sideOf(j));
      }
      const Interval3 x = intervalOf(c.point);
      c.key = d[0] * x[0] + d[1] * x[1] + d[2] * x[2];
    }
  }
  const Candidate *lo[2], *hi[2];
  for (int t = 0; t < 2; ++t) {
    if (count[t] != 2) return false;  // touching at a corner: exactly
    const Candidate &x = part[t][0], &y = part[t][1];
    if (x.key.hi < y.key.lo) {
      lo[t] = &x, hi[t] = &y;
    } else if (y.key.hi < x.key.lo) {
      lo[t] = &y, hi[t] = &x;
    } else {
      return false;
    }
  }
  // The overlap [max of starts, min of ends].
  const Candidate* start;
  if (lo[0]->key.lo > lo[1]->key.hi)
    start = lo[0];
  else if (lo[1]->key.lo > lo[0]->key.hi)
    start = lo[1];
  else
    return false;
  const Candidate* end;
  if (hi[0]->key.hi < hi[1]->key.lo)
    end = hi[0];
  else if (hi[1]->key.hi < hi[0]->key.lo)
    end = hi[1];
  else
    return false;
  contact = {};
  if (start->key.lo > end->key.hi) return true;  // the segments do not overlap
  if (!(start->key.hi < end->key.lo)) return false;
  contact.kind =
      (zeros[0] == 2 || zeros[1] == 2) ? ContactKind::kTouchAlongEdge : ContactKind::kCrossing;
  contact.points.reserve(2);  // one allocation each, not a growth step per point
  contact.exact.reserve(2);
  for (const Candidate* c : {start, end}) {
    ContactPoint p = c->tag;
    p.position = c->point.approx();
    contact.points.push_back(p);
    contact.exact.push_back(c->point);
  }
  return true;
}

// Crossing triangles with every corner strictly off the other's plane:
// the contact from the order of the segments' ends (CrossingOrder), only its
// two end points constructed. The same contact as classifyCrossing's where
// that decides; false when two ends coincide (edges of a and b meet on the
// line: a touching configuration for the exact classification).
bool classifyByOrder(const TrianglePoints& a, const TrianglePoints& b, const PlaneSides& side,
                     TriangleContact& contact) {
  const CrossingOrder order(a, b, side);
  using End = CrossingOrder::End;
  const int starts = order.compare(order.lo(0), order.lo(1));
  const int ends = order.compare(order.hi(0), order.hi(1));
  if (starts == 0 || ends == 0) return false;
  const End& start = starts > 0 ? order.lo(1) : order.lo(0);  // the later start
  const End& end = ends < 0 ? order.hi(1) : order.hi(0);      // the earlier end
  contact = {};
  if (start.triangle != end.triangle) {  // else one segment lies inside the other
    const int length = order.compare(start, end);
    if (length == 0) return false;
    if (length < 0) return true;  // the segments do not overlap
  }
  contact.kind = ContactKind::kCrossing;
  contact.points.reserve(2);
  contact.exact.reserve(2);
  const TrianglePoints* T[2] = {&a, &b};
  for (const End* e : {&start, &end}) {
    const TrianglePoints &own = *T[e->triangle], &other = *T[1 - e->triangle];
    contact.exact.push_back(
        ExactPoint::edgePlane(own[e->edge], own[(e->edge + 1) % 3], other[0], other[1], other[2]));
    ContactPoint p;
    p.kind = ContactPoint::Kind::kEdgeFace;
    p.triangle = e->triangle;
    p.index = e->edge;
    // The other triangle's chord of the line of the two planes runs through
    // its interior (none of its corners is on that line), and this end lies
    // strictly inside that chord (the comparisons above were not ties).
    p.inside_other = true;
    p.position = contact.exact.back().approx();
    contact.points.push_back(p);
  }
  return true;
}

class Classifier {
 public:
  Classifier(const TrianglePoints& a, const TrianglePoints& b) : a_(a), b_(b) {
    for (int i = 0; i < 3; ++i) {
      P_[0][i] = rationalOf(a[i]);
      P_[1][i] = rationalOf(b[i]);
    }
    // All twelve doubles as integers times one power of two, 2^scale_: the
    // plane-side determinants are then integer arithmetic (no fractions to
    // reduce), which is where the exact classification spends its time.
    int lowest = 0;
    bool any = false;
    for (const TrianglePoints* t : {&a, &b})
      for (const Point3& p : *t)
        for (int k = 0; k < 3; ++k)
          if (p[k] != 0) {
            int e;
            std::frexp(p[k], &e);
            lowest = any ? std::min(lowest, e - 53) : e - 53;
            any = true;
          }
    scale_ = lowest;
    for (int t = 0; t < 2; ++t)
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
          const double v = (t == 0 ? a : b)[i][k];
          mpz_class& z = I_[t][i][k];
          z = mpz_class(std::ldexp(std::frexp(v, &frexpExponent_), 53));  // exact 53-bit integer
          const int shift = frexpExponent_ - 53 - scale_;
          if (v == 0)
            z = 0;
          else
            z <<= shift;
        }
  }

  TriangleContact run() {
    // side[t][i]: corner i of triangle t against the other triangle's plane.
    for (int t = 0; t < 2; ++t)
      for (int i = 0; i < 3; ++i) side_[t][i] = integerSide(t, i);
    for (int t = 0; t < 2; ++t) {
      const int s[3] = {sgn(side_[t][0]), sgn(side_[t][1]), sgn(side_[t][2])};
      if (strictlyOneSide(s)) return {};
    }
    if (sgn(side_[0][0]) == 0 && sgn(side_[0][1]) == 0 && sgn(side_[0][2]) == 0) return coplanar();
    return transversal();
  }

 private:
  struct Point {
    ContactPoint tag;
    RationalPoint exact;
  };

  Point vertex(int t, int i) const {
    ContactPoint c;
    c.kind = ContactPoint::Kind::kVertex;
    c.triangle = std::uint8_t(t);
    c.index = std::uint8_t(i);
    return {c, P_[t][i]};
  }

  // Not coplanar: each triangle meets the other's plane in a point or a
  // segment; the contact is the overlap of the two along the planes' line.
  TriangleContact transversal() {
    std::vector<Point> part[2];
    int zeros[2] = {0, 0};
    for (int t = 0; t < 2; ++t)
      for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        const int si = sgn(side_[t][i]), sj = sgn(side_[t][j]);
        if (si == 0) {
          part[t].push_back(vertex(t, i));
          ++zeros[t];
        }
        if (si * sj < 0) {
          Point p;
          p.tag.kind = ContactPoint::Kind::kEdgeFace;
          p.tag.triangle = std::uint8_t(t);
          p.tag.index = std::uint8_t(i);
          // p + t (q - p) with t = s_p / (s_p - s_q): (s_p q - s_q p) / (s_p - s_q)
          const mpz_class &sp = side_[t][i], &sq = side_[t][j];
          const mpz_class den = sp - sq;
          for (int k = 0; k < 3; ++k) {
            mpq_class& c = p.exact.x[k];
            c = mpq_class(sp * I_[t][j][k] - sq * I_[t][i][k], den);
            c.canonicalize();
            if (scale_ > 0) mpq_mul_2exp(c.get_mpq_t(), c.get_mpq_t(), mp_bitcnt_t(scale_));
            if (scale_ < 0) mpq_div_2exp(c.get_mpq_t(), c.get_mpq_t(), mp_bitcnt_t(-scale_));
          }
          part[t].push_back(p);
        }
      }
    // Positions along the line: projections onto d = normal(a) x normal(b).
    RationalPoint n[2];
    for (int t = 0; t < 2; ++t) {
      RationalPoint e1, e2;
      for (int k = 0; k < 3; ++k) {
        e1.x[k] = P_[t][1].x[k] - P_[t][0].x[k];
        e2.x[k] = P_[t][2].x[k] - P_[t][0].x[k];
      }
      for (int k = 0; k < 3; ++k)
        n[t].x[k] = e1.x[(k + 1) % 3] * e2.x[(k + 2) % 3] - e1.x[(k + 2) % 3] * e2.x[(k + 1) % 3];
    }
    RationalPoint d;
    for (int k = 0; k < 3; ++k)
      d.x[k] =
          n[0].x[(k + 1) % 3] * n[1].x[(k + 2) % 3] - n[0].x[(k + 2) % 3] * n[1].x[(k + 1) % 3];
    auto key = [&](const Point& p) -> mpq_class {
      return d.x[0] * p.exact.x[0] + d.x[1] * p.exact.x[1] + d.x[2] * p.exact.x[2];
    };
    const Point *lo[2], *hi[2];
    mpq_class loKey[2], hiKey[2];
    for (int t = 0; t < 2; ++t) {
      lo[t] = hi[t] = &part[t][0];
      loKey[t] = hiKey[t] = key(part[t][0]);
      for (const Point& p : part[t]) {
        const mpq_class k = key(p);
        if (k < loKey[t]) lo[t] = &p, loKey[t] = k;
        if (k > hiKey[t]) hi[t] = &p, hiKey[t] = k;
      }
    }
    // The overlap [max of starts, min of ends]; on a tie a vertex describes
    // the point best, then triangle a's element.
    auto better = [](const Point* x, const Point* y) {
      return y->tag.kind == ContactPoint::Kind::kVertex &&
             x->tag.kind != ContactPoint::Kind::kVertex;
    };
    const Point* start = loKey[0] > loKey[1]   ? lo[0]
                         : loKey[1] > loKey[0] ? lo[1]
                                               : (better(lo[0], lo[1]) ? lo[1] : lo[0]);
    const mpq_class startKey = std::max(loKey[0], loKey[1]);
    const Point* end = hiKey[0] < hiKey[1]   ? hi[0]
                       : hiKey[1] < hiKey[0] ? hi[1]
                                             : (better(hi[0], hi[1]) ? hi[1] : hi[0]);
    const mpq_class endKey = std::min(hiKey[0], hiKey[1]);
    TriangleContact c;
    if (startKey > endKey) return c;
    if (startKey == endKey) {
      c.kind = ContactKind::kTouchAtPoint;
      finish(c, *start);
      return c;
    }
    c.kind =
        (zeros[0] == 2 || zeros[1] == 2) ? ContactKind::kTouchAlongEdge : ContactKind::kCrossing;
    finish(c, *start);
    finish(c, *end);
    return c;
  }

  // Coplanar: clip triangle a by the three edge lines of b (Sutherland-
  // Hodgman). Every clipped edge lies on a line of a's or b's edges, so each
  // new corner is an edge-edge crossing or a corner of b.
  TriangleContact coplanar() {
    const TrianglePoints a{nearestDoubles(P_[0][0]), nearestDoubles(P_[0][1]),
                           nearestDoubles(P_[0][2])};
    axis_ = projectionAxis(a[0], a[1], a[2]);
    const int orientation = sgn(orient2dValue(P_[1][0], P_[1][1], P_[1][2], axis_));
    struct Corner {
      Point point;
      int line;  // line of the edge leaving this corner: 0..2 edges of a, 3..5 edges of b
    };
    std::vector<Corner> polygon;
    for (int i = 0; i < 3; ++i) polygon.push_back({vertex(0, i), i});
    for (int j = 0; j < 3 && !polygon.empty(); ++j) {
      const RationalPoint &b0 = P_[1][j], &b1 = P_[1][(j + 1) % 3];
      auto inside = [&](const Point& p) {
        return sgn(orient2dValue(b0, b1, p.exact, axis_)) * orientation >= 0;
      };
      std::vector<Corner> out;
      for (std::size_t k = 0; k < polygon.size(); ++k) {
        const Corner& s = polygon[k];
        const Corner& e = polygon[(k + 1) % polygon.size()];
        const bool sIn = inside(s.point), eIn = inside(e.point);
        if (sIn && eIn) {
          out.push_back(e);
        } else if (sIn && !eIn) {
          out.push_back({crossing(s.line, j), 3 + j});
        } else if (!sIn && eIn) {
          out.push_back({crossing(s.line, j), s.line});
          out.push_back(e);
        }
      }
      polygon = std::move(out);
    }
    // Drop repeated points (touching configurations repeat corners).
    std::vector<Point> points;
    for (const Corner& c : polygon) {
      bool seen = false;
      for (const Point& p : points)
        seen |= p.exact.x[0] == c.point.exact.x[0] && p.exact.x[1] == c.point.exact.x[1] &&
                p.exact.x[2] == c.point.exact.x[2];
      if (!seen) points.push_back(c.point);
    }
    TriangleContact c;
    if (points.empty()) return c;
    mpq_class area2 = 0;
    for (std::size_t k = 0; k + 2 < points.size(); ++k)
      area2 += orient2dValue(points[0].exact, points[k + 1].exact, points[k + 2].exact, axis_);
    if (sgn(area2) != 0) {
      c.kind = ContactKind::kCoplanarOverlap;
      for (const Point& p : points) finish(c, p);
      return c;
    }
    c.kind = ContactKind::kCoplanarTouch;
    if (points.size() == 1) {
      finish(c, points[0]);
      return c;
    }
    // Collinear points: keep the two extremes.
    const int u = (axis_ + 1) % 3, v = (axis_ + 2) % 3;
    auto less = [&](const Point& x, const Point& y) {
      return x.exact.x[u] < y.exact.x[u] ||
             (x.exact.x[u] == y.exact.x[u] && x.exact.x[v] < y.exact.x[v]);
    };
    const auto [mn, mx] = std::minmax_element(points.begin(), points.end(), less);
    finish(c, *mn);
    finish(c, *mx);
    return c;
  }

  // Where a clipped edge lying on `line` crosses the line of b's edge j.
  Point crossing(int line, int j) const {
    if (line >= 3) {  // two edge lines of b meet at their common corner
      const int m = line - 3;
      return vertex(1, (m + 1) % 3 == j ? j : m);
    }
    Point p;
    p.tag.kind = ContactPoint::Kind::kEdgeEdge;
    p.tag.triangle = 0;
    p.tag.index = std::uint8_t(line);
    p.tag.other_index = std::uint8_t(j);
    // On a's edge `line` (from corner line to line+1), at the parameter where
    // it crosses b's edge line j.
    const RationalPoint &a0 = P_[0][line], &a1 = P_[0][(line + 1) % 3];
    const RationalPoint &b0 = P_[1][j], &b1 = P_[1][(j + 1) % 3];
    const mpq_class o0 = orient2dValue(b0, b1, a0, axis_), o1 = orient2dValue(b0, b1, a1, axis_);
    p.exact = along(a0, a1, o0 / (o0 - o1));
    return p;
  }

  // Appends p to the contact: its defining elements, rounded and exact positions.
  void finish(TriangleContact& contact, const Point& p) const {
    ContactPoint c = p.tag;
    c.position = nearestDoubles(p.exact);
    contact.points.push_back(c);
    contact.exact.push_back(exactPointOf(c, a_, b_));
  }

  TrianglePoints a_, b_;
  RationalPoint P_[2][3];
  // Corner i of triangle t against the other triangle's plane, as an
  // integer determinant (scaled by 2^(3 scale_)).
  mpz_class integerSide(int t, int i) const {
    const auto& o = I_[1 - t];
    const auto& p = I_[t][i];
    mpz_class b[3], c[3], d[3];
    for (int k = 0; k < 3; ++k) {
      b[k] = o[1][k] - o[0][k];
      c[k] = o[2][k] - o[0][k];
      d[k] = p[k] - o[0][k];
    }
    return b[0] * (c[1] * d[2] - c[2] * d[1]) - b[1] * (c[0] * d[2] - c[2] * d[0]) +
           b[2] * (c[0] * d[1] - c[1] * d[0]);
  }

  mpz_class I_[2][3][3];  // the coordinates as integers times 2^scale_
  int scale_ = 0;
  int frexpExponent_ = 0;
  mpz_class side_[2][3];
  int axis_ = 2;
};

}  // namespace

TriangleContact classifyContact(const TrianglePoints& a, const TrianglePoints& b) {
  PlaneSides side;
  for (int i = 0; i < 3; ++i) {
    side[0][i] = orient3d(b[0], b[1], b[2], a[i]);
    side[1][i] = orient3d(a[0], a[1], a[2], b[i]);
  }
  return classifyContact(a, b, side);
}

TriangleContact classifyContact(const TrianglePoints& a, const TrianglePoints& b,
                                const PlaneSides& side) {
  if (strictlyOneSide(side[0]) || strictlyOneSide(side[1])) return {};
  const bool coplanar = side[0][0] == 0 && side[0][1] == 0 && side[0][2] == 0;
  TriangleContact contact;
  if (!coplanar && allOffPlane(side) && classifyByOrder(a, b, side, contact)) return contact;
  if (!coplanar && classifyCrossing(a, b, side, contact)) return contact;
  return Classifier(a, b).run();
}

}  // namespace meshmend
