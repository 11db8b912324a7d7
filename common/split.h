// Intersect and split (intersection paper §2): the curves where meshes
// intersect are inserted into every mesh they cross, in place: each crossed
// face is re-triangulated on its own with its curve segments as constraints
// (retriangulate.h), points on an edge split that edge in both faces that
// share it, and every face not crossed stays exactly as it was.
#pragma once

#include <array>
#include <vector>

#include "common/intersections.h"
#include "common/json.h"
#include "common/mesh.h"
#include "common/progress.h"

namespace meshmend {

struct SplitOptions {
  bool between_meshes = true;    // insert the curves where different meshes meet
  bool self = false;             // also split each mesh along its own self-intersections
  bool weld_duplicates = false;  // first merge exact-duplicate vertices (scan seams) in each mesh
  // First remove faces with the same three vertices as another face of their
  // mesh (after welding): the same surface twice, intersecting itself
  // everywhere (decimated scans have them). The first of each group stays.
  bool remove_duplicate_faces = false;
  // Where surfaces overlap in a plane, both sides' faces there coincide
  // (same three vertices): keep each such face once in `merged` (the
  // intersection paper's result is free of duplicate geometry), and the
  // curve edges inside the overlap become ordinary edges. Off, `merged`
  // keeps both: each input part stays a whole surface there, as the patch
  // classification of booleans needs (patches.h).
  bool overlaps_once = false;
  bool separate_meshes = true;  // build `meshes` (one output per input)
  // Build `merged` (all meshes in one, welded along the curves) with
  // merged_curve_edges, merged_vertex and merged_new_face. Without it the
  // split does what refining the meshes in place does, and the counts (curve
  // loops, slivers) are the same; roundToFloat and remainingIntersections
  // need it. At least one of the two outputs must be asked for.
  bool merged_output = true;
  // Quality snapping (intersection paper §2.7), 0 = off. A new curve vertex
  // closer than snap_tolerance × the longest edge around it to an input
  // vertex it shares an edge with, or to the next curve vertex along its
  // curve, is merged into that vertex, and a new
  // vertex closer than snap_tolerance × |ab| to an input edge ab of its face
  // splits that edge instead of leaving a sliver. Scale-free; 0.05 removes
  // most slivers. Each snap is kept only if the meshes stay manifold, no
  // face flips, the smallest angle there grows and no face crosses more
  // faces than before (exact test). Snapping moves the other surface by at
  // most the tolerance near the curve, and may split input faces next to a
  // curve: those are no longer bit-identical to the input.
  double snap_tolerance = 0;
  // Snapping by absolute distance as well, 0 = off: a new curve vertex
  // closer than this many float steps (at its coordinates' magnitude) to a
  // vertex or edge as above is merged or splits it, under the same checks.
  // A float host (MeshLab 2020.09 stores float) cannot keep such points
  // apart; rounding them to float may make faces cross or collapse.
  double snap_float_steps = 0;
  Progress progress;  // called between stages
};

struct SplitResult {
  // Per input mesh: the mesh with the curves inserted (input vertices first,
  // in their order, then the new ones; provenance records every element's
  // birth), and its curve edges (pairs of vertex indices). Empty unless
  // options.separate_meshes.
  std::vector<Mesh> meshes;
  std::vector<std::vector<std::array<int, 2>>> curve_edges;
  // All meshes in one, welded along the curves: the curves become
  // non-manifold edges; provenance keeps the input mesh. These four are
  // empty unless options.merged_output.
  Mesh merged;
  std::vector<std::array<int, 2>> merged_curve_edges;
  std::vector<std::vector<int>> merged_vertex;  // per mesh, per vertex: its vertex in `merged`
  std::vector<char> merged_new_face;            // per face of `merged`: 1 when a split made it
  // Per face of `merged` (empty without snapping): 1 when quality snapping
  // reshaped or made it, so that it may lie off its birth face's plane.
  std::vector<char> merged_snapped_face;
  // Every intersecting pair of the inputs was searched for (and split): each
  // mesh's own and those between meshes. Faces left as they were then cross
  // nothing, so the intersections left are among pairs with a new face.
  bool complete = false;
  std::size_t intersecting_pairs = 0;              // pairs found (and split)
  std::size_t faces_split = 0;                     // input faces re-triangulated
  std::size_t faces_added = 0;                     // output faces minus input faces
  std::size_t new_vertices = 0;                    // curve points that are not input vertices
  std::size_t degenerate_faces_kept = 0;           // zero-area faces a curve touches, left unsplit
  std::size_t vertices_welded = 0;                 // duplicates merged first (weld_duplicates)
  std::size_t duplicate_faces_removed = 0;         // remove_duplicate_faces
  std::size_t coincident_faces = 0;                // merged: twins in planar overlaps
  std::size_t coincident_faces_removed = 0;        // the same, kept once (overlaps_once)
  std::size_t pairs_split_after_rounding = 0;      // splitRoundedAgain: pairs split again
  std::size_t collapsed_faces_removed = 0;         // merged: faces whose corners welded into one
  double smallest_new_angle_deg = 180;             // smallest angle of a face the split made
  double smallest_new_angle_deg_unsnapped = 180;   // the same before quality snapping
  std::size_t new_faces_below_1deg = 0;            // slivers: new faces with an angle under 1°
  std::size_t new_faces_below_1deg_unsnapped = 0;  // the same before quality snapping
  std::size_t vertices_snapped = 0;                // new vertices merged into input vertices
  std::size_t edges_snapped = 0;                   // input edges split at a new vertex
  std::size_t curve_edges_welded = 0;              // curve edges, each once (as in `merged`)
  std::size_t curve_loops = 0;                     // curve components without end points
  std::size_t open_curves = 0;                     // curve components with end points
  double time_ms = 0;
};

// Throws InvalidInputError for empty meshes, non-finite coordinates or when
// neither output (separate_meshes, merged_output) is asked for.
SplitResult splitAlongIntersections(const std::vector<const Mesh*>& meshes,
                                    const SplitOptions& options = {});

// Prepares the output for float storage (MeshLab's), which needs the merged
// output (SplitOptions::merged_output; throws InvalidInputError without
// it): every coordinate is rounded to float, and where that makes faces that
// met only along a curve cross, the new vertices of those faces are rounded
// the other way (each coordinate to the float just below or above its exact
// value, or where neither keeps surfaces meeting at a very small angle
// apart, the next float out), choosing the rounding under which the faces
// around the vertex cross nothing. Curve points a few float steps apart may
// leave crossings no rounding removes: snapping (snap_float_steps or
// snap_tolerance) merges them, and splitRoundedAgain splits what is left.
// Applied to `merged` and to `meshes` alike. Returns the pairs still
// crossing among those with a new face or a face that rounding moved (faces
// kept exactly as they were cannot cross anything new; faces with the same
// three vertices are never a crossing, see remainingIntersections); with
// `complete`, that is every intersecting pair of the rounded output.
std::size_t roundToFloat(SplitResult& result, int passes = 4);

// Where roundToFloat left faces of the merged output crossing: splits the
// merged output along its own intersections as rounded (exactly, on the
// float values) and rounds again, up to `rounds` times while crossings are
// left (each round's new points, rounded, may cross a little again: near
// coincident surfaces, a millionth of their size apart, took five to
// seven); a round that leaves more than twice the fewest crossings so far
// is not taken and ends the rounds (they run away there). Points that the float values put a step
// apart now meet where they cross. Provenance goes through to `inputs` (the meshes split first, for
// the barycentric coordinates of new vertices), and the merged output's curve edges, new-face flags
// and merged_vertex follow, and `meshes` (separate outputs), when there are any, are made again
// from the merged output (each input's vertices in their order, then the new ones), unless planar
// overlaps were kept once there (overlaps_once: then they stay). Uses options.snap_float_steps.
// Returns the pairs still crossing (as roundToFloat counts them).
std::size_t splitRoundedAgain(SplitResult& result, const std::vector<const Mesh*>& inputs,
                              const SplitOptions& options, int rounds = 8);

// How close (in float steps) roundForFloatHost merges curve points: far
// below any feature a float mesh can hold, and enough to take the points
// rounding confuses.
inline constexpr int kFloatSnapSteps = 8;

// The quality snapping roundForFloatHost tries (with kFloatSnapSteps) when
// the float result is still broken without it: the tolerance that removes
// most slivers (SplitOptions::snap_tolerance).
inline constexpr double kFloatQualitySnapTolerance = 0.05;

struct FloatOutput {
  std::size_t crossing = 0;                // pairs still crossing, as roundToFloat counts them
  bool snapped_for_float = false;          // the result is the second split (snap_float_steps)
  std::size_t collinear_faces_mended = 0;  // mendCollinearNewFaces
  // The result is the split with quality snapping (kFloatQualitySnapTolerance)
  // that roundForFloatHost tried (snapped_for_float is set too).
  bool quality_snapped_for_float = false;
};

// The result as a float host (MeshLab 2020.09) stores it: rounded
// (roundToFloat); where that left crossings or collapsed new faces and
// options.snap_float_steps was 0, the split of `inputs` again with
// snap_float_steps = kFloatSnapSteps, kept if it leaves fewer of both; then
// what still crosses split again (splitRoundedAgain; the separate outputs
// follow the merged one); new faces left with collinear corners are mended
// (mendCollinearNewFaces); last, where crossings or collapsed new faces are
// still left and options.snap_tolerance was 0, all of that from `inputs`
// with quality snapping (kFloatQualitySnapTolerance), kept if it leaves
// fewer.
FloatOutput roundForFloatHost(SplitResult& result, const std::vector<const Mesh*>& inputs,
                              const SplitOptions& options);

// Where rounding left a new face of the merged output (required, as
// above) with three collinear corners (a point a float step from an edge,
// where no float position keeps it off the line and nothing crossing), the
// corner between the other two lies on the edge they span. With one face
// beyond that edge (running the other way), the edge is flipped, splitting
// that face at the corner: the two faces that replace the pair cover it
// exactly, so nothing new can cross. With none, the flat face only fills a
// gap of no area between faces that already meet along its short sides,
// and is removed where that leaves its sides closer to closed (as many
// faces running each way; collapsed_faces_removed counts it). Curve edges,
// provenance and the separate outputs follow. Returns the flat faces gone.
std::size_t mendCollinearNewFaces(SplitResult& result);

// Intersecting pairs left in the merged output (required, as above), by the self-intersection
// rule (faces that meet only along a shared curve edge or vertex do not
// count), with coordinates as stored in double or, with `asFloat`, rounded
// to float as MeshLab stores them. Faces with the same three vertices do not
// count either: a planar overlap kept in each part (overlaps_once off;
// coincident_faces counts them) or duplicate faces of an input, which no
// split or rounding changes (a checker that takes them for intersecting
// pairs, as meshcheck does, counts one pair each).
std::size_t remainingIntersections(const SplitResult& result, bool asFloat);

// New faces of the merged output (required, as above) whose corners, as
// stored, coincide or are collinear (exactly): after rounding to float,
// curve points a float step apart may collapse a face. (Faces kept from
// the inputs are as the inputs had them.)
std::size_t degenerateNewFaces(const SplitResult& result);

// Per face of `mesh`: bit i set when its edge from corner i to corner i+1 is
// one of `curveEdges` (pairs of vertex indices, either order), so that later
// operations (patch painting) find the curves. MeshLab layers carry it as
// the per-face attribute named kCurveEdgesAttribute.
std::vector<std::uint8_t> curveEdgeFlags(const Mesh& mesh,
                                         const std::vector<std::array<int, 2>>& curveEdges);
inline constexpr const char* kCurveEdgesAttribute = "meshmend_curve_edges";

// The report_file keys: curve_edges, curve_loops, open_curves, faces_split, ...
JsonObject toJson(const SplitResult& result);

}  // namespace meshmend
