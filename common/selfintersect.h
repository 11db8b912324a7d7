// Self-intersection removal by valid region growing (TransforMesh paper §2):
// a consistently oriented mesh that folds through itself is cut along its
// self-intersection curves (split.h), the part of the surface that is
// *outside* with respect to its orientation is grown from seed faces, and
// the kept faces are stitched into a manifold mesh. Merges and splits of
// components come out of the side choice at the curves, as in the paper.
#pragma once

#include <cstddef>

#include "common/json.h"
#include "common/mesh.h"
#include "common/output_stage.h"
#include "common/progress.h"

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
  bool verify = true;         // count the intersecting pairs left (exact) in the result
  Progress progress;          // called between stages
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
  std::size_t vertices_duplicated = 0;  // singular vertices split while stitching (§2.4)
  std::size_t edges_duplicated = 0;     // singular edges (more than two kept faces) split
  std::size_t vertices_separated = 0;   // copies moved apart (separate_touching)
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
  double time_ms = 0;
  // Where the time went, in milliseconds (the stages of the paper, then ours).
  struct StageTimes {
    double pretreat = 0, split = 0, growing = 0, stitching = 0, separation = 0, verify = 0;
  } stage_ms;
};

// Preconditions: a non-empty mesh with finite coordinates whose faces are
// consistently oriented (no edge whose faces all run it the same way).
// Throws InvalidInputError / TopologyError otherwise, with the MeshLab
// filter that fixes it. A mesh with an edge used unequally in the two
// directions (a border, or a fin of three faces) has no winding number: its
// seeds follow the paper's rule (nothing in front of them), and borders stay
// borders.
SelfIntersectionResult removeSelfIntersections(const Mesh& input,
                                               const SelfIntersectionOptions& options = {});

// The report_file keys: faces_kept, faces_removed, components_before/after,
// genus_before/after, remaining_intersecting_pairs, time_ms, ...
JsonObject toJson(const SelfIntersectionResult& result);

}  // namespace meshmend
