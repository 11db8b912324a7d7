#include "common/repair/selfintersect/selfintersect.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/patches/patch_ops.h"
#include "common/repair/patches/patches.h"
#include "common/repair/split/split.h"
#include "tests/mesh_builders.h"
#include "tests/robustness_builders.h"

using namespace meshmend;
using namespace meshmend::testing;

namespace {

// Both meshes in one layer (two components).
Mesh together(const Mesh& a, const Mesh& b) {
  return appended(a, b);
}

// A closed tube of radius r swept along a helix of radius R around the z
// axis, rising by `rise` per turn, over `degrees`, capped at both ends: past
// one turn its end lies over its start, and overlaps it once r > rise / 2.
Mesh bentTube(double R, double r, double degrees, double rise = 0.3, int along = 64,
              int tube = 20) {
  std::vector<Point3> p;
  for (int i = 0; i <= along; ++i)
    for (int j = 0; j < tube; ++j) {
      const double u = degrees * M_PI / 180 * i / along, v = 2 * M_PI * j / tube;
      p.emplace_back((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                     r * std::sin(v) + rise * u / (2 * M_PI));
    }
  const int start = int(p.size());
  p.emplace_back(R, 0, 0);
  const double end = degrees * M_PI / 180;
  p.emplace_back(R * std::cos(end), R * std::sin(end), rise * end / (2 * M_PI));
  auto at = [&](int i, int j) { return i * tube + (j % tube); };
  std::vector<Triangle> t;
  for (int i = 0; i < along; ++i)
    for (int j = 0; j < tube; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  for (int j = 0; j < tube; ++j) {
    t.push_back({start, at(0, j), at(0, j + 1)});
    t.push_back({start + 1, at(along, j + 1), at(along, j)});
  }
  return makeMesh(p, t);
}

Mesh turnedOver(const Mesh& m) {
  std::vector<Triangle> t = trianglesOf(m);
  for (Triangle& f : t) std::swap(f[1], f[2]);
  return makeMesh(positionsOf(m), t);
}

// The union by the other road: split both, keep the patches whose winding
// numbers say they bound the union (patches.h), weld.
double unionVolumeByWindingNumbers(const Mesh& a, const Mesh& b) {
  SplitOptions so;
  so.separate_meshes = false;
  SplitResult split = splitAlongIntersections({&a, &b}, so);
  const FaceLabels labels = mergedOutputLabels(split);
  Patches patches = paintPatches(split.merged, labels);
  classifyPatches(split.merged, labels, patches);
  const PatchChoice choice = choosePatches(patches, BooleanOperation::kUnion);
  return volumeOf(extractPatches(split.merged, patches, choice.keep));
}

// What every result must be: no intersecting pair (exact), edge-manifold,
// closed when the input was.
void expectValid(const SelfIntersectionResult& r) {
  EXPECT_EQ(selfIntersectingPairs(r.mesh), 0u) << toJson(r).str();
  EXPECT_EQ(r.remaining_intersecting_pairs, 0u);
  EXPECT_EQ(r.non_manifold_edges_after, 0u);
  if (r.input_closed) {
    EXPECT_TRUE(r.output_closed);
  }
  EXPECT_EQ(r.faces_kept + r.faces_removed, r.faces_after_split);
}

}  // namespace

TEST(RemoveSelfIntersections, ValidMeshIsReturnedUnchanged) {
  const Mesh sphere = uvSphere(16, 24);
  const SelfIntersectionResult r = removeSelfIntersections(sphere);
  expectValid(r);
  EXPECT_EQ(r.intersecting_pairs_before, 0u);
  EXPECT_EQ(r.faces_removed, 0u);
  EXPECT_TRUE(r.unchanged);  // nothing to remove: the input as it was
  EXPECT_TRUE(r.contract_met);
  EXPECT_EQ(r.mesh.fn, sphere.fn);
  EXPECT_EQ(r.components_after, 1);
  EXPECT_EQ(r.genus_after, 0);
  EXPECT_NEAR(volumeOf(r.mesh), volumeOf(sphere), 1e-12);
}

TEST(RemoveSelfIntersections, OverlappingSpheresMergeIntoOne) {
  const Mesh a = uvSphere(24, 32), b = uvSphere(24, 32, 0.8, {0.9, 0.2, 0.1});
  const SelfIntersectionResult r = removeSelfIntersections(together(a, b));
  expectValid(r);
  EXPECT_GT(r.intersecting_pairs_before, 0u);
  EXPECT_EQ(r.components_before, 2);
  EXPECT_EQ(r.components_after, 1);
  EXPECT_EQ(r.genus_after, 0);
  EXPECT_NEAR(volumeOf(r.mesh), unionVolumeByWindingNumbers(a, b),
              1e-3);  // snapping moves the curves a little
  EXPECT_LT(volumeOf(r.mesh), volumeOf(a) + volumeOf(b));
}

TEST(RemoveSelfIntersections, SphereInsideASphereGoes) {
  const Mesh outer = uvSphere(16, 24), inner = uvSphere(8, 12, 0.3, {0.1, 0, 0});
  const SelfIntersectionResult r = removeSelfIntersections(together(outer, inner));
  expectValid(r);
  EXPECT_EQ(r.components_before, 2);
  EXPECT_EQ(r.components_after, 1);
  EXPECT_EQ(r.mesh.fn, outer.fn);
}

TEST(RemoveSelfIntersections, HollowPartKeepsItsInnerWall) {
  // A cavity is a sphere turned inwards: in front of it is empty space.
  const Mesh outer = uvSphere(16, 24), cavity = turnedOver(uvSphere(8, 12, 0.3));
  const SelfIntersectionResult r = removeSelfIntersections(together(outer, cavity));
  expectValid(r);
  EXPECT_EQ(r.components_after, 2);
  EXPECT_NEAR(volumeOf(r.mesh), volumeOf(outer) + volumeOf(cavity), 1e-12);
}

TEST(RemoveSelfIntersections, TorusWhoseHoleIsPinchedGetsTwoHoles) {
  // The left half of a torus (hole radius 0.3) pushed right across the hole
  // near y = 0, where its inner wall passes through the right inner wall:
  // the hole closes in the middle and two holes remain (genus 1 -> 2).
  std::vector<Point3> p = positionsOf(torusOf(1, 0.7, 48, 24));
  for (Point3& q : p) {
    const double blend = std::clamp((0.3 - q[0]) / 0.6, 0.0, 1.0);
    q[0] += 0.75 * blend * std::exp(-q[1] * q[1] / 0.16);
  }
  const Mesh closing = makeMesh(p, trianglesOf(torusOf(1, 0.7, 48, 24)));
  const SelfIntersectionResult r = removeSelfIntersections(closing);
  expectValid(r);
  EXPECT_GT(r.intersecting_pairs_before, 0u);
  EXPECT_EQ(r.genus_before, 1);
  EXPECT_EQ(r.components_after, 1);
  EXPECT_EQ(r.genus_after, 2);
  EXPECT_GT(r.faces_removed, 0u);
  EXPECT_LT(volumeOf(r.mesh), volumeOf(closing));  // the overlap counts once
}

TEST(RemoveSelfIntersections, TorusWhoseHoleClosesBecomesASphere) {
  // Both inner walls squeezed towards the axis (x -> x - 0.75 tanh(x / 0.05)
  // near the hole), strongly enough that near the hole's ends the surface
  // folds over itself: the walls pass through each other along the whole
  // hole, which closes (genus 1 -> 0).
  std::vector<Point3> p = positionsOf(torusOf(1, 0.45, 96, 24));
  for (Point3& q : p) q[0] -= 0.75 * std::tanh(q[0] / 0.05) * std::exp(-q[1] * q[1] / 0.3);
  const Mesh closing = makeMesh(p, trianglesOf(torusOf(1, 0.45, 96, 24)));
  const SelfIntersectionResult r = removeSelfIntersections(closing);
  expectValid(r);
  EXPECT_GT(r.intersecting_pairs_before, 0u);
  EXPECT_EQ(r.genus_before, 1);
  EXPECT_EQ(r.components_after, 1);
  EXPECT_EQ(r.genus_after, 0);
}

TEST(RemoveSelfIntersections, InflatedPartThatTouchesItselfCloses) {
  // A coiled tube whose end lies over its start: thin, it passes by; once
  // inflated the end and start overlap and the ring closes (genus 0 -> 1).
  const Mesh thin = bentTube(1, 0.1, 420);
  EXPECT_EQ(removeSelfIntersections(thin).intersecting_pairs_before, 0u);
  const SelfIntersectionResult r = removeSelfIntersections(bentTube(1, 0.25, 420));
  expectValid(r);
  EXPECT_GT(r.intersecting_pairs_before, 0u);
  EXPECT_EQ(r.genus_before, 0);
  EXPECT_EQ(r.components_after, 1);
  EXPECT_EQ(r.genus_after, 1);
}

TEST(RemoveSelfIntersections, SpherePushedThroughItselfKeepsTheOuterPart) {
  // The north cap pushed down through the south pole: the surface folds
  // through itself, and the part of the cap outside the sphere below is kept.
  Mesh sphere = uvSphere(24, 32);
  std::vector<Point3> p = positionsOf(sphere);
  for (Point3& q : p)
    if (q[2] > 0.3)
      q[2] -= 2.2 * (q[2] - 0.3) / 0.7 * std::sqrt(std::max(0.0, 1 - q[0] * q[0] - q[1] * q[1]));
  const Mesh pushed = makeMesh(p, trianglesOf(sphere));
  const SelfIntersectionResult r = removeSelfIntersections(pushed);
  expectValid(r);
  EXPECT_GT(r.intersecting_pairs_before, 0u);
  EXPECT_GT(r.faces_removed, 0u);
  EXPECT_GE(r.components_after, 1);
  EXPECT_GT(volumeOf(r.mesh), 0);
}

TEST(RemoveSelfIntersections, InsideOutMeshStaysInsideOut) {
  const Mesh a = uvSphere(16, 24), b = uvSphere(16, 24, 0.8, {0.9, 0.2, 0.1});
  const SelfIntersectionResult r = removeSelfIntersections(turnedOver(together(a, b)));
  expectValid(r);
  EXPECT_TRUE(r.inside_out);
  EXPECT_EQ(r.components_after, 1);
  EXPECT_NEAR(volumeOf(r.mesh), -unionVolumeByWindingNumbers(a, b), 1e-3);
}

TEST(RemoveSelfIntersections, KeepsRemovedFacesWhenAsked) {
  SelfIntersectionOptions o;
  o.keep_removed = true;
  const SelfIntersectionResult r =
      removeSelfIntersections(together(box(), moved(box(), {0.5, 0.5, 0.5})), o);
  expectValid(r);
  EXPECT_EQ(std::size_t(r.removed.fn), r.faces_removed);
  EXPECT_NEAR(volumeOf(r.mesh), 2 - 0.125, 1e-12);  // two unit cubes overlapping in 1/8
}

TEST(RemoveSelfIntersections, TouchingCubesAreSeparatedAtTheSharedEdge) {
  // Two cubes sharing one edge (a non-manifold edge of four faces).
  std::vector<Point3> p = positionsOf(box());
  std::vector<Triangle> t = trianglesOf(box());
  const Mesh second = moved(box(), {1, 1, 0});
  const int offset = int(p.size());
  for (const Point3& q : positionsOf(second)) p.push_back(q);
  for (Triangle f : trianglesOf(second)) {
    for (int& v : f) v += offset;
    t.push_back(f);
  }
  const SelfIntersectionResult r = removeSelfIntersections(makeMesh(p, t));
  EXPECT_EQ(r.non_manifold_edges_before, 1u);
  EXPECT_EQ(r.edges_duplicated, 1u);
  EXPECT_EQ(r.components_after, 2);
  EXPECT_GT(r.vertices_separated, 0u);
  expectValid(r);

  // Left where they are, the copies touch: the contract does not hold, so
  // the removal refuses, or with keep_partial returns the result marked.
  SelfIntersectionOptions o;
  o.separate_touching = false;
  EXPECT_THROW(removeSelfIntersections(makeMesh(p, t), o), ContractError);
  o.keep_partial = true;
  const SelfIntersectionResult touching = removeSelfIntersections(makeMesh(p, t), o);
  EXPECT_FALSE(touching.contract_met);
  ASSERT_EQ(touching.contract_failures.size(), 1u);
  EXPECT_NE(touching.contract_failures[0].find("intersecting face pairs"), std::string::npos);
  EXPECT_EQ(touching.vertices_separated, 0u);
  EXPECT_GT(touching.remaining_intersecting_pairs, 0u);
  EXPECT_EQ(touching.remaining_intersecting_pairs, selfIntersectingPairs(touching.mesh, true));
}

TEST(RemoveSelfIntersections, PretreatmentCollapsesAZeroAreaFace) {
  // A sphere with a vertex m inserted on edge ab and the zero-area face
  // (a, m, b) closing the gap: closed, consistent, degenerate.
  const Mesh sphere = uvSphere(8, 12);
  std::vector<Point3> p = positionsOf(sphere);
  std::vector<Triangle> t = trianglesOf(sphere);
  const int a = t[20][0], b = t[20][1];
  const int m = int(p.size());
  p.push_back((p[a] + p[b]) / 2);
  for (Triangle& f : t)
    for (int i = 0; i < 3; ++i)
      if (f[i] == b && f[(i + 1) % 3] == a) {  // the neighbour across ab: split it at m
        const int d = f[(i + 2) % 3];
        f = {b, m, d};
        t.push_back({m, a, d});
        goto split;
      }
split:
  t.push_back({a, m, b});
  const Mesh degenerate = makeMesh(p, t);
  const SelfIntersectionResult r = removeSelfIntersections(degenerate);
  EXPECT_EQ(r.degenerate_faces_before, 1u);
  EXPECT_EQ(r.collapses + r.flips, 1u);
  EXPECT_EQ(r.degenerate_faces_left, 0u);
  EXPECT_EQ(r.faces_kept, std::size_t(sphere.fn));  // the growing saw the collapsed mesh
  // Nothing crosses and nothing is enclosed: nothing to remove, so the
  // result is the input as it was (its zero-area face is its own).
  EXPECT_TRUE(r.unchanged);
  EXPECT_EQ(r.mesh.fn, degenerate.fn);
  expectValid(r);
  SelfIntersectionOptions off;
  off.pretreat = false;
  EXPECT_EQ(removeSelfIntersections(degenerate, off).degenerate_faces_left, 1u);
}

TEST(RemoveSelfIntersections, OpenMeshKeepsItsBorders) {
  // A box without its top, overlapping a whole box.
  Mesh open = box();
  std::vector<Triangle> t = trianglesOf(open);
  t.erase(t.begin() + 2, t.begin() + 4);  // faces 2, 3: the top (z = 1)
  const Mesh cup = makeMesh(positionsOf(open), t);
  const SelfIntersectionResult r =
      removeSelfIntersections(together(cup, moved(box(), {0.5, 0.5, -0.5})));
  expectValid(r);
  EXPECT_FALSE(r.input_closed);
  EXPECT_EQ(r.border_edges_before, 4u);  // the cup's rim, which the box does not reach
  EXPECT_EQ(r.border_edges_after, 4u);
}

TEST(RemoveSelfIntersections, RejectsBadInput) {
  EXPECT_THROW(removeSelfIntersections(Mesh()), InvalidInputError);
  std::vector<Point3> p = positionsOf(box());
  p[3][0] = NAN;
  EXPECT_THROW(removeSelfIntersections(makeMesh(p, trianglesOf(box()))), InvalidInputError);
  std::vector<Triangle> t = trianglesOf(box());
  std::swap(t[0][1], t[0][2]);  // one face turned over
  try {
    removeSelfIntersections(makeMesh(positionsOf(box()), t));
    FAIL() << "an inconsistently oriented mesh was accepted";
  } catch (const TopologyError& e) {
    EXPECT_NE(std::string(e.what()).find("Re-Orient all faces coherently"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("MeshMend: Close Gaps Between Borders"),
              std::string::npos);
  }
  SelfIntersectionOptions o;
  o.degenerate_angle_deg = -1;
  EXPECT_THROW(removeSelfIntersections(box(), o), InvalidInputError);
}

TEST(RemoveSelfIntersections, ReportHasTheDocumentedKeys) {
  const std::string json =
      toJson(removeSelfIntersections(together(box(), moved(box(), {0.5, 0.5, 0.5})))).str();
  for (const char* key : {"faces_kept", "faces_removed", "components_before", "components_after",
                          "remaining_intersecting_pairs", "time_ms", "genus_before", "genus_after"})
    EXPECT_NE(json.find(std::string("\"") + key + "\""), std::string::npos) << key;
}

// ---- Contract, work bounds, cancellation -------------------------------------

// The contract, checked here independently of the removal's own check:
// inspect() counts what meshcheck counts.
void expectContract(const SelfIntersectionResult& r, bool asFloat) {
  ASSERT_GT(r.mesh.fn, 0);
  const InspectResult shape = inspect(r.mesh);
  EXPECT_EQ(selfIntersectingPairs(r.mesh, asFloat), 0u);
  EXPECT_EQ(shape.non_manifold_edges, 0u);
  EXPECT_EQ(shape.non_manifold_vertices, 0u);
  EXPECT_EQ(shape.orientation_inconsistent_edges, 0u);
  if (r.input_closed && r.fin_edges_before == 0) {
    EXPECT_EQ(shape.border_edges, 0u);
  }
  EXPECT_TRUE(r.contract_met);
  EXPECT_TRUE(r.contract_failures.empty());
}

TEST(RemoveSelfIntersections, EveryGeneratedClassIsValidOrRefusedCleanly) {
  // Coordinates from 1e-30 to near FLT_MAX, coplanar contact, non-manifold
  // and inconsistently oriented exports, soups with T-junctions, walls with
  // holes, spindle and self-touching tori, an OpenSCAD-like export: in
  // double and as a float host stores it, each result meets the contract
  // or the removal throws one of the core's typed errors (the plugin then
  // leaves the layer unchanged).
  for (const auto& [name, mesh] : robustnessClasses())
    for (bool asFloat : {false, true}) {
      SCOPED_TRACE(name + (asFloat ? " (float)" : " (double)"));
      SelfIntersectionOptions o;
      o.round_to_float = asFloat;
      try {
        expectContract(removeSelfIntersections(mesh, o), asFloat);
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()), "");
      }
    }
}

TEST(RemoveSelfIntersections, ClassesThatMustComeOutValid) {
  // These have an outer surface the removal finds: no refusal allowed. (The
  // touching torus is not among them: its walls meet at a point where two
  // vertices nearly coincide and cross along two curves through it; the
  // removal leaves 3 pairs there and refuses, which the test above allows.)
  for (const auto& [name, mesh] : robustnessClasses()) {
    if (name != "tiny_1e-30" && name != "huge_1e37" && name != "part_in_flt_max_box" &&
        name != "stl_soup_t_junctions" && name != "wall_with_hole" &&
        name != "wall_with_open_hole" && name != "horn_torus")
      continue;
    SCOPED_TRACE(name);
    try {
      expectContract(removeSelfIntersections(mesh), false);
    } catch (const Error& e) {
      ADD_FAILURE() << e.what();
    }
  }
}

TEST(RemoveSelfIntersections, PartInsideAFltMaxBoxGoes) {
  // The box's corners at nearly +-FLT_MAX; the part inside does not touch it.
  const Mesh part = torusOf(1.0, 0.4, 32, 16);
  const Mesh box = boxAt({-0.99 * FLT_MAX, -0.99 * FLT_MAX, -0.99 * FLT_MAX},
                         {0.99 * FLT_MAX, 0.99 * FLT_MAX, 0.99 * FLT_MAX});
  SelfIntersectionOptions o;
  o.round_to_float = true;
  const SelfIntersectionResult r = removeSelfIntersections(combined({part, box}), o);
  expectContract(r, true);
  EXPECT_EQ(r.mesh.fn, 12);  // the box alone is the outer surface
}

TEST(RemoveSelfIntersections, InconsistentOrientationIsRefusedWithAMeshMendRemedy) {
  try {
    removeSelfIntersections(withFlippedFaces(box(), {0, 5}));
    FAIL() << "accepted";
  } catch (const TopologyError& e) {
    EXPECT_NE(std::string(e.what()).find("MeshMend: Close Gaps Between Borders"),
              std::string::npos);
  }
}

TEST(RemoveSelfIntersections, SpindleTorusStopsAtItsWorkBound) {
  // Every meridian passes through the two points where the tube meets the
  // axis: thousands of curve crossings per face there. The removal stops at
  // its bound on them, before cutting anything.
  for (bool asFloat : {false, true}) {
    SelfIntersectionOptions o;
    o.round_to_float = asFloat;
    try {
      removeSelfIntersections(torusOf(0.3, 1.0, 64, 32), o);
      FAIL() << "no bound reached";
    } catch (const WorkLimitError& e) {
      EXPECT_NE(std::string(e.what()).find("max_triple_points_per_face"), std::string::npos);
    }
  }
}

TEST(RemoveSelfIntersections, StopsAtItsBoundOnIntersectingPairs) {
  const Mesh two = together(uvSphere(16, 24), uvSphere(16, 24, 0.8, {0.9, 0.2, 0.1}));
  SelfIntersectionOptions o;
  o.max_intersecting_pairs = 10;
  try {
    removeSelfIntersections(two, o);
    FAIL() << "no bound reached";
  } catch (const WorkLimitError& e) {
    EXPECT_NE(std::string(e.what()).find("max_intersecting_pairs"), std::string::npos);
  }
  o.max_intersecting_pairs = 0;  // no bound
  expectContract(removeSelfIntersections(two, o), false);
}

TEST(RemoveSelfIntersections, CancelsAtEveryProgressReport) {
  // Each report is a point where the user may cancel: asked to stop at the
  // n-th report, for every n, the removal throws CancelledError.
  const Mesh two = together(uvSphere(12, 16), uvSphere(12, 16, 0.8, {0.9, 0.2, 0.1}));
  int reports = 0;
  SelfIntersectionOptions o;
  o.progress = [&](int, const char*) { return ++reports, true; };
  removeSelfIntersections(two, o);
  ASSERT_GT(reports, 5);
  for (int stopAt = 1; stopAt <= reports; ++stopAt) {
    int seen = 0;
    o.progress = [&](int, const char*) { return ++seen < stopAt; };
    EXPECT_THROW(removeSelfIntersections(two, o), CancelledError) << "report " << stopAt;
  }
}

TEST(RemoveSelfIntersections, NothingEnclosedNothingCrossingIsUnchanged) {
  // Two separate spheres, nothing crossing, nothing inside: unchanged.
  const Mesh two = together(uvSphere(8, 12), uvSphere(8, 12, 1, {3, 0, 0}));
  const SelfIntersectionResult r = removeSelfIntersections(two);
  EXPECT_TRUE(r.unchanged);
  EXPECT_EQ(r.mesh.fn, two.fn);
  EXPECT_EQ(positionsOf(r.mesh), positionsOf(two));
  EXPECT_EQ(trianglesOf(r.mesh), trianglesOf(two));
  // An unwelded copy (an STL soup) touches at its seams: not "unchanged".
  const SelfIntersectionResult soup = removeSelfIntersections(soupOf(uvSphere(8, 12)));
  EXPECT_FALSE(soup.unchanged);
  expectContract(soup, false);
}
