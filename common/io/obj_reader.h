// Reader for Wavefront OBJ files (and their MTL material libraries).
//
// MeshLab 2020.09's own OBJ importer, as Debian builds it, aborts on an
// assertion for valid files (even a single triangle); the io_mend_obj plugin
// replaces it with this reader. Polygons are kept as read: the plugin
// triangulates them.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "common/base/mesh.h"

namespace meshmend {

struct ObjCorner {
  int vertex = -1;    // 0-based position index
  int texcoord = -1;  // 0-based texture coordinate index, -1 if none
  int normal = -1;    // 0-based normal index, -1 if none
};

struct ObjMaterial {
  std::string name;
  std::array<float, 3> diffuse{0.8f, 0.8f, 0.8f};  // Kd
  float opacity = 1;                               // d, or 1 - Tr
  std::string diffuse_texture;                     // map_Kd, relative to the MTL file
};

struct ObjData {
  std::vector<Point3> positions;
  std::vector<std::array<float, 3>> vertex_colors;  // "v x y z r g b" extension; empty if absent
  std::vector<std::array<double, 2>> texcoords;
  std::vector<Point3> normals;
  std::vector<std::vector<ObjCorner>> polygons;  // faces with 3 or more corners
  std::vector<int> polygon_material;             // index into materials, -1 if none
  std::vector<ObjMaterial> materials;
  std::vector<std::string> warnings;  // skipped lines and missing files
};

// Reads an OBJ file. Throws InvalidInputError (with the file name and line)
// for an unreadable file, malformed numbers, non-finite coordinates, or an
// index out of range, and when the file holds no vertex.
ObjData readObj(const std::string& path);

}  // namespace meshmend
