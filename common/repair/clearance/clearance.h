// Minimum clearance between surfaces (Aycheh & Kyung, "Self-intersection
// avoidance for 3-D triangular mesh model"; docs/REFERENCES.md):
// measuring the smallest distance between non-adjacent triangles, and moving
// vertices as little as possible until every such pair is at least τ apart.
//
// Two faces are non-adjacent when they share no vertex (faces of different
// layers never do). Their distance is the smallest of their six vertex–face
// and nine edge–edge distances (§4.1), which is the distance of two disjoint
// triangles. Enforcing solves the paper's problem — minimal displacement such
// that every pair distance ≥ τ — with Gauss-Newton steps on the active pairs
// (those closer than τ plus a margin, re-detected after every step): the
// minimum-norm step of the linearised distances, rows beyond τ as
// inequalities, comes from Hildreth's dual method, which picks the binding
// rows, and a sparse solve over them, (J_Wᵀ J_W + λI) Δx = J_Wᵀ r = the
// minimum-norm J_Wᵀ (J_W J_Wᵀ)⁻¹ r for small λ (not the paper's dense SVD).
// A backtracking line search keeps every intermediate configuration free of
// intersections: conservative advancement along the step for faces sharing
// no vertex, the exact intersection test at its end for all moved faces.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <vcg/math/matrix44.h>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/repair/output_stage.h"

