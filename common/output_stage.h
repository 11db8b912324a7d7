// The split's output stage (DESIGN §4): the result is exact until it is
// stored; storing it in the host's scalar rounds it, checks it exactly and
// repairs what rounding broke.
#pragma once

#include <cstddef>
#include <vector>

#include "common/mesh.h"
#include "common/split.h"

namespace meshmend {

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

}  // namespace meshmend
