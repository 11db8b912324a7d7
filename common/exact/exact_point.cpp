#include "common/exact/exact_point.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <numeric>

#include "common/base/errors.h"
#include "common/exact/interval.h"
#include "common/exact/predicates.h"

namespace meshmend {

namespace {

Interval orient2dInterval(const Point3& a, const Point3& b, const Point3& c, int axis) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  return (Interval(b[u]) - a[u]) * (Interval(c[v]) - a[v]) -
         (Interval(b[v]) - a[v]) * (Interval(c[u]) - a[u]);
}

double nearestDouble(const mpq_class& q) {
  const double d = q.get_d();  // truncated toward zero
  if (mpq_class(d) == q) return d;
  const double away = std::nextafter(d, q > 0 ? INFINITY : -INFINITY);
  return abs(q - mpq_class(away)) < abs(q - mpq_class(d)) ? away : d;
}

// The approximation and error of a point whose coordinates lie in `x`.
void enclose(const Interval3& x, Point3& approx, double& error) {
  error = 0;
  for (int k = 0; k < 3; ++k) {
    const double mid = 0.5 * x[k].lo + 0.5 * x[k].hi;
    approx[k] = mid;
    error = std::max({error, up(x[k].hi - mid), up(mid - x[k].lo)});
  }
  if (!std::isfinite(error)) error = INFINITY;
}

}  // namespace

PlaneInterval::PlaneInterval(const Point3& r, const Point3& s, const Point3& t) : r_(r) {
  for (int k = 0; k < 3; ++k) {
    b_[k] = Interval(s[k]) - r[k];
    c_[k] = Interval(t[k]) - r[k];
  }
}

Interval PlaneInterval::operator()(const Point3& p) const {
  const Interval *b = b_, *c = c_;
  Interval d[3];
  for (int k = 0; k < 3; ++k) d[k] = Interval(p[k]) - r_[k];
  return b[0] * (c[1] * d[2] - c[2] * d[1]) - b[1] * (c[0] * d[2] - c[2] * d[0]) +
         b[2] * (c[0] * d[1] - c[1] * d[0]);
}

Interval3 PlaneInterval::normal() const {
  Interval3 n;
  for (int k = 0; k < 3; ++k)
    n[k] = b_[(k + 1) % 3] * c_[(k + 2) % 3] - b_[(k + 2) % 3] * c_[(k + 1) % 3];
  return n;
}

RationalPoint rationalOf(const Point3& p) {
  // GMP has no infinity or NaN (mpq_set_d raises SIGFPE on them).
  if (!isFinite(p))
    throw InvalidInputError(
        "an exact point met a non-finite coordinate (NaN or infinity), computed from "
        "coordinates near the limits of double: scale the mesh towards the origin");
  return {{mpq_class(p[0]), mpq_class(p[1]), mpq_class(p[2])}};
}

mpq_class orient3dValue(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
                        const RationalPoint& d) {
  mpq_class m[3][3];
  for (int k = 0; k < 3; ++k) {
    m[0][k] = b.x[k] - a.x[k];
    m[1][k] = c.x[k] - a.x[k];
    m[2][k] = d.x[k] - a.x[k];
  }
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

mpq_class orient2dValue(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
                        int axis) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  return (b.x[u] - a.x[u]) * (c.x[v] - a.x[v]) - (b.x[v] - a.x[v]) * (c.x[u] - a.x[u]);
}

// p + t (q - p)
RationalPoint along(const RationalPoint& p, const RationalPoint& q, const mpq_class& t) {
  RationalPoint r;
  for (int k = 0; k < 3; ++k) {
    r.x[k] = p.x[k] + t * (q.x[k] - p.x[k]);
    r.x[k].canonicalize();
  }
  return r;
}

Point3 nearestDoubles(const RationalPoint& p) {
  return {nearestDouble(p.x[0]), nearestDouble(p.x[1]), nearestDouble(p.x[2])};
}

ExactPoint::ExactPoint(const Point3& p) : kind_(Kind::kDouble), approx_(p), error_(0) {
  definition_[0] = p;
}

ExactPoint::ExactPoint(const RationalPoint& p) : kind_(Kind::kRational) {
  auto exact = std::make_shared<RationalPoint>(p);
  for (mpq_class& c : exact->x) c.canonicalize();
  approx_ = nearestDoubles(*exact);
  error_ = 0;
  for (int k = 0; k < 3; ++k)
    if (mpq_class(approx_[k]) != exact->x[k])
      error_ = std::max(error_, up(std::fabs(approx_[k]) * 0x1p-52 + kTiny));
  exact_ = std::move(exact);
}

