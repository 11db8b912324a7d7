// What the split's stages (common/split/*.cpp) and the output stage
// (output_stage.cpp) share: the output as arrays and a few helpers. Not an
// interface of the core.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "common/base/mesh.h"
#include "common/repair/split/split.h"

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

// Keeps each face that coincides with another of `merged` once (overlaps.cpp).
// Faces whose corners are all curve vertices (`onCurve`) can have a twin;
// `curves` (sorted) loses the curve edges inside an overlap. Returns the
// faces that coincide (removed when `remove`).
std::size_t keepOverlapsOnce(OutputArrays& merged, std::vector<char>& newFace,
                             const std::vector<char>& onCurve,
                             std::vector<std::array<int, 2>>& curves, bool remove = true);

// Removes faces with the same three vertices as an earlier face (in any
// order) from one input (overlaps.cpp); returns how many.
std::size_t removeDuplicateFaces(WeldedArrays& in);

// Quality snapping (snap.cpp; McLaurin 2012, §2.7) on the merged output:
// curve points near an input vertex or edge are merged into it or split it,
// where that keeps every surface manifold and improves the angles. Updates
// `curves` (sorted), the per-mesh `outputs` and the result's snapped counts,
// merged_vertex, curve_edges and merged_snapped_face.
void snapCurves(OutputArrays& merged, std::vector<std::array<int, 2>>& curves,
                std::vector<OutputArrays>& outputs, const SplitOptions& options, SplitResult& r);

}  // namespace meshmend::split_detail
