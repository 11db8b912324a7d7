#include "common/repair/holes/holes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "tests/mesh_builders.h"

using namespace meshmend;
using namespace meshmend::testing;

namespace {

// Largest distance of the new vertices from the sphere of radius r around the origin.
double maxSphereDeviation(const Mesh& mesh, const HoleFillResult& r, double radius = 1) {
  double worst = 0;
  const std::vector<Point3> P = positionsOf(mesh);
  for (int v : r.new_vertices) worst = std::max(worst, std::abs(P[v].Norm() - radius));
  return worst;
}

// Smallest angle (degrees) of the new faces.
double smallestNewAngle(const Mesh& mesh, const HoleFillResult& r) {
  const std::vector<Point3> P = positionsOf(mesh);
  const std::vector<Triangle> T = trianglesOf(mesh);
  double worst = 180;
  for (int f : r.new_faces)
    worst = std::min(worst, smallestAngle(P[T[f][0]], P[T[f][1]], P[T[f][2]]) * 180 / M_PI);
  return worst;
}

// Checks every property a filled mesh must have: the border edges expected,
// edge-manifold, consistently oriented, and no intersecting pair at all
// (the input meshes are free of them), by the exact count.
void expectSound(const Mesh& mesh, std::size_t borderEdges) {
  const EdgeStats s = edgeStats(mesh);
  EXPECT_EQ(s.border, borderEdges);
  EXPECT_EQ(s.nonManifold, 0u);
  EXPECT_EQ(s.inconsistent, 0u);
  EXPECT_EQ(selfIntersectingPairs(mesh), 0u);
}

// Options with one shape, and the whole-mesh count on (verify).
HoleFillOptions withFairing(HoleFairing fairing) {
  HoleFillOptions o;
  o.fairing = fairing;
  o.verify = true;
  return o;
}

Mesh plane(int n, double cell = 1) {
  return heightGrid(
      n, n, cell, [](double, double) { return 0.0; }, [](double, double) { return true; });
}

// The unit sphere (icosphere, 5120 faces) with the cap above z = 0.75 removed.
Mesh sphereWithCap(double z = 0.75) {
  return withHole(icosphere(4), [&](const Point3& c) { return c[2] > z; });
}

}  // namespace

// ---- Border loops ------------------------------------------------------------------

TEST(HoleLoops, CountsHolesAndTheOuterBorder) {
  // A 12 x 12 plane with two square holes: three border loops.
  Mesh m = heightGrid(
      12, 12, 1, [](double, double) { return 0.0; },
      [](double x, double y) {
        const bool first = x > 2 && x < 5 && y > 2 && y < 5;
        const bool second = x > 7 && x < 9 && y > 7 && y < 10;
        return !first && !second;
      });
  HoleFillOptions o;
  o.max_boundary_edges = 20;
  const HoleFillResult r = fillHoles(m, o);
  EXPECT_EQ(r.holes_found, 3u);
  EXPECT_EQ(r.holes_filled, 2u);
  EXPECT_EQ(r.holes_skipped, 1u);
  std::multiset<std::size_t> sizes;
  for (const HoleReport& h : r.holes) sizes.insert(h.boundary_edges);
  EXPECT_EQ(sizes, (std::multiset<std::size_t>{10, 12, 48}));
  expectSound(m, 48);
}

TEST(HoleLoops, TwoHolesTouchingAtABowTieVertexAreTwoLoops) {
  // Squares (2,2) and (3,3) removed: they meet at the vertex (3,3), whose
  // faces form two fans. The border through it is cut into the two holes.
  Mesh m = heightGrid(
      6, 6, 1, [](double, double) { return 0.0; },
      [](double x, double y) {
        const bool a = x > 2 && x < 3 && y > 2 && y < 3;
        const bool b = x > 3 && x < 4 && y > 3 && y < 4;
        return !a && !b;
      });
  HoleFillOptions o;
  o.max_boundary_edges = 8;
  const HoleFillResult r = fillHoles(m, o);
  EXPECT_EQ(r.holes_found, 3u);
  EXPECT_EQ(r.holes_filled, 2u);
  for (const HoleReport& h : r.holes) {
    if (h.filled) {
      EXPECT_EQ(h.boundary_edges, 4u);
    }
  }
  // The bow-tie vertex is now inside one closed fan: only the outer border is left.
  expectSound(m, 24);
}

TEST(HoleLoops, BorderPassingAVertexTwiceIsSplitThere) {
  // Two triangles sharing one vertex: the border of the region around them
  // passes that vertex twice and is cut into two loops of three edges. Each
  // would be filled by a copy of its triangle, which the exact check refuses.
  Mesh m =
      makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}}, {{0, 1, 2}, {0, 3, 4}});
  const HoleFillResult r = fillHoles(m);
  EXPECT_EQ(r.holes_found, 2u);
  EXPECT_EQ(r.holes_filled, 0u);
  EXPECT_EQ(r.holes_skipped, 2u);
  for (const HoleReport& h : r.holes) {
    EXPECT_EQ(h.boundary_edges, 3u);
    EXPECT_NE(h.reason.find("intersect"), std::string::npos) << h.reason;
  }
  EXPECT_EQ(m.fn, 2);
  EXPECT_EQ(m.vn, 5);
}

