// The repair filters' core entry points on small random meshes: removal of
// self-intersections, hole filling, trimming, stitching, gap closing and
// clearance. Each finishes or refuses with the core's typed errors, and
// what it returns meets its stated contract, checked here independently.
#include <algorithm>
#include <map>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/repair/clearance/clearance.h"
#include "common/repair/holes/holes.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/selfintersect/selfintersect.h"
#include "common/repair/stitch/stitch.h"
#include "fuzz/fuzz_input.h"

namespace meshmend::fuzz {

namespace {

constexpr std::size_t kVertices = 128, kFaces = 256;

Mesh meshOf(const DecodedMesh& d, int layer = 0) {
  return makeMesh(d.points, d.triangles, layer);
}

// Edges used by more than two faces, and edges two faces run the same way.
struct EdgeCounts {
  std::size_t non_manifold = 0, inconsistent = 0, border = 0;
};
EdgeCounts edgeCounts(const Mesh& m) {
  std::map<std::array<int, 2>, std::array<int, 2>> uses;  // per edge: uses each way
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    for (int i = 0; i < 3; ++i) {
      const int u = int(f.cV(i) - &m.vert[0]), v = int(f.cV((i + 1) % 3) - &m.vert[0]);
      ++uses[{std::min(u, v), std::max(u, v)}][u < v ? 0 : 1];
    }
  }
  EdgeCounts c;
  for (const auto& [edge, n] : uses) {
    c.non_manifold += n[0] + n[1] > 2;
    c.inconsistent += n[0] + n[1] == 2 && (n[0] == 0 || n[1] == 0);
    c.border += n[0] + n[1] == 1;
  }
  return c;
}

}  // namespace

void removeSelfIntersectionsBody(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const DecodedMesh d = decodeMesh(in, kVertices, kFaces);
  SelfIntersectionOptions o;
  o.round_to_float = d.flags & 1;
  o.snap_tolerance = d.flags & 2 ? 0 : 0.05;
  o.pretreat = !(d.flags & 4);
  o.weld_duplicates = !(d.flags & 8);
  o.separate_touching = !(d.flags & 16);
  o.keep_removed = d.flags & 32;
  try {
    const SelfIntersectionResult r = removeSelfIntersections(meshOf(d), o);
    // The contract (selfintersect.h), on the mesh as it would be stored.
    check(r.mesh.fn > 0, "a result has faces");
    check(selfIntersectingPairs(r.mesh, o.round_to_float) == 0, "no intersecting pair");
    const EdgeCounts e = edgeCounts(r.mesh);
    check(e.non_manifold == 0, "edge-manifold");
    check(e.inconsistent == 0, "consistently oriented");
  } catch (const Error&) {
  }
}

void fillHolesBody(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const DecodedMesh d = decodeMesh(in, kVertices, kFaces);
  HoleFillOptions o;
  o.fairing = HoleFairing(d.flags % 4);
  o.round_to_float = d.flags & 4;
  o.max_boundary_edges = d.flags & 8 ? 16 : 0;
  // The fronts' work bound (10 x uniform_face_limit triangles) scaled to
  // meshes of at most 192 faces under the sanitizers: a border with one edge
  // a thousandth of the others reached the default bound after minutes.
  o.uniform_face_limit = 2000;
  try {
    Mesh m = meshOf(d);
    const HoleFillResult r = fillHoles(m, o);
    check(r.holes_filled + r.holes_skipped <= r.holes_found, "holes add up");
  } catch (const Error&) {
  }
}

void trimAndStitchBody(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const DecodedMesh d = decodeMesh(in, kVertices, kFaces);
  std::vector<int> picked;
  std::vector<bool> selected(d.points.size(), false);
  for (int i = 0; i < 4 && !d.points.empty(); ++i) {
    const int v = int(in.byte() % d.points.size());
    picked.push_back(v);
    selected[v] = true;
  }
  try {
    Mesh m = meshOf(d);
    if (d.flags & 1) {
      TrimOptions o;
      o.picked_vertices = picked;
      o.keep_face = d.flags & 2 ? 0 : -1;
      const TrimResult r = trimAlongLoop(m, o);
      check(r.faces_kept + r.faces_removed == d.triangles.size(), "trimmed faces add up");
    } else {
      const std::vector<BorderPath> paths = borderPathsFromSelection(m, selected);
      if (paths.size() < 2) return;
      const EdgeCounts before = edgeCounts(m);
      StitchOptions o;
      o.a = paths[0];
      o.b = paths[1];
      o.max_aspect_ratio = d.flags & 4 ? 3 : 0;
      const StitchResult r = stitchPaths(m, o);
      const EdgeCounts after = edgeCounts(m);
      check(after.non_manifold <= before.non_manifold, "stitching makes no non-manifold edge");
      check(r.checked, "the stitch was checked");
    }
  } catch (const Error&) {
  }
}

void closeGapsBody(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const DecodedMesh d = decodeMesh(in, kVertices, kFaces);
  CloseGapsOptions o;
  o.merge_tolerance = d.flags & 1 ? 1e-3 : 0;
  o.orient_faces = !(d.flags & 2);
  o.max_gap = d.flags & 4 ? 0.1 : 0.01;
  o.max_aspect_ratio = d.flags & 8 ? 3 : 0;
  try {
    Mesh m = meshOf(d);
    const EdgeCounts before = edgeCounts(m);
    const CloseGapsResult r = closeGaps(m, o);
    const EdgeCounts after = edgeCounts(m);
    check(after.non_manifold <= before.non_manifold, "closing gaps makes no non-manifold edge");
    check(r.border_edges_after == after.border, "border edges counted");
  } catch (const Error&) {
  }
}

void clearanceBody(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const DecodedMesh a = decodeMesh(in, kVertices / 2, kFaces / 2);
  const DecodedMesh b = decodeMesh(in, kVertices / 2, kFaces / 2);
  const double tau = double(a.flags % 16 + 1) * 0.01 * gridScale(in.byte());
  try {
    Mesh ma = meshOf(a, 0), mb = meshOf(b, 1);
    std::vector<const Mesh*> measured{&ma};
    std::vector<Mesh*> layers{&ma};
    if (mb.fn > 0) measured.push_back(&mb), layers.push_back(&mb);
    ClearanceMeasureOptions mo;
    mo.tau = tau;
    const ClearanceMeasure m = measureClearance(measured, mo);
    check(!m.found || m.min_distance >= 0, "distances are not negative");
    ClearanceOptions o;
    o.tau = tau;
    o.max_iterations = 4;
    o.round_to_float = a.flags & 16;
    const ClearanceResult r = enforceClearance(layers, o);
    if (r.reached) {
      mo.tau = tau;
      const ClearanceMeasure after = measureClearance(measured, mo);
      check(after.violating_pairs == 0, "a reached clearance holds on the output");
    }
  } catch (const Error&) {
  }
}

}  // namespace meshmend::fuzz
