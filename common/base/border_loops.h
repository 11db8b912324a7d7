// The border loops of a triangle mesh: every border edge (an edge used by
// exactly one face) once, followed in its face's direction into loops. Where
// several borders pass through one vertex (a pinch, or bow-tie: two or more
// fans of faces meet only there), the border leaving a fan continues along
// the next fan counter-clockwise around the vertex, so each hole comes out
// as its own loop. Shared by the capabilities that work on borders (gap
// closing, hole filling).
//
// The border edges are found without building the mesh's adjacency: one
// pass over the faces sums, at each vertex, the indices (and their squares)
// of the vertices its faces lead to minus those they come from. Inside a
// consistently oriented surface every edge is run once each way and the
// sums cancel; a vertex whose sums do not cancel is on a border (or a
// non-manifold or inconsistently oriented edge), and only the faces at
// those vertices are gathered, in a second pass, to decide exactly which of
// their edges are border edges. The two sums cannot cancel at a vertex
// where one or two uses of edges are unpaired (integer identities, exact in
// 64-bit arithmetic); where more are, a vertex whose sums cancel by
// coincidence is still found from a border edge that ends there (a third
// pass gathers its faces).
#pragma once

#include <functional>
#include <vector>

#include "common/base/mesh.h"

namespace meshmend {

// A border edge in its face's direction: the face runs from -> to.
struct BorderEdge {
  int from, to, face;
};

// The border edges of a mesh and the faces at the vertices they touch.
struct BorderEdges {
  std::vector<BorderEdge> edges;  // each border edge once
  // The vertices at which some use of an edge is unpaired (border,
  // non-manifold and inconsistently oriented edges), ascending, and the
  // faces at each: faces[start[i] .. start[i + 1]) are at vertices[i], with
  // their corners (as read) in corners.
  std::vector<int> vertices;
  std::vector<int> start;
  std::vector<int> faces;
  std::vector<Triangle> corners;

  // The faces at vertex v, or none if v is not in `vertices`.
  std::pair<const int*, const int*> facesAt(int v) const;
};

// Every index of `triangles` must be below vertexCount.
BorderEdges findBorderEdges(const std::vector<Triangle>& triangles, std::size_t vertexCount);
// The same on a compact mesh, read in place (no copy of its faces).
BorderEdges findBorderEdges(const Mesh& mesh);

struct BorderLoop {
  // In the faces' direction: a face runs vertices[i] -> vertices[i + 1].
  std::vector<int> vertices;
  // faces[i]: the face of the border edge vertices[i] -> vertices[i + 1].
  std::vector<int> faces;
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

// The loops of the border edges found; `point` gives a vertex's position
// (asked only at vertices where several borders pass).
BorderLoops findBorderLoops(const BorderEdges& found, const std::function<Point3(int)>& point);

// Every index of `triangles` must be below points.size().
BorderLoops findBorderLoops(const std::vector<Point3>& points,
                            const std::vector<Triangle>& triangles);

}  // namespace meshmend
