#include "common/base/border_loops.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "tests/mesh_builders.h"

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

// ---- The border edges alone ---------------------------------------------------------

// Every edge used by exactly one face, in that face's direction, by
// counting every edge of every face (the definition, on all of them).
std::set<std::array<int, 3>> borderEdgesByCounting(const std::vector<Triangle>& T) {
  std::map<std::pair<int, int>, std::vector<std::array<int, 3>>> uses;
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = T[f][k], b = T[f][(k + 1) % 3];
      if (a == b) continue;
      uses[{std::min(a, b), std::max(a, b)}].push_back({a, b, int(f)});
    }
  std::set<std::array<int, 3>> out;
  for (const auto& [edge, list] : uses)
    if (list.size() == 1) out.insert(list[0]);
  return out;
}

std::set<std::array<int, 3>> asSet(const BorderEdges& found) {
  std::set<std::array<int, 3>> out;
  for (const BorderEdge& e : found.edges) EXPECT_TRUE(out.insert({e.from, e.to, e.face}).second);
  return out;
}

// The sums at each vertex find exactly the border edges counting finds, on
// a sphere with faces taken away at random (holes of every shape, pinched
// vertices, lone faces), a fin (an edge used three times) and a face turned
// over (its edges used twice the same way); and the faces given at each
// vertex they flag are all the faces there.
TEST(BorderEdges, SameAsCountingEveryEdge) {
  const Mesh sphere = icosphere(3);
  std::vector<Triangle> all = trianglesOf(sphere);
  std::mt19937 random(7);
  for (int round = 0; round < 20; ++round) {
    std::vector<Triangle> T;
    for (const Triangle& t : all)
      if (random() % 100 >= unsigned(5 + 3 * round)) T.push_back(t);
    if (round % 3 == 1) T.push_back({T[0][0], T[0][1], int(sphere.vert.size()) - 1});  // a fin
    if (round % 3 == 2) std::swap(T[5][0], T[5][1]);  // turned over
    const BorderEdges found = findBorderEdges(T, sphere.vert.size());
    EXPECT_EQ(asSet(found), borderEdgesByCounting(T)) << "round " << round;
    for (const BorderEdge& e : found.edges) {
      for (int v : {e.from, e.to}) {
        const auto [first, last] = found.facesAt(v);
        ASSERT_NE(first, nullptr) << v;
        std::set<int> given(first, last), there;
        for (std::size_t f = 0; f < T.size(); ++f)
          if (T[f][0] == v || T[f][1] == v || T[f][2] == v) there.insert(int(f));
        EXPECT_EQ(given, there) << "vertex " << v;
      }
    }
  }
}

// The mesh is read in place: the same edges as from its faces as arrays.
TEST(BorderEdges, AMeshGivesWhatItsArraysGive) {
  Mesh m = gridCube(4);
  std::vector<Triangle> T = trianglesOf(m);
  T.erase(T.begin() + 10, T.begin() + 14);
  const Mesh holed = makeMesh(positionsOf(m), T);
  EXPECT_EQ(asSet(findBorderEdges(holed)), asSet(findBorderEdges(T, holed.vert.size())));
  EXPECT_FALSE(findBorderEdges(holed).edges.empty());
  EXPECT_TRUE(findBorderEdges(m).edges.empty());
  EXPECT_TRUE(findBorderEdges(m).vertices.empty());
}

// Three holes meeting at one vertex (three fans there, six border edges at
// it): each comes out as its own loop through the pinch.
TEST(BorderLoops, ThreeHolesAtOneVertex) {
  // Around a centre, six triangles of a hexagon; every other one left out.
  std::vector<Point3> P{{0, 0, 0}};
  for (int k = 0; k < 6; ++k) P.push_back({std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0});
  std::vector<Triangle> T;
  for (int k = 0; k < 6; k += 2) T.push_back({0, 1 + k, 1 + (k + 1) % 6});
  const BorderLoops b = findBorderLoops(P, T);
  EXPECT_EQ(b.pinched, std::vector<int>{0});
  ASSERT_EQ(b.loops.size(), 3u);
  for (const BorderLoop& loop : b.loops) {
    EXPECT_TRUE(loop.closed);
    EXPECT_EQ(loop.vertices.size(), 3u);
    expectFollowsFaces(T, loop);
    ASSERT_EQ(loop.faces.size(), loop.vertices.size());
    for (std::size_t i = 0; i < loop.faces.size(); ++i) {  // the face of each border edge
      const Triangle& t = T[std::size_t(loop.faces[i])];
      const int a = loop.vertices[i], c = loop.vertices[(i + 1) % loop.vertices.size()];
      EXPECT_TRUE((t[0] == a && t[1] == c) || (t[1] == a && t[2] == c) || (t[2] == a && t[0] == c));
    }
  }
}

}  // namespace
