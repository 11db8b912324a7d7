// Exact triangle–triangle and segment–triangle intersection.
//
// Every decision is made by the filtered exact predicates of predicates.h on
// the input doubles. Intersection points are described by their defining
// input elements (a vertex, an edge crossing the other triangle's plane, or
// two crossing coplanar edges) together with their coordinates rounded from
// the exact rational value, so that later steps can keep deciding exactly.
#pragma once

#include <array>
#include <vector>

#include "common/base/mesh.h"
#include "common/exact/exact_point.h"

namespace meshmend {

using TrianglePoints = std::array<Point3, 3>;

// Exact: do the closed segment pq and the closed triangle t share a point?
// The triangle must not be degenerate.
bool segmentIntersectsTriangle(const Point3& p, const Point3& q, const TrianglePoints& t);

// Exact: do the two closed, non-degenerate triangles share at least one point?
bool trianglesIntersect(const TrianglePoints& a, const TrianglePoints& b);

// The exact sides of each triangle's corners against the other's plane:
// side[0][i] = orient3d(b[0], b[1], b[2], a[i]), side[1][j] = orient3d(a[0],
// a[1], a[2], b[j]). A caller that has them (a candidate search) passes them
// on, so that neither test below evaluates them again.
using PlaneSides = int[2][3];
// trianglesIntersect given the sides.
bool trianglesIntersect(const TrianglePoints& a, const TrianglePoints& b, const PlaneSides& side);

// The rule of CGAL::Polygon_mesh_processing::self_intersections for two
// faces of one mesh that share `shared` vertices (by index): 0 -> any
// contact; 1 -> the edge opposite the shared vertex in one triangle meets the
// other triangle; 2 -> coplanar and folded onto each other (both apexes on the
// same side of the shared edge); 3 -> always (duplicate faces).
// `a[ia]` / `b[ib]` are the shared vertex when shared == 1; when shared == 2
// they are the apexes (the unshared vertices).
bool intersectBeyondShared(const TrianglePoints& a, const TrianglePoints& b, int shared, int ia,
                           int ib);

// How two faces of one mesh share corners (by vertex index), in the form
// intersectBeyondShared takes: the shared corner when count == 1, the apexes
// (unshared corners) when count == 2.
struct SharedCorners {
  int count = 0;
  int ia = -1, ib = -1;
};
// Selections, not branches: whether two candidate faces share a corner is
// as good as random, and the mispredicted branches cost more than the nine
// comparisons.
inline SharedCorners sharedCorners(const Triangle& a, const Triangle& b) {
  SharedCorners s;
  int inB = 0, inA = 0;  // bit i: a[i] is a corner of b; bit j: b[j] is one of a
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const bool same = a[i] == b[j];
      s.count += same;
      s.ia = same ? i : s.ia;
      s.ib = same ? j : s.ib;
      inB |= int(same) << i;
      inA |= int(same) << j;
    }
  if (s.count == 2) {  // the corners not shared
    for (int i = 0; i < 3; ++i) s.ia = (inB >> i & 1) ? s.ia : i;
    for (int j = 0; j < 3; ++j) s.ib = (inA >> j & 1) ? s.ib : j;
  }
  return s;
}
// Do a and b have the same three vertices (the same face twice)?
inline bool sameVertices(const Triangle& a, const Triangle& b) {
  return sharedCorners(a, b).count == 3;
}

// How two triangles meet.
enum class ContactKind {
  kNone,             // disjoint
  kCrossing,         // not coplanar; a segment through the interior of both
  kTouchAtPoint,     // a single common point
  kTouchAlongEdge,   // not coplanar; a segment on an edge of at least one of them
  kCoplanarOverlap,  // coplanar; a common region of positive area
  kCoplanarTouch,    // coplanar; only boundaries meet (a point or a segment)
};

const char* toString(ContactKind kind);

// An exact intersection point, by its defining elements. Triangle 0 is `a`,
// triangle 1 is `b`; edge i of a triangle runs from its corner i to i+1.
struct ContactPoint {
  enum class Kind : std::uint8_t {
    kVertex,    // corner `index` of triangle `triangle`
    kEdgeFace,  // edge `index` of triangle `triangle` crossing the other triangle's plane
    kEdgeEdge,  // coplanar: edge `index` of a crossing edge `other_index` of b
  };
  Kind kind = Kind::kVertex;
  std::uint8_t triangle = 0;
  std::uint8_t index = 0;
  std::uint8_t other_index = 0;
  // Known to lie strictly inside the other triangle (off its edges and
  // corners), from how the point was found; false when not known.
  bool inside_other = false;
  Point3 position{0, 0, 0};  // the exact point, rounded to the nearest doubles
};

struct TriangleContact {
  ContactKind kind = ContactKind::kNone;
  // kCrossing / kTouchAlongEdge: the segment's two end points; kTouchAtPoint:
  // one point; coplanar: the common polygon's corners in order (or the touching
  // point or segment).
  std::vector<ContactPoint> points;
  std::vector<ExactPoint> exact;  // the same points, exactly
};

// Full classification with exact end points. Slower than trianglesIntersect:
// meant for pairs known to intersect. Crossing triangles (the common case)
// are classified from rounded values with error bounds; touching and
// coplanar ones fall back to rational arithmetic.
TriangleContact classifyContact(const TrianglePoints& a, const TrianglePoints& b);
// The same given the sides.
TriangleContact classifyContact(const TrianglePoints& a, const TrianglePoints& b,
                                const PlaneSides& side);

}  // namespace meshmend