TEST(HoleLoops, OpenBorderIsReportedNotFilled) {
  // Two faces running their shared edge the same way: the border stops at
  // the ends of that edge.
  Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, {{0, 1, 2}, {1, 2, 3}});
  const HoleFillResult r = fillHoles(m);
  EXPECT_GE(r.holes_found, 1u);
  EXPECT_EQ(r.holes_filled, 0u);
  bool named = false;
  for (const HoleReport& h : r.holes)
    named |= h.reason.find("not a closed loop") != std::string::npos;
  EXPECT_TRUE(named);
  EXPECT_EQ(m.fn, 2);
}

// ---- Pre-treatment (§3.1) ------------------------------------------------------------

namespace {

// A 6 x 6 plane with the squares inside [1,5]^2 removed, except that the
// hole's top side is one edge of length 4 (its row of faces is a fan).
Mesh longEdgeHole() {
  std::vector<Point3> p;
  for (int j = 0; j <= 6; ++j)
    for (int i = 0; i <= 6; ++i) p.emplace_back(i, j, 0);
  auto at = [](int i, int j) { return j * 7 + i; };
  std::vector<Triangle> t;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i) {
      const bool hole = i >= 1 && i < 5 && j >= 1 && j < 5;
      const bool fanRow = i >= 1 && i < 5 && j == 5;
      if (hole || fanRow) continue;
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  // The fan above the long edge (1,5)-(5,5).
  t.push_back({at(1, 5), at(5, 5), at(3, 6)});
  t.push_back({at(1, 5), at(3, 6), at(2, 6)});
  t.push_back({at(1, 5), at(2, 6), at(1, 6)});
  t.push_back({at(5, 5), at(4, 6), at(3, 6)});
  t.push_back({at(5, 5), at(5, 6), at(4, 6)});
  return makeMesh(p, t);
}

}  // namespace

TEST(HolePretreatment, SplitsLongBorderEdgesAndTheirFaces) {
  Mesh m = longEdgeHole();
  const std::size_t facesBefore = std::size_t(m.fn);
  ASSERT_EQ(edgeStats(m).border, 24u + 13u);

  HoleFillOptions o = withFairing(HoleFairing::Flat);
  o.long_edge_factor = 1.5;
  o.max_boundary_edges = 13;
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_filled, 1u);
  // 4 / (16/13) = 3.25 > 1.5: the edge is halved, then its halves once more
  // (2 > 1.5 x 16/14); the quarters (1 = the other edges) are short enough.
  EXPECT_EQ(r.edges_split, 3u);
  EXPECT_EQ(std::size_t(m.fn), facesBefore + 3 + r.faces_added);
  expectSound(m, 24);

  // The hole's border after splitting = the patch faces' edges shared with
  // the other faces: none longer than 1.5 x their mean.
  const std::vector<Triangle> T = trianglesOf(m);
  const std::vector<Point3> P = positionsOf(m);
  std::set<int> patch(r.new_faces.begin(), r.new_faces.end());
  std::map<std::pair<int, int>, std::vector<int>> faces;
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int k = 0; k < 3; ++k)
      faces[{std::min(T[f][k], T[f][(k + 1) % 3]), std::max(T[f][k], T[f][(k + 1) % 3])}].push_back(
          int(f));
  std::vector<double> lengths;
  for (const auto& [edge, list] : faces)
    if (list.size() == 2 && patch.count(list[0]) != patch.count(list[1]))
      lengths.push_back((P[edge.first] - P[edge.second]).Norm());
  ASSERT_EQ(lengths.size(), 16u);
  double mean = 0;
  for (double l : lengths) mean += l;
  mean /= double(lengths.size());
  for (double l : lengths) EXPECT_LE(l, 1.5 * mean + 1e-12);
  // The split vertices (new vertices of faces outside the patch) lie on the
  // fan's face they split, by provenance; patch vertices name the border
  // vertex whose attributes they take.
  VertexOriginHandle vo = vertexOrigins(m);
  std::set<int> onSurface;
  for (std::size_t f = 0; f < T.size(); ++f)
    if (!patch.count(int(f)))
      for (int v : T[f]) onSurface.insert(v);
  int split = 0;
  for (int v : r.new_vertices) {
    if (onSurface.count(v)) {
      ++split;
      EXPECT_GE(vo[v].face, 0);
      EXPECT_LT(vo[v].vertex, 0);
    } else {
      EXPECT_TRUE(vo[v].vertex >= 0 || vo[v].face >= 0) << "patch vertex " << v;
    }
  }
  EXPECT_EQ(split, 3);
}

TEST(HolePretreatment, FactorZeroLeavesTheBorderAlone) {
  Mesh m = longEdgeHole();
  HoleFillOptions o = withFairing(HoleFairing::Flat);
  o.long_edge_factor = 0;
  o.max_boundary_edges = 13;
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_filled, 1u);
  EXPECT_EQ(r.edges_split, 0u);
  expectSound(m, 24);
}

