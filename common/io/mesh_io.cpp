#include "common/io/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>

#include <wrap/io_trimesh/export_off.h>
#include <wrap/io_trimesh/export_ply.h>
#include <wrap/io_trimesh/import_off.h>
#include <wrap/io_trimesh/import_ply.h>
#include <wrap/io_trimesh/import_stl.h>

#include "common/base/errors.h"
#include "common/io/obj_reader.h"

namespace meshmend {

namespace {

std::string extensionOf(const std::string& path) {
  const std::size_t dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// vcglib's importers store raw face pointers without checking indices: check
// them before anything reads through them, then rebuild with provenance.
Mesh validated(Mesh& raw, const std::string& path) {
  std::vector<Point3> positions = positionsOf(raw);
  std::vector<Triangle> triangles;
  triangles.reserve(raw.face.size());
  const Vertex* first = raw.vert.empty() ? nullptr : &raw.vert.front();
  for (std::size_t f = 0; f < raw.face.size(); ++f) {
    Triangle t;
    for (int k = 0; k < 3; ++k) {
      const Vertex* v = raw.face[f].cV(k);
      const std::ptrdiff_t i = first ? v - first : -1;
      if (!first || i < 0 || i >= std::ptrdiff_t(raw.vert.size()))
        throw InvalidInputError("'" + path + "': face " + std::to_string(f) +
                                " refers to a vertex index out of range");
      t[k] = int(i);
    }
    triangles.push_back(t);
  }
  return makeMesh(positions, triangles);
}

}  // namespace

Mesh readMesh(const std::string& path) {
  if (!std::ifstream(path)) throw InvalidInputError("cannot open '" + path + "': check the path");
  const std::string ext = extensionOf(path);
  if (ext == "obj") {
    const ObjData obj = readObj(path);
    std::vector<Triangle> triangles;
    for (const auto& polygon : obj.polygons)
      for (std::size_t i = 1; i + 1 < polygon.size(); ++i)
        triangles.push_back({polygon[0].vertex, polygon[i].vertex, polygon[i + 1].vertex});
    return makeMesh(obj.positions, triangles);
  }
  Mesh raw;
  int error = 0;
  bool failed = false;
  std::string message;
  if (ext == "ply") {
    error = vcg::tri::io::ImporterPLY<Mesh>::Open(raw, path.c_str());
    failed = error != 0 && vcg::tri::io::ImporterPLY<Mesh>::ErrorCritical(error);
    if (failed) message = vcg::tri::io::ImporterPLY<Mesh>::ErrorMsg(error);
  } else if (ext == "off") {
    error = vcg::tri::io::ImporterOFF<Mesh>::Open(raw, path.c_str());
    failed = error != 0;
    if (failed) message = vcg::tri::io::ImporterOFF<Mesh>::ErrorMsg(error);
  } else if (ext == "stl") {
    int mask = 0;
    error = vcg::tri::io::ImporterSTL<Mesh>::Open(raw, path.c_str(), mask);
    failed = error != 0;
    if (failed) message = vcg::tri::io::ImporterSTL<Mesh>::ErrorMsg(error);
  } else {
    throw InvalidInputError("'" + path + "': unknown mesh format (use OFF, PLY, STL or OBJ)");
  }
  if (failed) throw InvalidInputError("cannot read '" + path + "': " + message);
  return validated(raw, path);
}

void writeMesh(const std::string& path, const Mesh& mesh) {
  Mesh& m = const_cast<Mesh&>(mesh);  // vcglib exporters take non-const meshes
  const std::string ext = extensionOf(path);
  int error = 0;
  if (ext == "off") {
    error = vcg::tri::io::ExporterOFF<Mesh>::Save(m, path.c_str(), vcg::tri::io::Mask::IOM_NONE);
  } else if (ext == "ply") {
    error =
        vcg::tri::io::ExporterPLY<Mesh>::Save(m, path.c_str(), vcg::tri::io::Mask::IOM_NONE, true);
  } else {
    throw InvalidInputError("'" + path + "': write OFF or PLY");
  }
  if (error != 0) throw InvalidInputError("cannot write '" + path + "'");
}

}  // namespace meshmend
