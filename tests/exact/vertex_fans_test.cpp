#include "common/exact/vertex_fans.h"

#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "tests/mesh_builders.h"

namespace meshmend {
namespace {

using testing::icosphere;

// Vertex 0 at the origin and a ring of `n` points at angles `step` apart
// (radians), at heights z(i), with the faces (0, i, i + 1); closed when
// `closed`, the last face joining the ring's end to its start.
struct Fan {
  std::vector<Point3> points{{0, 0, 0}};
  std::vector<Triangle> triangles;
};

template <class Height>
Fan ring(int n, double step, Height&& z, bool closed = true) {
  Fan f;
  for (int i = 0; i < n; ++i) f.points.push_back({std::cos(i * step), std::sin(i * step), z(i)});
  for (int i = 0; i + 1 < n; ++i) f.triangles.push_back({0, 1 + i, 2 + i});
  if (closed) f.triangles.push_back({0, n, 1});
  return f;
}

const double kTurn = 2 * M_PI;

TEST(VertexFans, EveryVertexOfAClosedSphereIsApart) {
  const Mesh s = icosphere(2);
  const std::vector<char> apart = fansApartInProjection(positionsOf(s), trianglesOf(s));
  EXPECT_EQ(std::accumulate(apart.begin(), apart.end(), 0), int(s.vert.size()));
}

TEST(VertexFans, AFlatClosedFanIsApartAndItsBorderIsNot) {
  const Fan f = ring(6, kTurn / 6, [](int) { return 0.0; });
  const std::vector<char> apart = fansApartInProjection(f.points, f.triangles);
  EXPECT_EQ(apart[0], 1);
  for (std::size_t v = 1; v < apart.size(); ++v) EXPECT_EQ(apart[v], 0) << v;
}

TEST(VertexFans, AnOpenFanIsNot) {
  // All but one face of a cone: every face turns the same way, once around.
  const Fan f = ring(
      6, kTurn / 6, [](int) { return 0.5; }, false);
  EXPECT_EQ(fansApartInProjection(f.points, f.triangles)[0], 0);
}

TEST(VertexFans, AFanThatTurnsTwiceIsNot) {
  // Eight faces a quarter turn each, rising: closed, every face
  // counter-clockwise seen from above, but twice around the vertex.
  const Fan f = ring(8, kTurn / 4, [](int i) { return 0.1 * i; });
  EXPECT_EQ(fansApartInProjection(f.points, f.triangles)[0], 0);
}

TEST(VertexFans, AFoldedFanIsNot) {
  // A flat hexagonal fan with one ring point moved past its neighbour: that
  // face turns the other way.
  Fan f = ring(6, kTurn / 6, [](int) { return 0.0; });
  f.points[2] = {std::cos(2.6), std::sin(2.6), 0};
  EXPECT_EQ(fansApartInProjection(f.points, f.triangles)[0], 0);
}

TEST(VertexFans, TwoFansAtOneVertexAreNot) {
  // Two cones joined at their apex: each neighbour once before and once
  // after the vertex, but two closed fans, twice around.
  Fan f = ring(5, kTurn / 5, [](int) { return 1.0; });
  const Fan g = ring(5, kTurn / 5, [](int) { return -1.0; });
  for (int i = 1; i <= 5; ++i) f.points.push_back(g.points[std::size_t(i)]);
  for (const Triangle& t : g.triangles) f.triangles.push_back({0, t[1] + 5, t[2] + 5});
  EXPECT_EQ(fansApartInProjection(f.points, f.triangles)[0], 0);
}

TEST(VertexFans, AFanWithAnInconsistentFaceOrADegenerateFaceIsNot) {
  Fan flipped = ring(6, kTurn / 6, [](int) { return 0.0; });
  std::swap(flipped.triangles[2][1], flipped.triangles[2][2]);
  EXPECT_EQ(fansApartInProjection(flipped.points, flipped.triangles)[0], 0);
  // A ring point on the vertex: its two faces are degenerate.
  Fan flat = ring(6, kTurn / 6, [](int) { return 0.0; });
  flat.points[3] = {0, 0, 0};
  EXPECT_EQ(fansApartInProjection(flat.points, flat.triangles)[0], 0);
}

TEST(VertexFans, AVerticalFanIsApartInAnotherProjection) {
  // The flat fan turned to stand in the xz plane: its normal is along y.
  Fan f = ring(7, kTurn / 7, [](int) { return 0.0; });
  for (Point3& p : f.points) p = {p[0], 0.0, p[1]};
  EXPECT_EQ(fansApartInProjection(f.points, f.triangles)[0], 1);
}

}  // namespace
}  // namespace meshmend