// ---- Advancing front (§3.2) -----------------------------------------------------------

TEST(HoleFront, PlanarRoundHoleIsCoveredWithGoodTriangles) {
  Mesh m =
      withHole(plane(30, 1), [](const Point3& c) { return (c - Point3(15, 15, 0)).Norm() < 9; });
  const std::size_t border = edgeStats(m).border;
  HoleFillOptions o = withFairing(HoleFairing::Flat);
  o.max_diameter = 0.5;  // not the outer border
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 2u);
  ASSERT_EQ(r.holes_filled, 1u);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectSound(m, 120);
  EXPECT_GT(border, 120u);
  const std::vector<Point3> P = positionsOf(m);
  for (int v : r.new_vertices) EXPECT_NEAR(P[v][2], 0, 1e-12);
  EXPECT_GT(smallestNewAngle(m, r), 20);
  // Triangles grade from the border's size (about 1) and never exceed the cap.
  const std::vector<Triangle> T = trianglesOf(m);
  double longest = 0;
  for (int f : r.new_faces)
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (P[T[f][k]] - P[T[f][(k + 1) % 3]]).Norm());
  EXPECT_LT(longest, 3 * 1.5 + 1);
  EXPECT_GT(r.faces_added, 100u);
}

TEST(HoleFront, ElongatedHole) {
  // A slot 1.5 wide and 30 long in a plane of half-unit squares.
  Mesh m = withHole(plane(80, 0.5), [](const Point3& c) {
    return c[0] > 5 && c[0] < 35 && c[1] > 19.25 && c[1] < 20.75;
  });
  HoleFillOptions o;
  o.verify = true;
  o.max_boundary_edges = 300;  // not the outer border
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_filled, 1u);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectSound(m, 320);
  EXPECT_GT(smallestNewAngle(m, r), 15);
  // The flat slot stays flat whatever the shape (the plane's Laplacians are 0).
  const std::vector<Point3> P = positionsOf(m);
  for (int v : r.new_vertices) EXPECT_NEAR(P[v][2], 0, 1e-9);
}

TEST(HoleFront, SaddleHoleInEveryMode) {
  auto saddle = [](double x, double y) {
    return 0.05 * ((x - 10) * (x - 10) - (y - 10) * (y - 10));
  };
  for (HoleFairing mode : {HoleFairing::Flat, HoleFairing::Harmonic, HoleFairing::Biharmonic,
                           HoleFairing::LaplacianRegression}) {
    SCOPED_TRACE(toString(mode));
    Mesh m = heightGrid(40, 40, 0.5, saddle,
                        [](double x, double y) { return std::hypot(x - 10, y - 10) > 5; });
    HoleFillOptions o = withFairing(mode);
    o.max_diameter = 0.5;
    const HoleFillResult r = fillHoles(m, o);
    ASSERT_EQ(r.holes_filled, 1u);
    for (const HoleReport& h : r.holes) {
      if (h.filled) {
        EXPECT_EQ(h.fairing, mode) << h.reason;
      }
    }
    EXPECT_EQ(r.new_intersecting_pairs, 0u);
    expectSound(m, 160);
    const std::vector<Point3> P = positionsOf(m);
    double worst = 0;
    for (int v : r.new_vertices)
      worst = std::max(worst, std::abs(P[v][2] - saddle(P[v][0], P[v][1])));
    // The saddle is harmonic: every fairing reproduces it closely; flat does not.
    if (mode == HoleFairing::Flat) {
      EXPECT_GT(worst, 0.1);
    } else {
      EXPECT_LT(worst, 0.02);
    }
    std::cout << toString(mode) << ": saddle max deviation " << worst << "\n";
  }
}

TEST(HoleFront, HoleAcrossASharpCornerInEveryMode) {
  // The border runs over three sides of a cube: far from planar.
  for (HoleFairing mode : {HoleFairing::Flat, HoleFairing::Harmonic, HoleFairing::Biharmonic,
                           HoleFairing::LaplacianRegression}) {
    SCOPED_TRACE(toString(mode));
    Mesh m =
        withHole(gridCube(12), [](const Point3& c) { return (c - Point3(1, 1, 1)).Norm() < 0.35; });
    ASSERT_GT(volumeOf(m), 0.9);
    const HoleFillResult r = fillHoles(m, withFairing(mode));
    ASSERT_EQ(r.holes_filled, 1u) << r.holes[0].reason;
    EXPECT_EQ(r.holes[0].fairing, mode) << r.holes[0].reason;
    expectSound(m, 0);
    // Flat and membrane patches cut the corner off; the others round it.
    EXPECT_GT(volumeOf(m), 0.98);
    EXPECT_LT(volumeOf(m), 1.01);
  }
}

