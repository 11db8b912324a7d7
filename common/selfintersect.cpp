#include "common/selfintersect.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <string>

#include "common/errors.h"
#include "common/intersections.h"
#include "common/selfintersect_stages.h"
#include "common/split.h"

namespace meshmend {

using namespace selfintersect;

namespace {

SelfIntersectionResult removeOnce(const Mesh& input, const SelfIntersectionOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto lap = start;
  // Milliseconds since the previous lap.
  auto elapsed = [&lap] {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - lap).count();
    lap = now;
    return ms;
  };
  requireFacesAndFiniteCoordinates(input, "the mesh");
  if (!(options.degenerate_angle_deg >= 0 && options.degenerate_angle_deg < 60))
    throw InvalidInputError("the degenerate face angle must be between 0 and 60 degrees");
  if (!(options.snap_tolerance >= 0 && options.snap_tolerance < 0.5))
    throw InvalidInputError("the snapping tolerance must be between 0 and 0.5");
  SelfIntersectionResult r;
  r.faces_in = std::size_t(input.fn);
  reportProgress(options.progress, 0, "checking the input");

  // The mesh as arrays, welded; each vertex and face remembers its input index.
  MeshArrays arrays = arraysOf(input);
  // Output in float is decided on float: the input as it will be stored
  // too (MeshLab's already is), so only new and moved vertices change later.
  if (options.round_to_float)
    for (Point3& p : arrays.points) p = roundedToFloat(p);
  std::vector<int> vertexOrigin(arrays.points.size()), faceOrigin(arrays.triangles.size());
  std::iota(vertexOrigin.begin(), vertexOrigin.end(), 0);
  std::iota(faceOrigin.begin(), faceOrigin.end(), 0);
  if (options.weld_duplicates) {
    WeldedArrays w = weldCoincident(arrays);
    r.vertices_welded = w.vertices_merged;
    arrays = std::move(w.mesh);
    vertexOrigin = std::move(w.vertex_origin);
    faceOrigin = std::move(w.face_origin);
  }
  std::vector<Point3>& P = arrays.points;
  std::vector<Triangle>& T = arrays.triangles;
  r.duplicate_faces_removed = removeDuplicateFaces(T, faceOrigin);
  if (T.empty()) throw InvalidInputError("the mesh has no faces left after welding");
  {
    const Edges edges(T);
    requireConsistentOrientation(edges, T);
    const TopologyCounts before = topologyOf(edges, T, P.size());
    r.components_before = before.components;
    r.genus_before = before.genus;
    r.border_edges_before = before.border_edges;
    r.non_manifold_edges_before = before.non_manifold_edges;
    r.fin_edges_before = before.fin_edges;
    r.input_closed = before.border_edges == 0;
  }
  // A closed mesh with negative volume is inside out: the region growing
  // keeps what is outside with respect to the orientation, which would be
  // nothing. It runs on the mesh turned over, and the result is turned back.
  r.inside_out = signedVolume(P, T) < 0;
  if (r.inside_out)
    for (Triangle& t : T) std::swap(t[1], t[2]);

  // §2.1 Pre-treatment.
  elapsed();
  {
    const PretreatmentCounts c = pretreat(P, T, faceOrigin, options.degenerate_angle_deg,
                                          options.pretreat, options.progress);
    r.degenerate_faces_before = c.degenerate_before;
    r.collapses = c.collapses;
    r.flips = c.flips;
    r.degenerate_faces_left = c.degenerate_left;
  }
  r.stage_ms.pretreat = elapsed();

  // §2.2 Self-intersections, cut into the faces (split.h).
  reportProgress(options.progress, 10, "splitting along the self-intersections");
  Mesh work;
  buildMesh(work, P, T);
  SplitOptions so;
  so.between_meshes = false;
  so.self = true;
  so.separate_meshes = false;
  so.snap_tolerance = options.snap_tolerance;
  SplitResult split = splitAlongIntersections({&work}, so);
  if (options.round_to_float) roundToFloat(split);
  r.intersecting_pairs_before = split.intersecting_pairs;
  r.faces_split = split.faces_split;
  const MeshArrays cut = arraysOf(split.merged);
  r.faces_after_split = cut.triangles.size();
  r.stage_ms.split = elapsed();