namespace {

// The interval of p + lambda (q - p), clamped to the segment's box.
Interval3 onSegmentAt(const Point3& p, const Point3& q, const Interval& lambda) {
  const Interval t = intersect(lambda, 0, 1);
  Interval3 x;
  for (int k = 0; k < 3; ++k)
    x[k] = intersect(Interval(p[k]) + t * (Interval(q[k]) - p[k]), std::min(p[k], q[k]),
                     std::max(p[k], q[k]));
  return x;
}

}  // namespace

ExactPoint ExactPoint::edgePlane(const Point3& p, const Point3& q, const Point3& r, const Point3& s,
                                 const Point3& t) {
  const PlaneInterval plane(r, s, t);
  return edgePlane(p, q, r, s, t, plane(p), plane(q));
}

ExactPoint ExactPoint::edgePlane(const Point3& p, const Point3& q, const Point3& r, const Point3& s,
                                 const Point3& t, const Interval& sp, const Interval& sq) {
  ExactPoint e;
  e.kind_ = Kind::kEdgePlane;
  e.definition_ = {p, q, r, s, t};
  e.approximate(onSegmentAt(p, q, sp / (sp - sq)));
  return e;
}

ExactPoint ExactPoint::edgeLine(const Point3& p, const Point3& q, const Point3& r, const Point3& s,
                                int axis) {
  ExactPoint e;
  e.kind_ = Kind::kEdgeLine;
  e.axis_ = std::uint8_t(axis);
  e.definition_ = {p, q, r, s, Point3(0, 0, 0)};
  const Interval op = orient2dInterval(r, s, p, axis), oq = orient2dInterval(r, s, q, axis);
  e.approximate(onSegmentAt(p, q, op / (op - oq)));
  return e;
}

void ExactPoint::approximate(const Interval3& x) {
  enclose(x, approx_, error_);
  if (!std::isfinite(error_)) *this = ExactPoint(exact());  // out of double range on the way
}

const RationalPoint& ExactPoint::exact() const {
  if (!exact_) computeExact();
  return *exact_;
}

namespace {

// The input points of a construction as integers: coordinate = integer ×
// 2^shift for one shift (the lowest bit any of them has), so that the
// construction runs on integers and needs one reduction at the end instead
// of a gcd after every rational operation.
struct ScaledPoints {
  std::array<std::array<mpz_class, 3>, 5> x;
  long shift = 0;

  ScaledPoints(const std::array<Point3, 5>& points, int count) {
    long lowest = LONG_MAX;
    for (int i = 0; i < count; ++i)
      for (int k = 0; k < 3; ++k)
        if (points[i][k] != 0) {
          int e;
          std::frexp(points[i][k], &e);  // |value| = m 2^e, m in [0.5, 1): lowest bit >= e - 53
          lowest = std::min(lowest, long(e) - 53);
        }
    shift = lowest == LONG_MAX ? 0 : lowest;
    for (int i = 0; i < count; ++i)
      for (int k = 0; k < 3; ++k) {
        int e;
        const double m = std::frexp(points[i][k], &e);
        mpz_class& z = x[i][k];
        z = std::ldexp(m, 53);                    // an integer below 2^53: exact
        const long raise = long(e) - 53 - shift;  // >= 0 for every non-zero coordinate
        if (z != 0 && raise > 0) mpz_mul_2exp(z.get_mpz_t(), z.get_mpz_t(), (unsigned long)raise);
      }
  }
};

mpz_class orient3dInteger(const std::array<mpz_class, 3>& a, const std::array<mpz_class, 3>& b,
                          const std::array<mpz_class, 3>& c, const std::array<mpz_class, 3>& d) {
  mpz_class m[3][3];
  for (int k = 0; k < 3; ++k) {
    m[0][k] = b[k] - a[k];
    m[1][k] = c[k] - a[k];
    m[2][k] = d[k] - a[k];
  }
  return mpz_class(m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                   m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                   m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]));
}

mpz_class orient2dInteger(const std::array<mpz_class, 3>& a, const std::array<mpz_class, 3>& b,
                          const std::array<mpz_class, 3>& c, int axis) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  return mpz_class((b[u] - a[u]) * (c[v] - a[v]) - (b[v] - a[v]) * (c[u] - a[u]));
}

