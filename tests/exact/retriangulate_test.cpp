#include "common/exact/retriangulate.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "common/base/errors.h"

namespace meshmend {
namespace {

RationalPoint R(mpq_class x, mpq_class y, mpq_class z) {
  return {{x, y, z}};
}

// A tilted triangle in 3-D (not axis-aligned), and points on it by their
// rational barycentric coordinates.
const std::array<RationalPoint, 3> kTri = {R(0, 0, 0), R(4, 0, 1), R(0, 4, 3)};

RationalPoint on(mpq_class s,
                 mpq_class t) {  // corner0 + s (corner1 - corner0) + t (corner2 - corner0)
  RationalPoint p;
  for (int k = 0; k < 3; ++k)
    p.x[k] = kTri[0].x[k] + s * (kTri[1].x[k] - kTri[0].x[k]) + t * (kTri[2].x[k] - kTri[0].x[k]);
  return p;  // not canonical when s, t are not: retriangulate must cope
}

// Twice the area, projected along z (the triangle's normal has a non-zero z).
mpq_class area2(const RetriangulatedPatch& p, const std::array<int, 3>& t) {
  const auto& a = p.vertices[t[0]].exact().x;
  const auto& b = p.vertices[t[1]].exact().x;
  const auto& c = p.vertices[t[2]].exact().x;
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Every triangle turns like the input, none is degenerate, and together they
// cover exactly the input's area.
void expectValidTiling(const RetriangulatedPatch& p) {
  const std::array<int, 3> whole{0, 1, 2};
  const mpq_class total = area2(p, whole);
  mpq_class sum = 0;
  for (const auto& t : p.triangles) {
    const mpq_class a = area2(p, t);
    EXPECT_EQ(sgn(a), sgn(total));
    sum += a;
  }
  EXPECT_EQ(sum, total);
}

bool hasEdge(const RetriangulatedPatch& p, int a, int b) {
  for (const auto& t : p.triangles)
    for (int i = 0; i < 3; ++i)
      if ((t[i] == a && t[(i + 1) % 3] == b) || (t[i] == b && t[(i + 1) % 3] == a)) return true;
  return false;
}

PatchInput input(const std::vector<RationalPoint>& points,
                 std::vector<std::array<int, 2>> segments) {
  PatchInput in;
  for (int k = 0; k < 3; ++k) in.corners[k] = ExactPoint(kTri[k]);
  for (const RationalPoint& p : points) in.points.push_back(ExactPoint(p));
  in.segments = std::move(segments);
  return in;
}

TEST(Retriangulate, NoPointsKeepsTheTriangle) {
  const RetriangulatedPatch p = retriangulate(input({}, {}));
  ASSERT_EQ(p.triangles.size(), 1u);
  EXPECT_EQ(p.triangles[0], (std::array<int, 3>{0, 1, 2}));
}

TEST(Retriangulate, InteriorPointSplitsIntoThree) {
  const RetriangulatedPatch p = retriangulate(input({on(mpq_class(1, 3), mpq_class(1, 3))}, {}));
  EXPECT_EQ(p.triangles.size(), 3u);
  expectValidTiling(p);
}

TEST(Retriangulate, PointOnAnEdgeSplitsIntoTwo) {
  const RetriangulatedPatch p = retriangulate(input({on(mpq_class(1, 2), 0)}, {}));
  EXPECT_EQ(p.triangles.size(), 2u);
  expectValidTiling(p);
}

TEST(Retriangulate, SegmentAcrossBecomesAConstrainedEdge) {
  // From a point on edge 0-1 to a point on edge 0-2, plus an interior point
  // that a Delaunay-like improvement would like to connect across it.
  const RetriangulatedPatch p = retriangulate(input(
      {on(mpq_class(1, 2), 0), on(0, mpq_class(1, 2)), on(mpq_class(1, 10), mpq_class(1, 10))},
      {{3, 4}}));
  expectValidTiling(p);
  EXPECT_TRUE(hasEdge(p, p.vertex_of_input[3], p.vertex_of_input[4]));
  ASSERT_EQ(p.constrained_edges.size(), 1u);
}

TEST(Retriangulate, CrossingConstraintsMeetAtTheirExactCrossing) {
  const RetriangulatedPatch p =
      retriangulate(input({on(mpq_class(1, 2), 0), on(0, mpq_class(1, 2)), on(0, 0),
                           on(mpq_class(1, 3), mpq_class(1, 3))},
                          {{3, 4}, {5, 6}}));
  expectValidTiling(p);
  EXPECT_EQ(p.vertices.size(), 3u + 3u + 1u);  // corner 0 repeated as a point; one crossing
  EXPECT_EQ(p.constrained_edges.size(), 4u);
  const RationalPoint& x =
      p.vertices.back().exact();  // the crossing: (1/4, 1/4) in barycentric terms
  const RationalPoint want = on(mpq_class(1, 4), mpq_class(1, 4));
  EXPECT_EQ(x.x, want.x);
}

TEST(Retriangulate, StopsAtItsBoundOnExactEvaluations) {
  // Two crossing constraints: their crossing point is computed exactly.
  PatchInput in = input({on(mpq_class(1, 2), 0), on(0, mpq_class(1, 2)), on(0, 0),
                         on(mpq_class(1, 3), mpq_class(1, 3))},
                        {{3, 4}, {5, 6}});
  const RetriangulatedPatch p = retriangulate(in);
  EXPECT_GE(p.exact_evaluations, 2u);
  in.max_exact_evaluations = 1;
  EXPECT_THROW(retriangulate(in), WorkLimitError);
  in.max_exact_evaluations = 0;  // no bound
  EXPECT_EQ(retriangulate(in).triangles.size(), p.triangles.size());
}

TEST(Retriangulate, VertexOnAConstraintSplitsIt) {
  const RetriangulatedPatch p = retriangulate(
      input({on(mpq_class(1, 2), 0), on(0, mpq_class(1, 2)), on(mpq_class(1, 4), mpq_class(1, 4))},
            {{3, 4}}));
  expectValidTiling(p);
  EXPECT_EQ(p.constrained_edges.size(), 2u);
}

TEST(Retriangulate, ConstraintAlongATriangleEdge) {
  const RetriangulatedPatch p =
      retriangulate(input({on(mpq_class(1, 4), 0), on(mpq_class(3, 4), 0)}, {{3, 4}}));
  expectValidTiling(p);
  EXPECT_EQ(p.triangles.size(), 3u);
  EXPECT_TRUE(hasEdge(p, p.vertex_of_input[3], p.vertex_of_input[4]));
}

TEST(Retriangulate, RejectsPointsOffTheTriangle) {
  EXPECT_THROW(retriangulate(input({on(1, 1)}, {})), InvalidInputError);  // outside, in the plane
  PatchInput off = input({R(1, 1, 100)}, {});                             // off the plane
  EXPECT_THROW(retriangulate(off), InvalidInputError);
  EXPECT_THROW(retriangulate(input({on(mpq_class(1, 4), 0)}, {{0, 9}})), InvalidInputError);
}

// A star of chords that all pass close to one point, as many curves do
// where a surface folds through itself: every pair crosses, and each
// crossing is the exact crossing of the two chords' lines (computed here
// directly in barycentric terms).
TEST(Retriangulate, StarOfChordsGetsEveryPairwiseCrossing) {
  const int n = 10;
  std::vector<RationalPoint> points;
  std::vector<std::array<mpq_class, 4>> chords;  // (s0, t0) -> (s1, t1)
  for (int i = 0; i < n; ++i) {
    // From edge t = 0 to edge s = 0, both ends moving the same way: every
    // two chords cross near (1/4, 1/4), none three in one point.
    const mpq_class a(1 + 3 * i, 8 * n), b(2 * n - 1 - 2 * i, 4 * n + i);
    chords.push_back({a, 0, 0, b});
    points.push_back(on(a, 0));
    points.push_back(on(0, b));
  }
  std::vector<std::array<int, 2>> segments;
  for (int i = 0; i < n; ++i) segments.push_back({3 + 2 * i, 4 + 2 * i});
  const RetriangulatedPatch p = retriangulate(input(points, segments));
  expectValidTiling(p);
  std::set<std::array<mpq_class, 3>> want, got;
  for (std::size_t i = 0; i < chords.size(); ++i)
    for (std::size_t j = i + 1; j < chords.size(); ++j) {
      // Line i: s / a_i + t / b_i = 1 (ends (a_i, 0) and (0, b_i)).
      const mpq_class ai = chords[i][0], bi = chords[i][3], aj = chords[j][0], bj = chords[j][3];
      const mpq_class det = 1 / (ai * bj) - 1 / (aj * bi);
      ASSERT_NE(sgn(det), 0);
      const mpq_class s = (1 / bj - 1 / bi) / det, t = (1 / ai - 1 / aj) / det;
      ASSERT_TRUE(s > 0 && t > 0 && s + t < 1);
      RationalPoint x = on(s, t);
      for (mpq_class& c : x.x) c.canonicalize();  // compared as values
      want.insert({x.x[0], x.x[1], x.x[2]});
    }
  for (std::size_t v = 3 + 2 * n; v < p.vertices.size(); ++v) {
    RationalPoint x = p.vertices[v].exact();
    for (mpq_class& c : x.x) c.canonicalize();
    got.insert({x.x[0], x.x[1], x.x[2]});
  }
  EXPECT_EQ(want.size(), std::size_t(n * (n - 1) / 2));
  EXPECT_EQ(got, want);
  EXPECT_EQ(p.vertices.size(), 3 + 2 * n + want.size());
}

// Random points and segments (crossing each other freely): always a valid
// tiling in which every segment is a chain of constrained edges.
TEST(Retriangulate, RandomConstraintsAlwaysGiveValidTilings) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> num(0, 12);
  for (int trial = 0; trial < 1000; ++trial) {
    std::vector<RationalPoint> points;
    for (int i = 0; i < 10; ++i) {
      int s = num(rng), t = num(rng);
      if (s + t > 12) s = 12 - s, t = 12 - t;  // fold into the triangle
      if (s + t > 12) t = 12 - s;
      points.push_back(on(mpq_class(s, 12), mpq_class(t, 12)));
    }
    std::vector<std::array<int, 2>> segments;
    std::uniform_int_distribution<int> pick(0, 12);
    for (int i = 0; i < 6; ++i) segments.push_back({pick(rng), pick(rng)});
    const RetriangulatedPatch p = retriangulate(input(points, segments));
    expectValidTiling(p);
    // Each segment's end points are joined by constrained edges along it.
    std::map<int, std::vector<int>> graph;
    for (const auto& e : p.constrained_edges) {
      EXPECT_TRUE(hasEdge(p, e[0], e[1]));
      graph[e[0]].push_back(e[1]);
      graph[e[1]].push_back(e[0]);
    }
    for (const auto& s : segments) {
      const int a = p.vertex_of_input[s[0]], b = p.vertex_of_input[s[1]];
      if (a == b) continue;
      std::vector<int> stack{a};
      std::set<int> seen{a};
      while (!stack.empty()) {
        const int v = stack.back();
        stack.pop_back();
        for (int w : graph[v])
          if (seen.insert(w).second) stack.push_back(w);
      }
      EXPECT_TRUE(seen.count(b)) << "trial " << trial;
    }
  }
}

// The triangles of a patch as a set, each rotated to start at its smallest vertex.
std::set<std::array<int, 3>> triangleSet(const RetriangulatedPatch& p) {
  std::set<std::array<int, 3>> set;
  for (std::array<int, 3> t : p.triangles) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    set.insert(t);
  }
  return set;
}

TEST(Retriangulate, SegmentAcrossACornerGivesWhatTheFlipsGive) {
  // One segment between points known to lie inside two edges (the common
  // patch where surfaces cross, which has a shortcut): the same triangles as
  // when the points arrive without saying which edges they are on (the
  // general insertion, constraint recovery and max-min angle flips), for
  // every pair of edges, both segment directions and points near corners.
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> numerator(1, 99);
  for (int trial = 0; trial < 600; ++trial) {
    const int k = trial % 3, direction = (trial / 3) % 2;
    const mpq_class s(numerator(rng), 100), t(numerator(rng), 100);
    // Inside edge k (corner k to k + 1) and inside edge k + 1.
    auto onEdge = [&](int edge, const mpq_class& f) {
      RationalPoint x;
      const RationalPoint &a = kTri[edge], &b = kTri[(edge + 1) % 3];
      for (int c = 0; c < 3; ++c) x.x[c] = a.x[c] + f * (b.x[c] - a.x[c]);
      return x;
    };
    std::vector<RationalPoint> points{onEdge(k, s), onEdge((k + 1) % 3, t)};
    std::vector<std::uint8_t> edges{std::uint8_t(1 << k), std::uint8_t(1 << (k + 1) % 3)};
    if (trial % 4 == 0) {  // the points listed the other way round
      std::swap(points[0], points[1]);
      std::swap(edges[0], edges[1]);
    }
    PatchInput unknown =
        input(points, {direction ? std::array<int, 2>{3, 4} : std::array<int, 2>{4, 3}});
    PatchInput known = unknown;
    known.on_edges = edges;
    const RetriangulatedPatch fast = retriangulate(known), general = retriangulate(unknown);
    ASSERT_EQ(fast.triangles.size(), 3u);
    expectValidTiling(fast);
    EXPECT_EQ(triangleSet(fast), triangleSet(general)) << "trial " << trial;
    ASSERT_EQ(fast.constrained_edges.size(), 1u);
    EXPECT_EQ(fast.constrained_edges[0], (std::array<int, 2>{3, 4}));
    EXPECT_EQ(fast.vertex_of_input, general.vertex_of_input);
  }
  // Exact ties between the two diagonals (a right isosceles triangle, points
  // at eighths of its legs), points listed both ways: still the same.
  const std::array<Point3, 3> right{Point3(0, 0, 0), Point3(3, 0, 0), Point3(0, 3, 0)};
  for (int k = 0; k < 3; ++k)
    for (int i = 1; i < 8; ++i)
      for (int j = 1; j < 8; ++j)
        for (int order = 0; order < 2; ++order) {
          auto at = [&](int edge, double f) {
            return right[edge] + (right[(edge + 1) % 3] - right[edge]) * f;
          };
          PatchInput unknown;
          for (int c = 0; c < 3; ++c) unknown.corners[c] = ExactPoint(right[c]);
          unknown.points = {ExactPoint(at(k, i / 8.0)), ExactPoint(at((k + 1) % 3, j / 8.0))};
          std::vector<std::uint8_t> edges{std::uint8_t(1 << k), std::uint8_t(1 << (k + 1) % 3)};
          if (order) {
            std::swap(unknown.points[0], unknown.points[1]);
            std::swap(edges[0], edges[1]);
          }
          unknown.segments = {{3, 4}};
          PatchInput known = unknown;
          known.on_edges = edges;
          const RetriangulatedPatch fast = retriangulate(known), general = retriangulate(unknown);
          EXPECT_EQ(triangleSet(fast), triangleSet(general))
              << "edge " << k << " at " << i << "/8 and " << j << "/8, order " << order;
        }
}

TEST(Retriangulate, PointsOnOneCircleGiveTheSameTrianglesInAnyOrder) {
  // Twelve points on one circle (integer points at distance 5 about the
  // origin of a tilted plane, its frame orthogonal and of equal lengths),
  // their polygon as constraints: inside it every split is a tie. Listed in
  // any order, the points give the same triangles, as two faces overlapping
  // in a plane need (each re-triangulates the overlap on its own).
  const Point3 c(5, -1, 3), u(1, 2, 2), w(2, 1, -2);
  auto at = [&](double s, double t) { return c + u * s + w * t; };
  const std::vector<std::array<int, 2>> ring = {{5, 0},   {4, 3},  {3, 4},  {0, 5},
                                                {-3, 4},  {-4, 3}, {-5, 0}, {-4, -3},
                                                {-3, -4}, {0, -5}, {3, -4}, {4, -3}};
  std::vector<int> order(ring.size());
  std::iota(order.begin(), order.end(), 0);
  std::mt19937 rng(3);
  std::set<std::vector<std::array<double, 9>>> results;
  for (int trial = 0; trial < 20; ++trial) {
    std::shuffle(order.begin(), order.end(), rng);
    PatchInput in;
    in.corners = {ExactPoint(at(-20, -20)), ExactPoint(at(40, -20)), ExactPoint(at(-20, 40))};
    std::vector<int> slot(ring.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
      slot[order[i]] = 3 + int(i);
      in.points.push_back(ExactPoint(at(ring[order[i]][0], ring[order[i]][1])));
    }
    for (std::size_t i = 0; i < ring.size(); ++i)
      in.segments.push_back({slot[i], slot[(i + 1) % ring.size()]});
    const RetriangulatedPatch p = retriangulate(in);
    std::vector<std::array<double, 9>> triangles;  // by coordinates, each from its smallest corner
    for (std::array<int, 3> t : p.triangles) {
      std::rotate(t.begin(),
                  std::min_element(t.begin(), t.end(),
                                   [&](int x, int y) {
                                     return compareLexicographic(p.vertices[x], p.vertices[y]) < 0;
                                   }),
                  t.end());
      std::array<double, 9> x;
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) x[3 * k + d] = p.vertices[t[k]].approx()[d];
      triangles.push_back(x);
    }
    std::sort(triangles.begin(), triangles.end());
    results.insert(triangles);
  }
  EXPECT_EQ(results.size(), 1u);
}

TEST(Retriangulate, SegmentAcrossADegenerateTriangleIsRefused) {
  // The shortcut leaves a triangle with collinear corners to the general
  // path, which refuses it.
  PatchInput in;
  in.corners = {ExactPoint(Point3(0, 0, 0)), ExactPoint(Point3(2, 0, 0)),
                ExactPoint(Point3(4, 0, 0))};
  in.points = {ExactPoint(Point3(1, 0, 0)), ExactPoint(Point3(3, 0, 0))};
  in.on_edges = {1, 2};
  in.segments = {{3, 4}};
  EXPECT_THROW(retriangulate(in), InvalidInputError);
}

}  // namespace
}  // namespace meshmend
