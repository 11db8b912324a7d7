#include "common/exact/intersections.h"

#include <algorithm>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "common/base/errors.h"
#include "common/exact/box_tree.h"
#include "common/exact/changed_faces.h"
#include "common/exact/predicates.h"
#include "common/exact/vertex_fans.h"
#include "tests/mesh_builders.h"

namespace meshmend {
namespace {

using testing::box;
using testing::icosphere;
using testing::moved;
using testing::uvSphere;

// Brute force over all face pairs with the same exact rules.
std::size_t bruteForceSelfPairs(const Mesh& m) {
  const std::vector<Point3> p = positionsOf(m);
  const std::vector<Triangle> t = trianglesOf(m);
  std::size_t pairs = 0;
  for (std::size_t f = 0; f < t.size(); ++f)
    for (std::size_t g = f + 1; g < t.size(); ++g) {
      const TrianglePoints a{p[t[f][0]], p[t[f][1]], p[t[f][2]]},
          b{p[t[g][0]], p[t[g][1]], p[t[g][2]]};
      if (collinear(a[0], a[1], a[2]) || collinear(b[0], b[1], b[2])) continue;
      const SharedCorners c = sharedCorners(t[f], t[g]);
      pairs += intersectBeyondShared(a, b, c.count, c.ia, c.ib);
    }
  return pairs;
}

TEST(Intersections, CleanClosedMeshHasNone) {
  const Mesh s = uvSphere(16, 24);
  const FindIntersectionsResult r = findIntersections({&s});
  EXPECT_EQ(r.self_pairs[0], 0u);
  EXPECT_GT(r.candidate_pairs, 0u);  // neighbours' boxes touch: tested, rejected
}

TEST(Intersections, TwoOverlappingCubesInOneMesh) {
  // The unit cube and a copy moved by (0.5, 0.5, 0.5): 18 intersecting pairs
  // (the count meshcheck and CGAL give).
  const Mesh both = appended(box(), moved(box(), {0.5, 0.5, 0.5}));
  const FindIntersectionsResult r = findIntersections({&both});
  EXPECT_EQ(r.self_pairs[0], 18u);
  EXPECT_EQ(r.self_pairs[0], bruteForceSelfPairs(both));
}

TEST(Intersections, TwoOverlappingCubesAsTwoMeshes) {
  const Mesh a = box(), b = moved(box(), {0.5, 0.5, 0.5});
  const FindIntersectionsResult r = findIntersections({&a, &b});
  EXPECT_EQ(r.cross_pairs, 18u);
  EXPECT_EQ(r.self_pairs[0] + r.self_pairs[1], 0u);
  EXPECT_EQ(r.cross_faces[0], 6u);
  EXPECT_EQ(r.cross_faces[1], 6u);
  for (const IntersectingPair& p : r.pairs) EXPECT_LT(p.a.mesh, p.b.mesh);
  FindIntersectionsOptions selfOnly;
  selfOnly.cross = false;
  EXPECT_EQ(findIntersections({&a, &b}, selfOnly).cross_pairs, 0u);
}

TEST(Intersections, SharedVertexAndSharedEdgeRules) {
  // Folded: two coplanar triangles on one edge, apexes on the same side.
  const Mesh fold = makeMesh({{0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, 2, 0}}, {{0, 1, 2}, {1, 0, 3}});
  EXPECT_EQ(findIntersections({&fold}).self_pairs[0], 1u);
  // A fan around one vertex with one triangle's far edge piercing the other.
  const Mesh pierce =
      makeMesh({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {2, 1, -1}, {2, 1, 1}}, {{0, 1, 2}, {0, 3, 4}});
  EXPECT_EQ(findIntersections({&pierce}).self_pairs[0], 1u);
  // The same fan, not piercing: only the shared vertex.
  const Mesh fan = makeMesh({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {-2, -1, -1}, {-2, -1, 1}},
                            {{0, 1, 2}, {0, 3, 4}});
  EXPECT_EQ(findIntersections({&fan}).self_pairs[0], 0u);
}

TEST(Intersections, MeshesWhoseCoordinatesSpanTooMuchTogetherAreRefused) {
  // Each mesh alone spans a few binades; together 1e-200 beside 1e100.
  const Mesh small = makeMesh({{1e-200, 0, 0}, {2e-200, 0, 0}, {0, 1e-200, 0}}, {{0, 1, 2}});
  const Mesh large = makeMesh({{1e100, 0, 0}, {2e100, 0, 0}, {0, 1e100, 0}}, {{0, 1, 2}});
  EXPECT_NO_THROW(findIntersections({&small}, FindIntersectionsOptions{}));
  EXPECT_NO_THROW(findIntersections({&large}, FindIntersectionsOptions{}));
  try {
    findIntersections({&small, &large}, FindIntersectionsOptions{});
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("the meshes together: its coordinates span"),
              std::string::npos)
        << e.what();
  }
}

TEST(Intersections, DuplicatePointsAreDifferentVertices) {
  // Two triangles that share an edge geometrically but not by index touch.
  const Mesh seam = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}},
                             {{0, 1, 2}, {3, 5, 4}});
  EXPECT_EQ(findIntersections({&seam}).self_pairs[0], 1u);
}

