// The distances of elements (Aycheh & Kyung): point–triangle region by
// region (vertex, edge, interior), so that no weight leaves [0, 1];
// segment–segment with clamped parameters; two disjoint triangles as the
// smallest of their six vertex–face and nine edge–edge distances.
#include <algorithm>
#include <cmath>

#include "common/repair/clearance/detail.h"

namespace meshmend::clearance_detail {

namespace {

// Point–segment: the fallback for a triangle with (numerically) no area.
PointTriangle pointSegment(const Point3& p, const Point3& a, const Point3& b, int ia, int ib) {
  const Point3 ab = b - a;
  const double len2 = ab.SquaredNorm();
  double s = len2 > 0 ? std::clamp(((p - a) * ab) / len2, 0.0, 1.0) : 0.0;
  PointTriangle r;
  r.point = a + ab * s;
  r.distance = (p - r.point).Norm();
  r.w[0] = r.w[1] = r.w[2] = 0;
  r.w[ia] = 1 - s;
  r.w[ib] = s;
  return r;
}

}  // namespace

PointTriangle pointTriangle(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  PointTriangle r;
  auto at = [&](double wa, double wb, double wc) {
    r.w[0] = wa;
    r.w[1] = wb;
    r.w[2] = wc;
    r.point = a * wa + b * wb + c * wc;
    r.distance = (p - r.point).Norm();
    return r;
  };
  const Point3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab * ap, d2 = ac * ap;
  if (d1 <= 0 && d2 <= 0) return at(1, 0, 0);
  const Point3 bp = p - b;
  const double d3 = ab * bp, d4 = ac * bp;
  if (d3 >= 0 && d4 <= d3) return at(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return at(1 - v, v, 0);
  }
  const Point3 cp = p - c;
  const double d5 = ab * cp, d6 = ac * cp;
  if (d6 >= 0 && d5 <= d6) return at(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return at(1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return at(0, 1 - w, w);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // No area: the closest of the three edges.
    PointTriangle best = pointSegment(p, a, b, 0, 1);
    for (const PointTriangle& e : {pointSegment(p, b, c, 1, 2), pointSegment(p, c, a, 2, 0)})
      if (e.distance < best.distance) best = e;
    return best;
  }
  const double v = vb / sum, w = vc / sum;
  return at(1 - v - w, v, w);
}

SegmentSegment segmentSegment(const Point3& p0, const Point3& p1, const Point3& q0,
                              const Point3& q1) {
  const Point3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.SquaredNorm(), e = d2.SquaredNorm(), f = d2 * r;
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) {
  } else if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1 * r;
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1 * d2, denom = a * e - b * b;
      // Parallel segments (denom 0): any s works for the lines; start at 0.
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  SegmentSegment out;
  out.s = s;
  out.t = t;
  out.pa = p0 + d1 * s;
  out.pb = q0 + d2 * t;
  out.distance = (out.pa - out.pb).Norm();
  return out;
}

TriangleDistance triangleDistance(const Point3* a, const Point3* b) {
  TriangleDistance best;
  for (int i = 0; i < 3; ++i) {
    const PointTriangle x = pointTriangle(a[i], b[0], b[1], b[2]);
    if (x.distance < best.distance) best = {x.distance, false, a[i], x.point};
    const PointTriangle y = pointTriangle(b[i], a[0], a[1], a[2]);
    if (y.distance < best.distance) best = {y.distance, false, y.point, b[i]};
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const SegmentSegment e = segmentSegment(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
      if (e.distance < best.distance) best = {e.distance, true, e.pa, e.pb};
    }
  return best;
}

}  // namespace meshmend::clearance_detail