namespace meshmend {

// Which face pairs a clearance applies to.
enum class ClearanceScope {
  kWithinLayers,   // pairs of non-adjacent faces of the same layer
  kBetweenLayers,  // pairs of faces of different layers
  kBoth,
};
const char* toString(ClearanceScope scope);

// Where a layer lies in the common frame: p ↦ M p, an affine matrix with an
// inverse (MeshLab's layer matrix). Tau, the distances, the closest points
// and the displacements are all in the common frame.
using Placement = vcg::Matrix44d;

// One pair of faces and where they come closest.
struct ClearancePair {
  int layer_a = -1, face_a = -1;  // (layer_a, face_a) < (layer_b, face_b)
  int layer_b = -1, face_b = -1;
  // Which elements realise the distance: "vertex_face" (a corner of one face
  // and the other face) or "edge_edge" (an edge of each).
  std::string kind;
  double distance = 0;
  Point3 point_a{0, 0, 0}, point_b{0, 0, 0};  // closest points on face_a and face_b
};

struct ClearanceMeasureOptions {
  // The clearance asked for (absolute, in mesh units); 0 = none: only the
  // minimum and the local clearances are measured. Must not be negative.
  double tau = 0;
  ClearanceScope scope = ClearanceScope::kBoth;  // which face pairs count
  // Faces within this many vertex rings of each other count as adjacent and
  // are never compared: 1 = faces sharing a vertex (the paper's rule); 2 also
  // skips faces touching a neighbour of a corner, so that a τ of the order of
  // the edge length measures the gaps between sheets, not the mesh's own
  // resolution. 1 or 2.
  int exclusion_rings = 1;
  // Per layer, its placement; empty = every layer as it is (the identity).
  std::vector<Placement> placements;
  // Local clearances (per vertex) and the histogram stop at this distance; 0
  // = 2τ, or 2 × the minimum when tau is 0.
  double local_max = 0;
  int histogram_bins = 10;            // equal bins over [0, local_max)
  std::size_t max_listed_pairs = 10;  // closest face pairs listed in the result
  Progress progress;                  // called between stages
};

struct ClearanceMeasure {
  double tau = 0;
  bool found = false;               // some pair in scope exists (false e.g. for one triangle)
  double min_distance = 0;          // smallest distance of a pair in scope (when found)
  ClearancePair closest;            // the pair that realises it
  std::size_t violating_pairs = 0;  // face pairs closer than tau
  // Per layer, per face: closer than tau to some face (the filter selects them).
  std::vector<std::vector<char>> faces_below_tau;
  std::size_t faces_below_tau_count = 0;
  // Per layer, per vertex: the smallest distance of any pair involving one of
  // the vertex's faces, capped at local_max (MeshLab's quality colouring).
  std::vector<std::vector<double>> vertex_clearance;
  double local_max = 0;                 // the cap used
  std::vector<std::size_t> histogram;   // face pairs by distance, bins over [0, local_max)
  std::vector<ClearancePair> shortest;  // the closest pairs (max_listed_pairs), closest first
  std::size_t candidate_pairs = 0;      // face pairs whose distance was computed
  double time_ms = 0;
};

// Measures the clearance of `layers` (compact, finite coordinates, placed by
// options.placements). Throws InvalidInputError for a negative tau, bad
// options or placements, or a layer without faces or with a non-finite
// coordinate.
ClearanceMeasure measureClearance(const std::vector<const Mesh*>& layers,
                                  const ClearanceMeasureOptions& options = {});

struct ClearanceOptions {
  // The clearance to reach (absolute, in mesh units; the plugin converts a
  // percentage of the bounding box). Must be > 0.
  double tau = 0;
  ClearanceScope scope = ClearanceScope::kBoth;  // which face pairs must be tau apart
  int exclusion_rings = 1;  // adjacency of faces, as in ClearanceMeasureOptions
  // Per layer, its placement; empty = every layer as it is. The layers are
  // read and written in their own frames: the solve works on the placed
  // positions, and each moved vertex is stored in its layer's frame (rounded
  // there, see round_to_float), placed again and checked there, so the
  // result describes what the layers hold as the user sees them.
  std::vector<Placement> placements;
  // Per layer, per vertex: vertices that must not move (e.g. MeshLab's
  // selection). Empty, or one list per layer of that layer's vertex count.
  std::vector<std::vector<char>> locked;
  // No vertex moves farther than this from its input position; 0 = no cap.
  // A vertex that reaches it stays there, and the others go on without it.
  double max_displacement = 0;
  int max_iterations = 100;  // Gauss-Newton steps at most
  // Work bound: more face pairs closer than tau than this in the input, and
  // nothing is moved (WorkLimitError). Each step's cost grows with them (a
  // torus with 130,000 short pairs takes 40 s); so many mean a tau larger
  // than the parts or than a few edge lengths (see exclusion_rings), not
  // gaps to open. 0 = no bound.
  std::size_t max_short_pairs = 100000;
  // Pairs closer than tau × (1 + active_margin) take part in each step, the
  // ones beyond tau as inequalities, so that the step does not push them
  // below tau.
  double active_margin = 0.5;
  // Make the final positions float-representable (MeshLab stores floats):
  // the input is taken as rounded to float (no change for MeshLab's meshes),
  // the solve aims a few float steps of the largest coordinate beyond tau,
  // and the rounded result is checked again (distances, exact intersections).
  // Displacements are then measured from the rounded input. A placed layer
  // is rounded in its own frame, where it is stored.
  bool round_to_float = false;
  std::size_t max_listed_pairs = 10;  // pairs still short listed in the result
  Progress progress;                  // called once per iteration
};

struct ClearanceResult {
  double tau = 0;
  bool reached = false;  // every pair in scope is at least tau apart
  // "reached", "iterations" (max_iterations used up), "stalled" (the line
  // search found no step that helps: locked vertices, the cap, or a tau the
  // shape cannot allow), "locked" (every pair still short has only locked or
  // capped vertices), "rounding" (tau was reached, but storing the moved
  // vertices, rounded to float or through a placement, brought pairs back
  // under it: see warnings).
  std::string stop_reason;
  double min_distance_before = 0, min_distance_after = 0;  // over pairs in scope
  std::size_t violating_pairs_before = 0;                  // face pairs closer than tau
  std::size_t violating_pairs_after = 0;
  // Displacements from the input positions: the largest, the mean over the
  // vertices that moved, the mean over all vertices.
  double max_displacement = 0, mean_displacement_moved = 0, mean_displacement_all = 0;
  std::size_t vertices_moved = 0;
  // A lower bound of max_displacement for any solution: over the input's
  // violating pairs, (tau - d) / 2 when both sides may move, tau - d when one
  // side is locked (each side's points move at most the largest displacement).
  double displacement_lower_bound = 0;
  std::size_t vertices_capped = 0;         // vertices that reached max_displacement
  int iterations = 0;                      // Gauss-Newton steps taken
  std::size_t step_halvings = 0;           // line search halvings (intersection or no progress)
  std::size_t constraints_last = 0;        // vertex–face / edge–edge rows in the last step
  std::vector<ClearancePair> short_pairs;  // pairs still closer than tau (a few, closest first)
  // Intersecting pairs (exact, the self-intersection rule) with a face
  // around a moved vertex, as stored: 0 unless rounding broke it.
  std::size_t new_intersecting_pairs = 0;
  StoredOutput stored;  // the output stage on the moved vertices (output_stage.h)
  bool rounded_to_float = false;
  std::vector<std::string> warnings;
  double time_ms = 0;
  struct StageTimes {
    double check = 0, detect = 0, solve = 0, line_search = 0, verify = 0;
  } stage_ms;
};

// Moves the vertices of `layers` (compact, finite coordinates, placed by
// options.placements) so
// that every pair in scope is at least tau apart, if it can. Preconditions:
// tau > 0 (InvalidInputError) and no intersecting faces within a layer or,
// when the scope includes them, between layers (TopologyError naming the
// MeshMend filter that resolves them). Positions are written back at the end,
// in each layer's own frame (a vertex that did not move keeps its
// coordinates bit for bit), also when tau was not reached (the result says so and lists the pairs
// still short); on an exception the layers are untouched.
ClearanceResult enforceClearance(std::vector<Mesh*>& layers, const ClearanceOptions& options);

// The contract of an enforced clearance, on what will be stored (the
// caller's values where it stores otherwise, e.g. through layer matrices):
// the surfaces do not cross (no intersecting pair), and no pair in scope ends
// closer than the closest was before. Tau not reached within the cap, the
// locks or the iterations is an outcome the result explains, not a failure.
// What does not hold, one item each (for requireContract, edit_contract.h).
std::vector<std::string> clearanceContractFailures(double minDistanceBefore,
                                                   double minDistanceAfter,
                                                   std::size_t intersectingPairs);
// The same on the result's own values (its positions as stored).
std::vector<std::string> clearanceContractFailures(const ClearanceResult& result);

// The report_file keys: tau, min_distance_before/after, violating_pairs_before/after,
// max_displacement, mean_displacement, time_ms, ... For a measurement, the
// "before" and "after" keys both hold the measured values.
JsonObject toJson(const ClearanceMeasure& measure);
JsonObject toJson(const ClearanceResult& result);

}  // namespace meshmend
