#include "common/exact/changed_faces.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>

#include <gtest/gtest.h>

namespace meshmend {
namespace {

using PairSet = std::set<std::array<std::uint32_t, 2>>;

// Small triangles over a large cube, and a cluster of changed ones in one
// corner of it: most faces lie far from every changed one, some beside.
struct Soup {
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  std::vector<char> changed;
};

Soup soup(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> anywhere(-50, 50), corner(-50, -30), size(-0.8, 0.8);
  Soup s;
  for (int f = 0; f < 6000; ++f) {
    const bool isChanged = f % 10 == 0;
    const Point3 at = isChanged ? Point3(corner(rng), corner(rng), corner(rng))
                                : Point3(anywhere(rng), anywhere(rng), anywhere(rng));
    const int first = int(s.points.size());
    for (int k = 0; k < 3; ++k) s.points.push_back(at + Point3(size(rng), size(rng), size(rng)));
    // Every fifth face shares a corner with the one before it.
    const int shared = f % 5 == 4 ? first - 1 : first;
    s.triangles.push_back({shared, first + 1, first + 2});
    s.changed.push_back(isChanged);
  }
  return s;
}

Box widenedByNextafter(Box b, int steps) {
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < steps; ++i) {
      b.lo[k] = std::nextafter(b.lo[k], -INFINITY);
      b.hi[k] = std::nextafter(b.hi[k], INFINITY);
    }
  return b;
}

// Every pair of faces with a changed one whose boxes overlap, the changed
// faces' boxes widened: (smaller, larger) for two changed, else (changed,
// unchanged).
PairSet bruteForcePairs(const Soup& s, int widenSteps) {
  std::vector<Box> boxes;
  for (std::size_t f = 0; f < s.triangles.size(); ++f) {
    const Triangle& t = s.triangles[f];
    const Box b = boxOf(s.points[t[0]], s.points[t[1]], s.points[t[2]]);
    boxes.push_back(s.changed[f] ? widenedByNextafter(b, widenSteps) : b);
  }
  PairSet pairs;
  for (std::uint32_t f = 0; f < boxes.size(); ++f)
    for (std::uint32_t g = f + 1; g < boxes.size(); ++g) {
      if (!(s.changed[f] || s.changed[g]) || !overlap(boxes[f], boxes[g])) continue;
      pairs.insert(s.changed[f] ? std::array<std::uint32_t, 2>{f, g}
                                : std::array<std::uint32_t, 2>{g, f});
    }
  return pairs;
}

TEST(ChangedFaceSearch, FindsEveryOverlappingPairWithAChangedFaceOnce) {
  const Soup s = soup(3);
  const int widenSteps = 5;
  const PairSet expected = bruteForcePairs(s, widenSteps);
  ASSERT_GT(expected.size(), 300u);
  const ChangedFaceSearch search(s.points, s.triangles, s.changed, widenSteps);
  const std::vector<std::array<std::uint32_t, 2>> found = search.pairs();
  EXPECT_EQ(found.size(), expected.size());  // each once
  EXPECT_EQ(PairSet(found.begin(), found.end()), expected);
  // The near faces are the few beside the changed ones, not the whole soup.
  const std::size_t changed = std::size_t(std::count(s.changed.begin(), s.changed.end(), 1));
  EXPECT_EQ(search.changedCount(), changed);
  EXPECT_LT(search.faces().size() - changed, s.triangles.size() / 4);
  // Positions: the first changed, smaller than the second.
  search.forEachPair([&](std::uint32_t a, std::uint32_t b, unsigned) {
    EXPECT_LT(a, b);
    EXPECT_LT(a, search.changedCount());
  });
  EXPECT_EQ(pairsWithChangedFaces(s.points, s.triangles, s.changed, widenSteps).size(),
            expected.size());
}

TEST(ChangedFaceSearch, CandidatesOfAFaceAreItsPairs) {
  const Soup s = soup(4);
  const ChangedFaceSearch search(s.points, s.triangles, s.changed, 2);
  const PairSet pairs = bruteForcePairs(s, 2);
  std::vector<std::uint32_t> asked;
  for (std::uint32_t f = 0; f < s.triangles.size() && asked.size() < 40; f += 7)
    if (s.changed[f]) asked.push_back(f);
  asked.push_back(1);  // unchanged: no pairs of its own
  const std::vector<std::vector<std::uint32_t>> rows = search.candidatesOf(asked);
  ASSERT_EQ(rows.size(), asked.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < asked.size(); ++i) {
    std::set<std::uint32_t> expected;
    for (const auto& [f, g] : pairs) {
      if (f == asked[i]) expected.insert(g);
      if (g == asked[i] && s.changed[f]) expected.insert(f);
    }
    if (!s.changed[asked[i]]) expected.clear();
    EXPECT_EQ(rows[i].size(), expected.size()) << "face " << asked[i];
    EXPECT_EQ(std::set<std::uint32_t>(rows[i].begin(), rows[i].end()), expected);
    total += rows[i].size();
  }
  EXPECT_GT(total, 40u);
}

TEST(ChangedFaceSearch, NoChangedFaceNoPairs) {
  Soup s = soup(5);
  std::fill(s.changed.begin(), s.changed.end(), 0);
  const ChangedFaceSearch search(s.points, s.triangles, s.changed, 3);
  EXPECT_TRUE(search.faces().empty());
  EXPECT_TRUE(search.pairs().empty());
  EXPECT_TRUE(search.candidatesOf({0, 1}).at(0).empty());
}

// The grid's faces touching it are those whose boxes touch it, for faces
// inside, across and outside the grid, with corners in double and stored as
// float (a point box of its own), some on the grid's bounds.
TEST(BoxGrid, FacesTouchingAreThoseWhoseBoxesTouch) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> inside(0, 10), around(-4, 14), size(-1.5, 1.5);
  std::vector<Box> boxes;
  for (int i = 0; i < 200; ++i) {
    const Point3 a(inside(rng), inside(rng), inside(rng));
    boxes.push_back(boxOf(a, a + Point3(0.1, 0.1, 0.1), a + Point3(0.1, 0, 0.05)));
  }
  const BoxGrid grid(boxes);
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  for (int i = 0; i < 20000; ++i) {
    const int first = int(points.size());
    const Point3 a(around(rng), around(rng), around(rng));
    points.push_back(a);
    points.push_back(i % 4 ? a + Point3(size(rng), size(rng), size(rng)) : a);
    points.push_back(i % 3 ? a + Point3(size(rng), size(rng), size(rng)) : Point3(-30, 40, 5));
    triangles.push_back({first, first + 1, first + 2});
  }
  Box bounds = boxes[0];  // the grid's
  for (const Box& b : boxes)
    for (int k = 0; k < 3; ++k) {
      bounds.lo[k] = std::min(bounds.lo[k], b.lo[k]);
      bounds.hi[k] = std::max(bounds.hi[k], b.hi[k]);
    }
  for (const Box& b : {bounds, boxes[0]}) {  // corners on the grid's bounds and a box's
    const int first = int(points.size());
    points.push_back(Point3(b.lo[0], b.lo[1], b.lo[2]));
    points.push_back(Point3(b.hi[0], b.hi[1], b.hi[2]));
    points.push_back(Point3(b.lo[0], b.hi[1], b.lo[2]));
    triangles.push_back({first, first, first + 1});
    triangles.push_back({first + 2, first + 2, first + 2});
  }
  std::vector<char> skip(triangles.size(), 0);
  for (std::size_t f = 0; f < skip.size(); f += 7) skip[f] = 1;
  for (const bool stored : {false, true}) {
    if (stored)
      for (Point3& p : points) p = storedAs(p, Scalar::kFloat);
    std::vector<std::uint32_t> expected;
    for (std::uint32_t f = 0; f < triangles.size(); ++f) {
      const Triangle& t = triangles[f];
      if (!skip[f] && grid.touches(boxOf(points[t[0]], points[t[1]], points[t[2]])))
        expected.push_back(f);
    }
    EXPECT_GT(expected.size(), 1000u);
    EXPECT_LT(expected.size(), 15000u);
    EXPECT_EQ(grid.facesTouching(points, triangles, skip), expected) << "stored " << stored;
  }
}