  // §2.3 Valid region growing.
  reportProgress(options.progress, 60, "growing the valid region");
  // The planes the radial order decides on: each face's birth face, or its
  // own, where snapping moved it off that plane (deciding on the birth plane
  // there let the growing pass from the outer surface into the inner one).
  std::vector<TrianglePoints> births(cut.triangles.size());
  {
    FaceOriginHandle birth = faceOrigins(split.merged);
    const std::vector<char>& snapped = split.merged_snapped_face;
    for (std::size_t f = 0; f < births.size(); ++f)
      births[f] = f < snapped.size() && snapped[f] ? pointsOf(cut.points, cut.triangles[f])
                                                   : pointsOf(P, T[birth[f].face]);
  }
  Grown grown = growAndStitch(cut.points, cut.triangles, split.merged_new_face, std::move(births),
                              options.progress);
  const std::vector<char>& valid = grown.valid;
  r.seeds = grown.seeds;
  r.rays = grown.rays;
  r.side_conflicts = grown.conflicts;
  for (char v : valid) r.faces_kept += v;
  r.faces_removed = valid.size() - r.faces_kept;
  r.stage_ms.growing = elapsed();

  // §2.4 Stitching (done by growAndStitch).
  const Stitched& stitched = grown.stitched;
  r.edges_duplicated = stitched.edges_duplicated;
  {
    std::vector<char> seen(cut.points.size(), 0);
    std::size_t distinct = 0;
    for (int v : stitched.source_vertex) distinct += !seen[v], seen[v] = 1;
    r.vertices_duplicated = stitched.source_vertex.size() - distinct;
  }
  std::vector<Point3> outPoints;
  outPoints.reserve(stitched.source_vertex.size());
  for (int v : stitched.source_vertex) outPoints.push_back(cut.points[v]);
  std::vector<Triangle> outTriangles;
  std::vector<int> outFace;
  for (std::size_t f = 0; f < valid.size(); ++f)
    if (valid[f]) {
      outTriangles.push_back({stitched.vertex_of_corner[3 * f],
                              stitched.vertex_of_corner[3 * f + 1],
                              stitched.vertex_of_corner[3 * f + 2]});
      outFace.push_back(int(f));
    }
  r.stage_ms.stitching = elapsed();
  if (options.separate_touching)
    r.vertices_separated =
        separateCopies(outPoints, outTriangles, stitched.source_vertex, options.round_to_float);
  r.stage_ms.separation = elapsed();
  if (r.inside_out)
    for (Triangle& t : outTriangles) std::swap(t[1], t[2]);
  buildMesh(r.mesh, outPoints, outTriangles);

  // Provenance back to the caller's mesh: the split names the vertices and
  // faces of the welded, pre-treated arrays.
  VertexOriginHandle cutVertex = vertexOrigins(split.merged);
  FaceOriginHandle cutFace = faceOrigins(split.merged);
  auto inputVertex = [&](int v) {
    VertexOrigin o = cutVertex[v];
    o.layer = 0;
    if (o.vertex >= 0) o.vertex = vertexOrigin[o.vertex];
    if (o.face >= 0) o.face = faceOrigin[o.face];
    return o;
  };
  auto inputFace = [&](int f) { return FaceOrigin{0, faceOrigin[cutFace[f].face]}; };
  {
    VertexOriginHandle vo = vertexOrigins(r.mesh);
    FaceOriginHandle fo = faceOrigins(r.mesh);
    for (std::size_t v = 0; v < stitched.source_vertex.size(); ++v)
      vo[v] = inputVertex(stitched.source_vertex[v]);
    for (std::size_t f = 0; f < outFace.size(); ++f) fo[f] = inputFace(outFace[f]);
  }
  if (options.keep_removed && r.faces_removed > 0) {
    std::vector<int> index(cut.points.size(), -1);
    std::vector<Point3> points;
    std::vector<int> source;
    std::vector<Triangle> triangles;
    std::vector<int> faces;
    for (std::size_t f = 0; f < valid.size(); ++f) {
      if (valid[f]) continue;
      Triangle t = cut.triangles[f];
      for (int& v : t) {
        if (index[v] < 0)
          index[v] = int(points.size()), points.push_back(cut.points[v]), source.push_back(v);
        v = index[v];
      }
      if (r.inside_out) std::swap(t[1], t[2]);
      triangles.push_back(t);
      faces.push_back(int(f));
    }
    buildMesh(r.removed, points, triangles);
    VertexOriginHandle vo = vertexOrigins(r.removed);
    FaceOriginHandle fo = faceOrigins(r.removed);
    for (std::size_t v = 0; v < source.size(); ++v) vo[v] = inputVertex(source[v]);
    for (std::size_t f = 0; f < faces.size(); ++f) fo[f] = inputFace(faces[f]);
  }

  const TopologyCounts after = topologyOf(Edges(outTriangles), outTriangles, outPoints.size());
  r.components_after = outTriangles.empty() ? 0 : after.components;
  r.genus_after = after.genus;
  r.border_edges_after = after.border_edges;
  r.non_manifold_edges_after = after.non_manifold_edges;
  r.output_closed = !outTriangles.empty() && after.border_edges == 0;

