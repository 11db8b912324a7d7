#include "common/repair/output_stage.h"

#include <gtest/gtest.h>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/repair/inspect/inspect.h"
#include "tests/mesh_builders.h"

namespace meshmend {
namespace {

using testing::cappedCylinder;
using testing::uvSphere;

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

// Two capped tubes of one radius crossing at right angles: their facets
// meet at angles of 1e-14 degrees where the tubes touch along their top and
// bottom lines (sines and cosines rounded to double), and the curve points
// there lie a few double steps apart.
struct Tubes {
  Mesh a, b;
  Tubes() {
    const Mesh tube = cappedCylinder(12, 2, 0.5, 0.5, -1, 2);
    a = cycled(tube, 1);
    b = cycled(tube, 2);
  }
  std::vector<const Mesh*> inputs() const { return {&a, &b}; }
};

InspectResult check(const Mesh& m, Scalar scalar) {
  Mesh stored = m;
  for (Vertex& v : stored.vert) v.P() = storedAs(v.cP(), scalar);
  InspectOptions o;
  o.self_intersections = true;
  return inspect(stored, o);
}

OutputStageOptions host(Scalar scalar) {
  OutputStageOptions stage;
  stage.scalar = scalar;
  return stage;
}

TEST(OutputStage, DoubleRoundingOfNearlyCoplanarFacetsIsRepaired) {
  const Tubes t;
  SplitOptions o;
  o.self = true;
  SplitResult r = splitAlongIntersections(t.inputs(), o);
  // The case this is about: the split's doubles, as computed, cross.
  ASSERT_GT(crossingsLeft(r, Scalar::kDouble), 0u);
  const StoredOutput stored = storeForHost(r, t.inputs(), o, host(Scalar::kDouble));
  EXPECT_EQ(stored.crossing, 0u);
  EXPECT_EQ(stored.degenerate_new_faces, 0u);
  EXPECT_TRUE(stored.explanation().empty());
  EXPECT_EQ(crossingsLeft(r, Scalar::kDouble), 0u);
  const InspectResult merged = check(r.merged, Scalar::kDouble);
  EXPECT_EQ(*merged.self_intersecting_pairs, 0u);
  EXPECT_EQ(merged.degenerate_faces, 0u);
  EXPECT_EQ(merged.border_edges, 0u);
  EXPECT_EQ(storedIntersectingPairs(r.merged, Scalar::kDouble), 0u);
  EXPECT_EQ(storedIntersectingPairs(r, stored, false), 0u);
  EXPECT_EQ(storedIntersectingPairs(r, stored, true), 0u);
  for (const Mesh& m : r.meshes) {  // each input's own output follows
    EXPECT_EQ(storedIntersectingPairs(m, Scalar::kDouble), 0u);
    EXPECT_TRUE(check(m, Scalar::kDouble).is_closed);
  }
}

TEST(OutputStage, FloatResultHoldsFloatsAndCrossesNothing) {
  const Tubes t;
  SplitOptions o;
  o.self = true;
  SplitResult r = splitAlongIntersections(t.inputs(), o);
  const StoredOutput stored = storeForHost(r, t.inputs(), o, host(Scalar::kFloat));
  EXPECT_EQ(stored.crossing, 0u);
  EXPECT_EQ(stored.degenerate_new_faces, 0u);
  for (const Vertex& v : r.merged.vert)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(v.cP()[k], double(float(v.cP()[k])));
  EXPECT_EQ(storedIntersectingPairs(r.merged, Scalar::kFloat), 0u);
  EXPECT_EQ(check(r.merged, Scalar::kFloat).degenerate_faces, 0u);
}

TEST(OutputStage, TakesTheSplitsArraysAndRepairsTheSameWithoutThem) {
  // The tubes as a float host holds them: only the new vertices move when
  // stored in float.
  Tubes t;
  for (Mesh* m : {&t.a, &t.b})
    for (Vertex& v : m->vert) v.P() = storedAs(v.cP(), Scalar::kFloat);
  SplitOptions o;
  o.self = true;
  SplitResult given = splitAlongIntersections(t.inputs(), o);
  EXPECT_EQ(given.merged_points, positionsOf(given.merged));
  EXPECT_EQ(given.merged_triangles, trianglesOf(given.merged));
  SplitResult copied = given;
  copied.merged_points.clear();
  copied.merged_triangles.clear();
  const StoredOutput sa = storeForHost(given, t.inputs(), o, host(Scalar::kFloat));
  const StoredOutput sb = storeForHost(copied, t.inputs(), o, host(Scalar::kFloat));
  EXPECT_TRUE(given.merged_points.empty());
  EXPECT_EQ(sa.crossing, 0u);
  EXPECT_EQ(sa.degenerate_new_faces, 0u);
  EXPECT_EQ(sa.crossing, sb.crossing);
  EXPECT_EQ(sa.vertices_rerounded, sb.vertices_rerounded);
  EXPECT_GT(sa.vertices_rerounded, 0u);  // rounding to nearest left crossings here
  EXPECT_EQ(positionsOf(given.merged), positionsOf(copied.merged));
  EXPECT_EQ(trianglesOf(given.merged), trianglesOf(copied.merged));
  EXPECT_EQ(storedIntersectingPairs(given.merged, Scalar::kFloat), 0u);
  // Arrays that no longer match `merged` are not used.
  SplitResult stale = splitAlongIntersections(t.inputs(), o);
  stale.merged_points.pop_back();
  stale.merged_triangles.pop_back();
  const StoredOutput s = storeForHost(stale, t.inputs(), o, host(Scalar::kDouble));
  EXPECT_EQ(s.crossing, 0u);
  EXPECT_EQ(storedIntersectingPairs(stale.merged, Scalar::kDouble), 0u);
}

TEST(OutputStage, FindsTheFacesNearTheNewOnesInTheSplitsTrees) {
  // The first tube with every third face twice (removed before the split,
  // so that the trees' faces are not numbered as the input's).
  Tubes t;
  std::vector<Triangle> twice;
  for (const Triangle& f : trianglesOf(t.a)) {
    twice.push_back(f);
    if (twice.size() % 3 == 0) twice.push_back(f);
  }
  t.a = makeMesh(positionsOf(t.a), twice);
  SplitOptions o;
  o.self = true;
  o.remove_duplicate_faces = true;
  SplitResult r = splitAlongIntersections(t.inputs(), o);
  ASSERT_GT(r.duplicate_faces_removed, 0u);
  ASSERT_EQ(r.input_face_trees.size(), 2u);
  const std::vector<Point3> P = positionsOf(r.merged);
  const std::vector<Triangle> T = trianglesOf(r.merged);
  const std::vector<char> changed = r.merged_new_face;
  SplitResult copy = r;
  const NearFaceFinder near = keptFacesNear(copy, T.size());
  ASSERT_TRUE(near);
  EXPECT_TRUE(copy.input_face_trees.empty() && copy.merged_face_origin.empty());
  // The same candidate pairs as a search over every face, some of them
  // with a face left as it was.
  const ChangedFaceSearch fromTrees(P, T, changed, 4, near), overAll(P, T, changed, 4);
  auto pairs = fromTrees.pairs(), all = overAll.pairs();
  std::sort(pairs.begin(), pairs.end());
  std::sort(all.begin(), all.end());
  EXPECT_EQ(pairs, all);
  std::size_t withKept = 0;
  for (const auto& p : pairs) withKept += !changed[p[0]] || !changed[p[1]];
  EXPECT_GT(withKept, 0u);
  for (std::size_t i = fromTrees.changedCount(); i < fromTrees.faces().size(); ++i)
    EXPECT_FALSE(changed[fromTrees.faces()[i]]);
  // Not without the trees (no self-intersections searched), nor when the
  // origins do not describe the faces.
  SplitOptions between;
  SplitResult noTrees = splitAlongIntersections(t.inputs(), between);
  EXPECT_TRUE(noTrees.input_face_trees.empty());
  EXPECT_FALSE(keptFacesNear(noTrees, noTrees.merged_triangles.size()));
  SplitResult changedAfter = r;
  changedAfter.merged_face_origin.pop_back();
  EXPECT_FALSE(keptFacesNear(changedAfter, T.size()));
  EXPECT_TRUE(changedAfter.input_face_trees.empty());
}

TEST(OutputStage, TheCheckersCountIncludesFacesWithTheSameThreeVertices) {
  // A box and its copy moved by half its width keep, each, their faces where
  // they overlap in a plane (overlaps_once off): no crossing for the stage,
  // one intersecting pair each for a checker (and for the report).
  const Mesh a = testing::gridCube(2), b = testing::moved(testing::gridCube(2), {0.5, 0, 0});
  SplitResult r = splitAlongIntersections({&a, &b});
  ASSERT_GT(r.coincident_faces, 0u);
  const StoredOutput stored = storeForHost(r, {&a, &b}, SplitOptions{}, host(Scalar::kDouble));
  EXPECT_EQ(stored.crossing, 0u);
  EXPECT_EQ(storedIntersectingPairs(r.merged, Scalar::kDouble), r.coincident_faces);
  EXPECT_EQ(storedIntersectingPairs(r.merged, Scalar::kDouble),
            *check(r.merged, Scalar::kDouble).self_intersecting_pairs);
  // Without a search (the split was complete): the same count.
  EXPECT_EQ(storedIntersectingPairs(r, stored, false), r.coincident_faces);
  EXPECT_EQ(storedIntersectingPairs(r, stored, true), 0u);  // each part on its own
  // Kept once, there is nothing to count.
  SplitOptions once;
  once.overlaps_once = true;
  SplitResult s = splitAlongIntersections({&a, &b}, once);
  storeForHost(s, {&a, &b}, once, host(Scalar::kDouble));
  EXPECT_EQ(storedIntersectingPairs(s.merged, Scalar::kDouble), 0u);
}

TEST(OutputStage, TheWorkBoundStopsTheRepairAndSaysSo) {
  const Tubes t;
  SplitOptions o;
  o.self = true;
  SplitResult r = splitAlongIntersections(t.inputs(), o);
  OutputStageOptions stage = host(Scalar::kDouble);
  stage.max_rounding_tests = 0;
  stage.max_pairs_split_again = 0;
  stage.resplit_with_snapping = false;
  const StoredOutput stored = storeForHost(r, t.inputs(), o, stage);
  EXPECT_TRUE(stored.bounded);
  EXPECT_GT(stored.crossing, 0u);
  EXPECT_EQ(stored.rounds_split_again, 0);
  EXPECT_EQ(stored.pairs_split_again, 0u);
  EXPECT_NE(stored.explanation().find("work bound"), std::string::npos);
  // What the report says is left is what is left, counted either way.
  EXPECT_EQ(stored.crossing, crossingsLeft(r, Scalar::kDouble));
  EXPECT_EQ(storedIntersectingPairs(r, stored, false),
            storedIntersectingPairs(r.merged, Scalar::kDouble));
  std::size_t each = 0;
  for (const Mesh& m : r.meshes) each += storedIntersectingPairs(m, Scalar::kDouble);
  EXPECT_EQ(storedIntersectingPairs(r, stored, true), each);
}

TEST(OutputStage, ProgressCanCancelIt) {
  const Tubes t;
  SplitOptions o;
  o.self = true;
  SplitResult r = splitAlongIntersections(t.inputs(), o);
  OutputStageOptions stage = host(Scalar::kDouble);
  int calls = 0;
  stage.progress = [&](int percent, const char*) {
    EXPECT_GE(percent, 95);
    return ++calls < 2;
  };
  EXPECT_THROW(storeForHost(r, t.inputs(), o, stage), CancelledError);
}

TEST(OutputStage, NothingToRepairLeavesTheDoubleResultAsComputed) {
  const Mesh a = uvSphere(12, 16), b = uvSphere(12, 16, 0.8, {0.6, 0.2, 0.1});
  SplitResult r = splitAlongIntersections({&a, &b});
  const std::vector<Point3> before = positionsOf(r.merged);
  const StoredOutput stored = storeForHost(r, {&a, &b}, SplitOptions{}, host(Scalar::kDouble));
  EXPECT_EQ(stored.crossing, 0u);
  EXPECT_EQ(stored.vertices_rerounded, 0u);
  EXPECT_FALSE(stored.snapped_for_host);
  EXPECT_EQ(positionsOf(r.merged), before);
}

TEST(OutputStage, NeedsTheMergedOutput) {
  const Mesh a = uvSphere(8, 8), b = uvSphere(8, 8, 0.8, {0.6, 0, 0});
  SplitOptions o;
  o.merged_output = false;
  SplitResult r = splitAlongIntersections({&a, &b}, o);
  EXPECT_THROW(storeForHost(r, {&a, &b}, o, host(Scalar::kDouble)), InvalidInputError);
}

}  // namespace
}  // namespace meshmend
