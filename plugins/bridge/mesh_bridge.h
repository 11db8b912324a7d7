// Conversion between MeshLab's CMeshO (float in 2020.09, double in 2022.02;
// optional components) and the core mesh (double, geometry + provenance). Attributes never enter the core:
// they are snapshotted from the input layers and carried to the output through
// the provenance every output element records.
#pragma once

#include <vector>

#include "common/base/mesh.h"
#include "plugins/bridge/meshlab_host.h"

namespace meshmend::bridge {

struct ToCoreOptions {
  int layer = 0;                 // recorded as the origin layer of every element
  bool apply_transform = false;  // apply the layer's matrix (cm.Tr): needed between layers
};

// Live vertices and faces of `cm` (deleted ones skipped). Origins index
// `cm.vert` / `cm.face` as they are (with their deleted slots).
Mesh toCore(const CMeshO& cm, const ToCoreOptions& options = {});
// The same into `out` (a Mesh cannot move: this saves a copy).
void toCore(const CMeshO& cm, Mesh& out, const ToCoreOptions& options = {});

// Everything the output may need from one input layer, copied out of the
// CMeshO so that the layer itself can be overwritten (in-place filters).
struct LayerAttributes {
  bool vertex_color = false, vertex_quality = false, vertex_texcoord = false;
  bool face_color = false, face_quality = false, wedge_texcoord = false;
  std::vector<vcg::Point3d> positions;    // to compute barycentric coordinates
  std::vector<std::array<int, 3>> faces;  // corner vertex indices
  std::vector<vcg::Color4b> vertex_colors;
  std::vector<HostScalar> vertex_qualities;
  std::vector<HostPoint> vertex_normals;
  std::vector<vcg::TexCoord2f> vertex_texcoords;
  std::vector<bool> vertex_selected, face_selected;
  std::vector<vcg::Color4b> face_colors;
  std::vector<HostScalar> face_qualities;
  std::vector<std::array<vcg::TexCoord2f, 3>> wedge_texcoords;
  std::vector<std::string> textures;  // texture file names (cm.textures)
};

// Snapshot of a layer's attributes (MeshModel's data mask says which exist).
LayerAttributes snapshot(const MeshModel& model);

// Writes `core` into `out` (cleared first; `out` may be one of the inputs),
// carrying each element's attributes from `inputs[origin.layer]`: copied from
// the origin vertex / face, or interpolated at the origin's barycentric
// coordinates for new vertices and for the wedge texture coordinates of
// faces cut from an input face. Faces without an origin get the default
// colour. Texture indices are offset so that the textures of all inputs
// coexist. Enables the components any input had; updates box and normals.
void writeMesh(const Mesh& core, const std::vector<LayerAttributes>& inputs, MeshModel& out);

// writeMesh also records in the output, per face, what the face is to the
// inputs (the shader meshmend_new_faces shows it): a copy of an input face,
// a piece cut from one, or new (no input face under it: hole patches,
// stitches). Each filter that rebuilds a layer through writeMesh replaces it.
inline constexpr const char* kFaceChangeAttribute = "meshmend_face_change";  // unsigned char
enum FaceChange : unsigned char { kFaceKept = 0, kFaceCut = 1, kFaceNew = 2 };

}  // namespace meshmend::bridge
