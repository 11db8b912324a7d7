// Exact triangle–triangle and segment–triangle intersection.
//
// Every decision is made by the filtered exact predicates of predicates.h on
// the input doubles. Intersection points are described by their defining
// input elements (a vertex, an edge crossing the other triangle's plane, or
// two crossing coplanar edges) together with their coordinates rounded from
// the exact rational value, so that later steps can keep deciding exactly.
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <array>
#include <cstdint>
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
// One bit per pair of corners, then a table: no branch on whether two
// candidate faces share a corner (as good as random, and a mispredicted
// branch costs more than the nine comparisons). The last match in the
// order (a[0], b[0]), (a[0], b[1]), ... gives ia and ib.
namespace shared_corners_detail {
struct Entry {
  std::int8_t count, ia, ib;
};
// The SharedCorners of each match mask (bit 3i + j: a[i] == b[j]).
constexpr std::array<Entry, 512> table() {
  std::array<Entry, 512> t{};
  for (unsigned m = 0; m < 512; ++m) {
    int count = 0, last = -1;
    for (int bit = 0; bit < 9; ++bit)
      if (m >> bit & 1) ++count, last = bit;
    int ia = last < 0 ? -1 : last / 3, ib = last < 0 ? -1 : last % 3;
    if (count == 2) {  // the corners not shared, where there are such
      for (int i = 0; i < 3; ++i)
        if (!(m >> (3 * i) & 7)) ia = i;  // a[i] is no corner of b (the last such)
      for (int j = 0; j < 3; ++j)
        if (!((m | m >> 3 | m >> 6) >> j & 1)) ib = j;
    }
    t[m] = {std::int8_t(count), std::int8_t(ia), std::int8_t(ib)};
  }
  return t;
}
inline constexpr std::array<Entry, 512> kTable = table();
}  // namespace shared_corners_detail
inline SharedCorners sharedCorners(const Triangle& a, const Triangle& b) {
  // Bit 3i + k of m: a's corner i is b's corner k.
#if defined(__SSE2__)
  // Each corner of a against b's three at once (a third of the
  // instructions of nine scalar comparisons; every candidate pair asks).
  const __m128i corners = _mm_setr_epi32(b[0], b[1], b[2], b[2]);
  auto row = [&](int v) {
    return unsigned(
               _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(corners, _mm_set1_epi32(v))))) &
           7u;
  };
  const unsigned m = row(a[0]) | row(a[1]) << 3 | row(a[2]) << 6;
#else
  // The nine comparisons written out: as a loop they took twice the
  // instructions.
  const int a0 = a[0], a1 = a[1], a2 = a[2], b0 = b[0], b1 = b[1], b2 = b[2];
  const unsigned m = unsigned(a0 == b0) | unsigned(a0 == b1) << 1 | unsigned(a0 == b2) << 2 |
                     unsigned(a1 == b0) << 3 | unsigned(a1 == b1) << 4 | unsigned(a1 == b2) << 5 |
                     unsigned(a2 == b0) << 6 | unsigned(a2 == b1) << 7 | unsigned(a2 == b2) << 8;
#endif
  const shared_corners_detail::Entry e = shared_corners_detail::kTable[m];
  return {e.count, e.ia, e.ib};
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
