// Local re-triangulation of one triangle (intersection paper §2.3–2.4): the
// points that lie on it become vertices (a point on an edge splits the edge),
// the constraint segments between them become edges (recovered by flips;
// two crossing constraints meet at their exact crossing point, which is
// inserted), and the result is improved by flips that never remove a
// constraint, maximising the smallest angle. Every decision is exact: the
// points are rational and lie exactly in the triangle's plane.
#pragma once

#include <array>
#include <vector>

#include "common/triangle_intersection.h"

namespace meshmend {

struct PatchInput {
  std::array<RationalPoint, 3> corners;      // the triangle, in its orientation
  std::vector<RationalPoint> points;         // on the triangle (inside or on an edge)
  std::vector<std::array<int, 2>> segments;  // constraints: 0..2 corners, 3 + i points[i]
  bool improve = true;                       // max-min angle flips after the constraints
};

struct Patch {
  // Vertices: the corners, then the distinct input points, then crossings of
  // constraints (new points).
  std::vector<RationalPoint> vertices;
  std::vector<int> vertex_of_input;           // per input index (corners, points): its vertex
  std::vector<std::array<int, 3>> triangles;  // oriented like the input triangle
  std::vector<std::array<int, 2>> constrained_edges;  // the constraints, split at vertices on them
};

// Throws InvalidInputError when a point is not on the triangle or a segment
// index is out of range.
Patch retriangulate(const PatchInput& input);

}  // namespace meshmend
