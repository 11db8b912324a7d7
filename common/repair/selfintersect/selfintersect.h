// Self-intersection removal by valid region growing (TransforMesh paper §2):
// a consistently oriented mesh that folds through itself is cut along its
// self-intersection curves (split.h), the part of the surface that is
// *outside* with respect to its orientation is grown from seed faces, and
// the kept faces are stitched into a manifold mesh. Merges and splits of
// components come out of the side choice at the curves, as in the paper.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/repair/output_stage.h"

namespace meshmend {

struct SelfIntersectionOptions {
  // Pre-treatment (§2.1): faces with zero area or a smallest angle below
  // degenerate_angle_deg are removed first, by collapsing their shortest
  // edge or flipping their longest one. Each operation is kept only if no
  // face turns over, no face gets thinner than the threshold, and no face
  // crosses a face it did not cross before (exact test).
  bool pretreat = true;
  double degenerate_angle_deg = 0.1;
  // Merge exactly coincident vertices first (scan seams): otherwise a seam
  // is a border and the two sides are grown apart.
  bool weld_duplicates = true;
  // Quality snapping of the split (split.h, SplitOptions::snap_tolerance):
  // curve points within this fraction of the local edge length of a vertex
  // or edge merge into it instead of leaving slivers, whose rounded corners
  // could cross again. Moves the surface by at most that much near a curve.
  // Where that leaves crossings or non-manifold edges (sheets closer than
  // the tolerance), the result is made again without snapping and, if that
  // one has fewer, returned instead (result.snapping_dropped).
  double snap_tolerance = 0.05;
  // Work on float coordinates (MeshLab's storage): the input is taken as
  // float, and new vertices are rounded before the region growing decides,
  // so that its decisions hold for the stored mesh.
  bool round_to_float = false;
  // Where the outer surface touches itself at a vertex or along an edge,
  // stitching gives each side its own copy of the vertex (§2.4); the copies
  // then move apart by 1/1000 of their fan's size, so that the result is
  // free of touching faces too (which count as intersections).
  bool separate_touching = true;
  bool keep_removed = false;  // also return the removed faces (result.removed)
  // Count the intersecting pairs of the result (exact, every pair, on the
  // coordinates as stored): part of the contract below. Off, the contract
  // is checked without it and the result says it was not verified.
  bool verify = true;
  // Work bound: more intersecting pairs than this (found exactly before
  // anything is cut; splitting costs about 0.1 ms per pair) and the removal
  // stops with WorkLimitError, the input unchanged. 0 = no bound. Each
  // face's re-triangulation has its own bound (PatchInput::max_exact_evaluations).
  std::size_t max_intersecting_pairs = 200000;
  // Work bound: a face in which more than this many pairs of the faces
  // crossing it cross each other too (triple points: three faces through
  // one point) stops the removal with WorkLimitError. The curves then cross
  // each other in that face about as often, each crossing an exact point of
  // long numbers (a spindle torus: thousands per face near its axis; the
  // real meshes: at most 6; boxes of a CAD export overlapping in planes: a
  // few hundred). 0 = no bound.
  std::size_t max_triple_points_per_face = 100;
  // A result that misses its contract: false throws ContractError, saying
  // what does not hold; true returns it with contract_met false and the
  // failures listed (the plugin marks such a layer as partial).
  bool keep_partial = false;
  Progress progress;  // called between stages and inside the long ones (cancellation)
};

struct SelfIntersectionResult {
  // The outer surface, oriented as the input; every element's provenance
  // names the input vertex or face it comes from (new curve vertices: the
  // input face they lie on). `removed`: the faces left out (keep_removed).
  Mesh mesh;
  Mesh removed;

