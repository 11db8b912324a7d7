// The edit contract (common/edit_contract.h) of the filters that edit a
// mesh in place: only what the edit made is judged, each rule on its own.
#include "common/repair/edit_contract.h"

#include <gtest/gtest.h>

#include "common/base/errors.h"

#include <string>
#include <vector>

#include "tests/mesh_builders.h"

using namespace meshmend;
using namespace meshmend::testing;

namespace {

// The unit box without its top (z = 1): 10 faces, a square border.
struct OpenBox {
  std::vector<Point3> points = positionsOf(box());
  std::vector<Triangle> faces;
  OpenBox() {
    for (const Triangle& t : trianglesOf(box()))
      if (!(points[t[0]][2] == 1 && points[t[1]][2] == 1 && points[t[2]][2] == 1))
        faces.push_back(t);
  }
  Mesh mesh() const { return makeMesh(points, faces); }
  // The open box's faces, each its own origin, then `added` (origin none),
  // with `extra` points appended.
  Mesh with(const std::vector<Triangle>& added, const std::vector<Point3>& extra = {}) const {
    std::vector<Point3> p = points;
    p.insert(p.end(), extra.begin(), extra.end());
    std::vector<Triangle> t = faces;
    std::vector<FaceOrigin> fo;
    for (std::size_t f = 0; f < faces.size(); ++f) fo.push_back({0, int(f)});
    for (const Triangle& a : added) t.push_back(a), fo.push_back({-1, -1});
    std::vector<VertexOrigin> vo(p.size());
    Mesh m;
    buildMesh(m, p, t, vo, fo);
    return m;
  }
};

bool mentions(const EditContract& c, const std::string& what) {
  return describeFailures(c).find(what) != std::string::npos;
}

}  // namespace

TEST(EditContract, AnUnchangedMeshMeetsIt) {
  const OpenBox b;
  const EditContract c = checkEditContract(b.mesh(), b.mesh());
  EXPECT_TRUE(c.met) << describeFailures(c);
  EXPECT_EQ(c.changed_faces, 0u);
  EXPECT_EQ(c.intersecting_pairs, 0u);
}

TEST(EditContract, ClosingTheHoleRightMeetsIt) {
  const OpenBox b;
  const EditContract c = checkEditContract(b.mesh(), b.with({{4, 5, 6}, {5, 7, 6}}));
  EXPECT_TRUE(c.met) << describeFailures(c);
  EXPECT_EQ(c.changed_faces, 2u);
}

TEST(EditContract, AFaceTurnedTheWrongWayIsNamed) {
  const OpenBox b;
  const Mesh after = b.with({{4, 6, 5}, {5, 7, 6}});  // the first cap face reversed
  const EditContract c = checkEditContract(b.mesh(), after);
  EXPECT_FALSE(c.met);
  EXPECT_GT(c.inconsistent_edges_after, c.inconsistent_edges_before);
  EXPECT_TRUE(mentions(c, "run the same way")) << describeFailures(c);
  // A stitch asked to join oppositely oriented sides may make such edges.
  EditContractOptions o;
  o.allow_orientation_conflicts = true;
  EXPECT_TRUE(checkEditContract(b.mesh(), after, o).met);
}

TEST(EditContract, ANewEdgeWithThreeFacesIsNamed) {
  const OpenBox b;
  // A fin on the bottom edge 0-1, which already has two faces.
  const EditContract c = checkEditContract(b.mesh(), b.with({{0, 1, 8}}, {{0.5, -1, -1}}));
  EXPECT_FALSE(c.met);
  EXPECT_EQ(c.non_manifold_edges_after, c.non_manifold_edges_before + 1);
  EXPECT_TRUE(mentions(c, "more than two faces")) << describeFailures(c);
}

