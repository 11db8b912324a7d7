// Exact geometric predicates on double coordinates.
//
// Each predicate first evaluates in floating point with a static/semi-static
// error bound (Shewchuk's bounds for the rounded determinant); only when the
// bound cannot certify the sign does it fall back to exact rational arithmetic
// (GMP). The sign returned is always the sign of the exact determinant of the
// given doubles.
#pragma once

#include <algorithm>
#include <cmath>

#include "common/base/mesh.h"

namespace meshmend {

// Sign of the 2-D orientation determinant of (a, b, c): +1 when c lies to the
// left of the directed line a->b (counter-clockwise), -1 right, 0 collinear.
inline int orient2d(double ax, double ay, double bx, double by, double cx, double cy);

// Sign of det[b-a, c-a, d-a]: +1 when d lies on the side of the plane through
// a, b, c that the normal (b-a)x(c-a) points to, -1 on the other side, 0 when
// the four points are coplanar.
int orient3d(const Point3& a, const Point3& b, const Point3& c, const Point3& d);

// Exact: are the three points collinear (including coincident points)?
bool collinear(const Point3& a, const Point3& b, const Point3& c);

// Exact: the coordinate axis (0, 1, 2) to drop so that the projection of the
// non-degenerate triangle (a, b, c) onto the other two axes is non-degenerate;
// among the valid axes, the one along which its normal is largest. -1 when
// the triangle is degenerate.
int projectionAxis(const Point3& a, const Point3& b, const Point3& c);

// orient2d of the projections of a, b, c onto the plane that drops `axis`
// (coordinates (axis+1)%3, (axis+2)%3).
inline int orient2dDropping(const Point3& a, const Point3& b, const Point3& c, int axis) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  return orient2d(a[u], a[v], b[u], b[v], c[u], c[v]);
}

// orient3d(a, b, c, p) for one triangle (a, b, c) against many points p: the
// triangle's edge cross products are computed once. It evaluates the same
// determinant with the same error bound (expanded along p's row), so its
// sign is exact: the filter falls back to orient3d when it cannot decide.
// PlaneFilter keeps only those products, for a caller that has the corners
// at hand (a mesh's faces: a third of the memory); PlaneSide keeps the
// corners too.
class PlaneFilter {
 public:
  PlaneFilter() = default;
  // Inline: made per candidate pair where no per-face filters are kept.
  PlaneFilter(const Point3& a, const Point3& b, const Point3& c) {
    const double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
    const double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
    n_[0] = by * cz - bz * cy;
    n_[1] = bz * cx - bx * cz;
    n_[2] = bx * cy - by * cx;
    nAbs_[0] = std::fabs(by * cz) + std::fabs(bz * cy);
    nAbs_[1] = std::fabs(bz * cx) + std::fabs(bx * cz);
    nAbs_[2] = std::fabs(bx * cy) + std::fabs(by * cx);
  }
  // orient3d(a, b, c, p) for the corners this filter was made from. Inline:
  // the search between meshes asks it some ten times per candidate pair,
  // and a call cost as much as the filter (orient3d only when it cannot
  // decide).
  int side(const Point3& a, const Point3& b, const Point3& c, const Point3& p) const {
    if (const int s = filteredSide(a, p)) return s;
    return orient3d(a, b, c, p);
  }
  // The filter alone (a is the first corner): the exact sign where the
  // rounded determinant's error bound certifies it, else 0 (p on the plane
  // or nearly so). A cheap first test, for callers with an exact test to
  // fall back on.
  int filteredSide(const Point3& a, const Point3& p) const {
    const double dx = p[0] - a[0], dy = p[1] - a[1], dz = p[2] - a[2];
    const double det = dx * n_[0] + dy * n_[1] + dz * n_[2];
    const double permanent =
        std::fabs(dx) * nAbs_[0] + std::fabs(dy) * nAbs_[1] + std::fabs(dz) * nAbs_[2];
    const double bound =
        kOrient3dBound * permanent + underflowSlack(std::fabs(dx) + std::fabs(dy) + std::fabs(dz));
    // Without branches: which way a candidate pair's point lies is as good
    // as random, and mispredicted branches cost more than the arithmetic.
    // (NaN compares false: a non-finite det is never certified.)
    const bool certified = (std::fabs(det) <= kLargest) & (permanent > kUnderflowGuard);
    return certified * (int(det > bound) - int(-det > bound));
  }

  // Shewchuk's forward error bound for orient3d's rounded determinant, and
  // the magnitude below which products may underflow and it no longer holds.
  static constexpr double kEpsilon = 0x1p-53;
  static constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;
  static constexpr double kUnderflowGuard = 1e-250;
  // Shewchuk's bound is relative: a product that underflows is off by up to
  // 2^-1075 absolutely, and a 2x2 minor off by 2^-1074 is then multiplied by
  // the third row's coordinate (up to 1e308). The bound adds 2^-1070 per
  // unit of that row's magnitude `sum` plus one (16 times the worst case),
  // so that tiny minors next to huge coordinates go to the exact evaluation
  // instead of deciding wrongly; a large permanent alone does not exclude
  // it. This returns at least 2^-1070 (sum + 1), and at least 2^-1009, in
  // normal numbers only: arithmetic that makes a subnormal takes a microcode
  // assist of a hundred cycles or more on x86, and the filters run some ten
  // times per candidate pair. No certifiable determinant notices the larger
  // floor: the guard keeps the relative term above 1e-266.
  static double underflowSlack(double sum) { return std::max(sum, 0x1p60) * 0x1p-1000 * 0x1p-69; }
  static constexpr double kLargest = 0x1.fffffffffffffp1023;  // std::isfinite, as a comparison

 private:
  double n_[3] = {0, 0, 0};     // (b-a) x (c-a), as rounded
  double nAbs_[3] = {0, 0, 0};  // the matching sums of absolute products
};

class PlaneSide {
 public:
  PlaneSide() = default;
  PlaneSide(const Point3& a, const Point3& b, const Point3& c)
      : a_(a), b_(b), c_(c), filter_(a, b, c) {}
  int operator()(const Point3& p) const { return filter_.side(a_, b_, c_, p); }

 private:
  Point3 a_, b_, c_;
  PlaneFilter filter_;
};

// orient2d where its filter cannot decide: exactly.
int orient2dBeyondFilter(double ax, double ay, double bx, double by, double cx, double cy);

// Inline: Shewchuk's filter certifies almost every call (the fans' test asks
// it about three times per vertex), and a call cost a third of the test.
inline int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  constexpr double kBound = (3.0 + 16.0 * PlaneFilter::kEpsilon) * PlaneFilter::kEpsilon;
  const double left = (ax - cx) * (by - cy);
  const double right = (ay - cy) * (bx - cx);
  const double det = left - right;
  const double sum = std::fabs(left) + std::fabs(right);
  // Below the guard the products may have underflowed and the bound no
  // longer holds (they are off by at most 2^-1074 then, far below it).
  if (std::isfinite(det) && sum > PlaneFilter::kUnderflowGuard) {
    if (det > kBound * sum) return 1;
    if (-det > kBound * sum) return -1;
  }
  return orient2dBeyondFilter(ax, ay, bx, by, cx, cy);
}

namespace exact {
// Pure-GMP evaluations, used as the fallback and as the reference in tests.
int orient2d(double ax, double ay, double bx, double by, double cx, double cy);
int orient3d(const Point3& a, const Point3& b, const Point3& c, const Point3& d);
}  // namespace exact

}  // namespace meshmend
