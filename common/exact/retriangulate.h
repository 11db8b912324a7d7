// Local re-triangulation of one triangle (McLaurin 2012, §2.3–2.4): the
// points that lie on it become vertices (a point on an edge splits the edge),
// the constraint segments between them become edges (recovered by flips;
// two crossing constraints meet at their exact crossing point, which is
// inserted), and the result is improved by flips that never remove a
// constraint, maximising the smallest angle. Every decision is exact
// (exact_point.h: from rounded values where their error bounds allow).
#pragma once

#include <array>
#include <vector>

#include "common/exact/triangle_intersection.h"

namespace meshmend {

struct PatchInput {
  std::array<ExactPoint, 3> corners;  // the triangle, in its orientation
  // On the triangle (inside or on an edge), exactly in its plane: a
  // precondition, checked only where the rounded values show a violation.
  std::vector<ExactPoint> points;
  // Optional, one per point: bit i set when the point is known to lie inside
  // edge i (corner i to i+1) — exact knowledge from how the point was made,
  // which spares the exact arithmetic that proving it would take.
  std::vector<std::uint8_t> on_edges;
  std::vector<std::array<int, 2>> segments;  // constraints: 0..2 corners, 3 + i points[i]
  bool improve = true;                       // max-min angle flips after the constraints
  // Work bound: exact (rational) evaluations of orientations and of the
  // flips' in-circle tests this patch may take, 0 = none. Points that the
  // rounded values cannot tell apart (dozens of curves crossing within a
  // few units in the last place, as every meridian of a spindle torus does
  // near its axis) need rational arithmetic on long numbers for every
  // decision; past the bound the patch stops with WorkLimitError. Real
  // meshes (the corpus, CAD parts a millionth of their size apart) take
  // under 500 per patch.
  std::size_t max_exact_evaluations = 20000;
};

// Named apart from patches.h's Patch: two classes of one name in one
// namespace break the one-definition rule (the booleans fuzz target found
// std::vector<Patch> of one used with the other's layout).
struct RetriangulatedPatch {
  // Vertices: the corners, then the distinct input points, then crossings of
  // constraints (new points).
  std::vector<ExactPoint> vertices;
  std::vector<int> vertex_of_input;           // per input index (corners, points): its vertex
  std::vector<std::array<int, 3>> triangles;  // oriented like the input triangle
  std::vector<std::array<int, 2>> constrained_edges;  // the constraints, split at vertices on them
  std::size_t exact_evaluations = 0;  // rational orientations and in-circle tests (the bound)
};

// Throws InvalidInputError when the triangle is degenerate, a point is not
// on it, or a segment index is out of range; WorkLimitError past
// max_exact_evaluations. Safe to call from several
// threads at once: each thread keeps its own working storage between calls,
// so that a patch in steady state allocates only the returned RetriangulatedPatch.
RetriangulatedPatch retriangulate(const PatchInput& input);

}  // namespace meshmend