TEST(HoleFront, HoleWrappingATubeIsTriangulatedOverADisk) {
  // A hole three quarters around an open tube: its border projects onto no
  // plane as a simple polygon, so the front runs over a disk.
  Mesh m = withHole(openTube(48, 24, 1, 3), [](const Point3& c) {
    return std::abs(std::atan2(c[1], c[0])) < 2.3 && c[2] > 1 && c[2] < 2;
  });
  const std::size_t ends = 2 * 48;
  HoleFillOptions o;
  o.selected_vertex_indices = {8 * 48};  // on the side hole's lower border (z = 1, angle 0)
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 3u);
  ASSERT_EQ(r.holes_filled, 1u);
  const HoleReport& side =
      *std::find_if(r.holes.begin(), r.holes.end(), [](const HoleReport& h) { return h.filled; });
  EXPECT_FALSE(side.planar_domain);
  expectSound(m, ends);
}

TEST(HoleFront, TriangularHoleGetsOneFace) {
  const Mesh closed = icosphere(2);
  std::vector<Triangle> t = trianglesOf(closed);
  const Triangle removed = t[7];
  t.erase(t.begin() + 7);
  Mesh m = makeMesh(positionsOf(closed), t);
  const HoleFillResult r = fillHoles(m);
  ASSERT_EQ(r.holes_filled, 1u);
  EXPECT_EQ(r.faces_added, 1u);
  EXPECT_EQ(r.vertices_added, 0u);
  expectSound(m, 0);
  const Triangle added = trianglesOf(m).back();
  EXPECT_TRUE(std::is_permutation(added.begin(), added.end(), removed.begin()));
}

// ---- Shape (§3.3, §3.4) -------------------------------------------------------------------

TEST(HoleShape, SphereCapInEveryMode) {
  std::map<HoleFairing, double> deviation;
  for (HoleFairing mode : {HoleFairing::Flat, HoleFairing::Harmonic, HoleFairing::Biharmonic,
                           HoleFairing::LaplacianRegression}) {
    SCOPED_TRACE(toString(mode));
    Mesh m = sphereWithCap();
    const HoleFillResult r = fillHoles(m, withFairing(mode));
    ASSERT_EQ(r.holes_found, 1u);
    ASSERT_EQ(r.holes_filled, 1u);
    EXPECT_EQ(r.holes[0].fairing, mode) << r.holes[0].reason;
    EXPECT_EQ(r.new_intersecting_pairs, 0u);
    expectSound(m, 0);
    EXPECT_GT(volumeOf(m), 0);
    deviation[mode] = maxSphereDeviation(m, r);
    std::cout << toString(mode) << ": max distance to the sphere " << deviation[mode]
              << ", residual " << r.holes[0].fairing_residual << ", faces " << r.faces_added
              << ", samples " << r.holes[0].training_samples << "\n";
  }
  EXPECT_GT(deviation[HoleFairing::Flat], 0.1);
  EXPECT_LT(deviation[HoleFairing::Biharmonic], 0.03);
  EXPECT_LT(deviation[HoleFairing::LaplacianRegression], 0.01);
  EXPECT_LT(deviation[HoleFairing::LaplacianRegression], deviation[HoleFairing::Flat] / 10);
  EXPECT_LT(deviation[HoleFairing::Biharmonic], deviation[HoleFairing::Flat] / 4);
}

// A tube of obtuse slivers (each triangle 0.52 wide and 0.1 high, like a
// CAD export's): the biharmonic patch of a hole in its side continues the
// cylinder. The slivers' cotangent weights are negative; raised to a floor
// they would bend the rows of the border vertices.
TEST(HoleShape, HoleInATubeOfSliversFollowsTheCylinder) {
  Mesh m = withHole(openTube(12, 40, 1, 4),
                    [](const Point3& c) { return (c - Point3(1, 0, 2)).Norm() < 0.9; });
  HoleFillOptions o = withFairing(HoleFairing::Biharmonic);
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 3u);  // the tube's two ends and the hole
  ASSERT_EQ(r.holes_filled, 3u);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectSound(m, 0);
  const std::vector<Point3> P = positionsOf(m);
  double worst = 0;
  std::size_t inSide = 0;
  for (int v : r.new_vertices)
    if (P[v][2] > 0.5 && P[v][2] < 3.5) {  // the side hole's (the ends' patches are flat)
      ++inSide;
      worst = std::max(worst, std::abs(std::hypot(P[v][0], P[v][1]) - 1));
    }
  ASSERT_GT(inSide, 10u);
  std::cout << "tube of slivers: " << inSide << " patch vertices, max distance to the cylinder "
            << worst << "\n";
  EXPECT_LT(worst, 0.1);  // raised to a floor of 0.05, the weights give 0.44
}