TEST(Intersections, DegenerateFacesAreSkipped) {
  const Mesh m = makeMesh({{0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, -1, -1}, {1, -1, 1}},
                          {{0, 1, 2}, {0, 1, 3}, {2, 4, 5}});
  const FindIntersectionsResult r = findIntersections({&m});
  EXPECT_EQ(r.degenerate_faces[0], 1u);
}

// The candidate search misses nothing: random soups against brute force.
TEST(Intersections, AgreesWithBruteForceOnRandomSoups) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Point3> p;
    std::vector<Triangle> t;
    for (int f = 0; f < 300; ++f) {
      const Point3 c(u(rng), u(rng), u(rng));
      for (int k = 0; k < 3; ++k) p.push_back(c + Point3(u(rng), u(rng), u(rng)) * 0.15);
      t.push_back({3 * f, 3 * f + 1, 3 * f + 2});
    }
    // Share some vertices so that every rule is exercised.
    for (int f = 1; f < 300; f += 7) t[f][0] = t[f - 1][1];
    const Mesh m = makeMesh(p, t);
    EXPECT_EQ(findIntersections({&m}).self_pairs[0], bruteForceSelfPairs(m)) << "trial " << trial;
  }
}

// Faces on a small integer grid sharing an edge, one corner or none
// (coplanar and jittered ones among them), where the plane and projection
// filters decide most pairs: facesIntersect agrees with the exact rules.
TEST(Intersections, FacesIntersectAgreesWithTheRulesOnNearbyFaces) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coordinate(-2, 2);
  std::uniform_real_distribution<double> jitter(-1e-15, 1e-15);
  std::size_t meeting[3] = {0, 0, 0}, apart[3] = {0, 0, 0};
  for (int trial = 0; trial < 30000; ++trial) {
    const int shared = 2 - trial % 3;  // corners the two faces share
    std::vector<Point3> p;
    for (int k = 0; k < 6 - shared; ++k) {
      Point3 q(coordinate(rng), coordinate(rng), coordinate(rng));
      if ((trial / 3) % 3 == 0) q += Point3(jitter(rng), jitter(rng), jitter(rng));
      p.push_back(q);
    }
    const std::vector<Triangle> t = shared == 2   ? std::vector<Triangle>{{0, 1, 2}, {1, 0, 3}}
                                    : shared == 1 ? std::vector<Triangle>{{0, 1, 2}, {0, 3, 4}}
                                                  : std::vector<Triangle>{{0, 1, 2}, {3, 4, 5}};
    if (collinear(p[t[0][0]], p[t[0][1]], p[t[0][2]]) ||
        collinear(p[t[1][0]], p[t[1][1]], p[t[1][2]]))
      continue;
    const TrianglePoints a{p[t[0][0]], p[t[0][1]], p[t[0][2]]},
        b{p[t[1][0]], p[t[1][1]], p[t[1][2]]};
    const SharedCorners c = sharedCorners(t[0], t[1]);
    ASSERT_EQ(c.count, shared);
    const bool expected = intersectBeyondShared(a, b, c.count, c.ia, c.ib);
    ASSERT_EQ(facesIntersect(p, t, 0, 1), expected) << "trial " << trial;
    (expected ? meeting : apart)[shared] += 1;
  }
  for (int shared = 0; shared < 3; ++shared) {  // both answers are exercised
    EXPECT_GT(meeting[shared], 100u) << shared << " shared corners";
    EXPECT_GT(apart[shared], 100u) << shared << " shared corners";
  }
}