// p + t (q - p) for t = wp / (wp - wq), that is (wp q - wq p) / (wp - wq),
// with p and q the scaled points 0 and 1 (wp and wq of one degree in them).
RationalPoint alongScaled(const ScaledPoints& s, const mpz_class& wp, const mpz_class& wq) {
  const mpz_class denominator = wp - wq;
  RationalPoint r;
  for (int k = 0; k < 3; ++k) {
    mpq_class& x = r.x[k];
    x.get_num() = wp * s.x[1][k] - wq * s.x[0][k];
    x.get_den() = denominator;
    if (sgn(x.get_den()) < 0) {
      x.get_num() = -x.get_num();
      x.get_den() = -x.get_den();
    }
    x.canonicalize();
    // The weights' scale cancels in the ratio; the coordinates' remains.
    if (s.shift > 0) mpq_mul_2exp(x.get_mpq_t(), x.get_mpq_t(), (unsigned long)s.shift);
    if (s.shift < 0) mpq_div_2exp(x.get_mpq_t(), x.get_mpq_t(), (unsigned long)-s.shift);
  }
  return r;
}

}  // namespace

void ExactPoint::computeExact() const {
  const auto& d = definition_;
  switch (kind_) {
    case Kind::kDouble:
    case Kind::kRational:  // always present
      exact_ = std::make_shared<RationalPoint>(rationalOf(d[0]));
      return;
    case Kind::kEdgePlane: {
      const ScaledPoints s(d, 5);
      const mpz_class sp = orient3dInteger(s.x[2], s.x[3], s.x[4], s.x[0]);
      const mpz_class sq = orient3dInteger(s.x[2], s.x[3], s.x[4], s.x[1]);
      exact_ = std::make_shared<RationalPoint>(alongScaled(s, sp, sq));
      return;
    }
    case Kind::kEdgeLine: {
      const ScaledPoints s(d, 4);
      const mpz_class op = orient2dInteger(s.x[2], s.x[3], s.x[0], axis_);
      const mpz_class oq = orient2dInteger(s.x[2], s.x[3], s.x[1], axis_);
      exact_ = std::make_shared<RationalPoint>(alongScaled(s, op, oq));
      return;
    }
  }
}

bool samePoint(const ExactPoint& a, const ExactPoint& b) {
  if (a.isInputPoint() && b.isInputPoint()) return a.approx() == b.approx();
  const double e = up(a.error() + b.error());
  for (int k = 0; k < 3; ++k)
    if (std::fabs(a.approx()[k] - b.approx()[k]) > up(e)) return false;
  const RationalPoint &x = a.exact(), &y = b.exact();
  return x.x[0] == y.x[0] && x.x[1] == y.x[1] && x.x[2] == y.x[2];
}

int compareCoordinate(const ExactPoint& a, const ExactPoint& b, int k) {
  const double d = a.approx()[k] - b.approx()[k];
  if (a.error() == 0 && b.error() == 0) return (d > 0) - (d < 0);  // exact sign of a difference
  const double bound = up(up(a.error() + b.error()) + std::fabs(d) * kRelative);
  if (d > bound) return 1;
  if (-d > bound) return -1;
  return sgn(a.exact().x[k] - b.exact().x[k]);
}

int orient2dDroppingFiltered(const ExactPoint& a, const ExactPoint& b, const ExactPoint& c,
                             int axis) {
  if (a.isInputPoint() && b.isInputPoint() && c.isInputPoint())
    return orient2dDropping(a.approx(), b.approx(), c.approx(), axis);
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const Interval3 pa = intervalOf(a), pb = intervalOf(b), pc = intervalOf(c);
  const Interval det = (pb[u] - pa[u]) * (pc[v] - pa[v]) - (pb[v] - pa[v]) * (pc[u] - pa[u]);
  if (det.positive()) return 1;
  if (det.negative()) return -1;
  return kUndecided;
}

int orient2dDropping(const ExactPoint& a, const ExactPoint& b, const ExactPoint& c, int axis) {
  const int sign = orient2dDroppingFiltered(a, b, c, axis);
  return sign != kUndecided ? sign : sgn(orient2dValue(a.exact(), b.exact(), c.exact(), axis));
}