// A narrow band cut two thirds of the way around a tube: its border
// projects simply onto the plane facing the band's middle, but towards the
// band's ends the tube turns up to 70 degrees away from that plane, where
// the front, sized by the foreshortened border, makes triangles that come
// out several times longer in space than the border's edges. The patch is
// refined where the shape stretched it and shaped again: no long edges or
// slivers, no fold, and the cylinder followed closely.
TEST(HoleShape, BandAroundATubeIsRefinedWhereTheShapeStretchesIt) {
  Mesh m = withHole(openTube(64, 64, 1, 4), [](const Point3& c) {
    return std::abs(std::atan2(c[1], c[0])) < 1.22 && std::abs(c[2] - 2) < 0.15;
  });
  HoleFillOptions o = withFairing(HoleFairing::Biharmonic);
  // The band only (not the tube's open ends): the vertices near its middle.
  const std::vector<Point3> before = positionsOf(m);
  for (std::size_t v = 0; v < before.size(); ++v)
    if (std::abs(before[v][2] - 2) < 0.2 && before[v][0] > 0.99)
      o.selected_vertex_indices.push_back(int(v));
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 3u);
  ASSERT_EQ(r.holes_filled, 1u);
  const HoleReport& band =
      *std::find_if(r.holes.begin(), r.holes.end(), [](const HoleReport& h) { return h.filled; });
  EXPECT_EQ(band.fairing, HoleFairing::Biharmonic) << band.reason;
  EXPECT_TRUE(band.planar_domain);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectSound(m, 2 * 64);
  const std::vector<Point3> P = positionsOf(m);
  const std::vector<Triangle> T = trianglesOf(m);
  double longestBorderEdge = 0;
  for (std::size_t k = 0; k < band.boundary.size(); ++k)
    longestBorderEdge =
        std::max(longestBorderEdge,
                 (P[band.boundary[(k + 1) % band.boundary.size()]] - P[band.boundary[k]]).Norm());
  double longest = 0, worst = 0;
  for (int f : r.new_faces)
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (P[T[f][k]] - P[T[f][(k + 1) % 3]]).Norm());
  for (int v : r.new_vertices) worst = std::max(worst, std::abs(std::hypot(P[v][0], P[v][1]) - 1));
  std::cout << "band around a tube: " << r.faces_added << " faces, longest edge "
            << longest / longestBorderEdge << " x the border's longest, smallest angle "
            << smallestNewAngle(m, r) << ", max distance to the cylinder " << worst << "\n";
  EXPECT_LT(longest, 1.5 * longestBorderEdge);
  EXPECT_GT(smallestNewAngle(m, r), 10);
  EXPECT_LT(worst, 5e-4);  // unrefined, the long triangles leave it 0.0009 away
}

// A round hole around the rim of a thin plate: its border folds over the
// rim, so every plane squeezes part of it. The patch over the disk competes
// with the plane's, and whichever is taken, the shape is biharmonic and
// stays near the plate.
TEST(HoleShape, HoleAroundTheRimOfAThinPlate) {
  Mesh plate = gridCube(12);
  for (auto& v : plate.vert) v.P()[2] *= 0.15;
  Mesh m =
      withHole(plate, [](const Point3& c) { return (c - Point3(1, 0.5, 0.075)).Norm() < 0.25; });
  const HoleFillResult r = fillHoles(m, withFairing(HoleFairing::Biharmonic));
  ASSERT_EQ(r.holes_found, 1u);
  ASSERT_EQ(r.holes_filled, 1u) << r.holes[0].reason;
  EXPECT_EQ(r.holes[0].fairing, HoleFairing::Biharmonic) << r.holes[0].reason;
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectSound(m, 0);
  const std::vector<Point3> P = positionsOf(m);
  for (int v : r.new_vertices) {
    EXPECT_GT(P[v][2], -0.05);
    EXPECT_LT(P[v][2], 0.2);
    EXPECT_LT(P[v][0], 1.05);
  }
  std::cout << "thin plate rim: " << r.faces_added << " faces, over "
            << (r.holes[0].planar_domain ? "the plane" : "a disk") << "\n";
}

// ---- Intersections ----------------------------------------------------------------------

TEST(HoleChecks, FairedPatchThatWouldHitAnotherPartFallsBackToAFlatterOne) {
  // A small upright plate where the sphere's cap was: the rounded patch
  // would cross it, a flatter one passes under it.
  const Mesh sphere = sphereWithCap();
  const Mesh plate = makeMesh({{0, -0.1, 0.85}, {0, 0.1, 0.85}, {0, 0.1, 1.1}, {0, -0.1, 1.1}},
                              {{0, 1, 2}, {0, 2, 3}});
  Mesh m = appended(sphere, plate);
  HoleFillOptions o;
  o.max_boundary_edges = 100;
  o.verify = true;
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 2u);
  ASSERT_EQ(r.holes_filled, 1u);
  EXPECT_EQ(r.fallbacks, 1u);
  const HoleReport& hole = r.holes[0].filled ? r.holes[0] : r.holes[1];
  EXPECT_NE(hole.fairing, HoleFairing::LaplacianRegression);
  EXPECT_NE(hole.reason.find("intersect"), std::string::npos) << hole.reason;
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  EXPECT_EQ(selfIntersectingPairs(m), 0u);
}

