// Trimming a mesh along a loop of its vertices and stitching borders across
// gaps (Widing & Ekeberg 2015, "Tailoring biomechanical model meshes for
// aero-acoustic simulations"; docs/REFERENCES.md). Trimming (§2.1) removes the faces on one
// side of a closed vertex loop without creating vertices; stitching (§2.2)
// fills the gap between two border paths with the merge-like triangulation
// that always takes the shorter of the two next diagonals. Beyond the paper:
// loops come from selections or a few picked vertices, stitched faces are
// oriented like the faces they join, closed loops are aligned automatically,
// wide gaps can be subdivided, junctions of three or more patches are
// stitched sequentially with the remaining paths concatenated (Figure 3),
// and facing borders are found and closed automatically (closeGaps).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/repair/edit_contract.h"
#include "common/repair/output_stage.h"

namespace meshmend {

// ---------------------------------------------------------------- trimming

struct TrimOptions {
  // ---- The loop: exactly one of these three is used, the first non-empty.
  // Loop vertices in order (the last joins back to the first; repeating the
  // first at the end is allowed); consecutive vertices must share an edge.
  std::vector<int> loop;
  // One flag per vertex: the selected vertices must form one closed path
  // along mesh edges (a triangle of three selected vertices at a sharp turn
  // is allowed: its short cut is not part of the path).
  std::vector<bool> selected_vertices;
  // A few vertices in order, joined by shortest edge paths (Dijkstra on edge
  // lengths) into a loop; each leg avoids the vertices of the earlier ones.
  std::vector<int> picked_vertices;