  std::size_t faces_in = 0;                   // input faces
  std::size_t intersecting_pairs_before = 0;  // self-intersecting pairs (exact) after pre-treatment
  std::size_t degenerate_faces_before = 0;    // faces under the threshold before pre-treatment
  std::size_t collapses = 0, flips = 0;       // pre-treatment operations
  std::size_t degenerate_faces_left = 0;      // under the threshold after pre-treatment
  std::size_t vertices_welded = 0;            // coincident vertices merged first
  std::size_t duplicate_faces_removed = 0;    // faces repeating another's three vertices
  std::size_t faces_split = 0;                // faces re-triangulated along the curves
  std::size_t faces_after_split = 0;          // faces the region growing chose from
  std::size_t faces_kept = 0, faces_removed = 0;
  std::size_t seeds = 0;           // seed faces the growing started from
  std::size_t rays = 0;            // exact ray tests cast to find them
  std::size_t side_conflicts = 0;  // curve edges where no face continued the surface consistently
  std::size_t vertices_duplicated = 0;    // singular vertices split while stitching (§2.4)
  std::size_t edges_duplicated = 0;       // singular edges (more than two kept faces) split
  std::size_t vertices_separated = 0;     // copies moved apart (separate_touching)
  bool separation_bound_reached = false;  // the separation's exact tests hit their bound
  bool inside_out =
      false;  // closed input with negative volume: grown turned over, returned as it was
  bool input_closed = false, output_closed = false;
  std::size_t border_edges_before = 0, border_edges_after = 0;
  std::size_t non_manifold_edges_before = 0, non_manifold_edges_after = 0;
  // Edges of the cleaned input (welded, opposite duplicate faces cancelled)
  // used more than once but unequally in the two directions: fins, where
  // the surface has no inside. A face that cannot be continued there leaves
  // a border (counted in side_conflicts), so a closed input with fins may
  // come out with small holes at them.
  std::size_t fin_edges_before = 0;
  int components_before = 0, components_after = 0;
  // Genus of a closed, edge-manifold mesh (summed over components), else -1.
  int genus_before = -1, genus_after = -1;
  // Snapping left crossings or non-manifold edges (sheets closer than its
  // tolerance): this result was made again without it.
  bool snapping_dropped = false;
  StoredOutput stored;                           // the output stage on the cut (output_stage.h)
  bool verified = false;                         // remaining_intersecting_pairs was counted
  std::size_t remaining_intersecting_pairs = 0;  // in the result, as stored (float if rounded)
  // The contract (see removeSelfIntersections), checked on `mesh` as stored.
  bool contract_met = false;
  std::vector<std::string> contract_failures;  // what does not hold, one item each
  // Nothing to remove: the input already met the contract and the growing
  // kept every face. `mesh` is then the input exactly as it was.
  bool unchanged = false;
  double time_ms = 0;
  // Where the time went, in milliseconds (the stages of the paper, then
  // ours); `split` finds the intersecting pairs and cuts along them.
  struct StageTimes {
    double pretreat = 0, split = 0, growing = 0, stitching = 0, separation = 0, verify = 0;
  } stage_ms;
};

// Preconditions, checked first: a non-empty mesh with finite coordinates
// whose faces are consistently oriented (no edge whose faces all run it the
// same way), with at most max_intersecting_pairs intersecting pairs.
// Throws InvalidInputError / TopologyError / WorkLimitError otherwise, with
// the filter that fixes it. A mesh with an edge used unequally in the two
// directions (a border, or a fin of three faces) has no winding number: its
// seeds follow the paper's rule (nothing in front of them), and borders stay
// borders.
//
// Contract, checked exactly at the end on the mesh as it will be stored
// (float coordinates with round_to_float): it has faces; no intersecting
// pair (meshcheck's rule; with verify); every edge has at most two faces and
// every vertex one fan; faces that share an edge run it opposite ways; it is
// closed where the input was closed without fins; no face is degenerate
// that the pre-treated input did not have. Where a result misses it, the
// removal is made again without snapping; if that misses it too, it throws
// ContractError (or, with keep_partial, returns the result marked).
// Stops with CancelledError when the progress callback asks.
SelfIntersectionResult removeSelfIntersections(const Mesh& input,
                                               const SelfIntersectionOptions& options = {});

// The report_file keys: faces_kept, faces_removed, components_before/after,
// genus_before/after, remaining_intersecting_pairs, time_ms, ...
JsonObject toJson(const SelfIntersectionResult& result);

}  // namespace meshmend
