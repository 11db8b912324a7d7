#include "common/exact/predicates.h"

#include "common/exact/expansion.h"

#include <cfloat>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace meshmend {
namespace {

TEST(Predicates, Orient2dBasicSigns) {
  EXPECT_EQ(orient2d(0, 0, 1, 0, 0, 1), 1);
  EXPECT_EQ(orient2d(0, 0, 0, 1, 1, 0), -1);
  EXPECT_EQ(orient2d(0, 0, 1, 1, 2, 2), 0);
  EXPECT_EQ(orient2d(0, 0, 0, 0, 5, 3), 0);
}

TEST(Predicates, Orient3dBasicSigns) {
  const Point3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(orient3d(a, b, c, Point3(0, 0, 1)), 1);
  EXPECT_EQ(orient3d(a, b, c, Point3(0, 0, -1)), -1);
  EXPECT_EQ(orient3d(a, b, c, Point3(3, 7, 0)), 0);
}

TEST(Predicates, Orient2dNearlyCollinearNeedsExactness) {
  // Points on the line y = x perturbed in the last bit: the naive
  // floating-point determinant gets many of these wrong.
  const double base = 0.5;
  for (int i = 1; i < 200; ++i) {
    const double x = base + i * DBL_EPSILON;
    const double y = std::nextafter(x, 2.0);
    EXPECT_EQ(orient2d(12, 12, 24, 24, x, y), exact::orient2d(12, 12, 24, 24, x, y));
    EXPECT_EQ(orient2d(12, 12, 24, 24, x, x), 0);
  }
}

TEST(Predicates, CollinearIsExact) {
  EXPECT_TRUE(collinear(Point3(0, 0, 0), Point3(1, 1, 1), Point3(3, 3, 3)));
  EXPECT_TRUE(collinear(Point3(1, 2, 3), Point3(1, 2, 3), Point3(4, 5, 6)));
  EXPECT_FALSE(collinear(Point3(0, 0, 0), Point3(1, 1, 1), Point3(3, 3, std::nextafter(3.0, 4.0))));
}

TEST(Predicates, HandlesHugeAndTinyCoordinates) {
  const double big = FLT_MAX;
  EXPECT_EQ(orient2d(-big, -big, big, -big, 0, big), 1);
  EXPECT_EQ(
      orient3d(Point3(-big, -big, 0), Point3(big, -big, 0), Point3(0, big, 0), Point3(0, 0, big)),
      1);
  const double tiny = 1e-300;  // products underflow: must fall back to exact
  EXPECT_EQ(orient2d(0, 0, tiny, 0, 0, tiny), 1);
  EXPECT_EQ(orient3d(Point3(0, 0, 0), Point3(tiny, 0, 0), Point3(0, tiny, 0), Point3(0, 0, tiny)),
            1);
}

// The filters' allowance for underflowed minors: at least 2^-1070 per unit
// of the third row's magnitude plus one (the bound the filters rely on), and
// a normal number (no arithmetic on subnormals) from a subnormal sum to
// DBL_MAX.
TEST(Predicates, UnderflowSlackBoundsInNormalNumbers) {
  std::vector<double> sums{0, 0x1p-1074, 1e-300, 0.5, 1, 3, 0x1p59, 0x1p60, 0x1p61, 1e200, DBL_MAX};
  std::mt19937_64 rng(99);
  std::uniform_int_distribution<int> exponent(-1074, 1023);
  std::uniform_real_distribution<double> mantissa(1, 2);
  for (int i = 0; i < 10000; ++i) sums.push_back(std::ldexp(mantissa(rng), exponent(rng)));
  for (double sum : sums) {
    const double slack = PlaneFilter::underflowSlack(sum);
    EXPECT_EQ(std::fpclassify(slack), FP_NORMAL) << sum;
    // 2^-1070 (sum + 1) scaled by 2^1070 into the range of long double, exactly.
    EXPECT_GE(std::ldexp(static_cast<long double>(slack), 1070), static_cast<long double>(sum) + 1)
        << sum;
  }
}

// Randomized comparison with the pure-GMP evaluation on near-degenerate input:
// coplanar/collinear points perturbed by a few ulps, shared points, and values
// near FLT_MAX.
TEST(Predicates, FilteredAgreesWithExactOnNearDegenerateInput) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::uniform_int_distribution<int> ulps(-4, 4), pick(0, 4);
  auto perturb = [&](double v) {
    for (int k = ulps(rng); k != 0; k += (k > 0 ? -1 : 1))
      v = std::nextafter(v, k > 0 ? INFINITY : -INFINITY);
    return v;
  };
  auto scaleOf = [&](int kind) {
    switch (kind) {
      case 0:
        return 1.0;
      case 1:
        return 1e-3;
      case 2:
        return double(FLT_MAX) / 4;
      case 3:
        return 1e6;
      default:
        return 1e-30;
    }
  };
  long disagreements = 0, exactZeros = 0;
  const int rounds = 1000000;  // 3 million predicate evaluations
  for (int i = 0; i < rounds; ++i) {
    const double s = scaleOf(pick(rng));
    const Point3 a(unit(rng) * s, unit(rng) * s, unit(rng) * s);
    const Point3 b(unit(rng) * s, unit(rng) * s, unit(rng) * s);
    const Point3 c(unit(rng) * s, unit(rng) * s, unit(rng) * s);
    // d on the plane of a, b, c (rounded), then perturbed by a few ulps;
    // sometimes exactly a shared point.
    const double u = unit(rng), v = unit(rng);
    Point3 d = a + (b - a) * u + (c - a) * v;
    if (pick(rng) == 0) d = b;
    d = Point3(perturb(d[0]), perturb(d[1]), perturb(d[2]));
    const int f3 = orient3d(a, b, c, d), e3 = exact::orient3d(a, b, c, d);
    disagreements += f3 != e3;
    disagreements += PlaneSide(a, b, c)(d) != e3;
    exactZeros += e3 == 0;
    // 2-D: c near the line a-b.
    const double t = unit(rng);
    const double cx = perturb(a[0] + (b[0] - a[0]) * t), cy = perturb(a[1] + (b[1] - a[1]) * t);
    disagreements +=
        orient2d(a[0], a[1], b[0], b[1], cx, cy) != exact::orient2d(a[0], a[1], b[0], b[1], cx, cy);
  }
  EXPECT_EQ(disagreements, 0);
  EXPECT_GT(exactZeros, 0);  // the generator does reach exact degeneracy
}

