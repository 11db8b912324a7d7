// Reading and writing core meshes from files, for tools, tests and
// benchmarks that work without MeshLab (the plugins get their meshes from
// MeshLab's own importers).
#pragma once

#include <string>

#include "common/base/mesh.h"

namespace meshmend {

// Reads an OFF, PLY (ASCII or binary, triangle strips included), STL or OBJ
// file. Vertices are kept as stored (no welding; an STL has 3 per facet),
// polygons are fan-triangulated. Throws InvalidInputError naming the file for
// an unreadable file, an unknown extension, or a face index out of range.
Mesh readMesh(const std::string& path);

// Writes a mesh as OFF or binary PLY (chosen by the extension), coordinates
// in double precision. Throws InvalidInputError when the file cannot be written.
void writeMesh(const std::string& path, const Mesh& mesh);

}  // namespace meshmend