  // ---- The side to keep. A face index: the faces on its side of the loop
  // are kept. -1: the loop's orientation decides (§2.1): kept are the faces
  // that run the loop's edges in the loop's direction, i.e. the side on the
  // left of the loop as seen from the side the normals point to. A loop
  // recovered from a selection has no direction: it needs keep_face.
  int keep_face = -1;
  // Drop the vertices that only removed faces used (indices change: see
  // TrimResult::vertex_index). false keeps every vertex (some unreferenced).
  bool remove_unreferenced_vertices = true;
  Progress progress;  // called between stages
};

struct TrimResult {
  std::vector<int> loop;  // the loop used, input vertex indices, in its direction
  Mesh removed;           // the removed faces and their vertices, provenance kept
  // For every input vertex its index in the trimmed mesh (-1: dropped).
  std::vector<int> vertex_index;
  std::size_t faces_kept = 0;
  std::size_t faces_removed = 0;
  std::size_t faces_on_loop = 0;  // faces with all three corners on the loop (classified too)
  std::size_t border_edges_before = 0;
  std::size_t border_edges_after = 0;
  double time_ms = 0;
};

// Removes the faces on one side of a closed vertex loop. No vertex is added
// or moved; connected components the loop does not touch are kept.
// Throws InvalidInputError for an empty mesh, a non-finite coordinate, deleted
// elements, a vertex index out of range, consecutive loop vertices that share
// no edge, or a selection that is not one closed path (the message names the
// vertex where it breaks and its position); TopologyError when the loop does
// not separate the mesh (both sides are connected around it) or the side
// cannot be decided by orientation (inconsistently oriented faces along the
// loop). The mesh is unchanged when it throws.
TrimResult trimAlongLoop(Mesh& mesh, const TrimOptions& options);

// ---------------------------------------------------------------- stitching

// A border path: vertices in order along a border (consecutive vertices
// normally share a border edge; they need not).
struct BorderPath {
  std::vector<int> vertices;
  // Open path or closed loop (the last vertex joins back to the first).
  // Auto: closed when the first vertex is repeated at the end or the first
  // and last vertices (of three or more) share a border edge.
  enum class Shape { Auto, Open, Closed } shape = Shape::Auto;
};

struct StitchOptions {
  BorderPath a, b;  // the two paths; every vertex must be on a border edge
  // Subdivision of wide gaps: when a stitched triangle's rung (the edge
  // across the gap) is longer than max_aspect_ratio x the mean edge length
  // of the two paths, rows of new vertices are inserted across the whole
  // strip, evenly spaced between the paths, and each row is resampled at
  // the edge length interpolated between the paths. 0 = never (no new vertices).
  double max_aspect_ratio = 0;
  int max_rows = 64;  // at most this many rows of new vertices
  // Stitching two sides whose faces are oppositely oriented (one of them
  // would need flipping) is refused with a TopologyError unless this is set;
  // then the new faces follow path a's side and the conflicts are counted.
  bool allow_orientation_conflict = false;
  // Exact check that no new face intersects the mesh (or another new face)
  // beyond the corners they share; counted in new_intersecting_pairs.
  bool check_intersections = true;
  // Store the result in float (MeshLab's float hosts): the mesh and the new
  // vertices rounded through the output stage (output_stage.h), the count
  // of new_intersecting_pairs on the stored values.
  bool round_to_float = false;
  Progress progress;  // called between stages
};

struct StitchResult {
  std::size_t faces_added = 0;
  std::size_t vertices_added = 0;  // rows of the subdivision
  std::size_t border_edges_before = 0;
  std::size_t border_edges_after = 0;
  bool closed = false;      // the paths were stitched as two closed loops
  bool reversed_b = false;  // path b was traversed backwards (orientation or geometry)
  std::size_t orientation_conflicts = 0;  // border edges of a path against its majority direction
                                          // (+ the whole side when allow_orientation_conflict)
  // Intersecting pairs (exact, the self-intersection rule) involving a new
  // face: with check_intersections, how many the stitch created.
  std::size_t new_intersecting_pairs = 0;
  bool checked = false;         // new_intersecting_pairs was counted
  StoredOutput stored;          // the output stage on the new vertices (output_stage.h)
  double max_aspect_ratio = 0;  // of the new faces: longest edge / shortest altitude
  // The two end rungs of an open stitch (vertex on path a, vertex on path b),
  // which are new border edges unless they existed; {-1,-1} for loops.
  std::array<int, 2> first_rung{-1, -1}, last_rung{-1, -1};
  std::vector<int> new_faces;     // indices of the new faces in the mesh
  std::vector<int> new_vertices;  // indices of the new vertices
  double time_ms = 0;
  // Where the time went, in milliseconds: triangulating (with the border
  // and orientation checks), the exact intersection check, counting the
  // mesh's border edges while copying the faces into a larger array (on a
  // second thread, during the triangulation), writing the new elements.
  struct StageTimes {
    double plan = 0, check = 0, count = 0, write = 0;
  } stage_ms;
};

// Stitches the gap between two border paths of `mesh` (two layers: append
// them first, meshmend::appended, and offset the indices of the second).
// New faces (and, with subdivision, vertices) are appended; existing
// indices stay. Paths may share their first or last vertex (a crack that
// closes at a point). Throws InvalidInputError for an empty mesh, a
// non-finite coordinate, a path vertex out of range, repeated, on both
// paths or not on a border edge (the message names it), an open path with a
// closed one, or a path of fewer than two vertices; TopologyError when the
// sides are oppositely oriented (see allow_orientation_conflict) or a new
// face would make an edge non-manifold (three faces) or run an edge the same
// way as the face already on it. The mesh is unchanged when it throws.
StitchResult stitchPaths(Mesh& mesh, const StitchOptions& options);

// Several patches stitched pairwise, in order (§2.2, Figure 3): after each
// stitch, two remaining paths whose ends the stitch joined (an end of one on
// the stitched path a's end, an end of the other on path b's matching end)
// are concatenated through the new end rung, so that a later stitch covers
// the junction too.
struct StitchSequenceOptions {
  std::vector<BorderPath> paths;
  // Pairs of indices into `paths`, stitched in this order. A path that was
  // concatenated into another is referred to by either original index.
  std::vector<std::array<int, 2>> pairs;
  bool concatenate = true;  // concatenate remaining paths joined by a stitch
  StitchOptions stitch;     // everything but a and b
};

struct StitchSequenceResult {
  std::vector<StitchResult> steps;  // one per pair
  // For every step, the paths concatenated after it (original indices).
  std::vector<std::vector<std::array<int, 2>>> concatenated;
  std::size_t faces_added = 0;
  std::size_t vertices_added = 0;
  std::size_t border_edges_before = 0;
  std::size_t border_edges_after = 0;
  std::size_t new_intersecting_pairs = 0;
  double time_ms = 0;
};

// Throws like stitchPaths (the message names the step); the mesh is
// unchanged when it throws.
StitchSequenceResult stitchPathsSequence(Mesh& mesh, const StitchSequenceOptions& options);

// The border paths formed by selected vertices (one flag per vertex): each
// connected run of selected border vertices along border edges, in the
// border's direction, closed when it is a whole border loop. Selected
// vertices not on a border are ignored. For the plugins: "two paths on one
// layer" are the two runs returned here.
std::vector<BorderPath> borderPathsFromSelection(const Mesh& mesh,
                                                 const std::vector<bool>& selected);

// ---------------------------------------------------------------- gap closing

struct CloseGapsOptions {
  // merge_tolerance and max_gap are fractions of the bounding box diagonal
  // (scripts then work on meshes of any size), or mesh units with this set.
  bool absolute_distances = false;
  // ---- Step 1 (what CGAL's stitch_borders does, with a tolerance and
  // more): border edges whose end points coincide within merge_tolerance
  // (0 = exactly equal coordinates) and that run opposite ways are merged
  // into one edge; a border edge whose two ends coincide collapses (its
  // face has no area: it goes). A merge that would make an edge non-manifold
  // or run it the same way twice is skipped. Where more than two border
  // edges coincide (solids touching along an edge), each pairs with the next
  // one around the edge behind its face; their vertices stay apart where the
  // solids only touch (a vertex split).
  double merge_tolerance = 0;
  // Before merging, faces are flipped so that faces meeting at an edge
  // (coincident border vertices count as one) run it opposite ways: the
  // facets of a soup oriented against their neighbours then merge. A part
  // that needs flips keeps, when closed, the outward orientation (positive
  // volume), else the orientation of most of its area. false: faces keep
  // their orientation, and edges they run the same way stay open.
  bool orient_faces = true;
  // ---- Step 2: border runs facing each other within max_gap are stitched
  // (stitchPaths' triangulation): runs of two loops, or the two sides of a
  // crack in one loop. 0 = no stitching.
  double max_gap = 0.01;
  // Within one part (vertices joined through faces), a slit or crack is
  // closed too where it is no wider than local_gap_factor x the mean length
  // of the border edges on either side (whichever is shorter), even beyond
  // max_gap: a crack as narrow as the edges around it, whatever the mesh's
  // size. Separate parts are stitched within max_gap only. 0 = max_gap alone.
  double local_gap_factor = 1.5;
  // Runs of fewer border vertices facing another border are left open.
  int min_path_vertices = 2;
  double max_aspect_ratio = 0;  // subdivision of the stitched strips (StitchOptions)
  // Exact check per stitch; a stitch whose faces would intersect the mesh is
  // left out (with its reason).
  bool check_intersections = true;
  // Count, exactly, the output's intersecting pairs that involve a merged or
  // stitched face (new_intersecting_pairs), and all of them by the checker's
  // rule (remaining_intersecting_pairs).
  bool verify = true;
  bool round_to_float = false;  // store in float, as StitchOptions::round_to_float
  Progress progress;            // called between stages
};

// One pair of facing border paths.
struct GapReport {
  std::vector<int> path_a, path_b;  // vertex indices in the output mesh
  bool closed = false;              // two whole loops
  double gap = 0;                   // largest distance from a vertex to its partner
  bool stitched = false;
  std::size_t faces_added = 0;
  std::string reason;  // why it was left open
};

struct CloseGapsResult {
  double merge_tolerance = 0;  // the distances used, in mesh units
  double max_gap = 0;
  std::size_t border_edges_before = 0;
  std::size_t border_edges_after_merge = 0;
  std::size_t border_edges_after = 0;
  std::size_t faces_flipped = 0;             // step 1, orient_faces
  std::size_t orientation_conflicts = 0;     // two-face edges left running one way (non-orientable)
  std::size_t vertices_merged = 0;           // step 1
  std::size_t edges_merged = 0;              // border edge pairs merged in step 1
  std::size_t merges_skipped = 0;            // step 1 merges refused (manifoldness, orientation)
  std::size_t degenerate_faces_removed = 0;  // collapsed by step 1
  std::size_t faces_added = 0;               // step 2
  std::size_t vertices_added = 0;            // step 2 subdivision
  std::size_t gaps_found = 0;                // facing pairs
  std::size_t gaps_stitched = 0;
  // With verify: intersecting pairs (exact, the self-intersection rule) of
  // the output with a merged or stitched face in them. Faces that only touch
  // where coincident vertices stay apart count.
  std::size_t new_intersecting_pairs = 0;
  // With verify: every intersecting pair of the output as stored, by the
  // rule of meshcheck (the input's own ones included).
  std::size_t remaining_intersecting_pairs = 0;
  bool verified = false;
  StoredOutput stored;  // the output stage on the new vertices (output_stage.h)
  std::vector<GapReport> gaps;
  // For every input vertex its index in the output (merged vertices share one).
  std::vector<int> vertex_index;
  double time_ms = 0;
};

// Closes the gaps between the borders of `mesh` (in place). Vertices merged
// in step 1 are removed, and so are collapsed faces (indices change: see
// vertex_index); stitched faces are appended. Never creates a non-manifold
// edge or an orientation conflict.
// Throws InvalidInputError for an empty mesh, a non-finite coordinate or a
// bad option.
CloseGapsResult closeGaps(Mesh& mesh, const CloseGapsOptions& options = {});

// Edges used by exactly one face.
std::size_t countBorderEdges(const Mesh& mesh);

// The end-of-edit contract (edit_contract.h) each operation's result is
// held to, with keep_partial as given. Trimming only removes faces: no pair
// is counted. A stitch is checked as stored (round_to_float), its pairs
// counted with check_intersections, and the edges run one way that
// allow_orientation_conflict permits are not failures. Closing gaps is
// checked as stored, its pairs always counted.
EditContractOptions editContractOptions(const TrimOptions& options, bool keepPartial);
EditContractOptions editContractOptions(const StitchOptions& options, bool keepPartial);
EditContractOptions editContractOptions(const CloseGapsOptions& options, bool keepPartial);

// closeGaps merged, stitched, flipped or removed something: a result that
// did not is the input as it was (and meets the contract unchecked).
bool changedAnything(const CloseGapsResult& result);

// The report_file keys: border_edges_before, border_edges_after,
// faces_added, vertices_merged (0 where not applicable), time_ms, and the
// operation's own counts.
JsonObject toJson(const TrimResult& result);
JsonObject toJson(const StitchResult& result);
JsonObject toJson(const StitchSequenceResult& result);
JsonObject toJson(const CloseGapsResult& result);

}  // namespace meshmend
