#include "common/exact/exact_point.h"

#include <random>

#include <gtest/gtest.h>

#include "common/exact/predicates.h"

namespace meshmend {
namespace {

RationalPoint rationalOf(const Point3& p) {
  return {{mpq_class(p[0]), mpq_class(p[1]), mpq_class(p[2])}};
}

// The exact value lies within the reported error of the approximation.
void expectEnclosed(const ExactPoint& p) {
  const RationalPoint& x = p.exact();
  for (int k = 0; k < 3; ++k)
    EXPECT_LE(abs(x.x[k] - mpq_class(p.approx()[k])), mpq_class(p.error())) << "coordinate " << k;
}

// An edge crossing a plane at random, at tiny angles (where the parameter
// of the crossing is ill-conditioned) and at coordinates of very different
// magnitudes: the exact crossing always lies in the reported error box, and
// lies on the plane and on the edge.
TEST(ExactPoint, EdgePlaneCrossingIsEnclosed) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  int built = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double scale = std::ldexp(1.0, int(trial % 7) * 40 - 120);
    auto point = [&] { return Point3(u(rng), u(rng), u(rng)) * scale; };
    const Point3 r = point(), s = point(), t = point();
    Point3 p = point(), q = point();
    if (trial % 3 == 0) q = p + (q - p) * 1e-9;  // a short edge
    const int sp = orient3d(r, s, t, p), sq = orient3d(r, s, t, q);
    if (sp * sq >= 0) continue;
    const ExactPoint x = ExactPoint::edgePlane(p, q, r, s, t);
    expectEnclosed(x);
    EXPECT_EQ(orient3d(rationalOf(r), rationalOf(s), rationalOf(t), x.exact()), 0);
    EXPECT_TRUE(onSegment(x, ExactPoint(p), ExactPoint(q)));
    EXPECT_LT(x.error(), 1e-12 * scale);  // the bound is tight enough to decide with
    ++built;
  }
  EXPECT_GT(built, 500);
}

TEST(ExactPoint, EdgeLineCrossingIsEnclosed) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-1, 1);
  int built = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Point3 p(u(rng), u(rng), 0.25), q(u(rng), u(rng), 0.25);
    const Point3 r(u(rng), u(rng), 0.25), s(u(rng), u(rng), 0.25);
    if (orient2dDropping(r, s, p, 2) * orient2dDropping(r, s, q, 2) >= 0) continue;
    const ExactPoint x = ExactPoint::edgeLine(p, q, r, s, 2);
    expectEnclosed(x);
    EXPECT_EQ(x.exact().x[2], mpq_class(0.25));
    EXPECT_EQ(orient2dDropping(ExactPoint(r), ExactPoint(s), x, 2), 0);
    ++built;
  }
  EXPECT_GT(built, 500);
}

// Predicates agree with rational arithmetic, including exact ties that the
// approximations cannot decide.
TEST(ExactPoint, PredicatesAreExact) {
  // The edge (0,0,0)-(2,2,2) crosses z = 1 at exactly (1,1,1).
  const ExactPoint x = ExactPoint::edgePlane({0, 0, 0}, {2, 2, 2}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1});
  const ExactPoint one(Point3(1, 1, 1));
  EXPECT_TRUE(samePoint(x, one));
  EXPECT_EQ(compareCoordinate(x, one, 0), 0);
  // One third, which no double equals: crossing of (0,0,0)-(1,3,0) with x... y = 1.
  const ExactPoint third =
      ExactPoint::edgePlane({0, 0, 0}, {1, 3, 0}, {0, 1, 0}, {1, 1, 0}, {0, 1, 1});
  EXPECT_EQ(third.exact().x[0], mpq_class(1, 3));
  EXPECT_FALSE(samePoint(third, ExactPoint(Point3(1.0 / 3, 1, 0))));
  EXPECT_EQ(compareCoordinate(third, ExactPoint(Point3(1.0 / 3, 1, 0)), 0),
            sgn(mpq_class(1, 3) - mpq_class(1.0 / 3)));
  // Collinear with (0,0,0) and (2,6,0), exactly.
  EXPECT_EQ(orient2dDropping(ExactPoint(Point3(0, 0, 0)), ExactPoint(Point3(2, 6, 0)), third, 2),
            0);
  EXPECT_TRUE(onSegment(third, ExactPoint(Point3(0, 0, 0)), ExactPoint(Point3(2, 6, 0))));
  EXPECT_FALSE(onSegment(third, ExactPoint(Point3(0, 0, 0)), ExactPoint(Point3(2, 6.0000001, 0))));
  // A rational point that is a double is exact.
  const ExactPoint half(RationalPoint{{mpq_class(1, 2), mpq_class(3), mpq_class(-5, 4)}});
  EXPECT_EQ(half.error(), 0);
  EXPECT_TRUE(samePoint(half, ExactPoint(Point3(0.5, 3, -1.25))));
}

