#include "common/repair/split/split.h"
#include "common/repair/output_stage.h"

#include <set>

#include <gtest/gtest.h>

#include "common/base/errors.h"
#include "common/repair/inspect/inspect.h"
#include "tests/mesh_builders.h"

namespace meshmend {
namespace {

using testing::box;
using testing::gridCube;
using testing::icosphere;
using testing::moved;
using testing::uvSphere;

InspectResult check(const Mesh& m) {
  InspectOptions o;
  o.self_intersections = true;
  return inspect(m, o);
}

// The output stage for a float host, as MeshLab 2020.09's filter runs it.
StoredOutput storeAsFloat(SplitResult& r, const std::vector<const Mesh*>& inputs,
                          const SplitOptions& o) {
  OutputStageOptions stage;
  stage.scalar = Scalar::kFloat;
  return storeForHost(r, inputs, o, stage);
}

// Step 1 of that stage alone.
std::size_t roundAsFloat(SplitResult& r) {
  OutputStageOptions stage;
  stage.scalar = Scalar::kFloat;
  return roundForHost(r, stage);
}

// Step 3 of that stage alone, on a result rounded to float.
std::size_t splitAgainAsFloat(SplitResult& r, const std::vector<const Mesh*>& inputs,
                              const SplitOptions& o) {
  OutputStageOptions stage;
  stage.scalar = Scalar::kFloat;
  StoredOutput out;
  out.crossing = crossingsLeft(r, Scalar::kFloat);
  return splitStoredAgain(r, inputs, o, stage, out);
}

TEST(Split, TwoSpheresMeetAlongOneClosedCurve) {
  const Mesh a = uvSphere(24, 32), b = uvSphere(24, 32, 1.0, {0.9, 0.13, 0.07});
  const SplitResult r = splitAlongIntersections({&a, &b});
  EXPECT_GT(r.intersecting_pairs, 0u);
  EXPECT_EQ(r.curve_loops, 1u);
  EXPECT_EQ(r.open_curves, 0u);
  // Each mesh stays closed and manifold; welded, they share the curve.
  for (const Mesh& m : r.meshes) {
    const InspectResult i = check(m);
    EXPECT_TRUE(i.is_closed);
    EXPECT_EQ(i.non_manifold_edges, 0u);
    EXPECT_EQ(*i.self_intersecting_pairs, 0u);
  }
  const InspectResult merged = check(r.merged);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  EXPECT_EQ(merged.non_manifold_edges, r.merged_curve_edges.size());
  EXPECT_EQ(merged.border_edges, 0u);
  EXPECT_EQ(merged.connected_components, 1u);
  // The smallest angle the split made is reported, and it bounds the output's.
  EXPECT_GT(r.smallest_new_angle_deg, 0);
  EXPECT_LE(r.smallest_new_angle_deg, 60);
  EXPECT_LE(merged.min_angle_deg, r.smallest_new_angle_deg + 1e-9);
  // Curve edges are flagged on every face that has them: four faces around
  // each welded curve edge, two in each closed mesh.
  auto flagged = [](const std::vector<std::uint8_t>& flags) {
    std::size_t n = 0;
    for (std::uint8_t f : flags) n += (f & 1) + ((f >> 1) & 1) + ((f >> 2) & 1);
    return n;
  };
  EXPECT_EQ(flagged(curveEdgeFlags(r.merged, r.merged_curve_edges)),
            4 * r.merged_curve_edges.size());
  for (std::size_t m = 0; m < 2; ++m)
    EXPECT_EQ(flagged(curveEdgeFlags(r.meshes[m], r.curve_edges[m])), 2 * r.curve_edges[m].size());
}

TEST(Split, QualitySnappingRemovesSliversAndKeepsTheResultValid) {
  // Offsets chosen so that the curves pass close to vertices and edges.
  for (const Point3& offset :
       {Point3(0.9, 0.13, 0.07), Point3(0.5, 0.31, 0.011), Point3(1.1, 0.0013, 0.2)}) {
    const Mesh a = uvSphere(24, 32), b = uvSphere(40, 52, 0.8, offset);
    const SplitResult plain = splitAlongIntersections({&a, &b});
    SplitOptions o;
    o.snap_tolerance = 0.1;
    const SplitResult r = splitAlongIntersections({&a, &b}, o);
    SCOPED_TRACE(offset[1]);
    EXPECT_EQ(plain.vertices_snapped + plain.edges_snapped, 0u);
    EXPECT_DOUBLE_EQ(r.smallest_new_angle_deg_unsnapped, plain.smallest_new_angle_deg);
    EXPECT_GT(r.vertices_snapped + r.edges_snapped, 0u);
    EXPECT_GT(r.smallest_new_angle_deg, plain.smallest_new_angle_deg);
    EXPECT_EQ(r.curve_loops, plain.curve_loops);
    EXPECT_EQ(r.open_curves, 0u);
    // Still two closed manifold meshes that share their curves and cross nowhere.
    for (std::size_t m = 0; m < 2; ++m) {
      const InspectResult i = check(r.meshes[m]);
      EXPECT_TRUE(i.is_closed);
      EXPECT_EQ(i.non_manifold_edges, 0u);
      EXPECT_EQ(i.non_manifold_vertices, 0u);
      EXPECT_EQ(i.degenerate_faces, 0u);
      EXPECT_EQ(*i.self_intersecting_pairs, 0u);
      EXPECT_EQ(r.curve_edges[m].size(), r.merged_curve_edges.size());
    }
    const InspectResult merged = check(r.merged);
    EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
    EXPECT_EQ(merged.non_manifold_edges, r.merged_curve_edges.size());
    EXPECT_EQ(merged.border_edges, 0u);
    EXPECT_LE(merged.min_angle_deg, r.smallest_new_angle_deg + 1e-9);
    // Snapping merged vertices away: fewer vertices than without it.
    EXPECT_EQ(r.merged.vn + r.vertices_snapped, plain.merged.vn);
    // The report counts what the output holds: faces added by edge snaps too.
    EXPECT_EQ(std::size_t(r.merged.fn), std::size_t(a.fn + b.fn) + r.faces_added);
    EXPECT_EQ(std::size_t(plain.merged.fn), std::size_t(a.fn + b.fn) + plain.faces_added);
  }
}

// Also for outputs large enough to be built in parts on two threads
// (MeshBuilder: from 4,096 output faces).
TEST(Split, FacesNotCrossedStayBitIdentical) {
  // Each output built from arrays (with the merged output), and written
  // directly by the split (without it).
  for (const bool merged : {true, false})
    for (const auto& [rings, segments] : {std::pair{16, 20}, std::pair{60, 80}}) {
      SCOPED_TRACE(rings);
      SCOPED_TRACE(merged);
      const Mesh a = uvSphere(rings, segments), b = uvSphere(16, 20, 1.0, {1.2, 0, 0});
      SplitOptions options;
      options.merged_output = merged;
      const SplitResult r = splitAlongIntersections({&a, &b}, options);
      const Mesh& out = r.meshes[0];
      // Input vertices keep their index, coordinates and origin.
      VertexOriginHandle vo = vertexOrigins(const_cast<Mesh&>(out));
      for (std::size_t v = 0; v < a.vert.size(); ++v) {
        EXPECT_EQ(out.vert[v].cP(), a.vert[v].cP());
        EXPECT_EQ(vo[v].vertex, int(v));
      }
      EXPECT_EQ(out.vn, int(out.vert.size()));
      EXPECT_EQ(out.fn, int(out.face.size()));
      // Every face not split appears unchanged (same corner indices), and the
      // split ones are covered by faces that record them as their birth face.
      FaceOriginHandle fo = faceOrigins(const_cast<Mesh&>(out));
      std::vector<int> children(a.face.size(), 0);
      for (std::size_t f = 0; f < out.face.size(); ++f) ++children[fo[f].face];
      const std::vector<Triangle> in = trianglesOf(a), result = trianglesOf(out);
      std::size_t unchanged = 0;
      for (std::size_t f = 0; f < out.face.size(); ++f)
        if (children[fo[f].face] == 1 && result[f] == in[fo[f].face]) ++unchanged;
      const std::size_t splitFaces =
          std::size_t(std::count_if(children.begin(), children.end(), [](int c) { return c > 1; }));
      EXPECT_EQ(unchanged + splitFaces, a.face.size());
      EXPECT_GT(unchanged, a.face.size() / 2);
    }
}

TEST(Split, CurveThroughAVertexAndAlongAnEdge) {
  // The boxes share the plane x = 1 partly (coplanar contact) and cross
  // elsewhere: degenerate transitions of the curve.
  const Mesh a = box(), b = moved(box(2, 0.5, 0.5), {0.5, 0.25, 0.25});
  const SplitResult r = splitAlongIntersections({&a, &b});
  EXPECT_GT(r.intersecting_pairs, 0u);
  const InspectResult merged = check(r.merged);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  for (const Mesh& m : r.meshes) EXPECT_TRUE(check(m).is_closed);
}

TEST(Split, AMeshWhoseFacesAllHaveNoAreaIsRefusedNotEmptied) {
  // Two vertices at one position, every face using both: welded or not,
  // the merged output would have no face (found by fuzzing: an empty
  // result in place of a refusal).
  const Mesh flat = makeMesh({{0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {1, 0, 3}});
  for (bool weld : {false, true}) {
    SplitOptions o;
    o.weld_duplicates = weld;
    try {
      splitAlongIntersections({&flat}, o);
      ADD_FAILURE() << "expected InvalidInputError (weld " << weld << ")";
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find("no face with three corners at distinct positions"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(Split, SelfIntersectionsOfOneMesh) {
  // Two overlapping cubes given as one mesh.
  std::vector<Point3> p = positionsOf(box());
  std::vector<Triangle> t = trianglesOf(box());
  for (const Point3& q : positionsOf(box())) p.push_back(q + Point3(0.5, 0.5, 0.5));
  for (const Triangle& f : trianglesOf(box())) t.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
  const Mesh m = makeMesh(p, t);
  SplitOptions o;
  o.self = true;
  const SplitResult r = splitAlongIntersections({&m}, o);
  EXPECT_EQ(r.intersecting_pairs, 18u);
  EXPECT_EQ(*check(r.meshes[0]).self_intersecting_pairs, 0u);
  EXPECT_EQ(r.curve_loops, 1u);
  // A caller's bound sees the pairs before anything is cut, and refuses by throwing.
  std::size_t seen = 0;
  o.pairs_found = [&](const std::vector<IntersectingPair>& pairs) {
    seen = pairs.size();
    for (const IntersectingPair& pair : pairs) EXPECT_TRUE(pair.a < pair.b);
    throw WorkLimitError("too many");
  };
  EXPECT_THROW(splitAlongIntersections({&m}, o), WorkLimitError);
  EXPECT_EQ(seen, 18u);
}

TEST(Split, VeryDifferentResolutions) {
  const Mesh coarse = box(2, 2, 2), fine = uvSphere(40, 60, 0.8, {1.7, 1.0, 1.0});
  const SplitResult r = splitAlongIntersections({&coarse, &fine});
  EXPECT_EQ(*check(r.merged).self_intersecting_pairs, 0u);
  EXPECT_EQ(r.open_curves, 0u);
  for (const Mesh& m : r.meshes) EXPECT_EQ(check(m).non_manifold_edges, 0u);
}

TEST(Split, WeldingDuplicatesFirstClosesSeams) {
  // A box whose top uses its own copies of the top corners, crossed by a
  // sphere: without welding the seam's faces touch each other as well.
  std::vector<Point3> p = positionsOf(box());
  std::vector<Triangle> t = trianglesOf(box());
  for (int v = 4; v < 8; ++v) p.push_back(p[v]);
  t[2] = {8, 9, 10};
  t[3] = {9, 11, 10};
  const Mesh seamed = makeMesh(p, t), ball = uvSphere(12, 16, 0.5, {0.5, 0.5, 1.0});
  SplitOptions o;
  o.self = true;
  const SplitResult plain = splitAlongIntersections({&seamed, &ball}, o);
  o.weld_duplicates = true;
  const SplitResult welded = splitAlongIntersections({&seamed, &ball}, o);
  EXPECT_EQ(welded.vertices_welded, 4u);
  EXPECT_LT(welded.intersecting_pairs, plain.intersecting_pairs);
  const InspectResult i = check(welded.meshes[0]);
  EXPECT_TRUE(i.is_closed);
  EXPECT_EQ(i.duplicate_points, 0u);
  EXPECT_EQ(*check(welded.merged).self_intersecting_pairs, 0u);
}

TEST(Split, RoundToFloatKeepsTheResultFreeOfCrossings) {
  const Mesh a = uvSphere(30, 40), b = uvSphere(30, 40, 0.9, {0.7, 0.31, 0.17});
  SplitResult r = splitAlongIntersections({&a, &b});
  EXPECT_EQ(roundAsFloat(r), 0u);
  for (const Vertex& v : r.merged.vert)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(v.cP()[k], double(float(v.cP()[k])));
  for (std::size_t m = 0; m < 2; ++m)  // the per-mesh outputs got the same positions
    for (std::size_t v = 0; v < r.meshes[m].vert.size(); ++v)
      EXPECT_EQ(r.meshes[m].vert[v].cP(), r.merged.vert[r.merged_vertex[m][v]].cP());
  EXPECT_EQ(crossingsLeft(r, Scalar::kDouble), 0u);
}

TEST(Split, CurveThroughAnExistingVertex) {
  // A square sheet (two triangles, diagonal 0-2) standing across a flat one
  // so that the curve passes exactly through the flat sheet's corner 1 and
  // centre vertex.
  const Mesh flat = makeMesh({{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}, {0, 0, 0}},
                             {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}});
  const Mesh wall =
      makeMesh({{-3, -3, -1}, {3, 3, -1}, {3, 3, 1}, {-3, -3, 1}}, {{0, 1, 2}, {0, 2, 3}});
  const SplitResult r = splitAlongIntersections({&flat, &wall});
  EXPECT_GT(r.intersecting_pairs, 0u);
  EXPECT_EQ(crossingsLeft(r, Scalar::kDouble), 0u);
  // The flat sheet needs no new vertex on the diagonal's interior points that
  // already are its vertices: its centre vertex stays a curve vertex.
  bool centreOnCurve = false;
  for (const auto& e : r.curve_edges[0]) centreOnCurve |= e[0] == 4 || e[1] == 4;
  EXPECT_TRUE(centreOnCurve);
  EXPECT_EQ(r.open_curves, 1u);  // one open curve across the flat sheet
}

TEST(Split, TrianglesTouchingAtOnePoint) {
  const Mesh a = makeMesh({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}, {{0, 1, 2}});
  const Mesh b = makeMesh({{1, 1, 0}, {1, 2, 3}, {2, 1, 3}}, {{0, 1, 2}});  // corner on a
  const SplitResult r = splitAlongIntersections({&a, &b});
  EXPECT_EQ(r.intersecting_pairs, 1u);
  EXPECT_EQ(r.meshes[0].fn, 3);  // the point splits a into three
  EXPECT_EQ(r.meshes[1].fn, 1);  // b's own corner: nothing to split
  EXPECT_EQ(r.merged_curve_edges.size(), 0u);
  EXPECT_EQ(crossingsLeft(r, Scalar::kDouble), 0u);
}

TEST(Split, PointOnASharedEdgeSplitsBothFaces) {
  // A needle through the shared edge of two faces: both faces are split at
  // the same point, so the sheet stays conforming (no T-junction).
  const Mesh sheet = makeMesh({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0}}, {{0, 1, 2}, {1, 3, 2}});
  const Mesh needle = makeMesh({{1, 1, -1}, {1.2, 0.8, 1}, {0.8, 1.2, 1}}, {{0, 1, 2}});
  const SplitResult r = splitAlongIntersections({&sheet, &needle});
  const InspectResult i = check(r.meshes[0]);
  EXPECT_EQ(i.border_edges, 4u + 0u);  // still the square's outline, split nowhere on it
  EXPECT_EQ(i.non_manifold_edges, 0u);
  EXPECT_EQ(i.connected_components, 1u);
  EXPECT_EQ(crossingsLeft(r, Scalar::kDouble), 0u);
}

TEST(Split, CoplanarOverlappingTriangles) {
  // Two triangles of different meshes in one plane, overlapping in the
  // triangle (1,1) (3,1) (1,3): both are cut along its outline, and both
  // then hold it as one face; the merged output keeps it once.
  const Mesh a = makeMesh({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}, {{0, 1, 2}});
  const Mesh b = makeMesh({{1, 1, 0}, {5, 1, 0}, {1, 5, 0}}, {{0, 1, 2}});
  // By default each mesh keeps its copy (a whole surface each, for booleans).
  const SplitResult both = splitAlongIntersections({&a, &b});
  EXPECT_EQ(both.coincident_faces, 1u);
  EXPECT_EQ(both.coincident_faces_removed, 0u);
  EXPECT_EQ(check(both.merged).duplicate_faces, 1u);
  SplitOptions once;
  once.overlaps_once = true;
  const SplitResult r = splitAlongIntersections({&a, &b}, once);
  EXPECT_EQ(r.intersecting_pairs, 1u);
  EXPECT_EQ(r.faces_split, 2u);
  EXPECT_GT(r.meshes[0].fn, 1);
  EXPECT_GT(r.meshes[1].fn, 1);
  EXPECT_EQ(r.merged_curve_edges.size(), 3u);  // the overlap's outline, shared by both
  EXPECT_EQ(r.curve_loops, 1u);
  EXPECT_EQ(r.open_curves, 0u);
  EXPECT_EQ(r.coincident_faces_removed, 1u);
  EXPECT_EQ(std::size_t(r.merged.fn), r.meshes[0].face.size() + r.meshes[1].face.size() - 1);
  const InspectResult merged = check(r.merged);
  EXPECT_EQ(merged.duplicate_faces, 0u);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  EXPECT_EQ(merged.non_manifold_edges, 0u);  // on each outline edge: the overlap, one piece beside
  EXPECT_EQ(crossingsLeft(r, Scalar::kFloat), 0u);
}

TEST(Split, TheSameSurfaceTwiceIsKeptOnce) {
  // Two copies of one closed mesh overlap everywhere: merged, the surface
  // is there once, and nothing of it is a curve.
  const Mesh a = icosphere(2);
  SplitOptions once;
  once.overlaps_once = true;
  const SplitResult r = splitAlongIntersections({&a, &a}, once);
  EXPECT_EQ(std::size_t(r.merged.fn), a.face.size());
  EXPECT_EQ(r.coincident_faces_removed, a.face.size());
  EXPECT_TRUE(r.merged_curve_edges.empty());
  const InspectResult merged = check(r.merged);
  EXPECT_TRUE(merged.is_closed);
  EXPECT_EQ(merged.non_manifold_edges, 0u);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  // Each separate output is still its own whole surface.
  for (const Mesh& m : r.meshes) EXPECT_EQ(m.face.size(), a.face.size());
}

TEST(Split, TheSameSelfIntersectingSurfaceTwiceKeepsItsOwnCurves) {
  // A layer that crosses itself (two boxes in one mesh) and its copy: the
  // surface is there once, and its own intersection curves are still
  // curves (four faces meet along them), as when the layer is split alone.
  const Mesh a = appended(gridCube(2), moved(gridCube(2), {0.5, 0.25, 0.125}));
  SplitOptions o;
  o.self = true;
  o.overlaps_once = true;
  o.separate_meshes = false;
  const SplitResult alone = splitAlongIntersections({&a}, o);
  ASSERT_GT(alone.merged_curve_edges.size(), 0u);
  const SplitResult twice = splitAlongIntersections({&a, &a}, o);
  EXPECT_EQ(twice.merged.face.size(), alone.merged.face.size());
  EXPECT_EQ(twice.merged_curve_edges.size(), alone.merged_curve_edges.size());
  EXPECT_EQ(twice.curve_loops, alone.curve_loops);
  EXPECT_EQ(check(twice.merged).non_manifold_edges, twice.merged_curve_edges.size());
}

TEST(Split, BoxesOverlappingInPlanesMeetAlongTheOverlapsOutline) {
  // A box and the same box moved by half its width: four of their sides
  // overlap in a plane, and the end faces of each cross the other box.
  // Merged, each overlap is there once; the curves are the outlines where
  // the surfaces part (non-manifold edges), closed, without end points.
  const Mesh a = gridCube(2), b = moved(gridCube(2), {0.5, 0, 0});
  SplitOptions once;
  once.overlaps_once = true;
  const SplitResult r = splitAlongIntersections({&a, &b}, once);
  EXPECT_GT(r.coincident_faces_removed, 0u);
  EXPECT_GT(r.curve_loops, 0u);
  EXPECT_EQ(r.open_curves, 0u);
  const InspectResult merged = check(r.merged);
  EXPECT_EQ(merged.duplicate_faces, 0u);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  EXPECT_EQ(merged.non_manifold_edges, r.merged_curve_edges.size());
  EXPECT_EQ(merged.border_edges, 0u);
}

TEST(Split, PlanarOverlapsKeptInEachPartAreNoCrossingsForTheFloatRepair) {
  // With each part keeping its copy of a planar overlap (overlaps_once off:
  // the separate outputs, the boolean filters), the merged output holds
  // faces with the same three vertices. They coincide however rounding
  // goes, so the float repair leaves them alone: no second split, nothing
  // split again, the same curves.
  const Mesh a = gridCube(2);
  for (const Mesh& b : {gridCube(2), moved(gridCube(2), {0.5, 0, 0})}) {
    SplitResult r = splitAlongIntersections({&a, &b});
    ASSERT_GT(r.coincident_faces, 0u);
    EXPECT_EQ(selfIntersectingPairs(r.merged), r.coincident_faces);  // as a checker counts them
    EXPECT_EQ(crossingsLeft(r, Scalar::kFloat), 0u);
    const std::size_t faces = r.merged.face.size(), curves = r.merged_curve_edges.size();
    const StoredOutput stored = storeAsFloat(r, {&a, &b}, SplitOptions{});
    EXPECT_EQ(stored.crossing, 0u);
    EXPECT_FALSE(stored.snapped_for_host);
    EXPECT_EQ(r.pairs_split_after_rounding, 0u);
    EXPECT_EQ(r.merged.face.size(), faces);
    EXPECT_EQ(r.merged_curve_edges.size(), curves);
    EXPECT_EQ(selfIntersectingPairs(r.merged), r.coincident_faces);
    for (std::size_t i = 0; i < 2; ++i) EXPECT_EQ(*check(r.meshes[i]).self_intersecting_pairs, 0u);
  }
}

// A merged output as rounding might leave it: every face new, one of them
// (the last) flat, its corner a = (1,0,0) between b = (0,0,0) and c = (2,0,0).
SplitResult withFlatFace(const std::vector<Triangle>& faces) {
  SplitResult r;
  const Mesh m = makeMesh({{1, 0, 0}, {0, 0, 0}, {2, 0, 0}, {1, -1, 0}, {1, 1, 0}}, faces);
  r.merged = m;
  r.merged_new_face.assign(faces.size(), 1);
  return r;
}

double areaOf(const Mesh& m) {
  double area = 0;
  for (const Face& f : m.face) area += ((f.cP(1) - f.cP(0)) ^ (f.cP(2) - f.cP(0))).Norm() / 2;
  return area;
}

TEST(Split, AFlatNewFaceIsFlippedIntoTheFaceBeyondItsLongSide) {
  // a = 0, b = 1, c = 2, d = 3 (below), e = 4 (above); the flat face
  // (a, b, c) lies between the faces above, along a-b and c-a, and the face
  // (c, b, d) below its long side.
  SplitResult r = withFlatFace({{1, 0, 4}, {0, 2, 4}, {2, 1, 3}, {0, 1, 2}});
  ASSERT_EQ(degenerateNewFaces(r), 1u);
  const double area = areaOf(r.merged);
  EXPECT_EQ(mendCollinearNewFaces(r), 1u);
  EXPECT_EQ(degenerateNewFaces(r), 0u);
  EXPECT_EQ(r.merged.face.size(), 4u);
  EXPECT_DOUBLE_EQ(areaOf(r.merged), area);
  const InspectResult i = check(r.merged);
  EXPECT_EQ(i.border_edges, 4u);  // b-e, e-c, c-d, d-b
  EXPECT_EQ(i.non_manifold_edges, 0u);
  EXPECT_TRUE(i.consistently_oriented);
  EXPECT_EQ(i.degenerate_faces, 0u);
}

TEST(Split, AFlatNewFaceFillingNoGapIsRemoved) {
  // The faces above and below already meet along a-b and c-a (a split put a
  // on both sides); the flat face (a, b, c) has nothing beyond its long side.
  SplitResult r = withFlatFace({{1, 0, 4}, {0, 2, 4}, {0, 1, 3}, {2, 0, 3}, {0, 1, 2}});
  ASSERT_EQ(check(r.merged).border_edges, 5u);  // the outline and the flat face's long side
  EXPECT_EQ(mendCollinearNewFaces(r), 1u);
  EXPECT_EQ(r.collapsed_faces_removed, 1u);
  EXPECT_EQ(r.merged.face.size(), 4u);
  EXPECT_EQ(r.merged_new_face.size(), 4u);
  EXPECT_EQ(faceOrigins(r.merged)[3].face, 3);  // provenance follows the faces kept
  const InspectResult i = check(r.merged);
  EXPECT_EQ(i.border_edges, 4u);
  EXPECT_EQ(i.non_manifold_edges, 0u);
  EXPECT_EQ(i.degenerate_faces, 0u);
  // A flat face whose removal would open the surface stays.
  SplitResult alone = withFlatFace({{1, 0, 4}, {0, 2, 4}, {0, 1, 2}});
  EXPECT_EQ(mendCollinearNewFaces(alone), 0u);
  EXPECT_EQ(alone.merged.face.size(), 3u);
}

TEST(Split, CurvesThatBranchWithoutEndingAreClosed) {
  // A cube and the same cube turned 45° about z (and scaled by 1.4, so
  // that its corners are exact doubles): their tops and bottoms overlap in
  // octagons, their sides cross along eight vertical lines. The curves
  // branch at the octagons' corners (three curve edges) and end nowhere:
  // one closed network.
  const Mesh a = moved(box(), {-0.5, -0.5, 0});
  Mesh b = a;
  for (Vertex& v : b.vert) {
    const Point3 p = v.cP();
    v.P() = Point3((p[0] - p[1]) * 0.7, (p[0] + p[1]) * 0.7, p[2]);
  }
  SplitOptions once;
  once.overlaps_once = true;
  const SplitResult r = splitAlongIntersections({&a, &b}, once);
  EXPECT_EQ(r.curve_loops, 1u);
  EXPECT_EQ(r.open_curves, 0u);
  const InspectResult merged = check(r.merged);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  EXPECT_EQ(merged.duplicate_faces, 0u);
  EXPECT_EQ(merged.non_manifold_edges, r.merged_curve_edges.size());
}

TEST(Split, TwoBoxesSharingOnlyAnEdgeMeetAlongAnOpenCurve) {
  const Mesh a = box(), b = moved(box(), {1, 1, 0});
  const SplitResult r = splitAlongIntersections({&a, &b});
  EXPECT_EQ(r.merged_curve_edges.size(), 1u);
  EXPECT_EQ(r.curve_loops, 0u);
  EXPECT_EQ(r.open_curves, 1u);  // its two ends are end points
}

// `m` with its coordinates turned round (x, y, z) -> (z, x, y), `times`
// times: a rotation, so orientation is kept.
Mesh cycled(const Mesh& m, int times) {
  Mesh out = m;
  for (Vertex& v : out.vert)
    for (int t = 0; t < times; ++t) {
      const Point3 p = v.cP();
      v.P() = Point3(p[2], p[0], p[1]);
    }
  return out;
}

TEST(Split, PointsAFloatStepApartAreMergedWhenAsked) {
  // Two unit spheres far from the origin (1e5 on every axis: a float step
  // is 1/128 there, an edge a seventh): rounded to float, curve points that
  // close to a vertex or an edge make faces cross or collapse, unless they
  // are merged first (snap_host_steps).
  const Point3 far(1e5, 1e5, 1e5);
  const Mesh a = moved(icosphere(3), far), b = moved(icosphere(3), far + Point3(0.7, 0.3, 0.2));
  SplitResult plain = splitAlongIntersections({&a, &b});
  const std::size_t plainLeft = roundAsFloat(plain);
  EXPECT_GT(plainLeft + degenerateNewFaces(plain), 0u);
  SplitOptions o;
  o.snap_host_steps = 8;
  o.host = Scalar::kFloat;
  SplitResult r = splitAlongIntersections({&a, &b}, o);
  EXPECT_GT(r.vertices_snapped + r.edges_snapped, 0u);
  EXPECT_EQ(roundAsFloat(r), 0u);
  EXPECT_EQ(degenerateNewFaces(r), 0u);
  const InspectResult merged = check(r.merged);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  EXPECT_EQ(merged.degenerate_faces, 0u);
  EXPECT_EQ(r.curve_loops, 1u);
  EXPECT_EQ(r.open_curves, 0u);
}

TEST(Split, CrossingsLeftByRoundingAreSplitAgain) {
  // Two capped tubes of one radius crossing at right angles touch where
  // their top lines cross: curve points there lie far closer than a float
  // step, and rounded to float some faces cross. Split again on the float
  // values, none is left and none collapses; provenance still leads to the
  // inputs, and the curves are the non-manifold edges.
  const Mesh tube = testing::cappedCylinder(24, 4, 0.5, 0.5, -1, 2);
  const Mesh a = cycled(tube, 1), b = cycled(tube, 2);
  SplitOptions o;
  o.snap_host_steps = 8;
  o.host = Scalar::kFloat;
  SplitResult r = splitAlongIntersections({&a, &b}, o);
  EXPECT_GT(roundAsFloat(r), 0u);  // the case this is about
  EXPECT_EQ(splitAgainAsFloat(r, {&a, &b}, o), 0u);
  EXPECT_GT(r.pairs_split_after_rounding, 0u);
  EXPECT_EQ(crossingsLeft(r, Scalar::kFloat), 0u);
  EXPECT_EQ(degenerateNewFaces(r), 0u);
  const InspectResult merged = check(r.merged);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  EXPECT_EQ(merged.degenerate_faces, 0u);
  EXPECT_EQ(merged.border_edges, 0u);
  EXPECT_EQ(merged.non_manifold_edges, r.merged_curve_edges.size());
  const Mesh* inputs[2] = {&a, &b};
  FaceOriginHandle fo = faceOrigins(r.merged);
  for (std::size_t f = 0; f < r.merged.face.size(); ++f) {
    ASSERT_TRUE(fo[f].layer == 0 || fo[f].layer == 1);
    ASSERT_LT(std::size_t(fo[f].face), inputs[fo[f].layer]->face.size());
  }
  VertexOriginHandle vo = vertexOrigins(r.merged);
  for (std::size_t v = 0; v < r.merged.vert.size(); ++v) {
    const VertexOrigin o = vo[v];
    ASSERT_TRUE(o.layer == 0 || o.layer == 1);
    const Mesh& in = *inputs[o.layer];
    Point3 expected;
    if (o.vertex >= 0) {
      expected = in.vert[o.vertex].cP();
    } else {
      const Face& f = in.face[o.face];
      expected =
          f.cP(0) * o.barycentric[0] + f.cP(1) * o.barycentric[1] + f.cP(2) * o.barycentric[2];
    }
    EXPECT_LT(Distance(r.merged.vert[v].cP(), expected), 1e-6) << "vertex " << v;
  }
  // Each input vertex's place in the merged output is where it is.
  for (int m = 0; m < 2; ++m)
    for (std::size_t v = 0; v < inputs[m]->vert.size(); ++v)
      EXPECT_LT(Distance(r.merged.vert[r.merged_vertex[m][v]].cP(), inputs[m]->vert[v].cP()), 1e-6);
}

TEST(Split, SurfacesAFewFloatStepsApartGetQualitySnappingForTheFloatResult) {
  // A sphere and its copy moved along x by a millionth of its size: the
  // curves run where the surface turns parallel to x, their points crowd
  // within float steps of each other and of the edges, and rounding them,
  // merging those a few float steps apart and splitting again leave
  // crossings. The float repair then tries quality snapping, which does
  // not leave any (nor a collapsed face); the user asked for none.
  const Mesh a = uvSphere(24, 36), b = moved(a, {2e-6, 0, 0});
  SplitOptions o;
  o.separate_meshes = false;
  SplitResult r = splitAlongIntersections({&a, &b}, o);
  ASSERT_GT(r.intersecting_pairs, 0u);
  const StoredOutput stored = storeAsFloat(r, {&a, &b}, o);
  EXPECT_TRUE(stored.quality_snapped_for_host);
  EXPECT_TRUE(stored.snapped_for_host);
  EXPECT_GT(r.vertices_snapped + r.edges_snapped, 0u);
  EXPECT_EQ(stored.crossing, 0u);
  EXPECT_EQ(crossingsLeft(r, Scalar::kFloat), 0u);
  EXPECT_EQ(degenerateNewFaces(r), 0u);
  EXPECT_EQ(r.curve_loops, 1u);
  EXPECT_EQ(r.open_curves, 0u);
  // With quality snapping asked for, the split is the user's as asked.
  SplitOptions asked = o;
  asked.snap_tolerance = 0.01;
  SplitResult s = splitAlongIntersections({&a, &b}, asked);
  EXPECT_FALSE(storeAsFloat(s, {&a, &b}, asked).quality_snapped_for_host);
}

TEST(Split, SeparateOutputsFollowTheSplitAfterRounding) {
  // The tubes above, kept as separate outputs: what the float host stores
  // is each input's own mesh, so the repair of the merged output must reach
  // them. Each is the merged output's faces of its input, vertex for vertex,
  // its input vertices first in their places, and crosses nothing itself.
  const Mesh tube = testing::cappedCylinder(24, 4, 0.5, 0.5, -1, 2);
  const Mesh a = cycled(tube, 1), b = cycled(tube, 2);
  SplitOptions o;
  o.separate_meshes = true;
  SplitResult r = splitAlongIntersections({&a, &b}, o);
  const StoredOutput stored = storeAsFloat(r, {&a, &b}, o);
  EXPECT_GT(r.pairs_split_after_rounding, 0u);  // the repair ran
  EXPECT_EQ(stored.crossing, 0u);
  ASSERT_EQ(r.meshes.size(), 2u);
  FaceOriginHandle fo = faceOrigins(r.merged);
  const Mesh* inputs[2] = {&a, &b};
  for (int m = 0; m < 2; ++m) {
    SCOPED_TRACE(m);
    const Mesh& mesh = r.meshes[m];
    ASSERT_EQ(r.merged_vertex[m].size(), mesh.vert.size());
    for (std::size_t v = 0; v < inputs[m]->vert.size(); ++v)
      EXPECT_LT(Distance(mesh.vert[v].cP(), inputs[m]->vert[v].cP()), 1e-6);
    std::multiset<std::array<int, 3>> here, there;
    for (const Face& f : mesh.face) {
      std::array<int, 3> t;
      for (int k = 0; k < 3; ++k) {
        const int v = int(vcg::tri::Index(mesh, f.cV(k)));
        t[k] = r.merged_vertex[m][v];
        EXPECT_EQ(mesh.vert[v].cP(), r.merged.vert[t[k]].cP());
      }
      here.insert(t);
    }
    for (std::size_t f = 0; f < r.merged.face.size(); ++f)
      if (fo[f].layer == m)
        there.insert({int(vcg::tri::Index(r.merged, r.merged.face[f].cV(0))),
                      int(vcg::tri::Index(r.merged, r.merged.face[f].cV(1))),
                      int(vcg::tri::Index(r.merged, r.merged.face[f].cV(2)))});
    EXPECT_EQ(here, there);
    const InspectResult i = check(mesh);
    EXPECT_EQ(*i.self_intersecting_pairs, 0u);
    EXPECT_TRUE(i.is_closed);
    EXPECT_FALSE(r.curve_edges[m].empty());
  }
}

TEST(Split, TJunctionOfTwoCurvesInOneFace) {
  // Two thin plates cross a big triangle and each other: the curves meet at
  // a point inside the triangle (a curve ending on another).
  const Mesh big = makeMesh({{-4, -4, 0}, {4, -4, 0}, {0, 4, 0}}, {{0, 1, 2}});
  const Mesh plateX = makeMesh({{-1, 0, -1}, {1, 0, -1}, {0, 0, 1}}, {{0, 1, 2}});
  const Mesh plateY = makeMesh({{0, -1, -1}, {0, 1, -1}, {0, 0.5, 1}}, {{0, 1, 2}});
  const SplitResult r = splitAlongIntersections({&big, &plateX, &plateY});
  EXPECT_EQ(r.intersecting_pairs, 3u);
  EXPECT_EQ(r.faces_split, 3u);
  EXPECT_EQ(crossingsLeft(r, Scalar::kDouble), 0u);
}

TEST(Split, DuplicateFacesAreRemovedFirst) {
  // The same face twice (opposite orientations) crossed by a plate.
  const Mesh sheet = makeMesh({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}, {{0, 1, 2}, {0, 2, 1}});
  const Mesh plate = makeMesh({{1, 1, -1}, {1, 1, 1}, {3, 0.5, 0}}, {{0, 1, 2}});
  SplitOptions keep;
  const SplitResult kept = splitAlongIntersections({&sheet, &plate}, keep);
  // The duplicate intersects its twin (a self-intersection checker counts
  // the pair); no split or rounding changes that, so it is no crossing left.
  EXPECT_GT(selfIntersectingPairs(kept.merged), 0u);
  EXPECT_EQ(crossingsLeft(kept, Scalar::kDouble), 0u);
  SplitOptions remove;
  remove.remove_duplicate_faces = true;
  SplitResult r = splitAlongIntersections({&sheet, &plate}, remove);
  EXPECT_EQ(r.duplicate_faces_removed, 1u);
  EXPECT_EQ(crossingsLeft(r, Scalar::kDouble), 0u);
  FaceOriginHandle birth = faceOrigins(r.meshes[0]);
  for (std::size_t f = 0; f < r.meshes[0].face.size(); ++f)
    EXPECT_EQ(birth[f].face, 0);  // the first of the two stays, and its pieces say so
}

TEST(Split, DuplicateFacesAreFoundAmongFacesSharingTheirSmallestCorner) {
  // A fan around vertex 0 with the first face three times and the second
  // twice, in other orders and orientations; a far plate to split against.
  const Mesh fan = makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 1, 0}},
                            {{0, 1, 2}, {0, 2, 3}, {2, 1, 0}, {0, 3, 4}, {3, 0, 2}, {1, 0, 2}});
  const Mesh plate = makeMesh({{5, 5, 5}, {6, 5, 5}, {5, 6, 5}}, {{0, 1, 2}});
  SplitOptions o;
  o.remove_duplicate_faces = true;
  SplitResult r = splitAlongIntersections({&fan, &plate}, o);
  EXPECT_EQ(r.duplicate_faces_removed, 3u);
  ASSERT_EQ(r.meshes[0].face.size(), 3u);
  FaceOriginHandle birth = faceOrigins(r.meshes[0]);
  std::vector<int> kept;
  for (std::size_t f = 0; f < 3; ++f) kept.push_back(birth[f].face);
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(kept, (std::vector<int>{0, 1, 3}));  // the first of each group
}

TEST(Split, NoIntersectionLeavesTheMeshes) {
  const Mesh a = box(), b = moved(box(), {5, 0, 0});
  const SplitResult r = splitAlongIntersections({&a, &b});
  EXPECT_EQ(r.intersecting_pairs, 0u);
  EXPECT_EQ(r.faces_split, 0u);
  EXPECT_EQ(trianglesOf(r.meshes[0]), trianglesOf(a));
}

TEST(Split, WithoutTheMergedOutputEachMeshIsTheSame) {
  // Three spheres (their curves cross each other), with and without
  // snapping, and a pair large enough that the meshes are built on a second
  // thread: without the merged output, each mesh, its curve edges and the
  // counts are exactly those of the default run, and `merged` is empty.
  const Mesh a = uvSphere(24, 32), b = uvSphere(40, 52, 0.8, {0.5, 0.31, 0.011}),
             c = uvSphere(20, 28, 0.7, {0.2, 0.6, 0.05}), large = uvSphere(180, 200),
             near = uvSphere(30, 40, 0.5, {0.9, 0.2, 0.1});
  const std::vector<std::vector<const Mesh*>> cases{{&a, &b, &c}, {&a, &b, &c}, {&large, &near}};
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(i);
    SplitOptions withMerged;
    withMerged.snap_tolerance = i == 1 ? 0.1 : 0;
    SplitOptions separateOnly = withMerged;
    separateOnly.merged_output = false;
    const SplitResult full = splitAlongIntersections(cases[i], withMerged);
    SplitResult r = splitAlongIntersections(cases[i], separateOnly);
    EXPECT_EQ(r.merged.vn, 0);
    EXPECT_EQ(r.merged.fn, 0);
    EXPECT_TRUE(r.merged_curve_edges.empty());
    EXPECT_TRUE(r.merged_vertex.empty());
    EXPECT_TRUE(r.merged_new_face.empty());
    ASSERT_EQ(r.meshes.size(), cases[i].size());
    for (std::size_t m = 0; m < r.meshes.size(); ++m) {
      const Mesh& mesh = r.meshes[m];
      EXPECT_EQ(positionsOf(mesh), positionsOf(full.meshes[m]));
      EXPECT_EQ(trianglesOf(mesh), trianglesOf(full.meshes[m]));
      EXPECT_EQ(mesh.vn, int(mesh.vert.size()));
      EXPECT_EQ(mesh.fn, int(mesh.face.size()));
      EXPECT_EQ(r.curve_edges[m], full.curve_edges[m]);
      VertexOriginHandle origin = vertexOrigins(r.meshes[m]);
      VertexOriginHandle fullOrigin = vertexOrigins(const_cast<Mesh&>(full.meshes[m]));
      for (std::size_t v = 0; v < mesh.vert.size(); ++v) {
        EXPECT_EQ(origin[v].layer, fullOrigin[v].layer);
        EXPECT_EQ(origin[v].vertex, fullOrigin[v].vertex);
        EXPECT_EQ(origin[v].face, fullOrigin[v].face);
        EXPECT_EQ(origin[v].barycentric, fullOrigin[v].barycentric);
      }
      FaceOriginHandle birth = faceOrigins(r.meshes[m]);
      FaceOriginHandle fullBirth = faceOrigins(const_cast<Mesh&>(full.meshes[m]));
      for (std::size_t f = 0; f < mesh.face.size(); ++f) {
        EXPECT_EQ(birth[f].layer, fullBirth[f].layer);
        EXPECT_EQ(birth[f].face, fullBirth[f].face);
      }
    }
    EXPECT_GT(full.faces_split, 0u);
    EXPECT_EQ(r.curve_edges_welded, full.merged_curve_edges.size());
    EXPECT_EQ(r.curve_loops, full.curve_loops);
    EXPECT_EQ(r.open_curves, full.open_curves);
    EXPECT_EQ(r.faces_split, full.faces_split);
    EXPECT_EQ(r.new_faces_below_1deg, full.new_faces_below_1deg);
    EXPECT_EQ(r.vertices_snapped, full.vertices_snapped);
    EXPECT_EQ(toJson(r).str(), toJson(full).set("time_ms", r.time_ms).str());
    // Rounding and the check need the merged output.
    EXPECT_THROW(roundAsFloat(r), InvalidInputError);
    EXPECT_THROW(crossingsLeft(r, Scalar::kFloat), InvalidInputError);
    EXPECT_THROW(splitAgainAsFloat(r, {&a, &b}, SplitOptions{}), InvalidInputError);
  }
  SplitOptions none;
  none.separate_meshes = none.merged_output = false;
  EXPECT_THROW(splitAlongIntersections({&a, &b}, none), InvalidInputError);
}

TEST(Split, BadInput) {
  const Mesh empty, a = box();
  EXPECT_THROW(splitAlongIntersections({&a, &empty}), InvalidInputError);
}

}  // namespace
}  // namespace meshmend
