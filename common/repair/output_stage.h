// The output stage. A split's result is exact until it is
// stored: its curve points are rationals, kept in double as approximations
// within a proven error. Storing it in the host's scalar (float or double,
// mesh.h: Scalar) rounds every coordinate, and near-coincident surfaces (CAD
// parts a hair apart, faces meeting at a tiny angle) may then cross or
// collapse where they met only along a curve: a double is not exact either.
// storeForHost rounds, checks exactly on the stored values and repairs, for
// either scalar:
//  1. roundForHost: each new vertex of a crossing or collapsed face is
//     re-rounded to the neighbouring scalar values (one, then two steps
//     each way per coordinate) where that removes the defect;
//  2. where defects are left, the split again from the inputs with curve
//     points within kHostSnapSteps steps of a vertex or edge merged into it;
//  3. splitStoredAgain: the stored result split along its own crossings (on
//     the stored values) and rounded again, a bounded number of rounds;
//  4. mendCollinearNewFaces: new faces left flat are flipped away or removed;
//  5. where defects are still left, all of that from the inputs with quality
//     snapping (kQualitySnapTolerance), kept if it leaves fewer.
// Every loop is bounded (rounds, pairs) and reports progress, which may
// cancel it (CancelledError).
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/repair/split/split.h"

namespace meshmend {

// How close (in steps of the host's scalar) the second split merges curve
// points: far below any feature the host can hold, and enough to take the
// points rounding confuses.
inline constexpr int kHostSnapSteps = 8;

// The quality snapping tried last (SplitOptions::snap_tolerance): the
// tolerance that removes most slivers.
inline constexpr double kQualitySnapTolerance = 0.05;

struct OutputStageOptions {
  Scalar scalar = Scalar::kDouble;  // the host's storage
  // Re-rounding passes at each reach (one step, then two steps away).
  int rounding_passes = 4;
  // Work bound of step 1: the most exact pair tests its runs make in all
  // (each re-rounding choice of a vertex tests the faces around it against
  // their neighbours), over the whole stage; past it, rounding stops where
  // it is (some ten million tests a second).
  std::size_t max_rounding_tests = 20000000;
  // Rounds of splitting the stored result again where it still crosses;
  // surfaces a millionth of their size apart took five to seven.
  int split_rounds = 8;
  // Work bound of step 3: the most pairs all its rounds together split
  // again. A round that would pass it is not run, and the stage ends with
  // the defects left (StoredOutput::bounded).
  std::size_t max_pairs_split_again = 100000;
  // Steps 2 and 5 (whole splits again, with snapping). Off: re-rounding,
  // splitting again and mending only, without moving any curve point by
  // more than the rounding does.
  bool resplit_with_snapping = true;
  Progress progress;  // between steps and rounds; returning false cancels
};

struct StoredOutput {
  Scalar scalar = Scalar::kDouble;
  // Pairs with a new or moved face still crossing once stored, by the
  // stage's rule: faces meeting only at shared vertices or along a shared
  // edge do not count, nor faces with the same three vertices (a planar
  // overlap kept in each part), which no rounding moves apart. With the
  // split's `complete`, no other pair can cross. The count of intersecting
  // pairs a checker gives is storedIntersectingPairs.
  std::size_t crossing = 0;
  std::size_t degenerate_new_faces = 0;  // new faces with collinear corners as stored
  std::size_t vertices_rerounded = 0;    // new vertices not at their nearest scalar values
  std::size_t rounding_tests = 0;        // exact pair tests step 1 made, over all its runs
  // Step 2 (or 5) made the result: curve points within kHostSnapSteps steps
  // of a vertex or edge were merged into it.
  bool snapped_for_host = false;
  bool quality_snapped_for_host = false;  // step 5 made it
  std::size_t collinear_faces_mended = 0;
  std::size_t pairs_split_again = 0;  // step 3, over its rounds
  int rounds_split_again = 0;
  // A work bound (max_rounding_tests, max_pairs_split_again) stopped a step
  // with defects left.
  bool bounded = false;
  double time_ms = 0;
  // Why defects are left, or empty: a sentence for the log and the report.
  std::string explanation() const;
};

// Rounds, checks and repairs `result` (which needs the merged output,
// SplitOptions::merged_output; throws InvalidInputError without it) for the
// host: `merged` and `meshes` hold the stored coordinates afterwards.
// `inputs` and `options` are those of the split (steps 2 and 5 split them
// again).
StoredOutput storeForHost(SplitResult& result, const std::vector<const Mesh*>& inputs,
                          const SplitOptions& options, const OutputStageOptions& stage);

// Step 1: every coordinate rounded to stage.scalar, and where that makes
// faces that met only along a curve cross (or a new face collinear), the
// new vertices of those faces re-rounded to the neighbouring values (each
// coordinate to the value just below or above its unrounded one, then the
// next out), choosing the position under which the faces around the vertex
// cross nothing: stage.rounding_passes passes per reach, at most
// stage.max_rounding_tests exact pair tests in all. Applied to `merged` and
// `meshes` alike. Returns the crossing pairs left (StoredOutput::crossing);
// `out` (optional) adds the vertices moved off their nearest value and
// whether the bound stopped it.
// Where rounding to nearest leaves more than `giveUpAbove` defects, nothing
// is re-rounded (a round of step 3 that ran away).
std::size_t roundForHost(SplitResult& result, const OutputStageOptions& stage,
                         StoredOutput* out = nullptr,
                         std::size_t giveUpAbove = std::numeric_limits<std::size_t>::max());

// The faces of `result.merged` the split left as they were (not
// merged_new_face) whose boxes overlap given boxes (NearFaceFinder), from
// the split's trees of the input faces, which it takes with
// merged_face_origin (emptied): a few descents where the search around the
// changed faces otherwise passes over the whole mesh. Empty where the trees
// are missing (the split searched no self-intersections) or the origins do
// not describe the `faces` faces stored (the merged output was changed).
NearFaceFinder keptFacesNear(SplitResult& result, std::size_t faces);

// Step 1 for any operation that computes new points in double (hole
// patches, stitches, vertices moved for clearance): `points` rounded to
// stage.scalar, and where that makes a face marked `changed` (new, or
// around a new or moved vertex) cross another or collapse, the vertices
// marked `movable` re-rounded. Returns what is left: `crossing` counts the
// pairs with a changed face that intersect beyond their shared corners
// (faces with the same three vertices apart), `degenerate_new_faces` the
// changed faces left collinear.
StoredOutput storeNewPoints(std::vector<Point3>& points, const std::vector<Triangle>& triangles,
                            const std::vector<char>& movable, const std::vector<char>& changed,
                            const OutputStageOptions& stage);

// Step 3: where the stored merged output still crosses, it is split along
// its own intersections as stored (exactly, on the stored values) and
// rounded again, up to stage.split_rounds times while crossings are left; a
// round that leaves more than twice the fewest crossings so far is not taken
// and ends the rounds (they run away where surfaces nearly coincide over a
// region). Provenance goes through to `inputs` (the meshes split first),
// curve edges, new-face flags and merged_vertex follow, and `meshes` are
// made again from the merged output unless planar overlaps were kept once
// there. Uses split.snap_host_steps. Returns the crossings left; `out`
// receives the pairs split, the rounds and whether the bound stopped it.
std::size_t splitStoredAgain(SplitResult& result, const std::vector<const Mesh*>& inputs,
                             const SplitOptions& split, const OutputStageOptions& stage,
                             StoredOutput& out);

// Step 4: where rounding left a new face of the merged output (required, as
// above) with three collinear corners (a point a step from an edge, where no
// position keeps it off the line and nothing crossing), the corner between
// the other two lies on the edge they span. With one face beyond that edge
// (running the other way), the edge is flipped, splitting that face at the
// corner: the two faces that replace the pair cover it exactly, so nothing
// new can cross. With none, the flat face only fills a gap of no area
// between faces that already meet along its short sides, and is removed
// where that leaves its sides closer to closed (as many faces running each
// way; collapsed_faces_removed counts it). Curve edges, provenance and the
// separate outputs follow. Returns the flat faces gone.
std::size_t mendCollinearNewFaces(SplitResult& result);

// Pairs crossing in the merged output (required, as above) by the stage's
// rule (StoredOutput::crossing), over the whole output, with coordinates
// rounded to `scalar`.
std::size_t crossingsLeft(const SplitResult& result, Scalar scalar);

// New faces of the merged output (required, as above) whose corners, as
// stored, coincide or are collinear (exactly).
std::size_t degenerateNewFaces(const SplitResult& result);

// Intersecting pairs of `mesh` stored in `scalar`, by the rule of the
// checker meshcheck and of CGAL's self_intersections (vertex identity =
// vertex index; faces with the same three vertices count, degenerate faces
// are never compared): what any such tool counts in the written file. Every
// report's remaining_intersecting_pairs is this count.
std::size_t storedIntersectingPairs(const Mesh& mesh, Scalar scalar);
std::size_t storedIntersectingPairs(MeshArrays mesh, Scalar scalar);

// The same count for a split's stored output: the merged one, or with
// `separate` the sum over `meshes` (each as its own file). Where every
// intersecting pair of the mesh split last was split (the split was
// complete, or the stage split its result again), faces the stage left as
// they were cross nothing: the count is then the stage's crossings plus the
// pairs of faces with the same three vertices, without a search.
std::size_t storedIntersectingPairs(const SplitResult& result, const StoredOutput& stored,
                                    bool separate);

// The report keys of the stage: host_scalar, snapped_for_host,
// quality_snapped_for_host, collinear_faces_mended, vertices_rerounded,
// rounds_split_again, output_stage_bounded, output_stage_ms.
void addToReport(const StoredOutput& stored, JsonObject& report);

}  // namespace meshmend