  elapsed();
  if (options.verify && !outTriangles.empty()) {
    reportProgress(options.progress, 90, "verifying");
    // The split searched every pair of the mesh it cut, and the faces it
    // left as they were cross nothing. So only a face that is new, moved
    // (rounding, separation) or re-connected (a corner on a copied vertex)
    // can cross anything: every pair with one of those is tested, exactly,
    // on the coordinates as stored.
    std::vector<int> copies(cut.points.size(), 0);
    for (int v : stitched.source_vertex) ++copies[v];
    std::vector<char> vertexChanged(outPoints.size(), 0);
    for (std::size_t v = 0; v < outPoints.size(); ++v) {
      const int c = stitched.source_vertex[v];
      const int birth = cutVertex[c].vertex;
      vertexChanged[v] = copies[c] > 1 || birth < 0 || !(outPoints[v] == P[birth]);
    }
    std::vector<char> faceChanged(outTriangles.size(), 0);
    for (std::size_t f = 0; f < outTriangles.size(); ++f) {
      faceChanged[f] = split.merged_new_face[outFace[f]];
      for (int v : outTriangles[f]) faceChanged[f] |= vertexChanged[v];
    }
    r.remaining_intersecting_pairs =
        intersectingOf(outPoints, outTriangles,
                       pairsWithChangedFaces(outPoints, outTriangles, faceChanged))
            .size();
    r.verified = true;
  }
  r.stage_ms.verify = elapsed();
  r.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  reportProgress(options.progress, 100, "done");
  return r;
}

// How far a result falls short of a valid outer surface: intersecting
// pairs left, non-manifold edges made. (A closed input with fins may open
// at them either way: see fin_edges_before.)
std::array<std::size_t, 2> shortfall(const SelfIntersectionResult& r) {
  return {r.verified ? r.remaining_intersecting_pairs : 0,
          r.non_manifold_edges_after > r.non_manifold_edges_before
              ? r.non_manifold_edges_after - r.non_manifold_edges_before
              : 0};
}

}  // namespace

SelfIntersectionResult removeSelfIntersections(const Mesh& input,
                                               const SelfIntersectionOptions& options) {
  SelfIntersectionResult r = removeOnce(input, options);
  // Snapping moves the surface near the curves by up to its tolerance:
  // where two sheets lie closer than that (nearly coincident scans), it can
  // carry one through the other, and the growing then passes into the inner
  // sheet. Without snapping every decision is exact: such a result is made
  // again without it, and returned instead where it falls short less.
  if (options.snap_tolerance > 0 && shortfall(r) != std::array<std::size_t, 2>{}) {
    SelfIntersectionOptions exact = options;
    exact.snap_tolerance = 0;
    SelfIntersectionResult again = removeOnce(input, exact);
    if (shortfall(again) < shortfall(r)) {
      again.snapping_dropped = true;
      again.time_ms += r.time_ms;
      return again;
    }
  }
  return r;
}

JsonObject toJson(const SelfIntersectionResult& r) {
  JsonObject j;
  j.set("faces_in", r.faces_in)
      .set("faces_kept", r.faces_kept)
      .set("faces_removed", r.faces_removed)
      .set("faces_out", std::size_t(r.mesh.fn))
      .set("intersecting_pairs_before", r.intersecting_pairs_before)
      .set("faces_split", r.faces_split)
      .set("components_before", r.components_before)
      .set("components_after", r.components_after)
      .set("genus_before", r.genus_before)
      .set("genus_after", r.genus_after)
      .set("input_closed", r.input_closed)
      .set("output_closed", r.output_closed)
      .set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("non_manifold_edges_before", r.non_manifold_edges_before)
      .set("fin_edges_before", r.fin_edges_before)
      .set("non_manifold_edges_after", r.non_manifold_edges_after)
      .set("degenerate_faces_before", r.degenerate_faces_before)
      .set("collapses", r.collapses)
      .set("flips", r.flips)
      .set("degenerate_faces_left", r.degenerate_faces_left)
      .set("vertices_welded", r.vertices_welded)
      .set("duplicate_faces_removed", r.duplicate_faces_removed)
      .set("seeds", r.seeds)
      .set("rays", r.rays)
      .set("side_conflicts", r.side_conflicts)
      .set("inside_out", r.inside_out)
      .set("vertices_duplicated", r.vertices_duplicated)
      .set("vertices_separated", r.vertices_separated)
      .set("edges_duplicated", r.edges_duplicated)
      .set("snapping_dropped", r.snapping_dropped);
  if (r.verified) j.set("remaining_intersecting_pairs", r.remaining_intersecting_pairs);
  j.set("time_ms", r.time_ms);
  const auto& t = r.stage_ms;
  j.set("stage_ms", JsonObject()
                        .set("pretreat", t.pretreat)
                        .set("split", t.split)
                        .set("growing", t.growing)
                        .set("stitching", t.stitching)
                        .set("separation", t.separation)
                        .set("verify", t.verify));
  return j;
}

}  // namespace meshmend
