// Values for MeshMend's render shaders (shaders/meshmend_*.gdp), carried in
// per-wedge texture coordinates. MeshLab 2020.09 hands a GLSL shader only
// positions, normals, colours and texture coordinates (no quality, no flags,
// no user attributes), so whatever a shader shows must travel in one of them;
// texture coordinates are the channel that holds exact floats and leaves the
// mesh's colours alone.
//
// Encoding of one face corner (u, v), with (b0, b1) the corner's own
// barycentric coordinates, (1, 0), (0, 1) and (0, 0) for corners 0, 1, 2, so
// that a fragment's interpolated (u, v) also says where in the face it lies:
//   per-vertex values: u = the corner vertex's value, v = tag
//   per-face labels:   u = 4 label + b0, v = tag + 4 boundary_mask + b1
// tag says which values these are (RenderChannel); bit k of boundary_mask is
// set when the face's edge from corner k to corner k+1 separates it from a
// face with another label. The shaders decode exactly as decodeChannel does.
#pragma once

#include <array>
#include <vector>

namespace meshmend {

enum class RenderChannel {
  kNone = 0,           // no MeshMend values
  kClearance = 100,    // per-vertex distance (vertex quality of Measure Clearance)
  kPatches = 200,      // per-face patch id (Paint Surface Patches)
  kFaceChanges = 300,  // per-face FaceChange of the last filter that rebuilt the layer
};

// Labels wrap at this value (colour only: boundaries come from the full
// labels) so that a float keeps the barycentric part to 1/4000 at least.
inline constexpr int kLabelModulus = 1024;
// Non-finite or larger per-vertex values are stored as this (finite, so
// that interpolation on the graphics card stays finite).
inline constexpr float kLargestValue = 1e30f;

using WedgeCoords = std::array<std::array<float, 2>, 3>;  // (u, v) per face corner
using Triangles = std::vector<std::array<int, 3>>;        // corner vertex indices

// Per-vertex values on every corner. Throws InvalidInputError when a face
// names a vertex without a value.
std::vector<WedgeCoords> encodeVertexValues(const Triangles& faces,
                                            const std::vector<double>& values);

// Per-face labels (0 or more) with their boundaries: an edge is a boundary
// where the faces sharing it do not all have the same label, and also, when
// `borders_are_boundaries`, where only one face uses it. Throws
// InvalidInputError for a negative label or a label count other than the
// face count.
std::vector<WedgeCoords> encodeFaceLabels(const Triangles& faces, const std::vector<int>& labels,
                                          RenderChannel channel, bool borders_are_boundaries);

// What a shader reads from an interpolated (u, v).
struct DecodedChannel {
  RenderChannel channel = RenderChannel::kNone;
  float value = 0;                     // per-vertex channels
  int label = 0;                       // per-face channels (modulo kLabelModulus)
  int boundary_mask = 0;               // per-face channels
  std::array<float, 3> barycentric{};  // per-face channels
};
DecodedChannel decodeChannel(float u, float v);

}  // namespace meshmend