// The expansion stage alone (what the filter falls back to) against GMP, on
// exactly degenerate and nearly degenerate input of mixed magnitudes.
TEST(Predicates, ExpansionStageAgreesWithGmp) {
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::uniform_int_distribution<int> grid(-3, 3), pick(0, 3);
  long disagreements = 0, zeros = 0;
  for (int i = 0; i < 300000; ++i) {
    const double s = pick(rng) == 0 ? 1e-20 : pick(rng) == 1 ? 1e20 : 1.0;
    auto coord = [&] {
      double v = pick(rng) < 3 ? grid(rng) * s : unit(rng) * s;
      if (v != 0 && pick(rng) == 0) v = std::nextafter(v, 1e300);
      return v;
    };
    const Point3 a(coord(), coord(), coord()), b(coord(), coord(), coord());
    const Point3 c(coord(), coord(), coord()), d(coord(), coord(), coord());
    // The stage's contract: magnitudes where no product can underflow (the
    // filtered predicates route other input to GMP).
    if (!expansion::safe({a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2]}))
      continue;
    const int e3 = exact::orient3d(a, b, c, d);
    disagreements += expansion::orient3d(a, b, c, d) != e3;
    zeros += e3 == 0;
    disagreements += expansion::orient2d(a[0], a[1], b[0], b[1], c[0], c[1]) !=
                     exact::orient2d(a[0], a[1], b[0], b[1], c[0], c[1]);
  }
  EXPECT_EQ(disagreements, 0);
  EXPECT_GT(zeros, 500);  // exact degeneracies are reached
}

}  // namespace
}  // namespace meshmend
