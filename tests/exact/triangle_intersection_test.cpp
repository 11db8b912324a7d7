#include "common/exact/triangle_intersection.h"

#include <array>
#include <cfloat>
#include <optional>
#include <random>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include "common/exact/predicates.h"

namespace meshmend {
namespace {

using Kind = ContactKind;
using PointKind = ContactPoint::Kind;

TrianglePoints tri(Point3 a, Point3 b, Point3 c) {
  return {a, b, c};
}

const TrianglePoints kBase = tri({0, 0, 0}, {4, 0, 0}, {0, 4, 0});  // in z = 0

// ---- hand-built cases: one per kind of contact -----------------------------

TEST(TriangleIntersection, Disjoint) {
  const TrianglePoints b = tri({0, 0, 1}, {4, 0, 1}, {0, 4, 1});  // parallel, above
  EXPECT_FALSE(trianglesIntersect(kBase, b));
  EXPECT_EQ(classifyContact(kBase, b).kind, Kind::kNone);
  const TrianglePoints far = tri({5, 5, -1}, {6, 5, 1}, {5, 6, 1});  // crosses the plane, misses
  EXPECT_FALSE(trianglesIntersect(kBase, far));
  EXPECT_EQ(classifyContact(kBase, far).kind, Kind::kNone);
}

TEST(TriangleIntersection, ProperCrossing) {
  const TrianglePoints b = tri({1, 1, -1}, {1, 1, 1}, {2, -1, 0});
  ASSERT_TRUE(trianglesIntersect(kBase, b));
  const TriangleContact c = classifyContact(kBase, b);
  EXPECT_EQ(c.kind, Kind::kCrossing);
  ASSERT_EQ(c.points.size(), 2u);
  // One end where b's edge (0,1) pierces a; the other on a's edge 0 (y = 0).
  bool pierce = false, onEdge = false;
  for (const ContactPoint& p : c.points) {
    if (p.kind == PointKind::kEdgeFace && p.triangle == 1 && p.index == 0) {
      pierce = true;
      EXPECT_EQ(p.position, Point3(1, 1, 0));
    }
    if (p.kind == PointKind::kEdgeFace && p.triangle == 0 && p.index == 0) {
      onEdge = true;
      EXPECT_NEAR(p.position[0], 1.5, 1e-15);
    }
  }
  EXPECT_TRUE(pierce && onEdge);
}

TEST(TriangleIntersection, TouchAtAVertex) {
  const TrianglePoints b = tri({1, 1, 0}, {1, 2, 3}, {2, 1, 3});  // corner on a's interior
  ASSERT_TRUE(trianglesIntersect(kBase, b));
  const TriangleContact c = classifyContact(kBase, b);
  EXPECT_EQ(c.kind, Kind::kTouchAtPoint);
  ASSERT_EQ(c.points.size(), 1u);
  EXPECT_EQ(c.points[0].kind, PointKind::kVertex);
  EXPECT_EQ(c.points[0].triangle, 1);
  EXPECT_EQ(c.points[0].index, 0);
}

TEST(TriangleIntersection, VertexToVertexTouch) {
  const TrianglePoints b = tri({4, 0, 0}, {5, 0, 1}, {5, 1, 1});
  EXPECT_TRUE(trianglesIntersect(kBase, b));
  EXPECT_EQ(classifyContact(kBase, b).kind, Kind::kTouchAtPoint);
}

TEST(TriangleIntersection, EdgeLyingInTheFace) {
  // b's edge (0,1) lies in a's plane, inside a; b stands up from it.
  const TrianglePoints b = tri({1, 1, 0}, {2, 1, 0}, {1.5, 1, 2});
  ASSERT_TRUE(trianglesIntersect(kBase, b));
  const TriangleContact c = classifyContact(kBase, b);
  EXPECT_EQ(c.kind, Kind::kTouchAlongEdge);
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_EQ(c.points[0].kind, PointKind::kVertex);
  EXPECT_EQ(c.points[1].kind, PointKind::kVertex);
}

TEST(TriangleIntersection, EdgeAlongAnEdge) {
  // Two non-coplanar triangles sharing part of a's edge 0 (y = 0).
  const TrianglePoints b = tri({1, 0, 0}, {3, 0, 0}, {2, 0, 2});
  EXPECT_TRUE(trianglesIntersect(kBase, b));
  EXPECT_EQ(classifyContact(kBase, b).kind, Kind::kTouchAlongEdge);
}

TEST(TriangleIntersection, CoplanarOverlap) {
  const TrianglePoints b = tri({1, 1, 0}, {5, 1, 0}, {1, 5, 0});
  ASSERT_TRUE(trianglesIntersect(kBase, b));
  const TriangleContact c = classifyContact(kBase, b);
  EXPECT_EQ(c.kind, Kind::kCoplanarOverlap);
  // The common region is the triangle (1,1), (3,1), (1,3): b's corner and two
  // crossings of a's hypotenuse with b's edges.
  ASSERT_EQ(c.points.size(), 3u);
  int crossings = 0, corners = 0;
  for (const ContactPoint& p : c.points) {
    crossings += p.kind == PointKind::kEdgeEdge;
    corners += p.kind == PointKind::kVertex;
  }
  EXPECT_EQ(crossings, 2);
  EXPECT_EQ(corners, 1);
}

TEST(TriangleIntersection, CoplanarContainment) {
  const TrianglePoints b = tri({1, 1, 0}, {2, 1, 0}, {1, 2, 0});
  const TriangleContact c = classifyContact(kBase, b);
  EXPECT_EQ(c.kind, Kind::kCoplanarOverlap);
  ASSERT_EQ(c.points.size(), 3u);
  for (const ContactPoint& p : c.points) EXPECT_EQ(p.triangle, 1);  // b's own corners
  EXPECT_TRUE(trianglesIntersect(b, kBase));
}

TEST(TriangleIntersection, CoplanarTouchAlongAnEdgeAndAtAPoint) {
  const TrianglePoints side = tri({0, 0, 0}, {0, 4, 0}, {-3, 2, 0});  // shares a's edge 2
  const TriangleContact c = classifyContact(kBase, side);
  EXPECT_EQ(c.kind, Kind::kCoplanarTouch);
  EXPECT_EQ(c.points.size(), 2u);
  const TrianglePoints corner = tri({4, 0, 0}, {6, 0, 0}, {5, -2, 0});
  const TriangleContact p = classifyContact(kBase, corner);
  EXPECT_EQ(p.kind, Kind::kCoplanarTouch);
  EXPECT_EQ(p.points.size(), 1u);
}

TEST(TriangleIntersection, SegmentTriangle) {
  EXPECT_TRUE(segmentIntersectsTriangle({1, 1, -1}, {1, 1, 1}, kBase));
  EXPECT_TRUE(segmentIntersectsTriangle({1, 1, 0}, {1, 1, 1}, kBase));     // end point on it
  EXPECT_TRUE(segmentIntersectsTriangle({-1, 1, 0}, {1, 1, 0}, kBase));    // coplanar, enters
  EXPECT_FALSE(segmentIntersectsTriangle({-2, 1, 0}, {-1, 1, 0}, kBase));  // coplanar, outside
  EXPECT_FALSE(segmentIntersectsTriangle({3, 3, -1}, {3, 3, 1}, kBase));   // beyond hypotenuse
  EXPECT_TRUE(segmentIntersectsTriangle({2, 2, -1}, {2, 2, 1}, kBase));    // on hypotenuse
}

// The rule of PMP::self_intersections for faces sharing vertices.
TEST(TriangleIntersection, SharedVertexRules) {
  // One shared vertex (a[0] == b[0]); b's opposite edge pierces a.
  const TrianglePoints pierce = tri({0, 0, 0}, {2, 1, -1}, {2, 1, 1});
  EXPECT_TRUE(intersectBeyondShared(kBase, pierce, 1, 0, 0));
  const TrianglePoints fan = tri({0, 0, 0}, {-1, 0, 1}, {0, -1, 1});  // only the vertex
  EXPECT_FALSE(intersectBeyondShared(kBase, fan, 1, 0, 0));
  // Two shared vertices (edge 0-1 of a == b's 0-1): folded vs. flat vs. bent.
  const TrianglePoints folded = tri({0, 0, 0}, {4, 0, 0}, {2, 1, 0});
  EXPECT_TRUE(intersectBeyondShared(kBase, folded, 2, 2, 2));
  const TrianglePoints flat = tri({0, 0, 0}, {4, 0, 0}, {2, -1, 0});
  EXPECT_FALSE(intersectBeyondShared(kBase, flat, 2, 2, 2));
  const TrianglePoints bent = tri({0, 0, 0}, {4, 0, 0}, {2, 1, 1});
  EXPECT_FALSE(intersectBeyondShared(kBase, bent, 2, 2, 2));
  EXPECT_TRUE(intersectBeyondShared(kBase, kBase, 3, 0, 0));
}

// ---- randomized comparison with CGAL (an independent exact oracle) ----------

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;

template <class K>
typename K::Triangle_3 cgal(const TrianglePoints& t) {
  auto p = [](const Point3& q) { return typename K::Point_3(q[0], q[1], q[2]); };
  return {p(t[0]), p(t[1]), p(t[2])};
}

// Random triangles on a tiny integer grid (many exact degeneracies: coplanar,
// shared points, collinear edges), optionally perturbed by an ulp or scaled
// near FLT_MAX.
class Generator {
 public:
  explicit Generator(unsigned seed) : rng_(seed) {}
  TrianglePoints next(int mode) {
    for (;;) {
      TrianglePoints t;
      for (Point3& p : t) {
        for (int k = 0; k < 3; ++k) {
          double v = grid_(rng_);
          if (mode == 1 && ulp_(rng_) == 0) v = std::nextafter(v, 10.0);
          if (mode == 2) v *= double(FLT_MAX) / 8;
          if (mode == 3)  // every coordinate a few ulps off the grid: strict signs, near ties
            for (int n = ulp_(rng_) - 1; n != 0; n += n > 0 ? -1 : 1)
              v = std::nextafter(v, n > 0 ? 10.0 : -10.0);
          p[k] = v;
        }
      }
      if (!collinear(t[0], t[1], t[2])) return t;
    }
  }