bool onSegment(const ExactPoint& p, const ExactPoint& a, const ExactPoint& b) {
  for (int k = 0; k < 3; ++k)  // between a and b, coordinate by coordinate
    if (compareCoordinate(p, a, k) * compareCoordinate(b, p, k) < 0) return false;
  if (p.isInputPoint() && a.isInputPoint() && b.isInputPoint())
    return collinear(p.approx(), a.approx(), b.approx());
  // (p - a) x (b - a) == 0
  const Interval3 x = intervalOf(p), y = intervalOf(a), z = intervalOf(b);
  for (int k = 0; k < 3; ++k) {
    const int u = (k + 1) % 3, v = (k + 2) % 3;
    const Interval c = (x[u] - y[u]) * (z[v] - y[v]) - (x[v] - y[v]) * (z[u] - y[u]);
    if (c.positive() || c.negative()) return false;
  }
  const RationalPoint &P = p.exact(), &A = a.exact(), &B = b.exact();
  for (int k = 0; k < 3; ++k) {
    const int u = (k + 1) % 3, v = (k + 2) % 3;
    if ((P.x[u] - A.x[u]) * (B.x[v] - A.x[v]) != (P.x[v] - A.x[v]) * (B.x[u] - A.x[u]))
      return false;
  }
  return true;
}

int orient3d(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
             const RationalPoint& d) {
  return sgn(orient3dValue(a, b, c, d));
}

int inCircle(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
             const RationalPoint& d) {
  // The planar in-circle determinant (rows b-a, c-a, d-a with their squared
  // lengths) in an orthonormal frame of the plane, times |n| > 0 with
  // n = (b-a) x (c-a): each 2-D cross product u x v there is (u x v) . n / |n|.
  using V = std::array<mpq_class, 3>;
  // (Explicit return types: gmpxx's expression templates would otherwise
  // outlive the temporaries they refer to.)
  auto minus = [](const RationalPoint& p, const RationalPoint& q) -> V {
    return V{p.x[0] - q.x[0], p.x[1] - q.x[1], p.x[2] - q.x[2]};
  };
  auto cross = [](const V& u, const V& v) -> V {
    return V{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  };
  auto dot = [](const V& u, const V& v) -> mpq_class {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  const V B = minus(b, a), C = minus(c, a), D = minus(d, a), n = cross(B, C);
  const mpq_class v =
      dot(B, B) * dot(cross(C, D), n) - dot(C, C) * dot(cross(B, D), n) + dot(D, D) * dot(n, n);
  return -sgn(v);  // negative inside (a, b, c counter-clockwise about n)
}

int compareLexicographic(const ExactPoint& a, const ExactPoint& b) {
  for (int k = 0; k < 3; ++k)
    if (const int c = compareCoordinate(a, b, k)) return c;
  return 0;
}

std::vector<int> coincidentGroups(const std::vector<const ExactPoint*>& points) {
  const std::size_t n = points.size();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  if (n < 2) return parent;
  // Each point's box of possible positions, and that box's extent along a
  // direction across every coordinate plane (axis-aligned inputs put many
  // points on one coordinate, hardly any on one plane across it): points
  // that coincide have overlapping extents, so a sweep over the extents in
  // order compares each point with the few whose extents overlap its own.
  constexpr double kDirection[3] = {1.0, 0.6180339887498949, 0.3819660112501051};
  std::vector<Point3> lo(n), hi(n);
  std::vector<double> low(n), high(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Point3& a = points[i]->approx();
    const double e = points[i]->error();
    if (!isFinite(a) || !std::isfinite(e)) {  // no bound: compared with every point
      lo[i] = Point3(-INFINITY, -INFINITY, -INFINITY);
      hi[i] = Point3(INFINITY, INFINITY, INFINITY);
      low[i] = -INFINITY;
      high[i] = INFINITY;
      continue;
    }
    double l = 0, h = 0;
    for (int k = 0; k < 3; ++k) {
      lo[i][k] = down(a[k] - e);
      hi[i][k] = up(a[k] + e);
      l = down(l + down(kDirection[k] * lo[i][k]));  // all weights positive: low corner, low end
      h = up(h + up(kDirection[k] * hi[i][k]));
    }
    low[i] = l;
    high[i] = h;
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return low[a] < low[b]; });
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t a = 0; a < n; ++a) {
    const int i = order[a];
    for (std::size_t b = a + 1; b < n && low[order[b]] <= high[i]; ++b) {
      const int j = order[b];
      bool overlap = true;
      for (int k = 0; k < 3; ++k) overlap = overlap && lo[i][k] <= hi[j][k] && lo[j][k] <= hi[i][k];
      if (!overlap) continue;
      const int ri = find(i), rj = find(j);
      if (ri != rj && samePoint(*points[i], *points[j]))
        parent[std::max(ri, rj)] = std::min(ri, rj);
    }
  }
  for (std::size_t i = 0; i < n; ++i) parent[i] = find(int(i));
  return parent;
}

}  // namespace meshmend
