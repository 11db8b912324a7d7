#include "common/border_loops.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "mesh_builders.h"

using namespace meshmend;
using namespace meshmend::testing;

namespace {

// An (n x n)-quad grid in the plane z = 0, normals up; vertex (i, j) is
// j * (n + 1) + i. The quads in missingQuads (quad (i, j) is j * n + i) are
// left out.
struct Grid {
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  int n;
  int at(int i, int j) const { return j * (n + 1) + i; }
};

Grid grid(int n, const std::set<int>& missingQuads = {}) {
  Grid g;
  g.n = n;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) g.points.push_back({double(i), double(j), 0});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (missingQuads.count(j * n + i)) continue;
      g.triangles.push_back({g.at(i, j), g.at(i + 1, j), g.at(i + 1, j + 1)});
      g.triangles.push_back({g.at(i, j), g.at(i + 1, j + 1), g.at(i, j + 1)});
    }
  return g;
}

// Each consecutive pair of a loop is run by a face in that direction.
void expectFollowsFaces(const std::vector<Triangle>& T, const BorderLoop& loop) {
  std::set<std::pair<int, int>> directed;
  for (const Triangle& t : T)
    for (int k = 0; k < 3; ++k) directed.insert({t[k], t[(k + 1) % 3]});
  const std::size_t m = loop.vertices.size();
  const std::size_t edges = loop.closed ? m : m - 1;
  for (std::size_t k = 0; k < edges; ++k) {
    const int a = loop.vertices[k], b = loop.vertices[(k + 1) % m];
    EXPECT_TRUE(directed.count({a, b})) << a << " -> " << b;
    EXPECT_FALSE(directed.count({b, a})) << a << " -> " << b << " is not a border edge";
  }
}

TEST(BorderLoops, ClosedMeshHasNone) {
  const Mesh cube = gridCube(3);
  const BorderLoops b = findBorderLoops(positionsOf(cube), trianglesOf(cube));
  EXPECT_TRUE(b.loops.empty());
  EXPECT_TRUE(b.pinched.empty());
}

TEST(BorderLoops, OuterBorderAndOneHoleInTheFacesDirection) {
  const Grid g = grid(4, {1 * 4 + 1, 1 * 4 + 2});  // a hole of two quads
  const BorderLoops b = findBorderLoops(g.points, g.triangles);
  ASSERT_EQ(b.loops.size(), 2u);
  std::vector<std::size_t> sizes;
  for (const BorderLoop& loop : b.loops) {
    EXPECT_TRUE(loop.closed);
    EXPECT_EQ(loop.broken_at, -1);
    sizes.push_back(loop.vertices.size());
    expectFollowsFaces(g.triangles, loop);
  }
  std::sort(sizes.begin(), sizes.end());
  EXPECT_EQ(sizes, (std::vector<std::size_t>{6, 16}));
  EXPECT_TRUE(b.pinched.empty());
}

TEST(BorderLoops, TwoHolesTouchingAtAVertexAreTwoLoops) {
  // Quads (1,1) and (2,2) missing: the holes share grid vertex (2,2).
  const Grid g = grid(4, {1 * 4 + 1, 2 * 4 + 2});
  const BorderLoops b = findBorderLoops(g.points, g.triangles);
  ASSERT_EQ(b.pinched, std::vector<int>{g.at(2, 2)});
  int squares = 0;
  for (const BorderLoop& loop : b.loops) {
    EXPECT_TRUE(loop.closed);
    expectFollowsFaces(g.triangles, loop);
    if (loop.vertices.size() == 4) {
      ++squares;
      // Each hole is one quad's outline, through the pinch.
      EXPECT_NE(std::find(loop.vertices.begin(), loop.vertices.end(), g.at(2, 2)),
                loop.vertices.end());
    }
  }
  EXPECT_EQ(squares, 2);
  EXPECT_EQ(b.loops.size(), 3u);  // and the outer border
}

TEST(BorderLoops, BowTieOfTwoTriangles) {
  const std::vector<Point3> P{{0, 0, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {-1, -1, 0}};
  const std::vector<Triangle> T{{0, 1, 2}, {0, 3, 4}};
  const BorderLoops b = findBorderLoops(P, T);
  ASSERT_EQ(b.loops.size(), 2u);
  EXPECT_EQ(b.pinched, std::vector<int>{0});
  for (const BorderLoop& loop : b.loops) {
    EXPECT_TRUE(loop.closed);
    EXPECT_EQ(loop.vertices.size(), 3u);
    expectFollowsFaces(T, loop);
  }
}

TEST(BorderLoops, InconsistentOrientationBreaksTheLoop) {
  // Two triangles sharing edge 1-2 but running it the same way: that edge
  // is used twice (not a border), and vertices 1 and 2 each have two border
  // edges leaving (or arriving): the border cannot be followed through them.
  const std::vector<Point3> P{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const std::vector<Triangle> T{{0, 1, 2}, {3, 1, 2}};
  const BorderLoops b = findBorderLoops(P, T);
  ASSERT_FALSE(b.loops.empty());
  std::size_t edges = 0;
  for (const BorderLoop& loop : b.loops) {
    EXPECT_FALSE(loop.closed);
    EXPECT_EQ(loop.broken_at, loop.vertices.back());
    expectFollowsFaces(T, loop);
    edges += loop.vertices.size() - 1;
  }
  EXPECT_EQ(edges, 4u);  // every border edge once
}

}  // namespace