// The faces a patch is checked against are gathered around the hole before
// it is shaped, other parts of the mesh among them: a plate above a tube's
// open end, which the biharmonic dome would cross, makes it fall back.
TEST(HoleChecks, PlateAboveATubesEndMakesTheDomeFallBack) {
  const Mesh tube = openTube(24, 30, 1, 4);
  const Mesh plate =
      makeMesh({{-0.1, -0.1, 4.5}, {0.1, -0.1, 4.5}, {0.1, 0.1, 4.5}, {-0.1, 0.1, 4.5}},
               {{0, 1, 2}, {0, 2, 3}});
  Mesh m = appended(tube, plate);
  const std::vector<Point3> before = positionsOf(m);
  HoleFillOptions o;
  o.verify = true;
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 3u);  // the tube's two ends and the plate's outline
  const HoleReport& top = *std::find_if(r.holes.begin(), r.holes.end(), [&](const HoleReport& h) {
    return h.boundary.size() == 24 && before[std::size_t(h.boundary[0])][2] > 3.9;
  });
  ASSERT_TRUE(top.filled) << top.reason;
  std::cout << "tube end under a plate: " << toString(top.fairing) << ", " << top.reason << "\n";
  EXPECT_NE(top.reason.find("biharmonic patch would intersect"), std::string::npos) << top.reason;
  EXPECT_EQ(r.remaining_intersecting_pairs, 0u);
  EXPECT_EQ(selfIntersectingPairs(m), 0u);
}

TEST(HoleChecks, VerificationCountsWhatAnUncheckedPatchCrosses) {
  // The same plate through the opening, with the check off: the hole is
  // filled through the plate and the independent recount sees it.
  const Mesh sphere = sphereWithCap();
  const Mesh plate = makeMesh({{0, -0.3, 0.5}, {0, 0.3, 0.5}, {0, 0.3, 1.5}, {0, -0.3, 1.5}},
                              {{0, 1, 2}, {0, 2, 3}});
  Mesh m = appended(sphere, plate);
  HoleFillOptions o;
  o.max_boundary_edges = 100;
  o.check_intersections = false;
  o.verify = true;
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_filled, 2u);  // the plate's border too, by a copy of the plate
  EXPECT_TRUE(r.verified);
  EXPECT_GT(r.new_intersecting_pairs, 0u);
  EXPECT_EQ(r.new_intersecting_pairs, selfIntersectingPairs(m));
  // The whole-mesh count, by the checker's rule, is the same here (the
  // input crossed nothing).
  EXPECT_TRUE(r.remaining_counted);
  EXPECT_EQ(r.remaining_intersecting_pairs, selfIntersectingPairs(m));
}

TEST(HoleChecks, HoleWhoseFillMustCrossAnotherPartIsSkipped) {
  // A vertical plate through the opening: every disk spanning the hole's
  // border meets it.
  const Mesh sphere = sphereWithCap();
  const Mesh plate = makeMesh({{0, -0.3, 0.5}, {0, 0.3, 0.5}, {0, 0.3, 1.5}, {0, -0.3, 1.5}},
                              {{0, 1, 2}, {0, 2, 3}});
  Mesh m = appended(sphere, plate);
  const std::vector<Point3> before = positionsOf(m);
  const std::size_t facesBefore = std::size_t(m.fn);
  HoleFillOptions o;
  o.verify = true;
  o.max_boundary_edges = 100;
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 2u);
  EXPECT_EQ(r.holes_filled, 0u);
  EXPECT_EQ(r.holes_skipped, 2u);
  for (const HoleReport& h : r.holes) {
    if (h.boundary_edges > 4) {
      EXPECT_NE(h.reason.find("intersect"), std::string::npos) << h.reason;
      // Every shape of the default chain was tried, the regression's last.
      for (const char* shape : {"biharmonic", "harmonic", "flat", "laplacian_regression"})
        EXPECT_NE(h.reason.find(std::string(shape) + " patch would intersect"), std::string::npos)
            << shape << ": " << h.reason;
    }
  }
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  EXPECT_EQ(std::size_t(m.fn), facesBefore);
  EXPECT_EQ(positionsOf(m), before);  // splits of a skipped hole are undone
}

// ---- Input handling ---------------------------------------------------------------------

TEST(HoleInput, NoHolesLeavesTheMeshUnchanged) {
  Mesh m = icosphere(2);
  const std::vector<Point3> p = positionsOf(m);
  const std::vector<Triangle> t = trianglesOf(m);
  const HoleFillResult r = fillHoles(m);
  EXPECT_EQ(r.holes_found, 0u);
  EXPECT_EQ(r.holes_filled, 0u);
  EXPECT_EQ(r.faces_added, 0u);
  EXPECT_EQ(positionsOf(m), p);
  EXPECT_EQ(trianglesOf(m), t);
  const std::string json = toJson(r).str();
  EXPECT_NE(json.find("\"holes_found\": 0"), std::string::npos) << json;
}

