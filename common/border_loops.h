// The border loops of a triangle mesh: every border edge (an edge used by
// exactly one face) once, followed in its face's direction into loops. Where
// several borders pass through one vertex (a pinch, or bow-tie: two or more
// fans of faces meet only there), the border leaving a fan continues along
// the next fan counter-clockwise around the vertex, so each hole comes out
// as its own loop. Shared by the capabilities that work on borders (gap
// closing, hole filling).
#pragma once

#include <vector>

#include "common/mesh.h"

namespace meshmend {

struct BorderLoop {
  // In the faces' direction: a face runs vertices[i] -> vertices[i + 1].
  std::vector<int> vertices;
  // false: the border could not be followed all around (a fan that is not a
  // plain open fan at a vertex: a non-manifold edge, or faces that run the
  // border both ways); then the path ends at broken_at, its last vertex.
  bool closed = true;
  int broken_at = -1;
};

struct BorderLoops {
  std::vector<BorderLoop> loops;  // closed loops are simple (no vertex twice)
  std::vector<int> pinched;       // sorted: vertices where several borders pass
};

// Every index of `triangles` must be below points.size().
BorderLoops findBorderLoops(const std::vector<Point3>& points,
                            const std::vector<Triangle>& triangles);

}  // namespace meshmend
