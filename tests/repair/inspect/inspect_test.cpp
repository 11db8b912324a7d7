#include "common/repair/inspect/inspect.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "common/base/errors.h"
#include "tests/mesh_builders.h"

namespace meshmend {
namespace {

using testing::box;
using testing::tetrahedron;
using testing::uvSphere;

TEST(Inspect, ClosedTetrahedronHasNoDefects) {
  const InspectResult r = inspect(tetrahedron());
  EXPECT_EQ(r.vertices, 4u);
  EXPECT_EQ(r.faces, 4u);
  EXPECT_EQ(r.edges, 6u);
  EXPECT_EQ(r.connected_components, 1u);
  EXPECT_EQ(r.border_edges, 0u);
  EXPECT_EQ(r.non_manifold_edges, 0u);
  EXPECT_EQ(r.non_manifold_vertices, 0u);
  EXPECT_TRUE(r.is_closed);
  EXPECT_TRUE(r.consistently_oriented);
  ASSERT_TRUE(r.volume.has_value());
  EXPECT_NEAR(*r.volume, 1.0 / 6.0, 1e-15);
  ASSERT_TRUE(r.genus.has_value());
  EXPECT_EQ(*r.genus, 0);
  EXPECT_EQ(r.euler_characteristic, 2);
}

TEST(Inspect, DetailOfAFewFloatStepsIsNamed) {
  // The unit tetrahedron: its shortest edge, 1, spans 2^23 float steps (and
  // 2^52 double steps) at coordinates up to 1.
  const InspectResult unit = inspect(tetrahedron());
  EXPECT_EQ(unit.max_abs_coordinate, 1.0);
  EXPECT_EQ(unit.shortest_edge, 1.0);
  EXPECT_EQ(unit.float_steps_in_shortest_edge, 8388608.0);
  EXPECT_EQ(unit.double_steps_in_shortest_edge, 4503599627370496.0);
  EXPECT_TRUE(precisionNote(unit).empty());
  EXPECT_EQ(toJson(unit).str().find("precision_note"), std::string::npos);
  // Shrunk to 1e-3 and moved to 1e4: a float step there is 2^-10, so the
  // edge spans about one step; a double step is 2^-39 (5.5e8 of them).
  std::vector<Point3> p = positionsOf(tetrahedron());
  for (Point3& q : p) q = q * 1e-3 + Point3(1e4, 1e4, 1e4);
  const InspectResult far = inspect(makeMesh(p, trianglesOf(tetrahedron())));
  EXPECT_NEAR(far.shortest_edge, 1e-3, 1e-12);
  EXPECT_NEAR(far.float_steps_in_shortest_edge, 1e-3 * 1024, 1e-6);
  EXPECT_NEAR(far.double_steps_in_shortest_edge, 1e-3 * 549755813888.0, 1);
  const std::string note = precisionNote(far);
  EXPECT_NE(note.find("double host"), std::string::npos) << note;
  EXPECT_NE(summarize(far).find(note), std::string::npos);
  EXPECT_NE(toJson(far).str().find("\"precision_note\": "), std::string::npos);
  // Past FLT_MAX a float holds no coordinate at all: 0 steps.
  for (Point3& q : p) q = q * 1e35;
  EXPECT_EQ(inspect(makeMesh(p, trianglesOf(tetrahedron()))).float_steps_in_shortest_edge, 0.0);
}

TEST(Inspect, CoordinatesSpanningTooMuchAreNamedAndNotCounted) {
  InspectOptions o;
  o.self_intersections = true;
  const Mesh wide = makeMesh({{1e-300, 0, 0}, {1e10, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const InspectResult r = inspect(wide, o);
  EXPECT_NEAR(r.coordinate_binades, std::log2(1e10) - std::log2(1e-300), 1e-9);
  EXPECT_FALSE(r.self_intersecting_pairs.has_value());
  EXPECT_NE(summarize(r).find("self-intersections are not counted"), std::string::npos);
  const InspectResult ok = inspect(testing::tetrahedron(), o);
  EXPECT_TRUE(ok.self_intersecting_pairs.has_value());
  EXPECT_EQ(summarize(ok).find("binades"), std::string::npos);
}

TEST(Inspect, SphereVolumeAndGenus) {
  const InspectResult r = inspect(uvSphere(24, 48));
  EXPECT_TRUE(r.is_closed);
  ASSERT_TRUE(r.volume);
  EXPECT_NEAR(*r.volume, 4.0 / 3.0 * M_PI, 0.05);
  EXPECT_EQ(*r.genus, 0);
}

TEST(Inspect, TwoBoxesAreTwoComponents) {
  Mesh a = box();
  const std::vector<Point3> p = positionsOf(a);
  std::vector<Triangle> t = trianglesOf(a);
  std::vector<Point3> p2 = p;
  for (const Point3& q : p) p2.push_back(q + Point3(3, 0, 0));
  for (const Triangle& f : trianglesOf(a)) t.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
  const InspectResult r = inspect(makeMesh(p2, t));
  EXPECT_EQ(r.connected_components, 2u);
  EXPECT_NEAR(*r.volume, 2.0, 1e-12);
  EXPECT_EQ(*r.genus, 0);
}

TEST(Inspect, FlippedFaceIsAnOrientationDefect) {
  std::vector<Triangle> t = trianglesOf(tetrahedron());
  std::swap(t[0][1], t[0][2]);
  const InspectResult r = inspect(makeMesh(positionsOf(tetrahedron()), t), {true});
  EXPECT_EQ(r.orientation_inconsistent_edges, 3u);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_FALSE(r.volume.has_value());
  EXPECT_TRUE(r.face_defects[0] & kFaceOrientationFlip);
}

TEST(Inspect, FinOnAnEdgeIsNonManifold) {
  std::vector<Point3> p = positionsOf(tetrahedron());
  p.emplace_back(1, 1, -1);
  std::vector<Triangle> t = trianglesOf(tetrahedron());
  t.push_back({0, 1, 4});  // a fifth face on edge (0,1)
  const InspectResult r = inspect(makeMesh(p, t), {true});
  EXPECT_EQ(r.non_manifold_edges, 1u);
  EXPECT_EQ(r.border_edges, 2u);
  EXPECT_EQ(r.border_loops, 1u);
  EXPECT_FALSE(r.volume.has_value());
  EXPECT_TRUE(r.face_defects[4] & kFaceOnNonManifoldEdge);
  EXPECT_TRUE(r.face_defects[4] & kFaceOnBorder);
}

TEST(Inspect, BowTieVertexIsNonManifold) {
  const InspectResult r = inspect(
      makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}}),
      {true});
  EXPECT_EQ(r.non_manifold_vertices, 1u);
  EXPECT_EQ(r.connected_components, 2u);  // a pinch vertex does not join
  EXPECT_EQ(r.border_edges, 6u);
  EXPECT_EQ(r.border_loops, 1u);  // border-edge components touch at the pinch
  EXPECT_EQ(r.vertex_defects[0], kVertexNonManifold | kVertexOnBorder);
}

TEST(Inspect, SoupDefectsAreCounted) {
  // Tetrahedron with a duplicate face, a collinear face, an unused point and
  // a point duplicating vertex 0.
  std::vector<Point3> p = positionsOf(tetrahedron());
  p.emplace_back(0.5, 0, 0);  // 4: on edge (0,1)
  p.emplace_back(5, 5, 5);    // 5: unused
  p.emplace_back(0, 0, 0);    // 6: duplicate of 0
  std::vector<Triangle> t = trianglesOf(tetrahedron());
  t.push_back({1, 2, 3});  // duplicate of face 3
  t.push_back({0, 4, 1});  // collinear
  t.push_back({6, 1, 2});  // repeated coordinates? no: 6 != 1,2; a real triangle
  t.push_back({2, 2, 3});  // repeated index
  const InspectResult r = inspect(makeMesh(p, t), {true});
  EXPECT_EQ(r.duplicate_faces, 1u);
  EXPECT_EQ(r.degenerate_faces, 2u);
  EXPECT_EQ(r.isolated_vertices, 1u);
  EXPECT_EQ(r.duplicate_points, 1u);
  EXPECT_TRUE(r.face_defects[4] & kFaceDuplicate);
  EXPECT_TRUE(r.face_defects[5] & kFaceDegenerate);
  EXPECT_TRUE(r.face_defects[7] & kFaceDegenerate);
  EXPECT_TRUE(r.vertex_defects[5] & kVertexIsolated);
  EXPECT_TRUE(r.vertex_defects[6] & kVertexDuplicate);
  EXPECT_FALSE(r.vertex_defects[0] & kVertexDuplicate);  // the first one is not the duplicate
}

// Without the measures (what the edit contracts ask for) the counts are
// those of the full inspection, and the measures are not made.
TEST(Inspect, CountsWithoutMeasuresAreTheSame) {
  std::vector<Point3> p = positionsOf(tetrahedron());
  p.emplace_back(0.5, 0, 0);  // 4: on edge (0,1)
  p.emplace_back(0, 0, 0);    // 5: duplicate of 0
  p.emplace_back(1, 1, -1);   // 6
  std::vector<Triangle> t = trianglesOf(tetrahedron());
  t.push_back({0, 4, 1});  // collinear
  t.push_back({0, 1, 6});  // a fin on edge (0,1)
  t.push_back({5, 2, 6});
  const Mesh mesh = makeMesh(p, t);
  InspectOptions counts;
  counts.measures = false;
  const InspectResult all = inspect(mesh), some = inspect(mesh, counts);
  EXPECT_GT(all.non_manifold_edges, 0u);
  EXPECT_GT(all.border_edges, 0u);
  EXPECT_EQ(all.degenerate_faces, 1u);
  EXPECT_EQ(all.duplicate_points, 1u);
  EXPECT_GT(all.mean_min_angle_deg, 0);
  EXPECT_EQ(some.non_manifold_edges, all.non_manifold_edges);
  EXPECT_EQ(some.non_manifold_vertices, all.non_manifold_vertices);
  EXPECT_EQ(some.orientation_inconsistent_edges, all.orientation_inconsistent_edges);
  EXPECT_EQ(some.border_edges, all.border_edges);
  EXPECT_EQ(some.connected_components, all.connected_components);
  EXPECT_EQ(some.degenerate_faces, all.degenerate_faces);
  EXPECT_EQ(some.duplicate_points, 0u);   // not looked for
  EXPECT_EQ(some.mean_min_angle_deg, 0);  // no angles measured
}

TEST(Inspect, NearlyCollinearFaceIsNotDegenerate) {
  // The third point is off the line by one unit in the last place: only an
  // exact test tells it apart from collinear.
  const double y = std::nextafter(0.0, 1.0);
  const InspectResult r = inspect(makeMesh({{0, 0, 0}, {1, 0, 0}, {0.5, y, 0}}, {{0, 1, 2}}));
  EXPECT_EQ(r.degenerate_faces, 0u);
  const InspectResult flat = inspect(makeMesh({{0, 0, 0}, {1, 0, 0}, {0.5, 0, 0}}, {{0, 1, 2}}));
  EXPECT_EQ(flat.degenerate_faces, 1u);
}

TEST(Inspect, OpenMeshHasBorderLoopsAndNoVolume) {
  std::vector<Triangle> t = trianglesOf(uvSphere(8, 12));
  t.erase(t.begin(), t.begin() + 12);  // remove the north cap fan: one hole of 12 edges
  t.erase(t.end() - 12, t.end());      // and the south one
  const InspectResult r = inspect(makeMesh(positionsOf(uvSphere(8, 12)), t));
  EXPECT_EQ(r.border_edges, 24u);
  EXPECT_EQ(r.border_loops, 2u);
  EXPECT_EQ(r.longest_border_loop, 12u);
  EXPECT_EQ(r.isolated_vertices, 2u);  // the two poles
  EXPECT_FALSE(r.is_closed);
  EXPECT_FALSE(r.volume.has_value());
  EXPECT_FALSE(r.genus.has_value());
}

TEST(Inspect, NonFiniteVerticesAreCountedNotFatal) {
  std::vector<Point3> p = positionsOf(tetrahedron());
  p[3][2] = std::numeric_limits<double>::quiet_NaN();
  const InspectResult r = inspect(makeMesh(p, trianglesOf(tetrahedron())), {true});
  EXPECT_EQ(r.non_finite_vertices, 1u);
  EXPECT_TRUE(r.vertex_defects[3] & kVertexNonFinite);
  EXPECT_TRUE(r.is_closed);            // topology is still known
  EXPECT_FALSE(r.volume.has_value());  // geometry is not
  EXPECT_EQ(r.degenerate_faces, 0u);
  EXPECT_EQ(r.bbox[5], 0.0);  // the box ignores the NaN vertex
  EXPECT_NE(summarize(r).find("1 vertices with NaN"), std::string::npos);
}

TEST(Inspect, CountsSelfIntersectionsWhenAsked) {
  // Two overlapping boxes in one mesh: 18 intersecting pairs on 12 faces.
  std::vector<Point3> p = positionsOf(box());
  std::vector<Triangle> t = trianglesOf(box());
  for (const Point3& q : positionsOf(box())) p.push_back(q + Point3(0.5, 0.5, 0.5));
  for (const Triangle& f : trianglesOf(box())) t.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
  const Mesh m = makeMesh(p, t);
  EXPECT_FALSE(inspect(m).self_intersecting_pairs.has_value());
  InspectOptions o;
  o.self_intersections = true;
  o.mark_defects = true;
  const InspectResult r = inspect(m, o);
  ASSERT_TRUE(r.self_intersecting_pairs.has_value());
  EXPECT_EQ(*r.self_intersecting_pairs, 18u);
  EXPECT_EQ(*r.self_intersecting_faces, 12u);
  int marked = 0;
  for (std::uint8_t d : r.face_defects) marked += (d & kFaceSelfIntersecting) != 0;
  EXPECT_EQ(marked, 12);
  EXPECT_NE(toJson(r).str().find("\"self_intersecting_pairs\": 18"), std::string::npos);
}

TEST(Inspect, EmptyMeshIsNotClosed) {
  const InspectResult r = inspect(Mesh());
  EXPECT_EQ(r.faces, 0u);
  EXPECT_FALSE(r.is_closed);
  EXPECT_EQ(r.connected_components, 0u);
}

TEST(Inspect, RejectsMeshWithDeletedElements) {
  Mesh m = tetrahedron();
  vcg::tri::Allocator<Mesh>::DeleteFace(m, m.face[0]);
  EXPECT_THROW(inspect(m), InvalidInputError);
}

TEST(Inspect, JsonUsesMeshcheckKeys) {
  const std::string json = toJson(inspect(tetrahedron())).str();
  for (const char* key :
       {"\"vertices\": 4", "\"faces\": 4", "\"connected_components\": 1", "\"border_edges\": 0",
        "\"border_loops\": 0", "\"non_manifold_edges\": 0", "\"non_manifold_vertices\": 0",
        "\"degenerate_faces\": 0", "\"duplicate_faces\": 0", "\"isolated_vertices\": 0",
        "\"is_closed\": true", "\"consistently_oriented\": true", "\"volume\": 0.1666666667",
        "\"time_ms\": "})
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing in " << json;
}

TEST(Inspect, SummaryNamesTheDefects) {
  std::vector<Triangle> t = trianglesOf(tetrahedron());
  t.pop_back();
  const std::string s = summarize(inspect(makeMesh(positionsOf(tetrahedron()), t)));
  EXPECT_NE(s.find("3 border edges in 1 loops"), std::string::npos) << s;
  EXPECT_NE(s.find("open"), std::string::npos) << s;
}

}  // namespace
}  // namespace meshmend