// The pairs of a search around changed faces that intersect, tested with
// each face's plane filter made once, are those the exact rule finds on
// every pair: nearly coplanar neighbours (a tilted grid stored as float,
// which the filters cannot tell and the projection or the exact test
// must), faces sharing an edge or a corner, a second grid crossing the
// first, faces with the same three vertices (not counted) and flat ones.
TEST(Intersections, SearchAroundChangedFacesMatchesTheRuleOnEveryPair) {
  std::vector<Point3> P;
  std::vector<Triangle> T;
  std::vector<char> changed;
  auto grid = [&](int n, auto at, auto isChanged) {
    const int first = int(P.size());
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) P.push_back(storedAs(at(i, j), Scalar::kFloat));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const int v = first + i * (n + 1) + j;
        for (const Triangle& t :
             {Triangle{v, v + 1, v + n + 2}, Triangle{v, v + n + 2, v + n + 1}}) {
          changed.push_back(isChanged(T.size()));  // by the face's index
          T.push_back(t);
        }
      }
  };
  grid(
      24, [](int i, int j) { return Point3(0.1 * i, 0.1 * j, 0.031 * i + 0.017 * j); },
      [](std::size_t f) { return f % 3 == 0; });
  grid(
      8, [](int i, int j) { return Point3(0.3 * i - 0.1, 1.2, 0.3 * j - 0.5); },
      [](std::size_t) { return true; });
  for (std::size_t f = 0; f < 40; f += 7) {  // the same face again, and a flat one
    T.push_back(T[f]);
    changed.push_back(1);
  }
  T.push_back({0, 1, 2});  // 0, 1, 2 lie on the grid's first row
  changed.push_back(1);
  std::vector<char> degenerate(T.size());
  for (std::size_t f = 0; f < T.size(); ++f)
    degenerate[f] = collinear(P[T[f][0]], P[T[f][1]], P[T[f][2]]);
  ASSERT_EQ(degenerate.back(), 1);

  std::set<std::array<std::uint32_t, 2>> expected;
  for (std::uint32_t f = 0; f < T.size(); ++f)
    for (std::uint32_t g = f + 1; g < T.size(); ++g) {
      if (!(changed[f] || changed[g]) || degenerate[f] || degenerate[g]) continue;
      const SharedCorners c = sharedCorners(T[f], T[g]);
      if (c.count == 3) continue;
      const TrianglePoints a{P[T[f][0]], P[T[f][1]], P[T[f][2]]},
          b{P[T[g][0]], P[T[g][1]], P[T[g][2]]};
      if (intersectBeyondShared(a, b, c.count, c.ia, c.ib)) expected.insert({f, g});
    }
  ASSERT_GT(expected.size(), 20u);  // the grids cross

  const ChangedFaceSearch search(P, T, changed, 4);
  std::set<std::array<std::uint32_t, 2>> found;
  for (auto [f, g] : intersectingOf(P, T, search, degenerate, false))
    found.insert({std::min(f, g), std::max(f, g)});
  EXPECT_EQ(found, expected);
}

TEST(Intersections, LargeMeshSelfJoinMatchesBruteForceOnAPushedSphere) {
  // A sphere whose north cap is pushed through its south side.
  Mesh s = uvSphere(20, 30);
  for (Vertex& v : s.vert)
    if (v.P()[2] > 0.7) v.P()[2] -= 1.5;
  const FindIntersectionsResult r = findIntersections({&s});
  EXPECT_GT(r.self_pairs[0], 0u);
  EXPECT_EQ(r.self_pairs[0], bruteForceSelfPairs(s));
}

