#include "common/repair/patches/patches.h"
#include "common/repair/patches/patch_ops.h"

#include <gtest/gtest.h>

#include "common/base/errors.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/split/split.h"
#include "tests/mesh_builders.h"

namespace meshmend {
namespace {

using testing::box;
using testing::uvSphere;
using testing::withHole;

InspectResult check(const Mesh& m) {
  InspectOptions o;
  o.self_intersections = true;
  return inspect(m, o);
}

// Two crossing spheres split along their curve, merged, with labels.
struct SplitPair {
  Mesh mesh;
  FaceLabels labels;
  double volumeA = 0, volumeB = 0;
};

SplitPair splitSpheres(Point3 offset, double radiusB = 1.0) {
  const Mesh a = uvSphere(24, 32), b = uvSphere(20, 28, radiusB, offset);
  SplitOptions o;
  o.separate_meshes = false;
  SplitResult r = splitAlongIntersections({&a, &b}, o);
  SplitPair pair;
  pair.volumeA = *inspect(a).volume;
  pair.volumeB = *inspect(b).volume;
  pair.labels = mergedOutputLabels(r);
  pair.mesh = r.merged;
  return pair;
}

TEST(Patches, AMeshWithoutBoundariesIsOnePatch) {
  const Mesh sphere = uvSphere(12, 16);
  const Patches p = paintPatches(sphere, {});
  ASSERT_EQ(p.patches.size(), 1u);
  EXPECT_EQ(p.patches[0].faces, sphere.face.size());
  EXPECT_EQ(p.boundary_edges, 0u);
  // Two separate spheres: one patch each.
  const Mesh two = appended(sphere, uvSphere(12, 16, 1, {5, 0, 0}));
  EXPECT_EQ(paintPatches(two, {}).patches.size(), 2u);
}

TEST(Patches, CurveEdgesBoundPatches) {
  // A square of two triangles whose diagonal is a curve edge.
  const Mesh square =
      makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
  FaceLabels labels;
  labels.curve_edges = {0b100, 0b001};  // edge 2 -> 0 of the first face, 0 -> 1 of the second
  EXPECT_EQ(paintPatches(square, labels).patches.size(), 2u);
  PaintOptions ignore;
  ignore.at_curves = false;
  EXPECT_EQ(paintPatches(square, labels, ignore).patches.size(), 1u);
}

TEST(Patches, BordersNonManifoldEdgesColoursAndCreasesBoundPatches) {
  // Three triangles on one edge (a non-manifold "book" of three pages).
  const Mesh book = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}},
                             {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  EXPECT_EQ(paintPatches(book, {}).patches.size(), 3u);
  PaintOptions across;
  across.at_non_manifold = false;
  EXPECT_EQ(paintPatches(book, {}, across).patches.size(), 1u);
  // Colours: two triangles of a square, coloured differently.
  const Mesh square =
      makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
  FaceLabels coloured;
  coloured.colour = {0xff0000ffu, 0xff00ff00u};
  EXPECT_EQ(paintPatches(square, coloured).patches.size(), 1u);
  PaintOptions byColour;
  byColour.at_colour_changes = true;
  EXPECT_EQ(paintPatches(square, coloured, byColour).patches.size(), 2u);
  // Creases: a box has six flat sides.
  const Mesh cube = box();
  EXPECT_EQ(paintPatches(cube, {}).patches.size(), 1u);
  PaintOptions creases;
  creases.crease_angle_deg = 30;
  const Patches sides = paintPatches(cube, {}, creases);
  ASSERT_EQ(sides.patches.size(), 6u);
  for (const Patch& side : sides.patches) EXPECT_EQ(side.faces, 2u);
  // Borders: a strip cut along a line (duplicated vertices) is two patches.
  const Mesh cut = makeMesh(
      {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {2, 0, 0}, {2, 1, 0}},
      {{0, 1, 2}, {0, 2, 3}, {4, 6, 7}, {4, 7, 5}});
  EXPECT_EQ(paintPatches(cut, {}).patches.size(), 2u);
}

TEST(Patches, BooleanResultsOfTwoCrossingSpheres) {
  const SplitPair pair = splitSpheres({0.9, 0.13, 0.07});
  Patches p = paintPatches(pair.mesh, pair.labels);
  ASSERT_EQ(p.patches.size(), 4u);  // each sphere: the part inside the other, the part outside
  classifyPatches(pair.mesh, pair.labels, p);
  EXPECT_TRUE(p.part_closed[0] && p.part_closed[1]);
  int inside = 0, onUnion = 0;
  for (const Patch& patch : p.patches) {
    const int other = 1 - patch.part;
    // Closed parts: integer winding numbers, ½ on the own surface (up to
    // the far-field approximation, a few thousandths).
    EXPECT_NEAR(patch.winding[patch.part], 0.5, 0.01);
    EXPECT_NEAR(patch.winding[other], std::round(patch.winding[other]), 0.01);
    inside += patch.inside(other);
    onUnion += patch.onUnionSurface();
  }
  EXPECT_EQ(inside, 2);
  EXPECT_EQ(onUnion, 2);

  double volumes[3];
  for (BooleanOperation op :
       {BooleanOperation::kUnion, BooleanOperation::kIntersection, BooleanOperation::kDifference}) {
    const PatchChoice choice = choosePatches(p, op);
    const Mesh result = extractPatches(pair.mesh, p, choice.keep, choice.flip);
    const InspectResult i = check(result);
    SCOPED_TRACE(toString(op));
    EXPECT_TRUE(i.is_closed);
    EXPECT_EQ(i.non_manifold_edges, 0u);
    EXPECT_EQ(i.border_edges, 0u);
    EXPECT_EQ(i.connected_components, 1u);
    EXPECT_EQ(*i.self_intersecting_pairs, 0u);
    EXPECT_TRUE(i.consistently_oriented);
    ASSERT_TRUE(i.volume.has_value());
    EXPECT_GT(*i.volume, 0);
    volumes[int(op)] = *i.volume;
  }
  // The three results partition the same faces: volumes add up exactly.
  EXPECT_NEAR(volumes[0] + volumes[1], pair.volumeA + pair.volumeB, 1e-9);
  EXPECT_NEAR(volumes[2], pair.volumeA - volumes[1], 1e-9);
  EXPECT_LT(volumes[1], std::min(pair.volumeA, pair.volumeB));
}

TEST(Patches, UnionOfBoxesSharingASideIsOneClosedBox) {
  // Two boxes side by side, their shared side triangulated alike: split
  // (each keeps its copy of the side, the default), the union drops the
  // side and is one closed box of twice the volume.
  const Mesh a = testing::gridCube(2), b = testing::moved(a, {1, 0, 0});
  SplitResult r = splitAlongIntersections({&a, &b});
  EXPECT_GT(r.coincident_faces, 0u);
  const FaceLabels labels = mergedOutputLabels(r);
  Patches p = paintPatches(r.merged, labels);
  classifyPatches(r.merged, labels, p);
  EXPECT_TRUE(p.part_closed[0] && p.part_closed[1]);
  const PatchChoice choice = choosePatches(p, BooleanOperation::kUnion);
  const InspectResult i = check(extractPatches(r.merged, p, choice.keep, choice.flip));
  EXPECT_TRUE(i.is_closed);
  EXPECT_EQ(i.non_manifold_edges, 0u);
  EXPECT_EQ(i.duplicate_faces, 0u);
  EXPECT_EQ(*i.self_intersecting_pairs, 0u);
  ASSERT_TRUE(i.volume.has_value());
  EXPECT_NEAR(*i.volume, 2, 1e-12);
}

// The boolean results of two unit boxes (2x2 grids on each side) where
// they overlap in planes: each result's faces once, closed, of the expected
// volume (0: nothing left).
struct BoxCase {
  const char* name;
  Point3 offset;  // of the second box
  double union_volume, intersection_volume, difference_volume;
};

TEST(Patches, InsideOutPartsAreClassifiedAsTurned) {
  // Some scans and exports come with every face pointing inward: a closed
  // part with a negative volume, whose winding number is -1 inside. Each
  // sphere turned so, and both: the same booleans as with both facing out,
  // every result facing out.
  const Mesh a = uvSphere(24, 32), b = uvSphere(20, 28, 1.0, {0.9, 0.13, 0.07});
  auto volumesOf = [](const Mesh& x, const Mesh& y, std::vector<bool>* insideOut) {
    SplitResult r = splitAlongIntersections({&x, &y});
    const FaceLabels labels = mergedOutputLabels(r);
    Patches p = paintPatches(r.merged, labels);
    classifyPatches(r.merged, labels, p);
    if (insideOut) *insideOut = p.part_inside_out;
    std::vector<double> volumes;
    for (BooleanOperation op : {BooleanOperation::kUnion, BooleanOperation::kIntersection,
                                BooleanOperation::kDifference}) {
      SCOPED_TRACE(toString(op));
      const PatchChoice choice = choosePatches(p, op);
      const InspectResult i = check(extractPatches(r.merged, p, choice.keep, choice.flip));
      EXPECT_TRUE(i.is_closed);
      EXPECT_EQ(i.non_manifold_edges, 0u);
      EXPECT_EQ(*i.self_intersecting_pairs, 0u);
      EXPECT_TRUE(i.consistently_oriented);
      volumes.push_back(i.volume.value_or(0));
    }
    return volumes;
  };
  const std::vector<double> expected = volumesOf(a, b, nullptr);
  ASSERT_GT(expected[1], 0);
  const Mesh turnedA = testing::flipped(a), turnedB = testing::flipped(b);
  const struct {
    const Mesh *x, *y;
    std::vector<bool> insideOut;
  } cases[] = {{&turnedA, &b, {true, false}},
               {&a, &turnedB, {false, true}},
               {&turnedA, &turnedB, {true, true}}};
  for (const auto& c : cases) {
    SCOPED_TRACE(::testing::Message() << "inside out: " << c.insideOut[0] << c.insideOut[1]);
    std::vector<bool> insideOut;
    const std::vector<double> volumes = volumesOf(*c.x, *c.y, &insideOut);
    EXPECT_EQ(insideOut, c.insideOut);
    for (int op = 0; op < 3; ++op) EXPECT_NEAR(volumes[op], expected[op], 1e-9);
  }
}

TEST(Patches, BooleansOfBoxesOverlappingInPlanes) {
  const BoxCase cases[] = {
      {"the same box", {0, 0, 0}, 1, 1, 0},
      {"half overlapping", {0.5, 0, 0}, 1.5, 0.5, 0.5},
      {"half overlapping, sides shifted", {0.5, 0.5, 0}, 1.75, 0.25, 0.75},
      {"touching along a side", {1, 0, 0}, 2, 0, 1},
      {"touching along half a side", {1, 0.5, 0}, 2, 0, 1},
  };
  const Mesh a = testing::gridCube(2);
  for (const BoxCase& c : cases) {
    SCOPED_TRACE(c.name);
    const Mesh b = testing::moved(a, c.offset);
    SplitResult r = splitAlongIntersections({&a, &b});
    const FaceLabels labels = mergedOutputLabels(r);
    Patches p = paintPatches(r.merged, labels);
    classifyPatches(r.merged, labels, p);
    const double expected[] = {c.union_volume, c.intersection_volume, c.difference_volume};
    for (BooleanOperation op : {BooleanOperation::kUnion, BooleanOperation::kIntersection,
                                BooleanOperation::kDifference}) {
      SCOPED_TRACE(toString(op));
      const PatchChoice choice = choosePatches(p, op);
      const Mesh result = extractPatches(r.merged, p, choice.keep, choice.flip);
      if (expected[int(op)] == 0) {
        EXPECT_EQ(result.face.size(), 0u);
        continue;
      }
      const InspectResult i = check(result);
      EXPECT_TRUE(i.is_closed);
      EXPECT_EQ(i.non_manifold_edges, 0u);
      EXPECT_EQ(i.duplicate_faces, 0u);
      EXPECT_EQ(*i.self_intersecting_pairs, 0u);
      EXPECT_TRUE(i.consistently_oriented);
      ASSERT_TRUE(i.volume.has_value());
      EXPECT_NEAR(*i.volume, expected[int(op)], 1e-12);
    }
  }
}

TEST(Patches, APlanarOverlapWithAnOpenPartIsKeptOnce) {
  // A closed box and the same box without its bottom (open), at coordinates
  // no float makes exact (face centres lie a rounding off their planes):
  // the five shared sides bound the intersection once, by the first part's
  // copy, unbroken by the open part's own faces there.
  const Mesh unit = testing::gridCube(2, 0.1);
  const std::vector<Point3> grid = positionsOf(unit);
  const std::vector<Triangle> all = trianglesOf(unit);
  std::vector<Triangle> open;
  for (const Triangle& t : all)
    if (!(grid[t[0]][2] == 0 && grid[t[1]][2] == 0 && grid[t[2]][2] == 0)) open.push_back(t);
  // Turned about an oblique axis and moved: no side is axis-aligned.
  std::vector<Point3> points;
  const double c = std::cos(0.7), s = std::sin(0.7), c2 = std::cos(0.3), s2 = std::sin(0.3);
  for (const Point3& q : grid) {
    const Point3 r(c * q[0] - s * q[1], s * q[0] + c * q[1], q[2]);
    points.emplace_back(r[0] + 0.1 / 3, c2 * r[1] - s2 * r[2] + 0.2 / 3, s2 * r[1] + c2 * r[2]);
  }
  const Mesh a = makeMesh(points, all), b = makeMesh(points, open);
  ASSERT_EQ(open.size() + 8, all.size());
  SplitResult r = splitAlongIntersections({&a, &b});
  const FaceLabels labels = mergedOutputLabels(r);
  Patches p = paintPatches(r.merged, labels);
  classifyPatches(r.merged, labels, p);
  EXPECT_TRUE(p.part_closed[0]);
  EXPECT_FALSE(p.part_closed[1]);
  const PatchChoice choice = choosePatches(p, BooleanOperation::kIntersection);
  // Faces of the shared sides: the first part's kept, the second's not.
  std::size_t keptShared = 0, keptOfSecond = 0;
  for (std::size_t f = 0; f < r.merged.face.size(); ++f) {
    const int birth = faceOrigins(r.merged)[f].face;
    const bool bottom = labels.part[f] == 0 && grid[all[birth][0]][2] == 0 &&
                        grid[all[birth][1]][2] == 0 && grid[all[birth][2]][2] == 0;
    if (bottom || !choice.keep[p.patch_of_face[f]]) continue;
    if (labels.part[f] == 0)
      ++keptShared;
    else
      ++keptOfSecond;
  }
  EXPECT_EQ(keptShared, open.size());
  EXPECT_EQ(keptOfSecond, 0u);
}

TEST(Patches, ClassificationWithHolesInTheOtherPart) {
  // A small sphere inside a big one with a hole cut at its top: the small
  // one is still inside, well above the ½ threshold.
  // (A hole of radius ~0.9 around the top.)
  const Mesh big = withHole(uvSphere(24, 32, 2.0), [](const Point3& c) { return c[2] >= 1.8; });
  const Mesh small = uvSphere(12, 16, 0.5, {0.2, 0.1, -0.3});
  const Mesh both = appended(small, big);
  FaceLabels labels;
  labels.part.assign(small.face.size(), 0);
  labels.part.resize(both.face.size(), 1);
  Patches p = paintPatches(both, labels);
  ASSERT_EQ(p.patches.size(), 2u);
  classifyPatches(both, labels, p);
  EXPECT_TRUE(p.part_closed[0]);
  EXPECT_FALSE(p.part_closed[1]);
  const Patch& inner = p.patches[p.patch_of_face[0]];
  EXPECT_GT(inner.winding[1], 0.8);
  EXPECT_LT(inner.winding[1], 1.0);
  EXPECT_TRUE(inner.inside(1));
  EXPECT_FALSE(inner.onUnionSurface());
  const Patch& outer = p.patches[p.patch_of_face[small.face.size()]];
  EXPECT_FALSE(outer.inside(0));
  EXPECT_TRUE(outer.onUnionSurface());
}

TEST(Patches, APatchOnBothSidesOfAnOpenPartIsSplit) {
  // A big sphere with a hole across half of the circle where a small
  // sphere crosses it: that curve ends at the hole's border, so it does not
  // separate the small sphere, whose one patch lies both inside and
  // outside the big one. Classification splits it at the ½ level set.
  const Mesh big =
      withHole(uvSphere(32, 48, 2.0), [](const Point3& c) { return c[2] > 1.5 && c[0] > 0; });
  const Mesh small = uvSphere(20, 28, 1.0, {0.05, 0.03, 2.0});
  SplitOptions o;
  o.separate_meshes = false;
  SplitResult r = splitAlongIntersections({&small, &big}, o);
  ASSERT_GT(r.open_curves, 0u);
  const FaceLabels labels = mergedOutputLabels(r);
  Patches p = paintPatches(r.merged, labels);
  const std::size_t painted = p.patches.size();
  classifyPatches(r.merged, labels, p);
  EXPECT_FALSE(p.part_closed[1]);
  EXPECT_GE(p.patches_split_at_open_parts, 1u);
  EXPECT_GT(p.patches.size(), painted);
  // Every patch of the small sphere is now clearly on one side of the big one.
  for (const Patch& patch : p.patches)
    if (patch.part == 0) {
      EXPECT_GT(std::fabs(patch.winding[1] - 0.5), 0.05);
    }
  const PatchChoice choice = choosePatches(p, BooleanOperation::kUnion);
  const InspectResult i = check(extractPatches(r.merged, p, choice.keep));
  EXPECT_EQ(i.non_manifold_edges, 0u);
  EXPECT_EQ(*i.self_intersecting_pairs, 0u);
}

TEST(Patches, SelfFoldsAreClassifiedLikeOverlaps) {
  // One part made of two overlapping spheres (a mesh that folds through
  // itself), split along its own curve: its interior patches are not on
  // the union's surface, just as for two parts.
  const Mesh a = uvSphere(16, 20), b = uvSphere(16, 20, 1, {1, 0.1, 0});
  const Mesh one = appended(a, b);
  SplitOptions o;
  o.self = true;
  o.between_meshes = false;
  o.separate_meshes = false;
  SplitResult r = splitAlongIntersections({&one}, o);
  FaceLabels labels;
  labels.curve_edges = curveEdgeFlags(r.merged, r.merged_curve_edges);
  Patches p = paintPatches(r.merged, labels);
  ASSERT_EQ(p.patches.size(), 4u);
  classifyPatches(r.merged, labels, p);
  const PatchChoice choice = choosePatches(p, BooleanOperation::kUnion);
  EXPECT_EQ(std::count(choice.keep.begin(), choice.keep.end(), 1), 2);
  const InspectResult i = check(extractPatches(r.merged, p, choice.keep));
  EXPECT_TRUE(i.is_closed);
  EXPECT_EQ(i.non_manifold_edges, 0u);
  EXPECT_EQ(*i.self_intersecting_pairs, 0u);
}

TEST(Patches, BadInput) {
  const Mesh sphere = uvSphere(8, 8);
  FaceLabels wrong;
  wrong.part = {0, 1};
  EXPECT_THROW(paintPatches(sphere, wrong), InvalidInputError);
  Patches p = paintPatches(sphere, {});
  EXPECT_THROW(choosePatches(p, BooleanOperation::kUnion), InvalidInputError);  // not classified
  EXPECT_THROW(extractPatches(sphere, p, {}), InvalidInputError);
  const Mesh other = uvSphere(10, 10);
  EXPECT_THROW(classifyPatches(other, {}, p), InvalidInputError);
}

}  // namespace
}  // namespace meshmend
