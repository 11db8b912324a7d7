// Intersect and split (McLaurin 2012, §2): the curves where meshes
// intersect are inserted into every mesh they cross, in place: each crossed
// face is re-triangulated on its own with its curve segments as constraints
// (retriangulate.h), points on an edge split that edge in both faces that
// share it, and every face not crossed stays exactly as it was.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/exact/intersections.h"

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
  // McLaurin 2012's result is free of duplicate geometry), and the
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
  // Quality snapping (McLaurin 2012, §2.7), 0 = off. A new curve vertex
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
  // closer than this many steps of the host's scalar (`host`, at its
  // coordinates' magnitude) to a vertex or edge as above is merged or splits
  // it, under the same checks. A host cannot keep such points apart:
  // rounding them to its scalar may make faces cross or collapse.
  double snap_host_steps = 0;
  Scalar host = Scalar::kDouble;  // the scalar whose steps snap_host_steps counts
  // Work bound: a face in which more than this many pairs of the faces
  // crossing it cross each other too (three faces through one point) stops
  // the split with WorkLimitError before anything is cut: the curves cross
  // each other about as often in that face, each crossing an exact point of
  // long numbers (a spindle torus near its axis: thousands; real meshes:
  // under ten; CAD boxes overlapping in planes: a few hundred). 0 = no bound.
  std::size_t max_triple_points_per_face = 1000;
  // Called once the intersecting pairs are found (faces numbered as the
  // inputs, after welding and removing duplicate faces), before anything is
  // cut: a caller's own work bounds, which refuse by throwing. None: no call.
  std::function<void(const std::vector<IntersectingPair>& pairs)> pairs_found;
  Progress progress;  // called between stages
};

// The most triple points (pairs of a face's crossing faces that cross each
// other) in one face of the meshes whose face counts are `faces`, and that
// face; counting stops past `bound`.
struct TriplePoints {
  std::size_t count = 0;
  FaceRef face;
};
TriplePoints mostTriplePoints(const std::vector<IntersectingPair>& pairs,
                              const std::vector<std::size_t>& faces, std::size_t bound);

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
  // `merged` as arrays, as the split made it: the output stage takes them
  // (and leaves them empty) instead of copying `merged` into arrays again.
  // Code that changes `merged` before the stage empties them.
  std::vector<Point3> merged_points;
  std::vector<Triangle> merged_triangles;
  std::vector<FaceOrigin> merged_face_origin;  // as merged's provenance
  // Where each input mesh's faces lie (with options.self and merged_output):
  // the search's tree of its faces' boxes, and the input face of each tree
  // box (FaceOrigin::face). With merged_face_origin they find the faces of
  // `merged` left as they were near a few boxes, without a pass over all.
  std::vector<std::shared_ptr<const BoxTree>> input_face_trees;
  std::vector<std::vector<int>> input_face_of_box;
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