// Closed meshes whose vertices are jittered by up to an edge length: most
// fans stay one-to-one in a projection (their pairs settled without a
// test), some fold, and some faces pass through others. The search agrees
// with the rule on every pair either way.
TEST(Intersections, FoldedClosedMeshesMatchBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::size_t pairs = 0, apart = 0, notApart = 0;
  for (int trial = 0; trial < 12; ++trial) {
    Mesh s = icosphere(2);
    const double jitter = 0.04 + 0.02 * trial;  // edges are about 0.3 long
    for (Vertex& v : s.vert) v.P() += Point3(u(rng), u(rng), u(rng)) * jitter;
    for (char a : fansApartInProjection(positionsOf(s), trianglesOf(s))) (a ? apart : notApart)++;
    const FindIntersectionsResult r = findIntersections({&s});
    EXPECT_EQ(r.self_pairs[0], bruteForceSelfPairs(s)) << "trial " << trial;
    pairs += r.self_pairs[0];
  }
  EXPECT_GT(pairs, 0u);
  EXPECT_GT(apart, 0u);
  EXPECT_GT(notApart, 0u);
}

TEST(Intersections, ContactsAreClassified) {
  const Mesh a = box(), b = moved(box(), {0.5, 0.5, 0.5});
  FindIntersectionsOptions o;
  o.contacts = true;
  const FindIntersectionsResult r = findIntersections({&a, &b}, o);
  ASSERT_EQ(r.contacts.size(), r.pairs.size());
  for (const TriangleContact& c : r.contacts) {
    EXPECT_NE(c.kind, ContactKind::kNone);
    EXPECT_GE(c.points.size(), 1u);
  }
  // The curves of two crossing cubes: closed polylines, every point on two edges.
  const SegmentSoup soup = contactSegments(r);
  ASSERT_GT(soup.edges.size(), 0u);
  std::vector<int> degree(soup.points.size(), 0);
  for (const auto& e : soup.edges) ++degree[e[0]], ++degree[e[1]];
  for (int d : degree) EXPECT_EQ(d % 2, 0);
}

// Between two meshes, against every pair of faces: the pairs, their
// contacts, and the candidates (the pairs of non-degenerate faces whose
// boxes overlap, each tested once), also where only the boxes' rounding to
// float makes faces of the two meshes candidates.
void expectCrossMatchesBruteForce(const Mesh& a, const Mesh& b, std::size_t& pairs) {
  FindIntersectionsOptions o;
  o.self = false;
  o.contacts = true;
  const FindIntersectionsResult r = findIntersections({&a, &b}, o);
  const std::vector<Point3> pa = positionsOf(a), pb = positionsOf(b);
  const std::vector<Triangle> ta = trianglesOf(a), tb = trianglesOf(b);
  std::size_t candidates = 0, k = 0;
  for (std::size_t f = 0; f < ta.size(); ++f)
    for (std::size_t g = 0; g < tb.size(); ++g) {
      const TrianglePoints x{pa[ta[f][0]], pa[ta[f][1]], pa[ta[f][2]]},
          y{pb[tb[g][0]], pb[tb[g][1]], pb[tb[g][2]]};
      if (collinear(x[0], x[1], x[2]) || collinear(y[0], y[1], y[2])) continue;
      candidates += overlap(boxOf(x[0], x[1], x[2]), boxOf(y[0], y[1], y[2]));
      if (!trianglesIntersect(x, y)) continue;
      ASSERT_LT(k, r.pairs.size());
      EXPECT_EQ(r.pairs[k].a, (FaceRef{0, std::uint32_t(f)}));
      EXPECT_EQ(r.pairs[k].b, (FaceRef{1, std::uint32_t(g)}));
      const TriangleContact c = classifyContact(x, y);
      EXPECT_EQ(r.contacts[k].kind, c.kind);
      ASSERT_EQ(r.contacts[k].points.size(), c.points.size());
      for (std::size_t i = 0; i < c.points.size(); ++i)
        EXPECT_EQ(r.contacts[k].points[i].position, c.points[i].position);
      ++k;
    }
  EXPECT_EQ(r.pairs.size(), k);
  EXPECT_EQ(r.candidate_pairs, candidates);
  pairs = k;
}