TEST(EditContract, ANewFaceWithoutAreaIsNamed) {
  const OpenBox b;
  // The cap, plus a sliver whose corners lie on one line (as stored).
  const EditContract c = checkEditContract(
      b.mesh(), b.with({{4, 5, 6}, {5, 7, 6}, {8, 9, 10}}, {{3, 0, 0}, {4, 0, 0}, {5, 0, 0}}));
  EXPECT_FALSE(c.met);
  EXPECT_EQ(c.degenerate_changed_faces, 1u);
  EXPECT_TRUE(mentions(c, "without area")) << describeFailures(c);
}

TEST(EditContract, ANewFaceThroughTheMeshIsNamedUnlessPairsAreNotCounted) {
  const OpenBox b;
  // The cap, plus a triangle that pierces the box's side x = 0.
  const Mesh after = b.with({{4, 5, 6}, {5, 7, 6}, {8, 9, 10}},
                            {{-1, 0.5, 0.2}, {0.5, 0.5, 0.2}, {0.5, 0.6, 0.8}});
  const EditContract c = checkEditContract(b.mesh(), after);
  EXPECT_FALSE(c.met);
  EXPECT_GT(c.intersecting_pairs, 0u);
  EXPECT_TRUE(mentions(c, "intersecting face pairs")) << describeFailures(c);
  EditContractOptions o;
  o.count_pairs = false;
  const EditContract unchecked = checkEditContract(b.mesh(), after, o);
  EXPECT_TRUE(unchecked.met) << describeFailures(unchecked);
  EXPECT_EQ(unchecked.intersecting_pairs, 0u);
}

TEST(EditContract, TheInputsOwnDefectsAreNotCounted) {
  // The open box with a fin already on edge 0-1: kept as it was, the fin is
  // the input's, and closing the hole meets the contract.
  OpenBox b;
  b.points.push_back({0.5, -1, -1});
  b.faces.push_back({0, 1, 8});
  const EditContract c = checkEditContract(b.mesh(), b.with({{4, 5, 6}, {5, 7, 6}}));
  EXPECT_EQ(c.non_manifold_edges_before, 1u);
  EXPECT_EQ(c.non_manifold_edges_after, 1u);
  EXPECT_TRUE(c.met) << describeFailures(c);
}

TEST(EditContract, AMovedFaceIsChanged) {
  // A face of the input whose corner moved counts as changed (and is judged).
  const OpenBox b;
  Mesh after = b.with({{4, 5, 6}, {5, 7, 6}});
  after.vert[4].P() = Point3(0, 0, 1.5);
  const EditContract c = checkEditContract(b.mesh(), after);
  EXPECT_GT(c.changed_faces, 2u);
}

TEST(EditContract, RequiredItThrowsNamingWhatFailedUnlessAPartialResultIsKept) {
  // A face turned the wrong way: refused, the message naming the filter, the
  // failure and what to try; kept, returned with met false and reported so.
  const OpenBox b;
  const Mesh after = b.with({{4, 6, 5}, {5, 7, 6}});
  EditContractOptions o;
  try {
    requireEditContract(b.mesh(), after, "Stitch Boundaries", o, "Try again.");
    FAIL() << "no ContractError";
  } catch (const ContractError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("Stitch Boundaries could not make a valid result: ", 0), 0u) << what;
    EXPECT_NE(what.find("run the same way"), std::string::npos) << what;
    EXPECT_NE(what.find(". Nothing was changed. Try again."), std::string::npos) << what;
  }
  o.keep_partial = true;
  const EditContract kept = requireEditContract(b.mesh(), after, "Stitch Boundaries", o, "");
  EXPECT_FALSE(kept.met);
  JsonObject report;
  reportContract(report, kept);
  const std::string json = report.str();
  EXPECT_NE(json.find("\"contract_met\": false"), std::string::npos) << json;
  EXPECT_NE(json.find("\"partial\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"changed_faces\": 2"), std::string::npos) << json;
  EXPECT_NE(json.find("run the same way"), std::string::npos) << json;
  EXPECT_NO_THROW(requireContract({}, "Stitch Boundaries", false, ""));
}
