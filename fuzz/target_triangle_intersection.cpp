// The exact triangle-triangle tests (common/triangle_intersection.h) on two
// triangles from a grid (coplanar, touching and shared corners are common)
// or raw coordinates: the yes/no test, its symmetries, the classification
// and every contact point, checked exactly against both triangles.
#include <cmath>

#include "common/exact/exact_point.h"
#include "common/exact/predicates.h"
#include "common/exact/triangle_intersection.h"
#include "fuzz/fuzz_input.h"

namespace meshmend::fuzz {

namespace {

// Is the exact point p on the closed triangle t?
bool onTriangle(const RationalPoint& p, const TrianglePoints& t) {
  const RationalPoint a = rationalOf(t[0]), b = rationalOf(t[1]), c = rationalOf(t[2]);
  if (orient3d(a, b, c, p) != 0) return false;
  const int axis = projectionAxis(t[0], t[1], t[2]);
  const int s = sgn(orient2dValue(a, b, c, axis));
  return sgn(orient2dValue(a, b, p, axis)) * s >= 0 && sgn(orient2dValue(b, c, p, axis)) * s >= 0 &&
         sgn(orient2dValue(c, a, p, axis)) * s >= 0;
}

TrianglePoints rotated(const TrianglePoints& t) {
  return {t[1], t[2], t[0]};
}
TrianglePoints reversed(const TrianglePoints& t) {
  return {t[0], t[2], t[1]};
}

}  // namespace

void triangleIntersection(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const std::uint8_t kind = in.byte(), share = in.byte();
  const double scale = gridScale(in.byte());
  TrianglePoints a, b;
  for (Point3& p : a) p = decodePoint(in, kind, scale);
  for (Point3& p : b) p = decodePoint(in, kind, scale);
  // Shared corners as meshes have them: b takes one or two of a's.
  if (share & 1) b[0] = a[share >> 6 & 1];
  if (share & 2) b[1] = a[2];
  for (const TrianglePoints* t : {&a, &b})
    for (const Point3& p : *t)
      if (!isFinite(p) || std::abs(p[0]) > 1e300 || std::abs(p[1]) > 1e300 ||
          std::abs(p[2]) > 1e300)
        return;  // inputs are finite meshes: the core checks that first
  if (collinear(a[0], a[1], a[2]) || collinear(b[0], b[1], b[2])) return;  // precondition

  const bool meet = trianglesIntersect(a, b);
  check(meet == trianglesIntersect(b, a), "symmetric");
  check(meet == trianglesIntersect(rotated(a), b), "independent of the corner order");
  check(meet == trianglesIntersect(a, reversed(b)), "independent of the orientation");
  bool edgeMeets = false;
  for (int i = 0; i < 3; ++i) {
    edgeMeets |= segmentIntersectsTriangle(a[i], a[(i + 1) % 3], b);
    edgeMeets |= segmentIntersectsTriangle(b[i], b[(i + 1) % 3], a);
  }
  check(meet == edgeMeets, "two triangles meet exactly when an edge of one meets the other");

  const TriangleContact contact = classifyContact(a, b);
  check((contact.kind != ContactKind::kNone) == meet, "classification agrees with the test");
  check(contact.exact.size() == contact.points.size(), "one exact point per contact point");
  if (meet) check(!contact.points.empty(), "a contact has points");
  for (const ExactPoint& p : contact.exact) {
    check(onTriangle(p.exact(), a) && onTriangle(p.exact(), b),
          std::string("contact points lie on both triangles (") + toString(contact.kind) + ")");
    for (int k = 0; k < 3; ++k) {
      const mpq_class error = abs(p.exact().x[k] - mpq_class(p.approx()[k]));
      check(error <= mpq_class(p.error()), "the error bound holds");
    }
  }
  const bool coplanar =
      contact.kind == ContactKind::kCoplanarOverlap || contact.kind == ContactKind::kCoplanarTouch;
  if (coplanar)
    for (const Point3& p : b) check(orient3d(a[0], a[1], a[2], p) == 0, "coplanar means coplanar");
  if (contact.kind == ContactKind::kCrossing)
    check(contact.points.size() == 2, "a crossing is a segment");

  // The self-intersection rule on faces that share no corner is any contact.
  check(intersectBeyondShared(a, b, 0, -1, -1) == meet, "the rule without shared corners");
}

}  // namespace meshmend::fuzz