TEST(Intersections, BetweenMeshesMatchesBruteForceAtTheEdgeOfTheirBounds) {
  const Mesh a = box();
  std::size_t pairs = 0;
  // Touching along the plane x = 1: coplanar faces and faces meeting it in an edge.
  expectCrossMatchesBruteForce(a, moved(box(), {1, 0.25, 0.5}), pairs);
  EXPECT_GT(pairs, 0u);
  // Apart by one double step, or by less than a float step: no contact, but
  // the float boxes of the faces near x = 1 still overlap.
  for (const double gap : {std::nextafter(1.0, 2.0) - 1, 1e-9}) {
    const Mesh b = moved(box(), {1 + gap, 0.25, 0.5});
    expectCrossMatchesBruteForce(a, b, pairs);
    EXPECT_EQ(pairs, 0u);
    EXPECT_GT(findIntersections({&a, &b}).candidate_pairs, 0u);
  }
  // Crossing spheres of different resolutions, each mesh passed first.
  const Mesh s = uvSphere(12, 18), t = uvSphere(7, 9, 0.6, {0.9, 0.1, 0.05});
  expectCrossMatchesBruteForce(s, t, pairs);
  EXPECT_GT(pairs, 0u);
  expectCrossMatchesBruteForce(t, s, pairs);
  EXPECT_GT(pairs, 0u);
  // Faces of very different sizes (a large triangle across the coarse
  // sphere, too wide for the search's grid cells): the same pairs.
  std::vector<Point3> p = positionsOf(t);
  std::vector<Triangle> f = trianglesOf(t);
  const int n = int(p.size());
  p.push_back({-1.5, -1.5, -0.9});
  p.push_back({2.5, -1.2, 0.9});
  p.push_back({0.4, 2.5, 0.1});
  f.push_back({n, n + 1, n + 2});
  const Mesh mixed = makeMesh(p, f);
  expectCrossMatchesBruteForce(s, mixed, pairs);
  EXPECT_GT(pairs, 0u);
  expectCrossMatchesBruteForce(mixed, s, pairs);
  EXPECT_GT(pairs, 0u);
}

TEST(Intersections, BadInput) {
  const Mesh empty;
  EXPECT_THROW(findIntersections({&empty}), InvalidInputError);
  Mesh nan = box();
  nan.vert[0].P()[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(findIntersections({&nan}), InvalidInputError);
}

// The tree's self-join and a query against brute force.
void expectTreeFindsEveryOverlap(const std::vector<Box>& boxes, BoxTree::Layout layout) {
  const BoxTree tree(boxes, layout);
  std::vector<std::size_t> perWorker(workerCount(), 0);
  tree.selfPairs([&](std::uint32_t i, std::uint32_t j, unsigned w) {
    EXPECT_LT(i, j);
    ++perWorker[w];
  });
  std::size_t pairs = 0;
  for (std::size_t n : perWorker) pairs += n;
  // Brute force over a sorted sweep on x.
  std::vector<std::uint32_t> order(boxes.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](auto x, auto y) { return boxes[x].lo[0] < boxes[y].lo[0]; });
  std::size_t expected = 0;
  for (std::size_t i = 0; i < order.size(); ++i)
    for (std::size_t j = i + 1; j < order.size() && boxes[order[j]].lo[0] <= boxes[order[i]].hi[0];
         ++j)
      expected += overlap(boxes[order[i]], boxes[order[j]]);
  EXPECT_GT(expected, 0u);
  EXPECT_EQ(pairs, expected);
  std::size_t hits = 0;
  tree.query(boxes[17], 0, [&](std::uint32_t, unsigned) { ++hits; });
  std::size_t expectedHits = 0;
  for (const Box& b : boxes) expectedHits += overlap(b, boxes[17]);
  EXPECT_EQ(hits, expectedHits);
}

TEST(BoxTree, QueryAndSelfPairsFindEveryOverlap) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 10);
  std::vector<Box> boxes;
  for (int i = 0; i < 30000; ++i) {
    const Point3 a(u(rng), u(rng), u(rng));
    boxes.push_back(boxOf(a, a + Point3(0.1, 0.2, 0.1), a + Point3(0.2, 0.05, 0.15)));
  }
  expectTreeFindsEveryOverlap(boxes, BoxTree::Layout::kMedianSplit);
  expectTreeFindsEveryOverlap(boxes, BoxTree::Layout::kMorton);
}