// Random orientations near degeneracy: the filtered sign equals the exact one.
TEST(ExactPoint, Orient2dMatchesRationalArithmetic) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 3000; ++trial) {
    const Point3 r(u(rng), u(rng), 0), s(u(rng), u(rng), 0);
    const Point3 p(u(rng), u(rng), 1), q(u(rng), u(rng), -1);
    const ExactPoint x = ExactPoint::edgePlane(p, q, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    // A point on the line r-s through x's projection, give or take a tiny bit.
    const Point3 a = r;
    const Point3 b = x.approx() + (x.approx() - r) * (trial % 2 ? 1.0 : 1.0 + 1e-15);
    const ExactPoint A(a), B(Point3(b[0], b[1], 0));
    const RationalPoint &ea = A.exact(), &eb = B.exact(), &ex = x.exact();
    const mpq_class det =
        (eb.x[0] - ea.x[0]) * (ex.x[1] - ea.x[1]) - (eb.x[1] - ea.x[1]) * (ex.x[0] - ea.x[0]);
    EXPECT_EQ(orient2dDropping(A, B, x, 2), sgn(det));
  }
}

TEST(ExactPoint, InCircleIsDecidedInThePlaneOfThePoints) {
  // The unit circle about c in a tilted plane spanned by u and w (orthogonal,
  // of equal length 3: circles stay circles), with points inside, on and
  // outside, and the three on the circle given in both orders.
  const mpq_class half(1, 2);
  auto at = [](const mpq_class& s, const mpq_class& t) {
    const mpq_class u[3] = {1, 2, 2}, w[3] = {2, 1, -2}, c[3] = {5, -1, 3};
    RationalPoint p;
    for (int k = 0; k < 3; ++k) p.x[k] = c[k] + s * u[k] + t * w[k];
    return p;
  };
  const RationalPoint a = at(1, 0), b = at(0, 1), c = at(-1, 0);
  EXPECT_EQ(inCircle(a, b, c, at(0, half)), 1);
  EXPECT_EQ(inCircle(a, b, c, at(0, -1)), 0);
  EXPECT_EQ(inCircle(a, b, c, at(mpq_class(3, 5), mpq_class(-4, 5))), 0);  // 3-4-5: on it
  EXPECT_EQ(inCircle(a, b, c, at(1, 1)), -1);
  EXPECT_EQ(inCircle(c, b, a, at(0, half)), 1);
  EXPECT_EQ(inCircle(c, b, a, at(1, -1)), -1);
}

TEST(ExactPoint, LexicographicOrderComparesExactly) {
  const ExactPoint a(Point3(0, 1, 2)), b(Point3(0, 1, 3)), c(Point3(-1, 5, 5));
  EXPECT_LT(compareLexicographic(a, b), 0);
  EXPECT_GT(compareLexicographic(a, c), 0);
  EXPECT_EQ(compareLexicographic(b, ExactPoint(Point3(0, 1, 3))), 0);
  // A constructed point that rounds to an input point but is not it.
  const ExactPoint crossing = ExactPoint::edgePlane(
      Point3(0, 0, -1), Point3(1e-30, 0, 1), Point3(0, 0, 0), Point3(1, 0, 0), Point3(0, 1, 0));
  EXPECT_GT(compareLexicographic(crossing, ExactPoint(Point3(0, 0, 0))), 0);
}

TEST(ExactPoint, CoincidentGroupsMergeExactlyEqualPointsOnly) {
  // The same point three ways, a point one ulp away, and another.
  const ExactPoint a = ExactPoint::edgePlane({0, 0, 0}, {2, 2, 2}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1});
  const ExactPoint b(Point3(1, 1, 1));
  const ExactPoint c = ExactPoint::edgePlane({1, 1, 0}, {1, 1, 4}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1});
  const ExactPoint d(Point3(1, 1, std::nextafter(1.0, 2.0)));
  const ExactPoint e(Point3(5, 1, 1));
  const std::vector<int> g = coincidentGroups({&d, &a, &e, &b, &c});
  EXPECT_EQ(g, (std::vector<int>{0, 1, 2, 1, 1}));
}

TEST(ExactPoint, CoincidentGroupsMatchComparingEveryPair) {
  // Points on a coarse grid (many share a coordinate, as on CAD inputs),
  // each also constructed as where a segment crosses a plane through it, and
  // points one ulp off: the groups are those of comparing every pair.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> cell(0, 4);
  std::vector<ExactPoint> points;
  for (int i = 0; i < 400; ++i) {
    const Point3 p(cell(rng), cell(rng) * 0.5, cell(rng) * 0.25);
    switch (i % 3) {
      case 0:
        points.emplace_back(p);
        break;
      case 1:  // through p, crossing the plane z = p.z
        points.push_back(ExactPoint::edgePlane(p - Point3(0.3, 0.1, 1), p + Point3(0.3, 0.1, 1),
                                               Point3(0, 0, p[2]), Point3(1, 0, p[2]),
                                               Point3(0, 1, p[2])));
        break;
      default:
        points.emplace_back(Point3(p[0], std::nextafter(p[1], 9.0), p[2]));
    }
  }
  std::vector<const ExactPoint*> pointers;
  for (const ExactPoint& p : points) pointers.push_back(&p);
  const std::vector<int> groups = coincidentGroups(pointers);
  for (std::size_t i = 0; i < points.size(); ++i) {
    int first = int(i);
    for (std::size_t j = 0; j < i; ++j)
      if (samePoint(points[i], points[j])) {
        first = int(j);
        break;
      }
    ASSERT_EQ(groups[i], first) << "point " << i;
  }
}

}  // namespace
}  // namespace meshmend