 private:
  std::mt19937 rng_;
  std::uniform_int_distribution<int> grid_{0, 3};
  std::uniform_int_distribution<int> ulp_{0, 3};
};

// CGAL's exact intersection of a and b as its corner points, or none when
// they are disjoint.
std::optional<std::vector<Epeck::Point_3>> cgalContactPoints(const TrianglePoints& a,
                                                             const TrianglePoints& b) {
  const auto result = CGAL::intersection(cgal<Epeck>(a), cgal<Epeck>(b));
  if (!result) return std::nullopt;
  std::vector<Epeck::Point_3> points;
  if (const auto* p = boost::get<Epeck::Point_3>(&*result)) points = {*p};
  if (const auto* s = boost::get<Epeck::Segment_3>(&*result)) points = {s->source(), s->target()};
  if (const auto* t = boost::get<Epeck::Triangle_3>(&*result))
    points = {t->vertex(0), t->vertex(1), t->vertex(2)};
  if (const auto* v = boost::get<std::vector<Epeck::Point_3>>(&*result)) points = *v;
  return points;
}

TEST(TriangleIntersection, AgreesWithCgalOnDegenerateRandomInput) {
  Generator gen(2024);
  long checked = 0, intersecting = 0, disagreements = 0;
  for (int mode = 0; mode < 3; ++mode)
    for (int i = 0; i < 60000; ++i) {
      const TrianglePoints a = gen.next(mode), b = gen.next(mode);
      const bool ours = trianglesIntersect(a, b);
      const bool theirs = CGAL::do_intersect(cgal<Epick>(a), cgal<Epick>(b));
      disagreements += ours != theirs;
      intersecting += theirs;
      ++checked;
      const Point3 p = a[0], q = b[1];
      disagreements += segmentIntersectsTriangle(p, q, b) !=
                       CGAL::do_intersect(cgal<Epick>(b),
                                          Epick::Segment_3({p[0], p[1], p[2]}, {q[0], q[1], q[2]}));
    }
  EXPECT_EQ(disagreements, 0) << "of " << checked;
  EXPECT_GT(intersecting, checked / 10);  // the generator is not trivially disjoint
  EXPECT_LT(intersecting, checked);
}

// The classification's end points equal CGAL's exact intersection.
TEST(TriangleIntersection, ContactPointsAgreeWithCgalExactIntersection) {
  Generator gen(7);
  int compared = 0;
  for (int i = 0; i < 20000; ++i) {
    const TrianglePoints a = gen.next(1), b = gen.next(1);
    const TriangleContact c = classifyContact(a, b);
    const auto result = cgalContactPoints(a, b);
    ASSERT_EQ(c.kind == ContactKind::kNone, !result);
    if (!result) continue;
    const std::vector<Epeck::Point_3>& expected = *result;
    ASSERT_EQ(c.points.size(), expected.size()) << toString(c.kind);
    for (const Epeck::Point_3& e : expected) {
      // Epeck's to_double is only an approximation: round the exact value.
      const Point3 want(CGAL::to_double(CGAL::exact(e.x())), CGAL::to_double(CGAL::exact(e.y())),
                        CGAL::to_double(CGAL::exact(e.z())));
      bool found = false;  // our exact point, rounded the same way
      for (const ExactPoint& p : c.exact)
        found |= (nearestDoubles(p.exact()) - want).Norm() <= 1e-15 * (1 + want.Norm());
      EXPECT_TRUE(found) << toString(c.kind) << " want " << want[0] << " " << want[1] << " "
                         << want[2] << " got " << c.points[0].position[0] << " "
                         << c.points[0].position[1] << " " << c.points[0].position[2] << " / "
                         << c.points.back().position[0] << " " << c.points.back().position[1] << " "
                         << c.points.back().position[2] << " a " << a[0][0] << "," << a[0][1] << ","
                         << a[0][2] << " " << a[1][0] << "," << a[1][1] << "," << a[1][2] << " "
                         << a[2][0] << "," << a[2][1] << "," << a[2][2] << " b " << b[0][0] << ","
                         << b[0][1] << "," << b[0][2] << " " << b[1][0] << "," << b[1][1] << ","
                         << b[1][2] << " " << b[2][0] << "," << b[2][1] << "," << b[2][2];
    }
    ++compared;
  }
  EXPECT_GT(compared, 1000);
}

// Triangles with every corner a few ulps off the other's plane, their
// segments' ends nearly coinciding along the common line: the search's test
// and the classification decide from orientations of input points
// (CrossingOrder), and agree with CGAL's exact kernel.
TEST(TriangleIntersection, NearTiesOffThePlanesAgreeWithCgal) {
  Generator gen(99);
  int offPlane = 0, crossing = 0;
  for (int i = 0; i < 8000; ++i) {
    const TrianglePoints a = gen.next(3), b = gen.next(3);
    bool off = true;
    for (int k = 0; k < 3; ++k)
      off &= orient3d(a[0], a[1], a[2], b[k]) != 0 && orient3d(b[0], b[1], b[2], a[k]) != 0;
    if (!off) continue;
    ++offPlane;
    const bool meet = CGAL::do_intersect(cgal<Epick>(a), cgal<Epick>(b));
    ASSERT_EQ(trianglesIntersect(a, b), meet);
    const TriangleContact c = classifyContact(a, b);
    const auto result = cgalContactPoints(a, b);
    ASSERT_EQ(c.kind == ContactKind::kNone, !result);
    if (!result) continue;
    ASSERT_EQ(c.points.size(), result->size()) << toString(c.kind);
    for (const Epeck::Point_3& e : *result) {
      bool found = false;
      for (const ExactPoint& p : c.exact) {
        const RationalPoint& x = p.exact();
        found |= x.x[0] == CGAL::exact(e.x()) && x.x[1] == CGAL::exact(e.y()) &&
                 x.x[2] == CGAL::exact(e.z());
      }
      EXPECT_TRUE(found) << toString(c.kind);
    }
    crossing += c.kind == ContactKind::kCrossing;
  }
  EXPECT_GT(offPlane, 6000);
  EXPECT_GT(crossing, 1500);
}

// Every contact point lies exactly on both triangles' planes, and its
// rounded position and approximation are within its error bound.
TEST(TriangleIntersection, ExactPositionsLieOnBothTriangles) {
  Generator gen(31);
  int checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const TrianglePoints a = gen.next(1), b = gen.next(1);
    const TriangleContact c = classifyContact(a, b);
    ASSERT_EQ(c.exact.size(), c.points.size());
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      const RationalPoint& x = c.exact[i].exact();
      for (const TrianglePoints* t : {&a, &b})
        ASSERT_EQ(orient3d(rationalOf((*t)[0]), rationalOf((*t)[1]), rationalOf((*t)[2]), x), 0)
            << toString(c.kind);
      for (int k = 0; k < 3; ++k) {
        const mpq_class error(c.exact[i].error());
        EXPECT_LE(abs(x.x[k] - mpq_class(c.exact[i].approx()[k])), error);
        EXPECT_LE(abs(x.x[k] - mpq_class(c.points[i].position[k])), error);
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 5000);
}

// A point flagged inside_other lies strictly inside the other triangle,
// exactly (on the inner side of each of its edges, in its plane); on near
// ties off the planes (mode 3) the crossings flag most of their points.
TEST(TriangleIntersection, InsideOtherIsExact) {
  auto strictlyInside = [](const RationalPoint& x, const TrianglePoints& t) {
    const RationalPoint c[3] = {rationalOf(t[0]), rationalOf(t[1]), rationalOf(t[2])};
    auto sub = [](const RationalPoint& p, const RationalPoint& q) {
      return std::array<mpq_class, 3>{p.x[0] - q.x[0], p.x[1] - q.x[1], p.x[2] - q.x[2]};
    };
    auto cross = [](const std::array<mpq_class, 3>& u, const std::array<mpq_class, 3>& v) {
      return std::array<mpq_class, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                      u[0] * v[1] - u[1] * v[0]};
    };
    const auto n = cross(sub(c[1], c[0]), sub(c[2], c[0]));
    for (int i = 0; i < 3; ++i) {
      const auto side = cross(sub(c[(i + 1) % 3], c[i]), sub(x, c[i]));
      if (sgn(side[0] * n[0] + side[1] * n[1] + side[2] * n[2]) <= 0) return false;
    }
    return true;
  };
  for (int mode : {1, 3}) {
    Generator gen(77 + mode);
    int flagged = 0, crossingPoints = 0;
    for (int i = 0; i < 5000; ++i) {
      const TrianglePoints a = gen.next(mode), b = gen.next(mode);
      const TriangleContact c = classifyContact(a, b);
      for (std::size_t k = 0; k < c.points.size(); ++k) {
        crossingPoints += c.kind == Kind::kCrossing;
        if (!c.points[k].inside_other) continue;
        ++flagged;
        const TrianglePoints& other = c.points[k].triangle == 0 ? b : a;
        ASSERT_TRUE(strictlyInside(c.exact[k].exact(), other)) << "mode " << mode;
      }
    }
    if (mode == 3) {
      EXPECT_GT(flagged, crossingPoints / 2);
    }
    EXPECT_GT(crossingPoints, 300) << "mode " << mode;
  }
}

// sharedCorners against its definition, on triangles over few vertices
// (repeated corners included).
TEST(SharedCorners, MatchesTheDefinition) {
  std::mt19937 rng(8);
  std::uniform_int_distribution<int> vertex(0, 4);
  for (int i = 0; i < 20000; ++i) {
    const Triangle a{vertex(rng), vertex(rng), vertex(rng)},
        b{vertex(rng), vertex(rng), vertex(rng)};
    int count = 0, ia = -1, ib = -1;
    for (int x = 0; x < 3; ++x)
      for (int y = 0; y < 3; ++y)
        if (a[x] == b[y]) ++count, ia = x, ib = y;
    if (count == 2) {
      for (int x = 0; x < 3; ++x)
        if (a[x] != b[0] && a[x] != b[1] && a[x] != b[2]) ia = x;
      for (int y = 0; y < 3; ++y)
        if (b[y] != a[0] && b[y] != a[1] && b[y] != a[2]) ib = y;
    }
    const SharedCorners c = sharedCorners(a, b);
    ASSERT_EQ(c.count, count) << i;
    ASSERT_EQ(c.ia, ia) << i;
    ASSERT_EQ(c.ib, ib) << i;
  }
}

}  // namespace
}  // namespace meshmend
