// Feature-preserving hole filling (Xu, Li, Tan 2013, "Feature Based Hole
// Filling Algorithm on Triangular Mesh"; docs/REFERENCES.md): border loops are found and their
// long edges split (§3.1), each hole is covered by an advancing-front patch
// whose triangles take the size of the input's border edges (§3.2), and the
// patch vertices are placed by a Poisson solve whose right-hand side is the
// Laplacian predicted by least-squares SVM regression from the rings of
// vertices around the hole (§2.2, §3.3, §3.4). Simpler shapes (flat,
// harmonic, biharmonic) are options. Every patch is checked exactly against
// itself and the mesh around it; a patch that would intersect falls back to a
// flatter shape or another domain, and is left out (the hole reported
// skipped) when none fits.
//
// The work follows the holes, not the mesh: the borders are found from one
// pass over the faces (common/border_loops.h), the faces around the holes
// are gathered in one pass over the points and one over the faces, and the
// mesh is never copied; the stages of one hole are in common/holes/.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/repair/output_stage.h"

namespace meshmend {

// How the patch vertices are placed once the patch is triangulated. The
// smooth shapes minimise the squared cotangent Laplacians (Eq. 1-4, true
// cotangent weights, each row weighted by its vertex's area) of the new
// vertices and of the boundary vertices, whose outer neighbours stay fixed:
// that is what joins the patch to the surface with a continuous tangent
// plane. Where their shape stretches the patch's triangles to more than
// twice the size the domain gave them (a plane foreshortens the part of a
// hole that turns away from it), the patch is refined there and shaped
// again. Biharmonic is the default: on the fidelity benchmark
// (docs/BENCHMARKS.md) it is closer to the removed surface than the
// paper's regression on most holes.
enum class HoleFairing {
  Flat,        // no fairing: where the advancing front put them (a height field over the
               // hole's plane; a uniform membrane when the hole has no plane it projects to)
  Harmonic,    // membrane: L x = 0 with the boundary fixed (no tangent continuity)
  Biharmonic,  // minimal curvature (the default): target Laplacians 0 (L^2 x = 0 in the
               // least-squares sense)
  // The paper's (§3.3-3.4): the mean curvature H of the vertices in the
  // rings around the hole, from their own Laplacians, is learnt by LS-SVM
  // regression over 3-D position; the Laplacian it implies at each patch
  // vertex (-4 A H n / sum of weights) is the Poisson target. (The paper
  // regresses each coordinate of the Laplacian from the same coordinate of
  // the position; the normal part scaled by the local area carries the shape
  // without depending on how the surface around was triangulated.)
  LaplacianRegression,
};

const char* toString(HoleFairing fairing);

struct HoleFillOptions {
  // ---- Which holes. A hole is filled when it passes every limit that is set.
  std::size_t max_boundary_edges = 0;  // holes with more boundary edges are skipped; 0 = no limit
  // Holes whose diameter (largest distance between two boundary vertices)
  // exceeds this fraction of the mesh's bounding box diagonal are skipped; 0 = no limit.
  double max_diameter = 0;
  // When not empty (one flag per vertex): only holes with a selected boundary vertex are filled.
  std::vector<bool> selected_vertices;
  // The same selection as vertex indices (either form, or both, may be given).
  std::vector<int> selected_vertex_indices;

  // ---- Pre-treatment (§3.1): boundary edges longer than long_edge_factor x
  // the hole's mean boundary edge length are halved (with the face they
  // border) until none is; 0 turns it off.
  double long_edge_factor = 1.5;

  // ---- Patch (§3.2). Patch triangles take the size of the input's border
  // edges around them (before the pre-treatment split them): the density of
  // the surface around the hole. A hole whose uniform patch would exceed
  // uniform_face_limit triangles gets triangles that grow by size_growth
  // per front layer towards its middle, up to max_size_factor x the mean
  // border edge length: a round hole of n border edges needs ~n^2/5
  // uniform triangles, a graded patch a few times n.
  std::size_t uniform_face_limit = 20000;
  double size_growth = 1.5;
  double max_size_factor = 16;
  // A new front vertex closer than merge_distance x its target size to
  // another front vertex is merged into it (step 4 of §3.2).
  double merge_distance = 0.6;

  // ---- Shape.
  HoleFairing fairing = HoleFairing::Biharmonic;
  // Rings of surface vertices around the hole whose Laplacians train the regression (§3.3).
  int regression_rings = 3;
  // LS-SVM regularisation gamma (Eq. 11): larger follows the samples more
  // closely, smaller smooths the predicted curvature more.
  double regression_gamma = 10;
  // At most this many training samples (evenly picked): the LS-SVM system is dense.
  int regression_max_samples = 150;