TEST(HoleInput, EmptyMeshIsRefused) {
  Mesh m;
  EXPECT_THROW(fillHoles(m), InvalidInputError);
  Mesh pointsOnly = makeMesh({{0, 0, 0}, {1, 0, 0}}, {});
  EXPECT_THROW(fillHoles(pointsOnly), InvalidInputError);
}

TEST(HoleInput, NonFiniteCoordinateIsRefusedAndTheMeshKept) {
  Mesh m = sphereWithCap();
  m.vert[5].P()[1] = std::nan("");
  const std::size_t faces = std::size_t(m.fn);
  try {
    fillHoles(m);
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos) << e.what();
  }
  EXPECT_EQ(std::size_t(m.fn), faces);
}

TEST(HoleInput, InfiniteCoordinateIsRefusedNamingTheVertex) {
  for (int axis = 0; axis < 3; ++axis) {
    Mesh m = sphereWithCap();
    m.vert[m.vert.size() - 1].P()[axis] = axis == 1 ? -INFINITY : INFINITY;
    const std::vector<Triangle> t = trianglesOf(m);
    try {
      fillHoles(m);
      FAIL() << "no error";
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find("vertex " + std::to_string(m.vert.size() - 1) +
                                           " has a non-finite"),
                std::string::npos)
          << e.what();
    }
    EXPECT_EQ(trianglesOf(m), t);
  }
}

// Options are checked before anything is read from the mesh (the cheap
// checks first): a bad option is named even when a coordinate is bad too.
TEST(HoleInput, BadOptionsAreRefusedBeforeTheMeshIsRead) {
  Mesh m = sphereWithCap();
  m.vert[0].P()[0] = INFINITY;
  HoleFillOptions o;
  o.long_edge_factor = 0.5;
  try {
    fillHoles(m, o);
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("long_edge_factor"), std::string::npos) << e.what();
  }
}

// Where nothing is filled, nothing is read but the faces: a closed mesh with
// a non-finite coordinate is left as it is, with no hole found.
TEST(HoleInput, ClosedMeshIsNotReadFurther) {
  Mesh m = icosphere(2);
  m.vert[3].P()[2] = std::nan("");
  const HoleFillResult r = fillHoles(m);
  EXPECT_EQ(r.holes_found, 0u);
}

TEST(HoleInput, DeletedElementsAreRefused) {
  Mesh m = sphereWithCap();
  vcg::tri::Allocator<Mesh>::DeleteFace(m, m.face[3]);
  try {
    fillHoles(m);
    FAIL() << "no error";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("deleted"), std::string::npos) << e.what();
  }
  EXPECT_EQ(m.face.size(), std::size_t(m.fn) + 1);
  Mesh n = sphereWithCap();
  vcg::tri::Allocator<Mesh>::DeleteVertex(n, n.vert[0]);
  EXPECT_THROW(fillHoles(n), InvalidInputError);
}

TEST(HoleInput, BadOptionsAreRefused) {
  Mesh m = sphereWithCap();
  HoleFillOptions o;
  o.long_edge_factor = 0.5;
  EXPECT_THROW(fillHoles(m, o), InvalidInputError);
  o = {};
  o.selected_vertices.assign(3, true);
  EXPECT_THROW(fillHoles(m, o), InvalidInputError);
  o = {};
  o.selected_vertex_indices = {-1};
  EXPECT_THROW(fillHoles(m, o), InvalidInputError);
}

TEST(HoleInput, CancellingLeavesTheMeshUnchanged) {
  Mesh m = sphereWithCap();
  const std::vector<Point3> p = positionsOf(m);
  const std::vector<Triangle> t = trianglesOf(m);
  HoleFillOptions o;
  o.progress = [](int percent, const char*) { return percent < 50; };
  EXPECT_THROW(fillHoles(m, o), CancelledError);
  EXPECT_EQ(positionsOf(m), p);
  EXPECT_EQ(trianglesOf(m), t);
}

// ---- Which holes ------------------------------------------------------------------------

