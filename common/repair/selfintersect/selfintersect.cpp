#include "common/repair/selfintersect/selfintersect.h"
#include "common/base/timing.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <string>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/output_stage.h"
#include "common/repair/selfintersect/stages.h"
#include "common/repair/split/split.h"

namespace meshmend {

using namespace selfintersect;

namespace {

// ---- The working state of one removal, filled stage by stage -------------

struct Removal {
  Removal(const Mesh& m, const SelfIntersectionOptions& o) : input(m), options(o) {}
  const Mesh& input;
  const SelfIntersectionOptions& options;
  SelfIntersectionResult r;
  // The input as arrays, welded, cleaned and pre-treated; each vertex and
  // face remembers its index in `input`.
  MeshArrays in;
  std::vector<int> vertexOrigin, faceOrigin;
  std::size_t degenerateIn = 0;  // collinear faces left after the pre-treatment
  // The mesh cut along its self-intersection curves (§2.2).
  SplitResult split;
  MeshArrays cut;
  // §2.3-2.4, and the output as arrays (outFace: each output face's cut face).
  Grown grown;
  std::vector<Point3> outPoints;
  std::vector<Triangle> outTriangles;
  std::vector<int> outFace;
};

std::size_t collinearFaces(const std::vector<Point3>& P, const std::vector<Triangle>& T) {
  std::size_t n = 0;
  for (const Triangle& t : T) n += collinear(P[t[0]], P[t[1]], P[t[2]]);
  return n;
}

void checkOptions(const SelfIntersectionOptions& options) {
  if (!(options.degenerate_angle_deg >= 0 && options.degenerate_angle_deg < 60))
    throw InvalidInputError("the degenerate face angle must be between 0 and 60 degrees");
  if (!(options.snap_tolerance >= 0 && options.snap_tolerance < 0.5))
    throw InvalidInputError("the snapping tolerance must be between 0 and 0.5");
}

// The input as welded arrays without duplicate faces, checked against the
// preconditions; a closed mesh turned inside out is turned over (the
// growing keeps what is outside with respect to the orientation, which
// would be nothing) and turned back at the end.
void readInput(Removal& w) {
  SelfIntersectionResult& r = w.r;
  requireFacesAndFiniteCoordinates(w.input, "the mesh");
  r.faces_in = std::size_t(w.input.fn);
  w.in = arraysOf(w.input);
  // Output in float is decided on float: the input as it will be stored
  // too (MeshLab's already is), so only new and moved vertices change later.
  if (w.options.round_to_float)
    for (Point3& p : w.in.points) p = roundedToFloat(p);
  w.vertexOrigin.resize(w.in.points.size());
  w.faceOrigin.resize(w.in.triangles.size());
  std::iota(w.vertexOrigin.begin(), w.vertexOrigin.end(), 0);
  std::iota(w.faceOrigin.begin(), w.faceOrigin.end(), 0);
  if (w.options.weld_duplicates) {
    WeldedArrays welded = weldCoincident(w.in);
    r.vertices_welded = welded.vertices_merged;
    w.in = std::move(welded.mesh);
    w.vertexOrigin = std::move(welded.vertex_origin);
    w.faceOrigin = std::move(welded.face_origin);
  }
  r.duplicate_faces_removed = removeDuplicateFaces(w.in.triangles, w.faceOrigin);
  if (w.in.triangles.empty()) throw InvalidInputError("the mesh has no faces left after welding");
  const Edges edges(w.in.triangles);
  requireConsistentOrientation(edges, w.in.triangles);
  const TopologyCounts before = topologyOf(edges, w.in.triangles, w.in.points.size());
  r.components_before = before.components;
  r.genus_before = before.genus;
  r.border_edges_before = before.border_edges;
  r.non_manifold_edges_before = before.non_manifold_edges;
  r.fin_edges_before = before.fin_edges;
  r.input_closed = before.border_edges == 0;
  r.inside_out = signedVolume(w.in.points, w.in.triangles) < 0;
  if (r.inside_out)
    for (Triangle& t : w.in.triangles) std::swap(t[1], t[2]);
}

// §2.1 Pre-treatment.
void pretreatInput(Removal& w) {
  const PretreatmentCounts c =
      pretreat(w.in.points, w.in.triangles, w.faceOrigin, w.options.degenerate_angle_deg,
               w.options.pretreat, w.options.progress);
  w.r.degenerate_faces_before = c.degenerate_before;
  w.r.collapses = c.collapses;
  w.r.flips = c.flips;
  w.r.degenerate_faces_left = c.degenerate_left;
  w.degenerateIn = collinearFaces(w.in.points, w.in.triangles);
}

// The work bounds, on the pairs the split finds before it cuts anything
// (SplitOptions::pairs_found: the search is not made twice). The split's
// cost grows with the intersecting pairs (about 0.1 ms each) and, within a
// face, with the square of the curves crossing there.
void boundWork(Removal& w, const std::vector<IntersectingPair>& pairs) {
  w.r.intersecting_pairs_before = pairs.size();
  const std::size_t bound = w.options.max_intersecting_pairs;
  if (bound > 0 && pairs.size() > bound)
    throw WorkLimitError(
        "the mesh has " + std::to_string(pairs.size()) +
        " intersecting face pairs, more than the work bound of " + std::to_string(bound) +
        " (max_intersecting_pairs): cutting them all would take minutes. Nothing was changed. "
        "Raise the bound if that is acceptable, or work on parts of the mesh (select a region "
        "and move it to its own layer)");
  const std::size_t tripleBound = w.options.max_triple_points_per_face;
  if (tripleBound == 0) return;
  const TriplePoints most = mostTriplePoints(pairs, {w.in.triangles.size()}, tripleBound);
  if (most.count > tripleBound)
    throw WorkLimitError(
        "in face " + std::to_string(w.faceOrigin[most.face.face]) + " more than " +
        std::to_string(tripleBound) +
        " pairs of the faces crossing it cross each other too (max_triple_points_per_face): the "
        "surface passes many times through nearly one point there, as the meridians of a "
        "spindle torus do near its axis, and cutting it would take the exact arithmetic "
        "minutes. Nothing was changed. Remove the faces around that point (select them, "
        "Filters > Selection > Delete Selected Faces) and close the hole with MeshMend: Fill "
        "Holes, then remove the self-intersections");
}

// §2.2 The self-intersection curves, cut into the faces (split.h).
void cutAlongCurves(Removal& w) {
  reportProgress(w.options.progress, 10, "splitting along the self-intersections");
  Mesh work;
  buildMesh(work, w.in.points, w.in.triangles);
  SplitOptions so;
  so.between_meshes = false;
  so.self = true;
  so.separate_meshes = false;
  so.snap_tolerance = w.options.snap_tolerance;
  so.progress = progressWithin(w.options.progress, 10, 50);
  so.pairs_found = [&w](const std::vector<IntersectingPair>& pairs) { boundWork(w, pairs); };
  w.split = splitAlongIntersections({&work}, so);
  // The cut as the host stores it (output_stage.h): the region growing
  // decides on those coordinates, so that its decisions hold for the result.
  OutputStageOptions stage;
  stage.scalar = w.options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
  stage.progress = progressWithin(w.options.progress, 50, 59);
  w.r.stored = storeForHost(w.split, {&work}, so, stage);
  w.r.intersecting_pairs_before = w.split.intersecting_pairs;
  w.r.faces_split = w.split.faces_split;
  w.cut = arraysOf(w.split.merged);
  w.r.faces_after_split = w.cut.triangles.size();
}

// §2.3 Valid region growing and §2.4 stitching. The planes the radial order
// decides on are each face's birth face, or its own where snapping moved it
// off that plane (deciding on the birth plane there let the growing pass
// from the outer surface into the inner one).
void growValidRegion(Removal& w) {
  reportProgress(w.options.progress, 60, "growing the valid region");
  std::vector<TrianglePoints> births(w.cut.triangles.size());
  FaceOriginHandle birth = faceOrigins(w.split.merged);
  const std::vector<char>& snapped = w.split.merged_snapped_face;
  for (std::size_t f = 0; f < births.size(); ++f)
    births[f] = f < snapped.size() && snapped[f]
                    ? pointsOf(w.cut.points, w.cut.triangles[f])
                    : pointsOf(w.in.points, w.in.triangles[birth[f].face]);
  w.grown = growAndStitch(w.cut.points, w.cut.triangles, w.split.merged_new_face, std::move(births),
                          w.options.progress);
  SelfIntersectionResult& r = w.r;
  r.seeds = w.grown.seeds;
  r.rays = w.grown.rays;
  r.side_conflicts = w.grown.conflicts;
  for (char v : w.grown.valid) r.faces_kept += v;
  r.faces_removed = w.grown.valid.size() - r.faces_kept;
  const Stitched& stitched = w.grown.stitched;
  r.edges_duplicated = stitched.edges_duplicated;
  std::vector<char> seen(w.cut.points.size(), 0);
  std::size_t distinct = 0;
  for (int v : stitched.source_vertex) distinct += !seen[v], seen[v] = 1;
  r.vertices_duplicated = stitched.source_vertex.size() - distinct;
}

// The kept faces on the stitched vertices.
void assembleOutput(Removal& w) {
  const Stitched& stitched = w.grown.stitched;
  w.outPoints.reserve(stitched.source_vertex.size());
  for (int v : stitched.source_vertex) w.outPoints.push_back(w.cut.points[v]);
  const std::vector<char>& valid = w.grown.valid;
  for (std::size_t f = 0; f < valid.size(); ++f)
    if (valid[f]) {
      w.outTriangles.push_back({stitched.vertex_of_corner[3 * f],
                                stitched.vertex_of_corner[3 * f + 1],
                                stitched.vertex_of_corner[3 * f + 2]});
      w.outFace.push_back(int(f));
    }
}

// Copies of singular vertices moved apart (separate_touching).
void separateTouching(Removal& w) {
  if (w.options.separate_touching && !w.outTriangles.empty())
    w.r.vertices_separated =
        separateCopies(w.outPoints, w.outTriangles, w.grown.stitched.source_vertex,
                       w.options.round_to_float, w.options.progress, &w.r.separation_bound_reached);
}

// The result mesh (turned back if the input was inside out) with its
// provenance: the split names the vertices and faces of the welded,
// pre-treated arrays, which name the input's.
void buildOutput(Removal& w) {
  SelfIntersectionResult& r = w.r;
  if (r.inside_out)
    for (Triangle& t : w.outTriangles) std::swap(t[1], t[2]);
  buildMesh(r.mesh, w.outPoints, w.outTriangles);
  VertexOriginHandle cutVertex = vertexOrigins(w.split.merged);
  FaceOriginHandle cutFace = faceOrigins(w.split.merged);
  auto inputVertex = [&](int v) {
    VertexOrigin o = cutVertex[v];
    o.layer = 0;
    if (o.vertex >= 0) o.vertex = w.vertexOrigin[o.vertex];
    if (o.face >= 0) o.face = w.faceOrigin[o.face];
    return o;
  };
  auto inputFace = [&](int f) { return FaceOrigin{0, w.faceOrigin[cutFace[f].face]}; };
  VertexOriginHandle vo = vertexOrigins(r.mesh);
  FaceOriginHandle fo = faceOrigins(r.mesh);
  const std::vector<int>& source = w.grown.stitched.source_vertex;
  for (std::size_t v = 0; v < source.size(); ++v) vo[v] = inputVertex(source[v]);
  for (std::size_t f = 0; f < w.outFace.size(); ++f) fo[f] = inputFace(w.outFace[f]);
  if (!w.options.keep_removed || r.faces_removed == 0) return;
  // The removed faces, each vertex once.
  std::vector<int> index(w.cut.points.size(), -1), sourceOf, faces;
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  for (std::size_t f = 0; f < w.grown.valid.size(); ++f) {
    if (w.grown.valid[f]) continue;
    Triangle t = w.cut.triangles[f];
    for (int& v : t) {
      if (index[v] < 0)
        index[v] = int(points.size()), points.push_back(w.cut.points[v]), sourceOf.push_back(v);
      v = index[v];
    }
    if (r.inside_out) std::swap(t[1], t[2]);
    triangles.push_back(t);
    faces.push_back(int(f));
  }
  buildMesh(r.removed, points, triangles);
  VertexOriginHandle rvo = vertexOrigins(r.removed);
  FaceOriginHandle rfo = faceOrigins(r.removed);
  for (std::size_t v = 0; v < sourceOf.size(); ++v) rvo[v] = inputVertex(sourceOf[v]);
  for (std::size_t f = 0; f < faces.size(); ++f) rfo[f] = inputFace(faces[f]);
}

void measureOutput(Removal& w) {
  SelfIntersectionResult& r = w.r;
  const TopologyCounts after =
      topologyOf(Edges(w.outTriangles), w.outTriangles, w.outPoints.size());
  r.components_after = w.outTriangles.empty() ? 0 : after.components;
  r.genus_after = after.genus;
  r.border_edges_after = after.border_edges;
  r.non_manifold_edges_after = after.non_manifold_edges;
  r.output_closed = !w.outTriangles.empty() && after.border_edges == 0;
}

// What the contract asks of a mesh that is stored as `mesh` (float values
// with asFloat): the failures, one item each; empty when it holds.
// `closed`: it must have no border edge; `degenerateAllowed`: collinear
// faces the input brought. Sets remaining/verified when `countPairs`.
// What the contract checks of a mesh's shape: counts, no measures.
const InspectOptions kCounts = [] {
  InspectOptions o;
  o.measures = false;
  return o;
}();

std::vector<std::string> contractFailures(const Mesh& mesh, bool asFloat, bool countPairs,
                                          bool closed, std::size_t degenerateAllowed,
                                          const Progress& progress,
                                          SelfIntersectionResult* counts = nullptr) {
  std::vector<std::string> failures;
  if (mesh.fn == 0) {
    failures.push_back(
        "no face is outside with respect to the orientation, so nothing would be kept (check "
        "the orientation: Filters > Normals > Invert Faces Orientation)");
    return failures;
  }
  const InspectResult shape = inspect(mesh, kCounts);
  auto fail = [&](std::size_t n, const char* what) {
    if (n > 0) failures.push_back(std::to_string(n) + " " + what);
  };
  if (countPairs) {
    reportProgress(progress, 92, "checking the result");
    // By the checker's rule, on the whole result as stored: the count a user
    // gets from any tool (output_stage.h).
    const std::size_t pairs =
        storedIntersectingPairs(mesh, asFloat ? Scalar::kFloat : Scalar::kDouble);
    if (counts) counts->remaining_intersecting_pairs = pairs, counts->verified = true;
    fail(pairs, "intersecting face pairs are left");
  }
  fail(shape.non_manifold_edges, "edges have more than two faces");
  fail(shape.non_manifold_vertices, "vertices join separate fans of faces");
  fail(shape.orientation_inconsistent_edges, "edges are run the same way by both their faces");
  if (closed) fail(shape.border_edges, "border edges opened in a closed mesh");
  if (shape.degenerate_faces > degenerateAllowed)
    fail(shape.degenerate_faces - degenerateAllowed, "faces are degenerate (no area) as stored");
  return failures;
}

void checkContract(Removal& w) {
  SelfIntersectionResult& r = w.r;
  const bool closed = r.input_closed && r.fin_edges_before == 0;
  r.contract_failures = contractFailures(r.mesh, w.options.round_to_float, w.options.verify, closed,
                                         w.degenerateIn, w.options.progress, &r);
  r.contract_met = r.contract_failures.empty();
}

double millisecondsSince(std::chrono::steady_clock::time_point& lap) {
  const auto now = Clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - lap).count();
  lap = now;
  return ms;
}

SelfIntersectionResult removeOnce(const Mesh& input, const SelfIntersectionOptions& options) {
  const auto start = Clock::now();
  auto lap = start;
  checkOptions(options);
  Removal w(input, options);
  SelfIntersectionResult::StageTimes& ms = w.r.stage_ms;
  reportProgress(options.progress, 0, "checking the input");
  readInput(w);
  millisecondsSince(lap);
  pretreatInput(w);
  ms.pretreat = millisecondsSince(lap);
  cutAlongCurves(w);
  ms.split = millisecondsSince(lap);
  growValidRegion(w);
  ms.growing = millisecondsSince(lap);
  assembleOutput(w);
  ms.stitching = millisecondsSince(lap);
  separateTouching(w);
  ms.separation = millisecondsSince(lap);
  buildOutput(w);
  measureOutput(w);
  checkContract(w);
  ms.verify = millisecondsSince(lap);
  w.r.time_ms = msSince(start);
  return std::move(w.r);
}

// How far a result falls short of its contract: the failures, then the
// intersecting pairs left (fewer is better).
std::array<std::size_t, 2> shortfall(const SelfIntersectionResult& r) {
  return {r.contract_failures.size(), r.remaining_intersecting_pairs};
}

// Nothing to remove: no pair was cut and the growing kept every face, and
// the input as it is already meets the contract (an unwelded soup does not:
// its seams touch). Then the input is the result, exactly as it was.
bool nothingToRemove(const Mesh& input, const SelfIntersectionResult& r,
                     const SelfIntersectionOptions& options) {
  if (r.intersecting_pairs_before > 0 || r.faces_removed > 0 || r.vertices_separated > 0)
    return false;
  const InspectResult shape = inspect(input, kCounts);
  return contractFailures(input, options.round_to_float, true,
                          r.input_closed && r.fin_edges_before == 0, shape.degenerate_faces,
                          options.progress)
      .empty();
}

std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const std::string& item : items) s += (s.empty() ? "" : "; ") + item;
  return s;
}

}  // namespace

