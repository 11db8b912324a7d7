// Defect inspection of a triangle mesh: the counts of `meshcheck` (same
// definitions, vertex identity = vertex index), the check every other MeshMend
// filter reuses on its own output.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"

namespace meshmend {

struct InspectOptions {
  bool mark_defects = false;        // fill InspectResult::face_defects / vertex_defects
  bool self_intersections = false;  // also count self-intersecting pairs (exact, slower)
  // The measures: bounding box, angles, shortest edge, volume, duplicate
  // points. Off, only the counts of the topology (edges, borders,
  // components, non-manifold vertices, duplicate faces) and of non-finite
  // vertices and degenerate faces are made: what the edit contracts check.
  bool measures = true;
};

// Bits of InspectResult::face_defects.
enum FaceDefect : std::uint8_t {
  kFaceOnNonManifoldEdge = 1,  // has an edge used by more than two faces
  kFaceOnBorder = 2,           // has an edge used by this face only
  kFaceDegenerate = 4,         // repeated vertex (index or coordinates) or collinear corners
  kFaceDuplicate = 8,          // same vertex set as an earlier face
  kFaceOrientationFlip = 16,   // shares an edge with a face that runs it the same way
  kFaceSelfIntersecting = 32,  // intersects another face (self_intersections option)
};

// Bits of InspectResult::vertex_defects.
enum VertexDefect : std::uint8_t {
  kVertexNonManifold = 1,  // its faces form more than one edge-connected fan
  kVertexOnBorder = 2,     // on a border edge
  kVertexIsolated = 4,     // used by no face
  kVertexDuplicate = 8,    // same coordinates as an earlier vertex
  kVertexNonFinite = 16,   // a coordinate is NaN or infinite
};

struct InspectResult {
  std::size_t vertices = 0;               // vertex records
  std::size_t faces = 0;                  // triangles
  std::size_t edges = 0;                  // undirected edges between distinct indices
  std::size_t connected_components = 0;   // faces joined through shared edges
  std::size_t border_edges = 0;           // edges used by exactly one face
  std::size_t border_loops = 0;           // connected components of the border edges
  std::size_t longest_border_loop = 0;    // edges of the largest border loop
  std::size_t non_manifold_edges = 0;     // edges used by more than two faces
  std::size_t non_manifold_vertices = 0;  // pinch / bow-tie vertices
  std::size_t isolated_vertices = 0;      // vertices used by no face
  std::size_t duplicate_points = 0;       // vertices repeating an earlier one's coordinates
  std::size_t non_finite_vertices = 0;    // NaN or infinite coordinates (geometry skips them)
  std::size_t degenerate_faces = 0;       // exact: repeated vertex or collinear
  std::size_t duplicate_faces = 0;        // same vertex set as an earlier face
  std::size_t orientation_inconsistent_edges = 0;  // two faces run the edge the same way
  bool is_closed = false;                          // no border edge, at least one face
  bool consistently_oriented = true;               // orientation_inconsistent_edges == 0
  std::optional<double> volume;   // signed; closed, oriented, edge-manifold, finite meshes only
  long euler_characteristic = 0;  // used vertices - edges + faces
  std::optional<long> genus;      // closed, edge- and vertex-manifold, oriented meshes only
  std::array<double, 6> bbox{};   // min x, y, z, max x, y, z over all finite vertices
  double bbox_diagonal = 0;
  double min_angle_deg = 180;     // smallest interior angle
  double mean_min_angle_deg = 0;  // mean over triangles of their smallest angle
  // Whether the host's scalar can hold the detail: the largest |coordinate|
  // (finite vertices), the shortest edge of a face between two distinct
  // points, and how many steps of float and of double (the spacing of the
  // scalar's values at the largest coordinate) that edge spans. A float host
  // (MeshLab's float builds) moves each coordinate by up to half a step when
  // it stores it: below a few steps, storing can make faces cross or
  // collapse (precision_note says so).
  double max_abs_coordinate = 0;
  double shortest_edge = 0;
  double float_steps_in_shortest_edge = 0;
  double double_steps_in_shortest_edge = 0;
  // log2 of the largest over the smallest nonzero |coordinate| of the faces'
  // corners: beyond kMaxCoordinateBinades (mesh.h) MeshMend's exact
  // operations refuse the mesh, and self-intersections are not counted.
  double coordinate_binades = 0;
  // With the self_intersections option (the rule of CGAL's self_intersections,
  // as in intersections.h); empty otherwise, without faces, with non-finite
  // coordinates or beyond kMaxCoordinateBinades.
  std::optional<std::size_t> self_intersecting_pairs;
  std::optional<std::size_t> self_intersecting_faces;
  double time_ms = 0;                        // compute time of inspect()
  std::vector<std::uint8_t> face_defects;    // per face FaceDefect bits (mark_defects)
  std::vector<std::uint8_t> vertex_defects;  // per vertex VertexDefect bits (mark_defects)
};

// Below this many float steps in the shortest edge, Inspect warns that
// float storage is not enough for the mesh (precisionNote).
inline constexpr double kFewFloatSteps = 64;

// A sentence for the log and the report when the shortest edge spans fewer
// than kFewFloatSteps float steps (pointing to a double host), else empty.
std::string precisionNote(const InspectResult& result);

// Inspects a compact mesh (no deleted elements). Never throws on defects: they
// are what it measures. Throws InvalidInputError if the mesh is not compact.
InspectResult inspect(const Mesh& mesh, const InspectOptions& options = {});

// The report_file object: meshcheck's key names, plus time_ms.
JsonObject toJson(const InspectResult& result);

// One-paragraph human summary ("closed, 1 component, genus 0, ..." or the list
// of defects found), used by the filters' logs.
std::string summarize(const InspectResult& result);

}  // namespace meshmend
