// What the split (split.cpp) and its output stage (output_stage.cpp) share:
// the output as arrays and a few helpers. Not an interface of the core.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "common/mesh.h"

namespace meshmend::split_detail {

// An output mesh as arrays, with the provenance of every element.
struct OutputArrays {
  std::vector<Point3> positions;
  std::vector<Triangle> triangles;
  std::vector<VertexOrigin> vertex_origin;
  std::vector<FaceOrigin> face_origin;

  void toMesh(Mesh& mesh) const {
    buildMesh(mesh, positions, triangles, vertex_origin, face_origin);
  }
};

// Sorts `pairs` (of values in [0, bound)) and removes the repeats, as
// std::sort and std::unique would, in linear time when `bound` is not much
// larger than their number.
void sortUnique(std::vector<std::array<int, 2>>& pairs, std::size_t bound);

// Barycentric coordinates of p in triangle (a, b, c), from the rounded values.
Point3 barycentric(const Point3& p, const Point3& a, const Point3& b, const Point3& c);

// Closed and open components of a curve graph on `vertices` vertices.
void countCurves(std::size_t vertices, const std::vector<std::array<int, 2>>& edges,
                 std::size_t& loops, std::size_t& open);

}  // namespace meshmend::split_detail
