#include "common/exact/predicates.h"

#include "common/base/errors.h"
#include "common/exact/expansion.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include <gmpxx.h>

namespace meshmend {

namespace {

// Shewchuk's forward error bound for orient3d's rounded determinant.
constexpr double kOrient3dBound = PlaneFilter::kOrient3dBound;
// Below this magnitude products may underflow and the bound no longer holds;
// orient3d's minors multiplied by a coordinate may have underflowed
// (PlaneFilter::underflowSlack).
constexpr double kUnderflowGuard = PlaneFilter::kUnderflowGuard;

int sign(const mpq_class& q) {
  return sgn(q);
}

// GMP has no infinity or NaN (mpq_set_d raises SIGFPE on them): a predicate
// on such a coordinate, which no mesh the core takes has but a point
// constructed near the double range may, refuses instead.
void requireFinite(std::initializer_list<double> values) {
  for (double v : values)
    if (!std::isfinite(v))
      throw InvalidInputError(
          "an exact test met a non-finite coordinate (NaN or infinity), computed from "
          "coordinates near the limits of double: scale the mesh towards the origin");
}

}  // namespace

namespace exact {

int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  requireFinite({ax, ay, bx, by, cx, cy});
  const mpq_class acx = mpq_class(ax) - mpq_class(cx), bcx = mpq_class(bx) - mpq_class(cx);
  const mpq_class acy = mpq_class(ay) - mpq_class(cy), bcy = mpq_class(by) - mpq_class(cy);
  return sign(acx * bcy - acy * bcx);
}

int orient3d(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  requireFinite({a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2]});
  mpq_class m[3][3];
  for (int k = 0; k < 3; ++k) {
    m[0][k] = mpq_class(b[k]) - mpq_class(a[k]);
    m[1][k] = mpq_class(c[k]) - mpq_class(a[k]);
    m[2][k] = mpq_class(d[k]) - mpq_class(a[k]);
  }
  const mpq_class det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                        m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                        m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return sign(det);
}

}  // namespace exact

int orient2dBeyondFilter(double ax, double ay, double bx, double by, double cx, double cy) {
  const double left = (ax - cx) * (by - cy);
  const double right = (ay - cy) * (bx - cx);
  if (left == 0 && right == 0 && ((ax == cx || by == cy) && (ay == cy || bx == cx)))
    return 0;  // both products exactly zero because a factor is exactly zero
  if (expansion::safe({ax, ay, bx, by, cx, cy})) return expansion::orient2d(ax, ay, bx, by, cx, cy);
  return exact::orient2d(ax, ay, bx, by, cx, cy);
}

int orient3d(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  const double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
  const double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
  const double dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
  const double m1 = cy * dz - cz * dy, m2 = cx * dz - cz * dx, m3 = cx * dy - cy * dx;
  const double det = bx * m1 - by * m2 + bz * m3;
  const double permanent = (std::fabs(cy * dz) + std::fabs(cz * dy)) * std::fabs(bx) +
                           (std::fabs(cx * dz) + std::fabs(cz * dx)) * std::fabs(by) +
                           (std::fabs(cx * dy) + std::fabs(cy * dx)) * std::fabs(bz);
  const double bound = kOrient3dBound * permanent +
                       PlaneFilter::underflowSlack(std::fabs(bx) + std::fabs(by) + std::fabs(bz));
  if (std::isfinite(det) && permanent > kUnderflowGuard) {
    if (det > bound) return 1;
    if (-det > bound) return -1;
  }
  if (expansion::safe({a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2]}))
    return expansion::orient3d(a, b, c, d);
  return exact::orient3d(a, b, c, d);
}

int projectionAxis(const Point3& a, const Point3& b, const Point3& c) {
  const Point3 normal = (b - a) ^ (c - a);  // component k = orientation dropping axis k
  // The axes by decreasing |normal| component (three compares, no sort).
  int order[3] = {0, 1, 2};
  auto before = [&](int x, int y) { return std::fabs(normal[x]) > std::fabs(normal[y]); };
  if (before(order[1], order[0])) std::swap(order[0], order[1]);
  if (before(order[2], order[1])) std::swap(order[1], order[2]);
  if (before(order[1], order[0])) std::swap(order[0], order[1]);
  for (int axis : order)
    if (orient2dDropping(a, b, c, axis) != 0) return axis;
  return -1;
}

bool collinear(const Point3& a, const Point3& b, const Point3& c) {
  // The cross product (b-a)x(c-a) vanishes exactly iff its three components,
  // the orientations of the projections onto the three coordinate planes, do.
  return orient2d(a[0], a[1], b[0], b[1], c[0], c[1]) == 0 &&
         orient2d(a[1], a[2], b[1], b[2], c[1], c[2]) == 0 &&
         orient2d(a[2], a[0], b[2], b[0], c[2], c[0]) == 0;
}

}  // namespace meshmend
