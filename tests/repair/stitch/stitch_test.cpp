#include "common/repair/stitch/stitch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <string>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "tests/mesh_builders.h"

using namespace meshmend;
using namespace meshmend::testing;

namespace {

// A sheet of (nu x nv) quads, each cut into two triangles, with vertex
// (i, j) at pos(i, j) (index j * (nu + 1) + i); faces turn from du to dv.
Mesh sheet(int nu, int nv, const std::function<Point3(int, int)>& pos) {
  std::vector<Point3> p;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) p.push_back(pos(i, j));
  auto at = [&](int i, int j) { return j * (nu + 1) + i; };
  std::vector<Triangle> t;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return makeMesh(p, t);
}

std::vector<int> row(int nu, int j, int offset = 0) {
  std::vector<int> r;
  for (int i = 0; i <= nu; ++i) r.push_back(offset + j * (nu + 1) + i);
  return r;
}
std::vector<int> column(int nu, int nv, int i, int offset = 0) {
  std::vector<int> c;
  for (int j = 0; j <= nv; ++j) c.push_back(offset + j * (nu + 1) + i);
  return c;
}

std::vector<int> reversed(std::vector<int> v) {
  std::reverse(v.begin(), v.end());
  return v;
}

// A mesh with every face turned over.
Mesh flipped(const Mesh& m) {
  std::vector<Triangle> t = trianglesOf(m);
  for (Triangle& f : t) std::swap(f[1], f[2]);
  return makeMesh(positionsOf(m), t);
}

// Torus around the z axis (radii R, r): `nu` steps around the axis, `nv`
// around the tube; closed, outward normals. Vertex (i, j) = j * nu + i.
Mesh torus(int nu, int nv, double R = 1, double r = 0.3) {
  std::vector<Point3> p;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      p.emplace_back((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                     r * std::sin(v));
    }
  auto at = [&](int i, int j) { return (j % nv) * nu + (i % nu); };
  std::vector<Triangle> t;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return makeMesh(p, t);
}