  // ---- Checks. Exact test of every patch (with the faces its pre-treatment
  // split) against itself and the surface around it; a patch that
  // intersects is replaced by a flatter one (LaplacianRegression ->
  // Biharmonic -> Harmonic -> Flat; from Biharmonic, LaplacianRegression
  // last), or left out. Each shape is tried over every domain (the hole's
  // plane, a disk, a disk with smaller triangles: the border's spacing,
  // growing inwards to at most twice it) before the next shape. Its counts make
  // new_intersecting_pairs exact.
  bool check_intersections = true;
  // Count every intersecting pair of the finished mesh as stored, by the
  // checker's rule (remaining_intersecting_pairs): a search of the whole mesh.
  bool verify = false;
  // New vertices take float coordinates (as MeshLab stores them) before the
  // checks, so that what is checked is what is stored.
  bool round_to_float = false;
  Progress progress;  // called once per hole
};

// What happened to one border loop.
struct HoleReport {
  std::vector<int> boundary;       // its vertices in order (before splitting), mesh indices
  std::size_t boundary_edges = 0;  // as found
  // Largest distance between two boundary vertices (within a few percent
  // above 512 of them).
  double diameter = 0;
  std::size_t edges_split = 0;     // long boundary edges split (§3.1)
  std::size_t faces_added = 0;     // patch faces (split faces not counted)
  std::size_t vertices_added = 0;  // patch and split vertices
  bool filled = false;
  std::string reason;                       // why it was skipped, or why the shape fell back
  HoleFairing fairing = HoleFairing::Flat;  // the shape the patch got (after fallbacks)
  bool planar_domain = true;                // triangulated over its plane (false: over a disk)
  // RMS residual of the fairing system, in units of the mean boundary edge
  // length (0 for Flat): how far the solution is from the target Laplacians.
  double fairing_residual = 0;
  std::size_t training_samples = 0;  // LS-SVM samples (LaplacianRegression)
  double time_ms = 0;
};

struct HoleFillResult {
  std::size_t holes_found = 0;  // border loops (a loop through a non-manifold vertex counts
                                // once per part it is split into)
  std::size_t holes_filled = 0;
  std::size_t holes_skipped = 0;  // not selected, too large, or not fillable: see holes[i].reason
  std::size_t faces_added = 0;    // patch faces
  std::size_t vertices_added = 0;
  std::size_t edges_split = 0;  // boundary edges split by the pre-treatment
  std::size_t fallbacks = 0;    // holes whose patch took a flatter shape than asked
  // new_intersecting_pairs is known: the patches' checks ran, or verify.
  bool verified = false;
  // Intersecting pairs (exact, the self-intersection rule) that involve a
  // patch or split face, as stored: 0 unless a problem was found.
  std::size_t new_intersecting_pairs = 0;
  // With verify: every intersecting pair of the result as stored, by the
  // rule of meshcheck (the input's own ones included).
  std::size_t remaining_intersecting_pairs = 0;
  bool remaining_counted = false;
  StoredOutput stored;  // the output stage (output_stage.h)
  double time_ms = 0;
  // Where the time went, in milliseconds of wall time on the calling
  // thread, summed over the holes (they add up to about time_ms): find is
  // the borders, the selection and the gathering of the faces around the
  // holes; triangulate, fair and check are the patches' stages.
  struct StageTimes {
    double find = 0, split = 0, triangulate = 0, fair = 0, check = 0, verify = 0, write = 0;
  } stage_ms;
  std::vector<HoleReport> holes;  // one per border loop, in the order found
  std::vector<int> new_faces;     // indices of the patch faces in the filled mesh
  std::vector<int> new_vertices;  // indices of the vertices added (patch and split)
};

// Fills the holes of `mesh` in place. New vertices and faces are appended
// (existing indices stay; a face split by the pre-treatment keeps its index
// for one half); provenance: split vertices lie on the face they split,
// patch vertices take the origin of the border vertex nearest to them along
// the patch's edges (so attributes carried by origins continue into the
// patch), patch faces have no origin face.
// Throws InvalidInputError for an empty mesh, deleted elements or a bad
// option (checked first), or a non-finite coordinate (found as the fill
// reads the points: a mesh with nothing to fill is not read further); the
// mesh is unchanged when it throws (CancelledError included). A mesh without
// holes is returned unchanged with holes_found = 0.
HoleFillResult fillHoles(Mesh& mesh, const HoleFillOptions& options = {});

// The report_file keys: holes_found, holes_filled, holes_skipped, skipped
// (hole, boundary_edges, reason), faces_added, vertices_added, edges_split,
// new_intersecting_pairs, with verify remaining_intersecting_pairs, time_ms,
// holes (per hole).
JsonObject toJson(const HoleFillResult& result);

}  // namespace meshmend
