// Intersect and split (common/split.h) and the booleans' patch pipeline
// (common/patches.h) on one or two small random meshes: they finish, or
// refuse with the core's typed errors; in double, the split leaves no
// intersecting pair among the faces it made.
#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/repair/output_stage.h"
#include "common/repair/patches/patch_ops.h"
#include "common/repair/patches/patches.h"
#include "common/repair/split/split.h"
#include "fuzz/fuzz_input.h"

namespace meshmend::fuzz {

namespace {

constexpr std::size_t kVertices = 96, kFaces = 192;
constexpr std::size_t kFuzzRoundingTests = 1000000;  // the default is 20 million

SplitOptions splitOptions(std::uint8_t flags, bool two) {
  SplitOptions o;
  o.between_meshes = two;
  o.self = !two || (flags & 1);
  o.weld_duplicates = flags & 2;
  o.remove_duplicate_faces = flags & 4;
  o.overlaps_once = flags & 8;
  o.snap_tolerance = flags & 16 ? 0.05 : 0;
  return o;
}

}  // namespace

void split(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const std::uint8_t options = in.byte();
  const DecodedMesh a = decodeMesh(in, kVertices, kFaces);
  const DecodedMesh b = decodeMesh(in, kVertices, kFaces);
  const bool two = !b.triangles.empty();
  try {
    const Mesh ma = makeMesh(a.points, a.triangles, 0), mb = makeMesh(b.points, b.triangles, 1);
    std::vector<const Mesh*> meshes{&ma};
    if (two) meshes.push_back(&mb);
    const SplitOptions o = splitOptions(options, two);
    SplitResult r = splitAlongIntersections(meshes, o);
    check(r.merged.fn > 0 || ma.fn == 0, "the merged output has faces");
    // The output stage for a float or a double host, then the checker's count.
    OutputStageOptions stage;
    stage.scalar = options & 32 ? Scalar::kFloat : Scalar::kDouble;
    // Bounds for meshes of at most 192 faces under the sanitizers (10 to 20
    // times slower): reached in seconds, so that an input the default
    // bound would stop only after a minute tests the bound's path instead.
    stage.max_rounding_tests = kFuzzRoundingTests;
    const StoredOutput stored = storeForHost(r, meshes, o, stage);
    (void)storedIntersectingPairs(r, stored, false);
    (void)toJson(r).str();
  } catch (const Error&) {
  }
}

void booleans(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const std::uint8_t operation = in.byte();
  const DecodedMesh a = decodeMesh(in, kVertices, kFaces);
  const DecodedMesh b = decodeMesh(in, kVertices, kFaces);
  try {
    const Mesh ma = makeMesh(a.points, a.triangles, 0), mb = makeMesh(b.points, b.triangles, 1);
    SplitOptions so;
    so.separate_meshes = false;
    so.weld_duplicates = operation & 8;
    SplitResult split = splitAlongIntersections({&ma, &mb}, so);
    const FaceLabels labels = mergedOutputLabels(split);
    Patches patches = paintPatches(split.merged, labels);
    classifyPatches(split.merged, labels, patches);
    const BooleanOperation op = BooleanOperation(operation % kBooleanOperations);
    const PatchChoice choice = choosePatches(patches, op);
    const Mesh out = extractPatches(split.merged, patches, choice.keep, choice.flip);
    check(out.fn <= split.merged.fn, "a boolean keeps some of the split's faces");
    (void)toJson(patches).str();
  } catch (const Error&) {
  }
}

}  // namespace meshmend::fuzz