// Every property a stitched mesh must have: the border edges expected,
// edge-manifold, consistently oriented, vertices as expected, and no
// intersecting pair at all (the inputs have none), by the exact count.
void expectClean(const Mesh& m, std::size_t border, std::size_t vertices) {
  const EdgeStats s = edgeStats(m);
  EXPECT_EQ(s.border, border);
  EXPECT_EQ(s.nonManifold, 0u);
  EXPECT_EQ(s.inconsistent, 0u);
  EXPECT_EQ(m.vert.size(), vertices);
  EXPECT_EQ(selfIntersectingPairs(m), 0u);
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// ---------------------------------------------------------------- Figure 2

// Two sheets facing each other across a gap that widens along x: sheet a
// above the curve f, sheet b below f - gap, with different densities.
// Returns the mesh (a then b) and the two facing rows.
struct TwoSheets {
  Mesh mesh;
  std::vector<int> a, b;
  std::size_t borderBefore = 0;
};

TwoSheets smoothSheets(int na, int nb, double widen) {
  const double w = 2, h = 0.1;
  auto f = [](double x) { return 0.3 * std::sin(2 * x); };
  auto gap = [&](double x) { return 0.02 + widen * x; };
  const Mesh A = sheet(na, 3, [&](int i, int j) {
    const double x = w * i / na;
    return Point3(x, f(x) + j * h, 0);
  });
  const Mesh B = sheet(nb, 3, [&](int i, int j) {
    const double x = w * i / nb;
    return Point3(x, f(x) - gap(x) - (3 - j) * h, 0);
  });
  TwoSheets s;
  s.mesh = appended(A, B);
  s.a = row(na, 0);
  s.b = row(nb, 3, int(A.vert.size()));
  s.borderBefore = 2 * (na + 3) + 2 * (nb + 3);
  return s;
}

TEST(StitchFigure2, ParallelPathsWithWideningGap) {
  TwoSheets s = smoothSheets(40, 27, 0.15);
  const std::size_t vertices = s.mesh.vert.size();
  StitchOptions o;
  o.a.vertices = s.a;
  o.b.vertices = s.b;
  const StitchResult r = stitchPaths(s.mesh, o);
  // One sheet: the path edges are interior, the two end rungs are border.
  EXPECT_EQ(r.faces_added, 40u + 27u);
  EXPECT_EQ(r.vertices_added, 0u);
  EXPECT_EQ(r.border_edges_before, s.borderBefore);
  EXPECT_EQ(r.border_edges_after, s.borderBefore - 40 - 27 + 2);
  EXPECT_FALSE(r.closed);
  EXPECT_FALSE(r.reversed_b);
  EXPECT_EQ(r.orientation_conflicts, 0u);
  EXPECT_TRUE(r.checked);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectClean(s.mesh, r.border_edges_after, vertices);
}

TEST(StitchCheck, CountsThePairsTheStitchMakesAsAWholeMeshCountDoes) {
  // A small triangle standing across the gap, touching neither sheet: the
  // strip passes through it.
  TwoSheets s = smoothSheets(40, 27, 0.15);
  const double y = 0.3 * std::sin(2.0) - 0.085;  // halfway across the gap at x = 1
  const Mesh pin = makeMesh({{1.0, y, -0.05}, {1.0, y, 0.05}, {1.02, y, 0}}, {{0, 1, 2}});
  Mesh m = appended(s.mesh, pin);
  ASSERT_EQ(selfIntersectingPairs(m), 0u);
  StitchOptions o;
  o.a.vertices = s.a;
  o.b.vertices = s.b;
  const StitchResult r = stitchPaths(m, o);
  ASSERT_TRUE(r.checked);
  EXPECT_GT(r.new_intersecting_pairs, 0u);
  EXPECT_EQ(r.new_intersecting_pairs, selfIntersectingPairs(m));
  // Without the check nothing is counted, and the same faces are added.
  Mesh unchecked = appended(s.mesh, pin);
  o.check_intersections = false;
  const StitchResult u = stitchPaths(unchecked, o);
  EXPECT_FALSE(u.checked);
  EXPECT_EQ(u.new_intersecting_pairs, 0u);
  EXPECT_EQ(trianglesOf(unchecked), trianglesOf(m));
}

TEST(StitchFigure2, PathGivenBackwardsIsTurnedAround) {
  TwoSheets s = smoothSheets(30, 21, 0.1);
  StitchOptions o;
  o.a.vertices = s.a;
  o.b.vertices = reversed(s.b);
  const StitchResult r = stitchPaths(s.mesh, o);
  EXPECT_TRUE(r.reversed_b);
  expectClean(s.mesh, s.borderBefore - 30 - 21 + 2, s.mesh.vert.size());
}

TEST(StitchFigure2, SharplyTurningStaircasePaths) {
  // Regular grids cut along curves: their borders are staircases with
  // sharp turns, the gap between them widens, and the cells differ.
  const double ca = 0.1, cb = 0.07, w = 2;
  auto f = [](double x) { return 1.0 + 0.4 * std::sin(3 * x); };
  auto g = [&](double x) { return f(x) - 0.05 - 0.25 * x; };
  const int nxa = int(std::lround(w / ca)), nxb = int(std::lround(w / cb));
  const Mesh A = heightGrid(
      nxa, 20, ca, [](double, double) { return 0.0; },
      [&](double x, double y) { return y > f(x); });
  const Mesh B = heightGrid(
      nxb, 30, cb, [](double, double) { return 0.0; },
      [&](double x, double y) { return y < g(x); });
  // The staircase of each grid: along x, climbing at the column changes.
  auto staircase = [](int nx, int ny, double cell, const std::function<bool(double, double)>& keep,
                      bool lowestKept, int offset) {
    std::vector<int> path;
    auto at = [&](int i, int j) { return offset + j * (nx + 1) + i; };
    int prevRow = -1;
    for (int i = 0; i < nx; ++i) {
      // The row of the border in column i: below the lowest kept cell (a),
      // above the highest kept cell (b).
      int r = lowestKept ? ny : 0;
      for (int j = 0; j < ny; ++j)
        if (keep((i + 0.5) * cell, (j + 0.5) * cell)) {
          if (lowestKept) {
            r = std::min(r, j);
          } else {
            r = std::max(r, j + 1);
          }
        }
      if (prevRow >= 0)
        for (int j = prevRow; j != r; j += r > prevRow ? 1 : -1) path.push_back(at(i, j));
      path.push_back(at(i, r));
      prevRow = r;
    }
    path.push_back(at(nx, prevRow));
    return path;
  };
  Mesh m = appended(A, B);
  const std::size_t vertices = m.vert.size();
  const std::size_t borderBefore = edgeStats(m).border;
  StitchOptions o;
  o.a.vertices = staircase(
      nxa, 20, ca, [&](double x, double y) { return y > f(x); }, true, 0);
  o.b.vertices = staircase(
      nxb, 30, cb, [&](double x, double y) { return y < g(x); }, false, int(A.vert.size()));
  // Both climb and drop several rows: vertical steps between the columns.
  EXPECT_GT(o.a.vertices.size(), std::size_t(nxa + 1 + 8));
  EXPECT_GT(o.b.vertices.size(), std::size_t(nxb + 1 + 8));
  const StitchResult r = stitchPaths(m, o);
  const std::size_t pathEdges = o.a.vertices.size() - 1 + o.b.vertices.size() - 1;
  EXPECT_EQ(r.faces_added, pathEdges);
  EXPECT_EQ(r.border_edges_after, borderBefore - pathEdges + 2);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectClean(m, r.border_edges_after, vertices);
}

TEST(StitchFigure2, WideGapSubdivided) {
  // A gap of 0.3 to 1.1 across paths of edge length 0.1 to 0.13.
  TwoSheets s = smoothSheets(20, 15, 0.4);
  const std::size_t firstB = std::size_t(s.b.front()) - 3 * 16;  // sheet b's vertices
  for (std::size_t v = firstB; v < s.mesh.vert.size(); ++v) s.mesh.vert[v].P()[1] -= 0.28;
  StitchOptions o;
  o.a.vertices = s.a;
  o.b.vertices = s.b;
  Mesh plain = s.mesh;
  const StitchResult coarse = stitchPaths(plain, o);
  o.max_aspect_ratio = 3;
  const std::size_t vertices = s.mesh.vert.size();
  const StitchResult r = stitchPaths(s.mesh, o);
  EXPECT_GT(r.vertices_added, 0u);
  EXPECT_EQ(s.mesh.vert.size(), vertices + r.vertices_added);
  EXPECT_LT(r.max_aspect_ratio, coarse.max_aspect_ratio / 2);
  EXPECT_LT(r.max_aspect_ratio, 8);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  const EdgeStats st = edgeStats(s.mesh);
  EXPECT_EQ(st.border, r.border_edges_after);
  EXPECT_EQ(st.nonManifold, 0u);
  EXPECT_EQ(st.inconsistent, 0u);
  EXPECT_EQ(selfIntersectingPairs(s.mesh), 0u);
}

// ---------------------------------------------------------------- Figure 4

TEST(StitchFigure4, NonCoplanarPatches) {
  // Sheet a in the plane z = 0 (y >= 0.1); sheet b tilted by 40 degrees
  // about the x axis, so that the two planes meet along y = z = 0, in the
  // middle of the gap.
  const int na = 24, nb = 17, nv = 4;
  const double c = std::cos(40 * M_PI / 180), sn = std::sin(40 * M_PI / 180);
  const Mesh A =
      sheet(na, nv, [&](int i, int j) { return Point3(2.0 * i / na, 0.1 + 0.9 * j / nv, 0); });
  const Mesh B = sheet(nb, nv, [&](int i, int j) {
    const double s = 1 - 0.9 * j / nv;
    return Point3(2.0 * i / nb, -s * c, s * sn);
  });
  Mesh m = appended(A, B);
  const std::size_t vertices = m.vert.size();
  StitchOptions o;
  o.a.vertices = row(na, 0);
  o.b.vertices = row(nb, nv, int(A.vert.size()));
  const StitchResult r = stitchPaths(m, o);
  EXPECT_EQ(r.faces_added, std::size_t(na + nb));
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectClean(m, 2 * (na + nv) + 2 * (nb + nv) - na - nb + 2, vertices);
}

// ---------------------------------------------------------------- Figure 3

// Three rhombi of a hexagon, each shrunk towards its centre so that gaps
// separate them and their corners near the hexagon's centre form a small
// triangle: the junction. Patch k has side `minus` (towards hexagon vertex
// 2k) and `plus` (towards 2k + 2), both starting at its inner corner.
struct ThreePatches {
  Mesh mesh;
  std::array<std::vector<int>, 3> minus, plus;
  std::size_t outerBorder = 0;
};

ThreePatches threePatches(const std::array<int, 3>& n) {
  ThreePatches t;
  auto hex = [](int k) { return Point3(std::cos(M_PI * k / 3), std::sin(M_PI * k / 3), 0); };
  int offset = 0;
  for (int k = 0; k < 3; ++k) {
    const Point3 u = hex(2 * k), v = hex(2 * k + 2), centre = (u + v) / 2;
    const Mesh patch = sheet(n[k], n[k], [&](int i, int j) {
      const Point3 p = u * (double(i) / n[k]) + v * (double(j) / n[k]);
      return centre + (p - centre) * 0.94;
    });
    t.minus[k] = row(n[k], 0, offset);
    t.plus[k] = column(n[k], n[k], 0, offset);
    t.outerBorder += 2 * n[k];
    t.mesh = k == 0 ? patch : appended(t.mesh, patch);
    offset += int(patch.vert.size());
  }
  return t;
}

TEST(StitchFigure3, JunctionOfThreePatchesIsCovered) {
  ThreePatches t = threePatches({9, 7, 11});
  const std::size_t vertices = t.mesh.vert.size();
  // Patch 2 faces both others with one path through its inner corner.
  std::vector<int> third = reversed(t.plus[2]);
  third.insert(third.end(), t.minus[2].begin() + 1, t.minus[2].end());
  StitchSequenceOptions o;
  o.paths = {{t.plus[0]}, {t.minus[1]}, {t.minus[0]}, {t.plus[1]}, {third}};
  o.pairs = {{0, 1}, {2, 4}};
  const StitchSequenceResult r = stitchPathsSequence(t.mesh, o);
  ASSERT_EQ(r.steps.size(), 2u);
  ASSERT_EQ(r.concatenated[0].size(), 1u);  // paths 2 and 3 joined at the junction
  EXPECT_EQ(r.concatenated[0][0], (std::array<int, 2>{2, 3}));
  // Only the hexagon's outline is left open: its three patch sides and the
  // three gap ends.
  EXPECT_EQ(r.border_edges_after, t.outerBorder + 3);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectClean(t.mesh, t.outerBorder + 3, vertices);
}

TEST(StitchFigure3, SeparateStitchesLeaveTheJunctionOpen) {
  // Figure 3b: the three pairs stitched on their own miss the junction face.
  ThreePatches t = threePatches({9, 7, 11});
  StitchSequenceOptions o;
  o.paths = {{t.plus[0]}, {t.minus[1]}, {t.plus[1]}, {t.minus[2]}, {t.plus[2]}, {t.minus[0]}};
  o.pairs = {{0, 1}, {2, 3}, {4, 5}};
  o.concatenate = false;
  const StitchSequenceResult r = stitchPathsSequence(t.mesh, o);
  EXPECT_EQ(r.border_edges_after, t.outerBorder + 3 + 3);  // the junction triangle is a hole
  const EdgeStats s = edgeStats(t.mesh);
  EXPECT_EQ(s.nonManifold, 0u);
  EXPECT_EQ(s.inconsistent, 0u);
}

// ---------------------------------------------------------------- loops

TEST(StitchLoops, TwoTubeEndsOfDifferentDensity) {
  const Mesh A = openTube(24, 6, 1, 1);
  const Mesh B = moved(openTube(17, 5, 1.1, 1), {0, 0, 1.3});
  Mesh m = appended(A, B);
  const std::size_t vertices = m.vert.size();
  StitchOptions o;
  for (int i = 0; i < 24; ++i) o.a.vertices.push_back(6 * 24 + (i + 5) % 24);   // top of A
  for (int i = 0; i < 17; ++i) o.b.vertices.push_back(int(A.vert.size()) + i);  // bottom of B
  const StitchResult r = stitchPaths(m, o);
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(r.faces_added, 24u + 17u);
  EXPECT_EQ(r.border_edges_after, 24u + 17u);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectClean(m, 24 + 17, vertices);
}

// ---------------------------------------------------------------- bad input

TEST(StitchErrors, PathOnInteriorVertex) {
  TwoSheets s = smoothSheets(10, 8, 0.1);
  StitchOptions o;
  o.a.vertices = row(10, 1);  // the second row of sheet a: interior
  o.b.vertices = s.b;
  const Mesh before = s.mesh;
  const std::string msg = messageOf([&] { stitchPaths(s.mesh, o); });
  EXPECT_NE(msg.find("vertex 12 "), std::string::npos) << msg;
  EXPECT_NE(msg.find("not on a border"), std::string::npos) << msg;
  EXPECT_THROW(stitchPaths(s.mesh, o), InvalidInputError);
  EXPECT_EQ(trianglesOf(s.mesh), trianglesOf(before));
}

TEST(StitchErrors, OppositelyOrientedSides) {
  const int na = 10, nb = 8;
  const Mesh A = sheet(na, 2, [&](int i, int j) { return Point3(1.0 * i / na, 0.1 + 0.1 * j, 0); });
  const Mesh B =
      flipped(sheet(nb, 2, [&](int i, int j) { return Point3(1.0 * i / nb, -0.2 + 0.1 * j, 0); }));
  Mesh m = appended(A, B);
  StitchOptions o;
  o.a.vertices = row(na, 0);
  o.b.vertices = row(nb, 2, int(A.vert.size()));
  const std::string msg = messageOf([&] { stitchPaths(m, o); });
  EXPECT_NE(msg.find("oppositely oriented"), std::string::npos) << msg;
  EXPECT_THROW(stitchPaths(m, o), TopologyError);
  o.allow_orientation_conflict = true;
  const StitchResult r = stitchPaths(m, o);
  EXPECT_GT(r.orientation_conflicts, 0u);
}

TEST(StitchErrors, EmptyMeshAndNaN) {
  Mesh empty;
  StitchOptions o;
  o.a.vertices = {0, 1};
  o.b.vertices = {2, 3};
  EXPECT_THROW(stitchPaths(empty, o), InvalidInputError);
  TrimOptions t;
  t.loop = {0, 1, 2};
  EXPECT_THROW(trimAlongLoop(empty, t), InvalidInputError);
  EXPECT_THROW(closeGaps(empty), InvalidInputError);
  TwoSheets s = smoothSheets(10, 8, 0.1);
  s.mesh.vert[3].P()[1] = std::numeric_limits<double>::quiet_NaN();
  o.a.vertices = s.a;
  o.b.vertices = s.b;
  EXPECT_THROW(stitchPaths(s.mesh, o), InvalidInputError);
  EXPECT_THROW(closeGaps(s.mesh), InvalidInputError);
}

TEST(StitchErrors, VertexOutOfRangeOrRepeated) {
  TwoSheets s = smoothSheets(10, 8, 0.1);
  StitchOptions o;
  o.a.vertices = s.a;
  o.b.vertices = {1 << 20, 5};
  EXPECT_THROW(stitchPaths(s.mesh, o), InvalidInputError);
  o.b.vertices = s.a;  // both paths the same
  EXPECT_THROW(stitchPaths(s.mesh, o), InvalidInputError);
}

// ---------------------------------------------------------------- trimming

TEST(Trim, EquatorByListKeepsTheLeftSide) {
  const int rings = 8, segments = 12;
  Mesh m = uvSphere(rings, segments);
  const std::size_t faces = m.face.size();
  TrimOptions o;
  for (int j = 0; j < segments; ++j) o.loop.push_back(1 + (rings / 2 - 1) * segments + j);
  const TrimResult r = trimAlongLoop(m, o);
  // Running east along the equator, the north is on the left seen from outside.
  EXPECT_EQ(r.faces_kept + r.faces_removed, faces);
  EXPECT_EQ(r.faces_kept, faces / 2);
  EXPECT_EQ(r.border_edges_before, 0u);
  EXPECT_EQ(r.border_edges_after, std::size_t(segments));
  for (const Triangle& t : trianglesOf(m)) {
    const std::vector<Point3> P = positionsOf(m);
    EXPECT_GT((P[t[0]] + P[t[1]] + P[t[2]])[2], 0);
  }
  for (const Triangle& t : trianglesOf(r.removed)) {
    const std::vector<Point3> P = positionsOf(r.removed);
    EXPECT_LT((P[t[0]] + P[t[1]] + P[t[2]])[2], 0);
  }
  EXPECT_EQ(edgeStats(r.removed).border, std::size_t(segments));
  // No vertex is new: the loop is in both halves.
  EXPECT_EQ(m.vert.size() + r.removed.vert.size(),
            positionsOf(uvSphere(rings, segments)).size() + std::size_t(segments));
  // Provenance: kept faces name their input faces.
  FaceOriginHandle fo = faceOrigins(m);
  for (std::size_t f = 0; f < m.face.size(); ++f) EXPECT_GE(fo[f].face, 0);
  // Going west keeps the south.
  Mesh south = uvSphere(rings, segments);
  o.loop = reversed(o.loop);
  trimAlongLoop(south, o);
  const std::vector<Point3> P = positionsOf(south);
  for (const Triangle& t : trianglesOf(south)) EXPECT_LT((P[t[0]] + P[t[1]] + P[t[2]])[2], 0);
}

// A 6 x 6 grid (normals +z) and the boundary of the square [1,4]^2 on it,
// counter-clockwise. At two corners of the square a face has all three
// corners on the loop (the grid's diagonals cut those corners).
Mesh flatGrid() {
  return heightGrid(
      6, 6, 1.0, [](double, double) { return 0.0; }, [](double, double) { return true; });
}
int gridAt(int i, int j) {
  return j * 7 + i;
}
std::vector<int> squareLoop() {
  std::vector<int> l;
  for (int i = 1; i < 4; ++i) l.push_back(gridAt(i, 1));
  for (int j = 1; j < 4; ++j) l.push_back(gridAt(4, j));
  for (int i = 4; i > 1; --i) l.push_back(gridAt(i, 4));
  for (int j = 4; j > 1; --j) l.push_back(gridAt(1, j));
  return l;
}

TEST(Trim, FacesWithAllCornersOnTheLoop) {
  Mesh m = flatGrid();
  TrimOptions o;
  o.loop = squareLoop();
  const TrimResult r = trimAlongLoop(m, o);
  EXPECT_EQ(r.faces_on_loop, 2u);
  EXPECT_EQ(r.faces_kept, 18u);  // the 9 squares inside, both corner faces with them
  EXPECT_EQ(r.faces_removed, 72u - 18u);
  EXPECT_EQ(r.border_edges_after, 12u);
  EXPECT_EQ(m.vert.size(), 16u);
  EXPECT_EQ(edgeStats(r.removed).border, 24u + 12u);
  // Clockwise: the outside is kept and the corner faces go.
  Mesh outside = flatGrid();
  o.loop = reversed(o.loop);
  const TrimResult r2 = trimAlongLoop(outside, o);
  EXPECT_EQ(r2.faces_kept, 72u - 18u);
  EXPECT_EQ(r2.faces_on_loop, 2u);
}

TEST(Trim, SelectionWithSharpTurnsAndAKeptFace) {
  Mesh m = flatGrid();
  TrimOptions o;
  o.selected_vertices.assign(m.vert.size(), false);
  for (int v : squareLoop()) o.selected_vertices[v] = true;
  EXPECT_THROW(trimAlongLoop(m, o), InvalidInputError);  // no direction, no face
  o.keep_face = 0;                                       // the corner square at the origin
  const TrimResult r = trimAlongLoop(m, o);
  EXPECT_EQ(r.faces_kept, 72u - 18u);
  EXPECT_EQ(r.loop.size(), 12u);
  Mesh inside = flatGrid();
  o.keep_face = 2 * (2 * 6 + 2);  // a face of the square (2, 2)
  EXPECT_EQ(trimAlongLoop(inside, o).faces_kept, 18u);
}

TEST(Trim, PickedVerticesJoinedByShortestPaths) {
  Mesh m = flatGrid();
  TrimOptions o;
  o.picked_vertices = {gridAt(1, 1), gridAt(4, 1), gridAt(4, 4), gridAt(1, 4)};
  const TrimResult r = trimAlongLoop(m, o);
  EXPECT_EQ(r.loop, squareLoop());
  EXPECT_EQ(r.faces_kept, 18u);
}

TEST(Trim, SelectionThatIsNotALoopNamesTheVertex) {
  Mesh m = flatGrid();
  TrimOptions o;
  o.keep_face = 0;
  o.selected_vertices.assign(m.vert.size(), false);
  for (int i = 1; i <= 4; ++i) o.selected_vertices[gridAt(i, 1)] = true;  // an open path
  std::string msg = messageOf([&] { trimAlongLoop(m, o); });
  EXPECT_NE(msg.find("the path ends at vertex 8 (1, 1, 0)"), std::string::npos) << msg;
  // A branch.
  for (int v : squareLoop()) o.selected_vertices[v] = true;
  o.selected_vertices[gridAt(5, 2)] = true;
  msg = messageOf([&] { trimAlongLoop(m, o); });
  EXPECT_NE(msg.find("vertex 10 (3, 1, 0) has 3 selected neighbours"), std::string::npos) << msg;
  EXPECT_THROW(trimAlongLoop(m, o), InvalidInputError);
  // A list whose neighbours share no edge.
  TrimOptions l;
  l.loop = {gridAt(1, 1), gridAt(3, 1), gridAt(3, 3)};
  msg = messageOf([&] { trimAlongLoop(m, l); });
  EXPECT_NE(msg.find("share no edge"), std::string::npos) << msg;
  EXPECT_EQ(m.face.size(), 72u);  // unchanged
}

TEST(Trim, LoopThatDoesNotSeparate) {
  const int nu = 16, nv = 8;
  Mesh m = torus(nu, nv);
  TrimOptions o;
  for (int j = 0; j < nv; ++j) o.loop.push_back(j * nu);  // around the tube: a meridian
  const std::string msg = messageOf([&] { trimAlongLoop(m, o); });
  EXPECT_NE(msg.find("does not separate"), std::string::npos) << msg;
  EXPECT_THROW(trimAlongLoop(m, o), TopologyError);
  o.keep_face = 5;
  EXPECT_THROW(trimAlongLoop(m, o), TopologyError);
  EXPECT_EQ(m.face.size(), std::size_t(2 * nu * nv));
}

TEST(Trim, ThenStitchBack) {
  // Trim a sphere at the equator, then stitch the two halves back.
  Mesh north = uvSphere(8, 12);
  TrimOptions o;
  for (int j = 0; j < 12; ++j) o.loop.push_back(1 + 3 * 12 + j);
  TrimResult r = trimAlongLoop(north, o);
  Mesh south = moved(r.removed, {0, 0, -0.2});
  Mesh m = appended(north, south);
  const std::vector<bool> all(m.vert.size(), true);
  const std::vector<BorderPath> paths = borderPathsFromSelection(m, all);
  ASSERT_EQ(paths.size(), 2u);
  EXPECT_EQ(paths[0].shape, BorderPath::Shape::Closed);
  StitchOptions so;
  so.a = paths[0];
  so.b = paths[1];
  const StitchResult sr = stitchPaths(m, so);
  EXPECT_TRUE(sr.closed);
  EXPECT_EQ(sr.faces_added, 24u);
  expectClean(m, 0, m.vert.size());
}

// ---------------------------------------------------------------- close gaps

// The two halves of a grid cube cut at z = 1/2, as separate meshes (the
// seam's vertices duplicated), the upper one lifted by `lift`.
Mesh openBoxHalves(int n, double lift) {
  const Mesh cube = gridCube(n);
  const std::vector<Point3> P = positionsOf(cube);
  std::vector<Triangle> lower, upper;
  for (const Triangle& t : trianglesOf(cube))
    ((P[t[0]] + P[t[1]] + P[t[2]])[2] < 1.5 ? lower : upper).push_back(t);
  auto compact = [&](const std::vector<Triangle>& tris) {
    std::vector<int> index(P.size(), -1);
    std::vector<Point3> points;
    std::vector<Triangle> out = tris;
    for (Triangle& t : out)
      for (int& v : t) {
        if (index[v] < 0) {
          index[v] = int(points.size());
          points.push_back(P[v]);
        }
        v = index[v];
      }
    return makeMesh(points, out);
  };
  return appended(compact(lower), moved(compact(upper), {0, 0, lift}));
}

TEST(CloseGaps, CoincidentDuplicatedBorderVertices) {
  const int n = 4;
  Mesh m = openBoxHalves(n, 0);
  const CloseGapsResult r = closeGaps(m);
  EXPECT_EQ(r.border_edges_before, 2u * 4 * n);
  EXPECT_EQ(r.vertices_merged, 4u * n);
  EXPECT_EQ(r.edges_merged, 4u * n);
  EXPECT_EQ(r.merges_skipped, 0u);
  EXPECT_EQ(r.faces_added, 0u);
  EXPECT_EQ(r.border_edges_after, 0u);
  expectClean(m, 0, 6u * n * n + 2);
}

TEST(CloseGaps, NearlyCoincidentWithinTolerance) {
  Mesh m = openBoxHalves(4, 1e-7);
  CloseGapsOptions o;
  o.max_gap = 0;
  EXPECT_EQ(closeGaps(m, o).vertices_merged, 0u);  // exact coincidence only
  o.merge_tolerance = 1e-6;
  const CloseGapsResult r = closeGaps(m, o);
  EXPECT_EQ(r.vertices_merged, 16u);
  EXPECT_EQ(r.border_edges_after, 0u);
}

TEST(CloseGaps, SmallGapBetweenBoxHalvesIsStitched) {
  const int n = 4;
  Mesh m = openBoxHalves(n, 0.02);
  const std::size_t vertices = m.vert.size();
  CloseGapsOptions o;
  o.max_gap = 0.02;  // of the bounding box diagonal (about 1.75)
  const CloseGapsResult r = closeGaps(m, o);
  EXPECT_EQ(r.vertices_merged, 0u);
  ASSERT_EQ(r.gaps_found, 1u);
  EXPECT_TRUE(r.gaps[0].closed);
  EXPECT_TRUE(r.gaps[0].stitched) << r.gaps[0].reason;
  EXPECT_EQ(r.faces_added, 8u * n);
  EXPECT_EQ(r.border_edges_after, 0u);
  expectClean(m, 0, vertices);
  // A bound below the gap leaves it open.
  Mesh far = openBoxHalves(n, 0.02);
  o.max_gap = 0.005;
  EXPECT_EQ(closeGaps(far, o).border_edges_after, 2u * 4 * n);
}

TEST(CloseGaps, FacingSidesOfTwoPlates) {
  // Two plates side by side: only their facing sides are stitched.
  const Mesh A = sheet(10, 5, [](int i, int j) { return Point3(0.1 * i, 0.1 * j, 0); });
  const Mesh B = sheet(7, 5, [](int i, int j) { return Point3(1.03 + 0.1 * i, 0.1 * j, 0); });
  Mesh m = appended(A, B);
  CloseGapsOptions o;
  o.max_gap = 0.04;
  o.absolute_distances = true;
  const CloseGapsResult r = closeGaps(m, o);
  EXPECT_EQ(r.gaps_stitched, 1u);
  EXPECT_EQ(r.faces_added, 10u);
  expectClean(m, 2 * 15 + 2 * 12 - 10 + 2, m.vert.size());
  EXPECT_EQ(r.border_edges_after, 2u * 15 + 2 * 12 - 10 + 2);
}

// Every face with its own three vertices, as an STL file stores it; the
// faces for which flip(face) holds are turned over.
Mesh soupOf(
    const Mesh& m, const std::function<bool(int)>& flip = [](int) { return false; }) {
  const std::vector<Point3> P = positionsOf(m);
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  const std::vector<Triangle> T = trianglesOf(m);
  for (std::size_t f = 0; f < T.size(); ++f) {
    const int first = int(points.size());
    for (int v : T[f]) points.push_back(P[v]);
    triangles.push_back(flip(int(f)) ? Triangle{first, first + 2, first + 1}
                                     : Triangle{first, first + 1, first + 2});
  }
  return makeMesh(points, triangles);
}

TEST(CloseGaps, SoupWithFacetsAgainstTheirNeighboursIsOrientedOutwardAndClosed) {
  const int n = 3;
  const Mesh cube = gridCube(n);
  auto everyThird = [](int f) { return f % 3 == 0; };
  Mesh m = soupOf(cube, everyThird);
  const std::size_t flippedInInput = (cube.face.size() + 2) / 3;
  const CloseGapsResult r = closeGaps(m);
  EXPECT_EQ(r.faces_flipped, flippedInInput);  // the minority, back
  EXPECT_EQ(r.orientation_conflicts, 0u);
  EXPECT_EQ(r.border_edges_after, 0u);
  expectClean(m, 0, cube.vert.size());
  EXPECT_NEAR(volumeOf(m), 1.0, 1e-12);  // outward
  // Mostly inward facets: the closed part is still turned outward.
  Mesh inward = soupOf(cube, [](int f) { return f % 3 != 0; });
  const CloseGapsResult ri = closeGaps(inward);
  EXPECT_EQ(ri.faces_flipped, cube.face.size() - flippedInInput);
  EXPECT_NEAR(volumeOf(inward), 1.0, 1e-12);
  // Without orienting, the edges between facets that disagree stay open.
  Mesh kept = soupOf(cube, everyThird);
  CloseGapsOptions o;
  o.orient_faces = false;
  const CloseGapsResult rk = closeGaps(kept, o);
  EXPECT_EQ(rk.faces_flipped, 0u);
  EXPECT_GT(rk.border_edges_after, 0u);
  EXPECT_EQ(edgeStats(kept).nonManifold, 0u);
  EXPECT_EQ(edgeStats(kept).inconsistent, 0u);
  EXPECT_EQ(rk.border_edges_after, edgeStats(kept).border);
}

TEST(CloseGaps, OpenSheetKeepsTheOrientationOfMostOfItsArea) {
  const Mesh s = sheet(4, 3, [](int i, int j) { return Point3(i, j, 0.1 * i * j); });
  Mesh m = soupOf(s, [](int f) { return f == 5 || f == 10; });
  const CloseGapsResult r = closeGaps(m);
  EXPECT_EQ(r.faces_flipped, 2u);
  expectClean(m, 2 * (4 + 3), s.vert.size());
  // Every face runs its corners the way the sheet's faces do (normals up).
  for (const Face& f : m.face) {
    const Point3 normal = (f.cV(1)->cP() - f.cV(0)->cP()) ^ (f.cV(2)->cP() - f.cV(0)->cP());
    EXPECT_GT(normal[2], 0);
  }
}

TEST(CloseGaps, SolidsTouchingAlongAnEdgeCloseSeparately) {
  // Two unit cubes sharing only the edge x = y = 1: four facets meet there.
  const Mesh a = gridCube(2), b = moved(gridCube(2), {1, 1, 0});
  Mesh m = soupOf(appended(a, b), [](int f) { return f % 2 == 1; });
  const CloseGapsResult r = closeGaps(m);
  EXPECT_EQ(r.border_edges_after, 0u);
  const EdgeStats s = edgeStats(m);
  EXPECT_EQ(s.border, 0u);
  EXPECT_EQ(s.nonManifold, 0u);
  EXPECT_EQ(s.inconsistent, 0u);
  // The vertices of the shared edge stay apart (one copy per cube).
  EXPECT_EQ(m.vert.size(), a.vert.size() + b.vert.size());
  EXPECT_NEAR(volumeOf(m), 2.0, 1e-12);
  // The cubes touch along the edge without sharing a vertex there: those
  // pairs count, and the count is the whole output's (every face merged).
  ASSERT_TRUE(r.verified);
  EXPECT_GT(r.new_intersecting_pairs, 0u);
  EXPECT_EQ(r.new_intersecting_pairs, selfIntersectingPairs(m));
}

TEST(CloseGaps, BorderEdgeOfZeroLengthCollapsesItsFace) {
  // CGAL's deg_border case: a fan above the x axis whose border repeats the
  // point (2, 0) (a face of zero area on it), a fan below without it.
  const std::vector<Point3> P{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 0, 0}, {3, 0, 0}, {1, 1, 0},
                              {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {1, -1, 0}};
  const std::vector<Triangle> T{{0, 1, 5},  {1, 2, 5},  {2, 3, 5}, {3, 4, 5},
                                {7, 6, 10}, {8, 7, 10}, {9, 8, 10}};
  Mesh m = makeMesh(P, T);
  const CloseGapsResult r = closeGaps(m);
  EXPECT_EQ(r.border_edges_before, 11u);
  EXPECT_EQ(r.degenerate_faces_removed, 1u);
  EXPECT_EQ(r.edges_merged, 3u);
  EXPECT_EQ(r.border_edges_after, 4u);  // the two fans' outer sides
  EXPECT_EQ(m.face.size(), 6u);
  EXPECT_EQ(edgeStats(m).border, 4u);
  EXPECT_EQ(edgeStats(m).nonManifold, 0u);
  EXPECT_EQ(edgeStats(m).inconsistent, 0u);
  // Without the collapse (the repeated point apart), CGAL's count remains.
  std::vector<Point3> apart = P;
  apart[3] = {2.5, 0, 0};
  Mesh n = makeMesh(apart, T);
  CloseGapsOptions o;
  o.max_gap = 0;
  EXPECT_EQ(closeGaps(n, o).degenerate_faces_removed, 0u);
}

TEST(CloseGaps, CrackInsideOneBorderIsClosed) {
  // A 6 x 4 grid whose faces above y = 2 no longer share the vertices
  // (2..4, 2) with the faces below: their own copies are 0.01 higher. The
  // crack between x = 1 and x = 5 is one border loop whose two sides face
  // each other, with its tips at (1, 2) and (5, 2).
  const int nu = 6, nv = 4;
  Mesh grid = sheet(nu, nv, [](int i, int j) { return Point3(i, j, 0); });
  std::vector<Point3> P = positionsOf(grid);
  std::vector<Triangle> T = trianglesOf(grid);
  std::map<int, int> upper;  // crack vertex (i, 2), 1 < i < 5 -> its upper copy
  for (int i = 2; i <= 4; ++i) {
    const int v = 2 * (nu + 1) + i;
    upper[v] = int(P.size());
    P.push_back(P[v] + Point3(0, 0.01, 0));
  }
  for (Triangle& t : T) {
    double y = 0;
    for (int v : t) y += P[v][1];
    if (y / 3 > 2)
      for (int& v : t)
        if (upper.count(v)) v = upper[v];
  }
  Mesh m = makeMesh(P, T);
  ASSERT_EQ(edgeStats(m).border, 2u * (nu + nv) + 2 * 4);
  CloseGapsOptions o;
  o.absolute_distances = true;
  o.max_gap = 0.05;
  const CloseGapsResult r = closeGaps(m, o);
  ASSERT_EQ(r.gaps_found, 1u);
  EXPECT_TRUE(r.gaps[0].stitched) << r.gaps[0].reason;
  // Sides of four edges sharing both tips: four faces on one side, two on
  // the other, whose end edges close the strip at the tips.
  EXPECT_EQ(r.faces_added, 6u);
  expectClean(m, 2u * (nu + nv), P.size());
  // A bound below the crack's width leaves it, when it is the only bound;
  // the crack is far narrower than its edges, so the local one closes it.
  Mesh wide = makeMesh(P, T);
  o.max_gap = 0.005;
  o.local_gap_factor = 0;
  EXPECT_EQ(closeGaps(wide, o).faces_added, 0u);
  Mesh local = makeMesh(P, T);
  o.local_gap_factor = 1.5;
  EXPECT_EQ(closeGaps(local, o).faces_added, 6u);
  expectClean(local, 2u * (nu + nv), P.size());
}

// A sheet of unit edges with a slit one edge wide: the faces of column 3,
// rows 1 to 3, are missing.
Mesh slitSheet(int nu, int nv) {
  Mesh full = sheet(nu, nv, [](int i, int j) { return Point3(i, j, 0); });
  std::vector<Triangle> T;
  for (const Triangle& t : trianglesOf(full)) {
    const int i = std::min({t[0], t[1], t[2]}) % (nu + 1), j = t[0] / (nu + 1);
    if (!(i == 3 && j >= 1 && j <= 3)) T.push_back(t);
  }
  return makeMesh(positionsOf(full), T);
}

TEST(CloseGaps, SlitOneEdgeWideIsClosedByDefault) {
  const int nu = 8, nv = 6;
  Mesh m = slitSheet(nu, nv);
  const std::size_t vertices = m.vert.size();
  ASSERT_EQ(edgeStats(m).border, 2u * (nu + nv) + 8);
  // The default max_gap (1 % of the diagonal, 0.1) is a tenth of the slit's
  // width; its sides are as far apart as their edges are long.
  const CloseGapsResult r = closeGaps(m);
  EXPECT_LT(r.max_gap, 0.2);
  ASSERT_EQ(r.gaps_stitched, 1u);
  EXPECT_EQ(r.faces_added, 6u);
  EXPECT_EQ(r.border_edges_after, 2u * (nu + nv));
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectClean(m, 2u * (nu + nv), vertices);
  // With the diagonal's fraction alone it stays open.
  Mesh open = slitSheet(nu, nv);
  CloseGapsOptions o;
  o.local_gap_factor = 0;
  EXPECT_EQ(closeGaps(open, o).faces_added, 0u);
  EXPECT_EQ(edgeStats(open).border, 2u * (nu + nv) + 8);
}

TEST(CloseGaps, SeparatePartsAreStitchedWithinMaxGapOnly) {
  // Two sheets of unit edges facing each other across `gap`: separate
  // parts, so the local bound (1.5 edges) does not join them, whether the
  // gap is within it or beyond it; max_gap does.
  auto twoSheets = [](double gap) {
    const Mesh a = sheet(6, 2, [](int i, int j) { return Point3(i, j, 0); });
    const Mesh b = sheet(6, 2, [&](int i, int j) { return Point3(i, 2 + gap + j, 0); });
    return appended(a, b);
  };
  for (const double gap : {1.0, 2.0}) {
    Mesh m = twoSheets(gap);
    const std::size_t border = edgeStats(m).border;
    CloseGapsOptions o;
    o.absolute_distances = true;
    o.max_gap = 0.5 * gap;
    const CloseGapsResult r = closeGaps(m, o);
    EXPECT_EQ(r.gaps_found, 0u) << "gap " << gap;
    EXPECT_EQ(r.faces_added, 0u) << "gap " << gap;
    EXPECT_EQ(edgeStats(m).border, border) << "gap " << gap;
    Mesh joined = twoSheets(gap);
    o.max_gap = 1.01 * gap;
    EXPECT_EQ(closeGaps(joined, o).faces_added, 12u) << "gap " << gap;
    expectClean(joined, border - 12 + 2, m.vert.size());
  }
}

TEST(CloseGaps, DistancesAreFractionsOfTheDiagonalUnlessAbsolute) {
  Mesh m = openBoxHalves(4, 1e-3);
  vcg::Box3d box;
  for (const Point3& p : positionsOf(m)) box.Add(p);
  CloseGapsOptions o;
  o.max_gap = 0;
  o.merge_tolerance = 1e-3;  // of the diagonal (about 1.73): more than the lift
  const CloseGapsResult r = closeGaps(m, o);
  EXPECT_DOUBLE_EQ(r.merge_tolerance, 1e-3 * box.Diag());
  EXPECT_EQ(r.vertices_merged, 16u);
  EXPECT_EQ(r.border_edges_after, 0u);
  Mesh apart = openBoxHalves(4, 1e-3);
  o.absolute_distances = true;
  o.merge_tolerance = 0.9e-3;  // less than the lift
  const CloseGapsResult ra = closeGaps(apart, o);
  EXPECT_DOUBLE_EQ(ra.merge_tolerance, 0.9e-3);
  EXPECT_EQ(ra.vertices_merged, 0u);
  EXPECT_EQ(ra.border_edges_after, 2u * 4 * 4);
}

TEST(CloseGaps, VerifyCountsThePairsOfMergedAndStitchedFaces) {
  Mesh m = openBoxHalves(4, 0.02);
  CloseGapsOptions o;
  o.max_gap = 0.02;
  const CloseGapsResult r = closeGaps(m, o);
  ASSERT_EQ(r.gaps_stitched, 1u);
  EXPECT_TRUE(r.verified);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  EXPECT_EQ(selfIntersectingPairs(m), 0u);
  EXPECT_NE(toJson(r).str().find("new_intersecting_pairs"), std::string::npos);
  // A small triangle across the gap, through the wall y = 0: the checked
  // stitch leaves the gap open; unchecked, the verification finds the pairs
  // the stitch made (the only ones: the triangle touches nothing else).
  const Mesh across =
      makeMesh({{0.6, -0.03, 0.505}, {0.6, 0.03, 0.505}, {0.6, 0, 0.515}}, {{0, 1, 2}});
  Mesh checked = appended(openBoxHalves(4, 0.02), across);
  EXPECT_EQ(closeGaps(checked, o).gaps_stitched, 0u);
  EXPECT_EQ(selfIntersectingPairs(checked), 0u);
  Mesh crossed = appended(openBoxHalves(4, 0.02), across);
  o.check_intersections = false;
  const CloseGapsResult rc = closeGaps(crossed, o);
  ASSERT_GE(rc.gaps_stitched, 1u);
  EXPECT_GT(rc.new_intersecting_pairs, 0u);
  EXPECT_EQ(rc.new_intersecting_pairs, selfIntersectingPairs(crossed));
  o.verify = false;
  Mesh unverified = openBoxHalves(4, 0.02);
  const CloseGapsResult ru = closeGaps(unverified, o);
  EXPECT_FALSE(ru.verified);
  EXPECT_EQ(toJson(ru).str().find("new_intersecting_pairs"), std::string::npos);
}

TEST(Reports, JsonKeys) {
  TwoSheets s = smoothSheets(10, 8, 0.1);
  StitchOptions o;
  o.a.vertices = s.a;
  o.b.vertices = s.b;
  const std::string j = toJson(stitchPaths(s.mesh, o)).str();
  for (const char* key :
       {"border_edges_before", "border_edges_after", "faces_added", "vertices_merged", "time_ms"})
    EXPECT_NE(j.find(key), std::string::npos) << key;
  Mesh box = openBoxHalves(3, 0);
  const std::string c = toJson(closeGaps(box)).str();
  for (const char* key :
       {"border_edges_before", "border_edges_after", "faces_added", "vertices_merged", "time_ms"})
    EXPECT_NE(c.find(key), std::string::npos) << key;
  Mesh g = flatGrid();
  TrimOptions t;
  t.loop = squareLoop();
  const std::string tj = toJson(trimAlongLoop(g, t)).str();
  EXPECT_NE(tj.find("\"vertices_merged\": 0"), std::string::npos) << tj;
}

}  // namespace