// A cluster far smaller than the whole extent (one box far away): the
// Morton codes of the cluster are all equal, and its ranges are split at
// their middle.
TEST(BoxTree, ClusteredBoxesWithAnOutlierFindEveryOverlap) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(0, 1e-3);
  std::vector<Box> boxes;
  for (int i = 0; i < 25000; ++i) {
    const Point3 a(u(rng), u(rng), u(rng));
    boxes.push_back(boxOf(a, a + Point3(2e-5, 1e-5, 0), a + Point3(0, 2e-5, 1e-5)));
  }
  boxes.push_back(boxOf(Point3(1e6, 1e6, 1e6)));
  expectTreeFindsEveryOverlap(boxes, BoxTree::Layout::kMorton);
  expectTreeFindsEveryOverlap(boxes, BoxTree::Layout::kMedianSplit);
}

// Clusters nested about a point, each a sixteenth the size of the last (a
// part graded towards a point): coded again at every cluster, the codes'
// splits would peel off a few boxes per level, far deeper than a query's
// stack; the depth stays bounded and every overlap is found.
TEST(BoxTree, NestedClustersKeepTheTreeShallow) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Box> boxes;
  for (int level = 0; level < 30; ++level) {
    const double scale = std::ldexp(1.0, -4 * level);
    for (int i = 0; i < 100; ++i) {
      const Point3 a = Point3(u(rng), u(rng), u(rng)) * scale;
      boxes.push_back(
          boxOf(a, a + Point3(0.02, 0.01, 0) * scale, a + Point3(0, 0.02, 0.01) * scale));
    }
  }
  expectTreeFindsEveryOverlap(boxes, BoxTree::Layout::kMorton);
  const BoxTree tree(boxes, BoxTree::Layout::kMorton);
  EXPECT_LE(tree.depth(), 61);
  EXPECT_LE(BoxTree(boxes, BoxTree::Layout::kMedianSplit).depth(), 12);
  for (const Box& b : {boxes[0], boxes[1500], boxes[2999]}) {
    std::size_t hits = 0, expected = 0;
    tree.query(b, 0, [&](std::uint32_t, unsigned) { ++hits; });
    for (const Box& x : boxes) expected += overlap(x, b);
    EXPECT_EQ(hits, expected);
  }
}

// Every query reports exactly the boxes that overlap it (touching counts),
// each once, against brute force.
void expectGridFindsEveryOverlapOnce(const HashedBoxGrid& grid, const std::vector<Box>& boxes,
                                     const std::vector<Box>& queries) {
  for (std::size_t q = 0; q < queries.size(); ++q) {
    std::vector<std::uint32_t> hits, expected;
    grid.query(queries[q], [&](std::uint32_t i) { hits.push_back(i); });
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
      if (overlap(boxes[i], queries[q])) expected.push_back(i);
    std::sort(hits.begin(), hits.end());
    ASSERT_EQ(hits, expected) << "query " << q;
  }
}

TEST(HashedBoxGrid, QueriesFindEveryOverlapOnce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 10), size(0.05, 0.3);
  auto randomBox = [&](double scale) {
    const Point3 a(u(rng), u(rng), 0.3 * u(rng));  // a slab, as faces near a curve
    return boxOf(a, a + Point3(size(rng), size(rng), size(rng)) * scale,
                 a + Point3(size(rng), -size(rng), size(rng)) * scale);
  };
  std::vector<Box> boxes, queries;
  for (int i = 0; i < 3000; ++i) boxes.push_back(randomBox(1));
  for (int i = 0; i < 2000; ++i) queries.push_back(randomBox(1));
  for (int i = 0; i < 20; ++i) queries.push_back(randomBox(30));  // wide: every box tested
  for (int i = 0; i < 50; ++i) queries.push_back(boxes[i]);       // the same box
  for (int i = 50; i < 100; ++i) {  // touching a box at its corner only
    Box b = boxes[i];
    for (int k = 0; k < 3; ++k) b.lo[k] = b.hi[k], b.hi[k] += 0.1f;
    queries.push_back(b);
  }
  queries.push_back({{-5, -5, -5}, {-4, -4, -4}});  // beyond the grid
  queries.push_back({{-1e30f, -1e30f, -1e30f}, {1e30f, 1e30f, 1e30f}});
  const HashedBoxGrid grid(boxes);
  EXPECT_TRUE(grid.suits(queries));
  expectGridFindsEveryOverlapOnce(grid, boxes, queries);
}

