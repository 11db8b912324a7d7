// Triangulating a hole's domain with an advancing front (Xu, Li, Tan 2013,
// §3.2): the front vertex with the smallest interior angle is treated
// first; below 75 degrees its two neighbours are joined, below 135 one new
// vertex is put on its bisector, above that two (the paper's three rules);
// a new vertex closer than the merge distance to a front vertex is replaced
// by it (step 4), which splits the front in two. Each new triangle is added
// only after exact tests that it lies in the part still uncovered
// (orientation, no front edge crossing a new edge, no front vertex inside),
// so the front stays a set of simple polygons whatever happens; when no
// rule applies any more, the rest is cut into ears.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include "common/repair/holes/plane.h"

namespace meshmend::holes {

struct FrontSettings {
  double growth = 1;       // target size growth per front layer (1: uniform triangles)
  double maxSize = 1e300;  // cap on the target size
  double merge = 0.6;      // merge distance, relative to the target size
  // Work bound: the front stops (the hole not covered) past this many
  // triangles. Its own estimate from the smallest border size can reach
  // millions where one border edge is a thousandth of the others.
  std::size_t maxTriangles = 200000;
};

struct Front {
  bool covered = false;                    // false: some of the polygon is left uncovered
  std::vector<Vec2> uv;                    // boundary vertices first, then new ones
  std::vector<double> size;                // target edge length at each vertex
  std::vector<std::array<int, 2>> parent;  // new vertices: the front edge they were built on
  std::vector<Triangle> triangles;         // counter-clockwise in the plane
};

// Covers the simple counter-clockwise polygon `boundary` (sizes: the
// target edge length at each of its vertices) with triangles whose edges
// grade from those sizes. No triangle gets an edge of `existingEdges`
// (pairs of boundary indices: edges the mesh has already, outside the
// hole), other than the polygon's own.
Front advanceFront(const std::vector<Vec2>& boundary, const std::vector<double>& sizes,
                   const std::vector<std::pair<int, int>>& existingEdges,
                   const FrontSettings& settings);

// The triangles around each vertex of a patch, in one array (ascending).
class TrianglesAround {
 public:
  struct Range {
    const int *first, *last;
    const int* begin() const { return first; }
    const int* end() const { return last; }
  };
  TrianglesAround() = default;
  TrianglesAround(const std::vector<Triangle>& triangles, std::size_t vertexCount);
  Range operator[](std::size_t v) const {
    return {triangles_.data() + start_[v], triangles_.data() + start_[v + 1]};
  }

 private:
  std::vector<int> start_, triangles_;
};

// Moves each vertex from `fixed` on towards the centroid of its
// neighbours (`rounds` rounds) where no triangle around it turns over
// (exact): rounder triangles for the fairing's cotangent weights. `height`
// moves along.
void relaxInterior(std::vector<Vec2>& uv, std::vector<double>& height, std::size_t fixed,
                   const std::vector<Triangle>& triangles, int rounds);

}  // namespace meshmend::holes