// A grid whose extent overflows float along an axis (corners near -/+3e38):
// a point's offset times the cells per unit is NaN there (infinity times
// zero); faces with such corners are found as touches() finds them (the
// cells' boxes: one cell along x, both boxes in it).
TEST(BoxGrid, FacesTouchingAcrossAnExtentPastFloat) {
  const float big = 3e38f;
  const std::vector<Box> boxes = {{{-big, 0, 0}, {-big, 1, 1}}, {{big, 0, 0}, {big, 1, 1}}};
  const BoxGrid grid(boxes);
  const std::vector<Point3> points = {{big, 0.5, 0.5}, {big, 0.6, 0.5}, {big, 0.5, 0.6},
                                      {-big, 5, 5},    {-big, 6, 5},    {-big, 5, 6},
                                      {0, 0.5, 0.5},   {1, 0.5, 0.5},   {0, 0.6, 0.6}};
  const std::vector<Triangle> triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  std::vector<std::uint32_t> expected;
  for (std::uint32_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    if (grid.touches(boxOf(points[t[0]], points[t[1]], points[t[2]]))) expected.push_back(f);
  }
  EXPECT_EQ(expected, (std::vector<std::uint32_t>{0, 2}));  // face 1 is above the grid in y
  EXPECT_EQ(grid.facesTouching(points, triangles, std::vector<char>(3, 0)), expected);
}

