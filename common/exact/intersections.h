// Finding intersecting triangles, exactly: within each mesh (the rule of
// CGAL::Polygon_mesh_processing::self_intersections, vertex identity = vertex
// index) and between meshes (any contact). Candidates come from a box
// hierarchy (box_tree.h); every decision is exact (triangle_intersection.h).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/exact/box_tree.h"
#include "common/exact/changed_faces.h"
#include "common/exact/triangle_intersection.h"

namespace meshmend {

struct FindIntersectionsOptions {
  bool self = true;       // pairs of faces of the same mesh
  bool cross = true;      // pairs of faces of different meshes
  bool contacts = false;  // classify every pair and keep its exact contact points
  // Two faces of one mesh with the same three vertices (the same face twice:
  // duplicate faces, or a planar overlap kept in each part of a welded
  // merged mesh) are a pair. They coincide everywhere, so splitting finds
  // nothing in them and no rounding moves them apart: the split and its
  // checks of the float result leave them out.
  bool same_vertices = true;
  // The candidate search: 0 (the default) a Morton-order hierarchy of each
  // mesh's faces for its own pairs, and between meshes a hashed grid (a
  // median-split hierarchy where it does not suit); 1 median-split
  // hierarchies for both (the alternative the benchmarks measure).
  int layout = 0;
  // Hand each mesh's tree of its faces' boxes (built for `self`) to the
  // result's face_trees, for later searches near a few faces.
  bool keep_trees = false;
  Progress progress;  // called between stages
};

// A face of one of the input meshes.
struct FaceRef {
  std::uint32_t mesh = 0;
  std::uint32_t face = 0;
  bool operator<(const FaceRef& o) const {
    return mesh < o.mesh || (mesh == o.mesh && face < o.face);
  }
  bool operator==(const FaceRef& o) const { return mesh == o.mesh && face == o.face; }
};

struct IntersectingPair {
  FaceRef a, b;  // a < b
};

struct FindIntersectionsResult {
  std::vector<IntersectingPair> pairs;           // sorted by (a, b)
  std::vector<TriangleContact> contacts;         // parallel to pairs (only with options.contacts)
  std::vector<std::size_t> self_pairs;           // per mesh: pairs within it
  std::vector<std::size_t> self_faces;           // per mesh: distinct faces in those pairs
  std::size_t cross_pairs = 0;                   // pairs between different meshes
  std::vector<std::size_t> cross_faces;          // per mesh: distinct faces in cross pairs
  std::vector<std::vector<bool>> face_involved;  // per mesh, per face: in any pair
  // Per mesh: collinear faces, skipped (never compared). With `self`, all
  // of the mesh's; between meshes only, those within another mesh's bounds.
  std::vector<std::size_t> degenerate_faces;
  std::size_t candidate_pairs = 0;  // box pairs tested exactly
  // Per mesh (with `self` and keep_trees): the tree of its faces' boxes,
  // box i that of face i.
  std::vector<std::shared_ptr<const BoxTree>> face_trees;
  double build_ms = 0, search_ms = 0, time_ms = 0;
};

// Finds every intersecting pair among `meshes` (compact, finite coordinates,
// all in one frame). Degenerate (collinear) faces are skipped, as in CGAL.
// Throws InvalidInputError for a non-finite coordinate or coordinates that
// together span more than kMaxCoordinateBinades (mesh.h).
FindIntersectionsResult findIntersections(const std::vector<const Mesh*>& meshes,
                                          const FindIntersectionsOptions& options = {});
// The same on plain arrays (every vertex index in range).
FindIntersectionsResult findIntersectionsInArrays(const std::vector<const MeshArrays*>& meshes,
                                                  const FindIntersectionsOptions& options = {});

// Self-intersecting pairs of one mesh (the self-intersection rule), with its
// coordinates as stored or, with `asFloat`, rounded to float as MeshLab
// stores them; faces with the same three vertices count unless
// `sameVertices` is false (FindIntersectionsOptions::same_vertices).
std::size_t selfIntersectingPairs(const Mesh& mesh, bool asFloat = false, bool sameVertices = true);
// The same with the coordinates rounded to `scalar`.
std::size_t selfIntersectingPairs(const Mesh& mesh, Scalar scalar, bool sameVertices);

// The self-intersection rule for faces f and g of one mesh (never for a
// degenerate face): they meet beyond what their shared corners explain.
bool facesIntersect(const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
                    std::uint32_t f, std::uint32_t g);
// The same for two faces given by their corners (vertex indices: equal
// indices are shared corners) and their points.
bool facesIntersect(const Triangle& ta, const TrianglePoints& a, const Triangle& tb,
                    const TrianglePoints& b);

// Of `pairs`, those that intersect (facesIntersect), in parallel.
std::vector<std::array<std::uint32_t, 2>> intersectingOf(
    const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
    const std::vector<std::array<std::uint32_t, 2>>& pairs);
// The same given, per face, whether it is degenerate (collinear corners, as
// collinear() decides): a face in many pairs is tested once. Faces with the
// same three vertices count unless `sameVertices` is false.
std::vector<std::array<std::uint32_t, 2>> intersectingOf(
    const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
    const std::vector<std::array<std::uint32_t, 2>>& pairs, const std::vector<char>& degenerate,
    bool sameVertices);
// The same for the candidate pairs of `search`, tested as they are found.
std::vector<std::array<std::uint32_t, 2>> intersectingOf(const std::vector<Point3>& points,
                                                         const std::vector<Triangle>& triangles,
                                                         const ChangedFaceSearch& search,
                                                         const std::vector<char>& degenerate,
                                                         bool sameVertices);

// The contact segments of every pair (a coplanar overlap contributes its
// outline, a single touching point nothing), with coinciding end points
// merged: the intersection curves as a polyline soup. Needs options.contacts.
struct SegmentSoup {
  std::vector<Point3> points;
  std::vector<std::array<int, 2>> edges;
};
SegmentSoup contactSegments(const FindIntersectionsResult& result);

// The report_file keys: self_intersecting_pairs/faces (summed over meshes),
// cross_intersecting_pairs, per-mesh lists, candidates and time_ms.
JsonObject toJson(const FindIntersectionsResult& result);

}  // namespace meshmend