SelfIntersectionResult removeSelfIntersections(const Mesh& input,
                                               const SelfIntersectionOptions& options) {
  SelfIntersectionResult r = removeOnce(input, options);
  if (r.contract_met && nothingToRemove(input, r, options)) {
    r.mesh = input;
    r.unchanged = true;
  }
  // Snapping moves the surface near the curves by up to its tolerance:
  // where two sheets lie closer than that (nearly coincident scans), it can
  // carry one through the other, and the growing then passes into the inner
  // sheet. Without snapping every decision is exact: a result that misses
  // its contract is made again without it, and that one is returned where
  // it falls short less.
  if (!r.contract_met && options.snap_tolerance > 0) {
    SelfIntersectionOptions exact = options;
    exact.snap_tolerance = 0;
    SelfIntersectionResult again = removeOnce(input, exact);
    if (shortfall(again) < shortfall(r)) {
      again.snapping_dropped = true;
      again.time_ms += r.time_ms;
      r = std::move(again);
    }
  }
  reportProgress(options.progress, 100, "done");
  if (r.contract_met || options.keep_partial) return r;
  throw ContractError(
      "Remove Self-Intersections could not make a valid surface of this mesh: " +
      joined(r.contract_failures) +
      ". Nothing was changed. This happens where sheets overlap in a plane or touch along "
      "edges (solids of a CAD export placed side by side), where the surface passes many "
      "times through nearly one point, or where rounding to " +
      std::string(options.round_to_float ? "float" : "double") +
      " cannot keep nearly coincident faces apart. To try: the layer's parts one at a time "
      "(Filters > Layer and Mesh > Split in Connected Components), the double host (pymeshlab, "
      "or MeshLab's double build) where the float one fails, or 'Keep a partial result' to see "
      "what could be made");
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
      .set("snapping_dropped", r.snapping_dropped)
      .set("contract_met", r.contract_met)
      .set("contract_failures", r.contract_failures)
      .set("unchanged", r.unchanged)
      .set("verified", r.verified);
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