// Boxes in a thin slab (10 x 10 x 0.3, as around a shallow intersection
// curve; the cells are cubes, so the slab has few along z): a face whose box
// overlaps one of them touches the grid, and the faces touching it are
// those whose boxes touch it.
TEST(BoxGrid, FacesTouchingInAThinSlab) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> inside(0, 10), thin(0, 0.3), around(-1, 11),
      aroundThin(-0.2, 0.5), size(-0.2, 0.2);
  std::vector<Box> boxes;
  for (int i = 0; i < 300; ++i) {
    const Point3 a(inside(rng), inside(rng), thin(rng));
    boxes.push_back(boxOf(a, a + Point3(0.1, 0.1, 0.01), a + Point3(0.1, 0, 0.005)));
  }
  const BoxGrid grid(boxes);
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  int overlapping = 0;
  for (int i = 0; i < 20000; ++i) {
    const int first = int(points.size());
    const Point3 a(around(rng), around(rng), aroundThin(rng));
    points.insert(points.end(), {a, a + Point3(size(rng), size(rng), size(rng) / 10),
                                 a + Point3(size(rng), size(rng), size(rng) / 10)});
    triangles.push_back({first, first + 1, first + 2});
    const Box q = boxOf(points[first], points[first + 1], points[first + 2]);
    bool overlaps = false;
    for (const Box& b : boxes) overlaps |= overlap(b, q);
    if (!overlaps) continue;
    ++overlapping;
    EXPECT_TRUE(grid.touches(q)) << i;
  }
  EXPECT_GT(overlapping, 50);
  std::vector<std::uint32_t> expected;
  for (std::uint32_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    if (grid.touches(boxOf(points[t[0]], points[t[1]], points[t[2]]))) expected.push_back(f);
  }
  EXPECT_LT(expected.size(), triangles.size() / 2);  // the grid turns most away
  EXPECT_EQ(grid.facesTouching(points, triangles, std::vector<char>(triangles.size(), 0)),
            expected);
}

// Boxes spanning one or two cells along each axis (most faces' boxes): a
// box overlapping one of the grid's touches it, along whichever axes it
// spans two cells, and a box more than two cells from all of them does not.
TEST(BoxGrid, SmallBoxesTouchWhereTheGridsBoxesAre) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> inside(0, 10), around(-1, 11), size(0, 0.15);
  std::vector<Box> boxes;
  for (int i = 0; i < 500; ++i) {
    const Point3 a(inside(rng), inside(rng), inside(rng));
    boxes.push_back(boxOf(a, a + Point3(0.1, 0.1, 0.1), a + Point3(0.1, 0, 0.05)));
  }
  const BoxGrid grid(boxes);
  const double cell = 10.0 / 64, far = 2.5 * cell;  // the grid spans about 10 in 64 cells
  int overlapping = 0, distant = 0;
  for (int i = 0; i < 40000; ++i) {
    // Every other one beside a box of the grid, where it may reach into the
    // cell next to that box's.
    const Box& b = boxes[std::size_t(i) % boxes.size()];
    const Point3 a = i % 2 ? Point3(around(rng), around(rng), around(rng))
                           : Point3(b.lo[0] - size(rng), b.lo[1] - size(rng), b.lo[2] - size(rng));
    const Box q = boxOf(a, a + Point3(size(rng), size(rng), size(rng)), a);
    bool overlaps = false, nearAny = false;
    for (const Box& b : boxes) {
      overlaps |= overlap(b, q);
      bool near = true;
      for (int k = 0; k < 3; ++k) near &= b.lo[k] - q.hi[k] < far && q.lo[k] - b.hi[k] < far;
      nearAny |= near;
    }
    if (overlaps) {
      ++overlapping;
      EXPECT_TRUE(grid.touches(q)) << i;
    } else if (!nearAny) {
      ++distant;
      EXPECT_FALSE(grid.touches(q)) << i;
    }
  }
  EXPECT_GT(overlapping, 1000);
  EXPECT_GT(distant, 5000);
}

TEST(Box, WidenedIsThatManyNextafterSteps) {
  std::vector<float> values = {0.0f,
                               -0.0f,
                               std::numeric_limits<float>::denorm_min(),
                               -std::numeric_limits<float>::denorm_min(),
                               std::numeric_limits<float>::min(),
                               -std::numeric_limits<float>::min(),
                               1.0f,
                               -1.0f,
                               std::numeric_limits<float>::max(),
                               -std::numeric_limits<float>::max()};
  std::mt19937 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const std::uint32_t bits = rng();
    float f;
    std::memcpy(&f, &bits, sizeof f);
    if (std::isfinite(f)) values.push_back(f);
  }
  for (float v : values)
    for (int steps : {0, 1, 2, 7}) {
      const Box b{{v, v, v}, {v, v, v}};
      const Box w = widened(b, steps), n = widenedByNextafter(b, steps);
      ASSERT_EQ(w.lo[0], n.lo[0]) << v << " " << steps;
      ASSERT_EQ(w.hi[2], n.hi[2]) << v << " " << steps;
    }
  const float inf = std::numeric_limits<float>::infinity();
  const Box infinite = widened(Box{{-inf, 0, 0}, {inf, 0, 0}}, 3);
  EXPECT_EQ(infinite.lo[0], -inf);
  EXPECT_EQ(infinite.hi[0], inf);
}

}  // namespace
}  // namespace meshmend