TEST(HashedBoxGrid, FlatAndMixedSizedBoxes) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Box> flat, queries;
  for (int i = 0; i < 500; ++i) {
    const Point3 a(u(rng), u(rng), 2);
    flat.push_back(boxOf(a, a + Point3(0.02, 0.01, 0), a + Point3(0.01, 0.03, 0)));
    const Point3 q(u(rng), u(rng), 1.99);
    queries.push_back(boxOf(q, q + Point3(0.03, 0.01, 0.02), q + Point3(0.01, 0.02, 0.01)));
  }
  const HashedBoxGrid flatGrid(flat);  // one cell across the plane
  EXPECT_TRUE(flatGrid.suits(queries));
  expectGridFindsEveryOverlapOnce(flatGrid, flat, queries);
  // One box across everything: listed, it would fill every cell; the grid
  // lists none, leaves the search to a tree, and still answers right.
  std::vector<Box> mixed(flat.begin(), flat.end());
  mixed.push_back(boxOf(Point3(-1, -1, 1), Point3(2, 2, 3), Point3(2, -1, 1)));
  const HashedBoxGrid mixedGrid(mixed);
  EXPECT_FALSE(mixedGrid.suits(queries));
  expectGridFindsEveryOverlapOnce(mixedGrid, mixed, queries);
  // Queries each wider than many cells: every one would test every box.
  std::vector<Box> wide(100, boxOf(Point3(0, 0, 1), Point3(1, 1, 3), Point3(1, 0, 1)));
  EXPECT_FALSE(flatGrid.suits(wide));
  expectGridFindsEveryOverlapOnce(flatGrid, flat, wide);
  const HashedBoxGrid empty({});
  std::size_t hits = 0;
  empty.query(queries[0], [&](std::uint32_t) { ++hits; });
  EXPECT_EQ(hits, 0u);
}

TEST(BoxTree, BoxesAreConservative) {
  const double x = 0.1;  // not a float: the box must still contain it
  const Box b = boxOf({x, x, x}, {x, x, x}, {x, x, x});
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(double(b.lo[k]), x);
    EXPECT_GE(double(b.hi[k]), x);
  }
}

// Each side of a box is the float nearest the coordinate on its side:
// the largest float not above it (lo), the smallest not below it (hi), for
// floats, numbers between floats, both zeros, the smallest and largest
// magnitudes and numbers beyond the largest float.
TEST(BoxTree, BoxesAreTheTightestFloatBoxes) {
  std::vector<double> xs = {0.0,
                            -0.0,
                            0.1,
                            -0.1,
                            1.0,
                            -1.0,
                            1e-45,
                            -1e-45,
                            1e-300,
                            -1e-300,
                            double(std::numeric_limits<float>::max()),
                            -double(std::numeric_limits<float>::max()),
                            1e39,
                            -1e39,
                            1e300,
                            -1e300};
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int i = 0; i < 2000; ++i)
    xs.push_back(unit(random) * std::pow(10.0, int(random() % 60) - 30));
  for (double x : xs) {
    const Box b = boxOf(Point3(x, x, x));
    float lo = float(x), hi = float(x);  // the float nearest x, then stepped with nextafter
    if (double(lo) > x) lo = std::nextafter(lo, -std::numeric_limits<float>::infinity());
    if (double(hi) < x) hi = std::nextafter(hi, std::numeric_limits<float>::infinity());
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(b.lo[k], lo) << "x = " << x;
      EXPECT_EQ(b.hi[k], hi) << "x = " << x;
      EXPECT_LE(double(b.lo[k]), x);
      EXPECT_GE(double(b.hi[k]), x);
    }
  }
}

}  // namespace
}  // namespace meshmend
