// Points known exactly by their construction from input doubles.
//
// An intersection point (an edge crossing a plane, two coplanar edges
// crossing) has rational coordinates whose exact value is costly to compute
// and to compare. An ExactPoint carries its construction, a rounded
// approximation and a rigorous bound on that approximation's error; the
// predicates below decide from the approximation whenever the bound allows
// and compute the exact rational value (once per point, on first use) only
// when it does not, so that the common case never touches GMP.
#pragma once

#include <array>
#include <memory>

#include <gmpxx.h>

#include "common/base/mesh.h"
#include "common/exact/interval.h"

namespace meshmend {

// A point with exact rational coordinates.
struct RationalPoint {
  std::array<mpq_class, 3> x;
};

// det[s-r, t-r, p-r] in interval arithmetic for one plane (r, s, t) and many
// points p: the plane's edge vectors are computed once. Every construction
// on the plane evaluates it through this class, so a caller that shares one
// gets values identical to edgePlane's own.
class PlaneInterval {
 public:
  PlaneInterval(const Point3& r, const Point3& s, const Point3& t);
  Interval operator()(const Point3& p) const;
  // (s-r) x (t-r)
  Interval3 normal() const;

 private:
  Point3 r_;
  Interval b_[3], c_[3];  // s-r, t-r
};

class ExactPoint {
 public:
  ExactPoint() = default;
  explicit ExactPoint(const Point3& p);         // an input point (exactly its doubles)
  explicit ExactPoint(const RationalPoint& p);  // a given rational point

  // Where segment pq crosses the plane through r, s, t; p and q must lie
  // strictly on opposite sides of that plane.
  static ExactPoint edgePlane(const Point3& p, const Point3& q, const Point3& r, const Point3& s,
                              const Point3& t);
  // The same given sp, sq = PlaneInterval(r, s, t) of p and q (a caller
  // building several points on one plane evaluates each corner once).
  static ExactPoint edgePlane(const Point3& p, const Point3& q, const Point3& r, const Point3& s,
                              const Point3& t, const Interval& sp, const Interval& sq);
  // Coplanar: where segment pq crosses the line through r and s, in the
  // projection that drops `axis`; p and q strictly on opposite sides of it.
  static ExactPoint edgeLine(const Point3& p, const Point3& q, const Point3& r, const Point3& s,
                             int axis);

  // |approx()[k] - exact k-th coordinate| <= error() for k = 0, 1, 2.
  const Point3& approx() const { return approx_; }
  double error() const { return error_; }
  bool isInputPoint() const { return kind_ == Kind::kDouble; }

  // The exact coordinates, computed on first use. Not safe to call from two
  // threads on one object (copies are independent).
  const RationalPoint& exact() const;

 private:
  enum class Kind : std::uint8_t { kDouble, kRational, kEdgePlane, kEdgeLine };
  void computeExact() const;
  // Sets the approximation and error to enclose `x`; computes the exact
  // value instead when the intervals overflowed.
  void approximate(const Interval3& x);

  Kind kind_ = Kind::kDouble;
  std::uint8_t axis_ = 0;
  std::array<Point3, 5> definition_{};  // the input points of the construction
  Point3 approx_{0, 0, 0};
  double error_ = 0;
  mutable std::shared_ptr<const RationalPoint> exact_;
};

// The box of coordinates the exact point may have, as intervals.
inline Interval3 intervalOf(const ExactPoint& p) {
  const double e = p.error();
  const Point3& a = p.approx();
  if (e == 0) return intervalOf(a);
  return {Interval(down(a[0] - e), up(a[0] + e)), Interval(down(a[1] - e), up(a[1] + e)),
          Interval(down(a[2] - e), up(a[2] + e))};
}

// Exact predicates on ExactPoints (filtered).

// Do a and b have the same exact coordinates?
bool samePoint(const ExactPoint& a, const ExactPoint& b);

// Sign of a[k] - b[k].
int compareCoordinate(const ExactPoint& a, const ExactPoint& b, int k);

// Sign of the orientation of (a, b, c) projected onto the plane that drops
// `axis` (coordinates (axis+1)%3, (axis+2)%3): +1 counter-clockwise.
int orient2dDropping(const ExactPoint& a, const ExactPoint& b, const ExactPoint& c, int axis);
// The same when the rounded values decide it (input points always do);
// otherwise kUndecided, and only the exact value can tell.
inline constexpr int kUndecided = 2;
int orient2dDroppingFiltered(const ExactPoint& a, const ExactPoint& b, const ExactPoint& c,
                             int axis);

// Is p on the closed segment ab (collinear in 3-D and between them)?
bool onSegment(const ExactPoint& p, const ExactPoint& a, const ExactPoint& b);

// Rational arithmetic, for the exact fallbacks.
RationalPoint rationalOf(const Point3& p);
// det[b-a, c-a, d-a]
mpq_class orient3dValue(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
                        const RationalPoint& d);
// The orientation of the projections dropping `axis` (coordinates (axis+1)%3, (axis+2)%3).
mpq_class orient2dValue(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
                        int axis);
// p + t (q - p), canonical.
RationalPoint along(const RationalPoint& p, const RationalPoint& q, const mpq_class& t);

// Sign of det[b-a, c-a, d-a] on exact rational points.
int orient3d(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
             const RationalPoint& d);

// For coplanar a, b, c, d (a, b, c not collinear): +1 when d lies strictly
// inside the circle through a, b and c, 0 on it, -1 outside. In the plane
// itself, so independent of any projection and of the order of a, b, c.
int inCircle(const RationalPoint& a, const RationalPoint& b, const RationalPoint& c,
             const RationalPoint& d);

// Sign of a - b in lexicographic order of the coordinates (x, then y, z).
int compareLexicographic(const ExactPoint& a, const ExactPoint& b);

// The double nearest to each coordinate.
Point3 nearestDoubles(const RationalPoint& p);

// Representatives of exactly coincident points: result[i] is the smallest
// index j with samePoint(points[j], points[i]). Sorts by the approximations
// and compares exactly only where their error boxes overlap.
std::vector<int> coincidentGroups(const std::vector<const ExactPoint*>& points);

}  // namespace meshmend