TEST(HoleSelection, SizeLimitsAndSelectionChooseTheHoles) {
  // A sphere with a small hole at the top and a large one at the bottom.
  auto make = [] {
    return withHole(icosphere(4), [](const Point3& c) { return c[2] > 0.9 || c[2] < -0.6; });
  };
  {
    Mesh m = make();
    HoleFillOptions o;
    o.max_boundary_edges = 60;
    const HoleFillResult r = fillHoles(m, o);
    ASSERT_EQ(r.holes_found, 2u);
    EXPECT_EQ(r.holes_filled, 1u);
    for (const HoleReport& h : r.holes) {
      EXPECT_EQ(h.filled, h.boundary_edges <= 60);
      if (!h.filled) {
        EXPECT_NE(h.reason.find("limit"), std::string::npos);
      }
    }
  }
  {
    Mesh m = make();
    HoleFillOptions o;
    o.max_diameter = 0.3;  // of the diagonal (2 sqrt 3): the top hole is ~0.87 wide
    const HoleFillResult r = fillHoles(m, o);
    EXPECT_EQ(r.holes_filled, 1u);
    for (const HoleReport& h : r.holes) EXPECT_EQ(h.filled, h.diameter < 0.3 * 2 * std::sqrt(3.0));
  }
  {
    // One vertex of the larger hole's border selected (its borders listed
    // by a first call that fills nothing).
    Mesh m = make();
    HoleFillOptions none;
    none.max_boundary_edges = 1;
    const HoleFillResult listed = fillHoles(m, none);
    ASSERT_EQ(listed.holes.size(), 2u);
    const HoleReport& larger = listed.holes[0].boundary_edges > listed.holes[1].boundary_edges
                                   ? listed.holes[0]
                                   : listed.holes[1];
    const std::size_t smallerEdges =
        std::min(listed.holes[0].boundary_edges, listed.holes[1].boundary_edges);
    HoleFillOptions o;
    o.selected_vertex_indices = {larger.boundary[3]};
    const HoleFillResult r = fillHoles(m, o);
    ASSERT_EQ(r.holes_filled, 1u);
    for (const HoleReport& h : r.holes) {
      EXPECT_EQ(h.filled, h.boundary_edges == larger.boundary_edges);
      if (!h.filled) {
        EXPECT_NE(h.reason.find("not selected"), std::string::npos);
      }
    }
    EXPECT_EQ(edgeStats(m).border, smallerEdges);
  }
}

TEST(HoleSelection, ManySmallHolesAreAllFilled) {
  // 16 holes of 2 x 2 squares: past the first few, the checks use a box
  // hierarchy of the input faces instead of scanning them.
  Mesh m = heightGrid(
      40, 40, 1, [](double x, double y) { return 0.05 * std::sin(x) * std::cos(y); },
      [](double x, double y) {
        const int i = int(x), j = int(y);
        return !(i % 10 >= 4 && i % 10 < 6 && j % 10 >= 4 && j % 10 < 6);
      });
  HoleFillOptions o;
  o.max_boundary_edges = 10;
  o.verify = true;
  const HoleFillResult r = fillHoles(m, o);
  EXPECT_EQ(r.holes_found, 17u);
  EXPECT_EQ(r.holes_filled, 16u);
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  expectSound(m, 160);
}

// ---- Large holes -------------------------------------------------------------------------

// A band of the unit sphere below the circle at polar angle `cap`, with
// `segments` vertices around and near-square faces: the cap is a hole of
// `segments` border edges (and the band's lower edge another).
Mesh sphereBand(int segments, double cap, int rings) {
  std::vector<Point3> p;
  double theta = cap;
  for (int i = 0; i <= rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * M_PI * (j + 0.5 * (i % 2)) / segments;
      p.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                     std::cos(theta));
    }
    theta += 2 * M_PI * std::sin(theta) / segments * 0.87;
  }
  std::vector<Triangle> t;
  auto at = [&](int i, int j) { return i * segments + (j % segments); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      if (i % 2 == 0) {
        t.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        t.push_back({at(i, j + 1), at(i + 1, j), at(i + 1, j + 1)});
      } else {
        t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      }
    }
  return makeMesh(p, t);
}

TEST(HoleLarge, ThousandBorderVertexHoleIsFilled) {
  Mesh m = sphereBand(1000, 0.6, 6);
  HoleFillOptions o;
  o.verify = true;
  std::vector<bool> top(std::size_t(m.vn), false);
  for (int j = 0; j < 1000; ++j) top[j] = true;
  o.selected_vertices = top;
  const HoleFillResult r = fillHoles(m, o);
  ASSERT_EQ(r.holes_found, 2u);
  ASSERT_EQ(r.holes_filled, 1u) << r.holes[0].reason << " / " << r.holes[1].reason;
  EXPECT_EQ(r.new_intersecting_pairs, 0u);
  const HoleReport& hole = r.holes[0].filled ? r.holes[0] : r.holes[1];
  EXPECT_EQ(hole.boundary_edges, 1000u);
  EXPECT_EQ(hole.fairing, HoleFairing::Biharmonic) << hole.reason;
  expectSound(m, 1000);
  EXPECT_LT(maxSphereDeviation(m, r), 0.02);
  std::cout << "1000-edge hole: " << r.faces_added << " faces, " << hole.time_ms
            << " ms, deviation " << maxSphereDeviation(m, r) << "\n";
}

// ---- Report ---------------------------------------------------------------------------------

TEST(HoleReportJson, HasTheKeysScriptsRead) {
  Mesh m = withHole(icosphere(4), [](const Point3& c) { return c[2] > 0.9 || c[2] < -0.6; });
  HoleFillOptions o;
  o.max_boundary_edges = 60;
  const HoleFillResult r = fillHoles(m, o);
  const std::string json = toJson(r).str();
  for (const char* key : {"\"holes_found\": 2", "\"holes_filled\": 1", "\"holes_skipped\": 1",
                          "\"faces_added\": ", "\"new_intersecting_pairs\": 0",
                          "\"time_ms\": ", "\"skipped\": [{", "\"reason\": "})
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
  EXPECT_EQ(r.new_faces.size(), r.faces_added);
}
