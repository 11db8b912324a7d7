// The OBJ reader (common/obj_reader.h) on any bytes: it reads them or
// refuses with InvalidInputError; what it reads is consistent.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "common/base/errors.h"
#include "common/io/obj_reader.h"
#include "fuzz/fuzz_input.h"

namespace meshmend::fuzz {

namespace {

// A folder of this process's own for the file the reader opens (it reads
// a path; material libraries are looked up beside it), removed at exit.
// The name is never destroyed: the exit handler, registered while it was
// being made, runs after the destructors of statics made later.
const std::string& scratchFolder() {
  static const std::string* folder = [] {
    char name[] = "/tmp/meshmend-fuzz-XXXXXX";
    if (!mkdtemp(name)) {
      std::perror("mkdtemp");
      std::abort();
    }
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(scratchFolder(), ignored);
    });
    return new std::string(name);
  }();
  return *folder;
}

void checkRead(const ObjData& d) {
  check(!d.positions.empty(), "a file read without error has vertices");
  for (const Point3& p : d.positions) check(isFinite(p), "positions are finite");
  check(d.vertex_colors.empty() || d.vertex_colors.size() == d.positions.size(),
        "one colour per vertex or none");
  check(d.polygon_material.size() == d.polygons.size(), "one material per polygon");
  for (std::size_t p = 0; p < d.polygons.size(); ++p) {
    check(d.polygons[p].size() >= 3, "polygons have three corners or more");
    const int m = d.polygon_material[p];
    check(m >= -1 && m < int(d.materials.size()), "material index in range");
    for (const ObjCorner& c : d.polygons[p]) {
      check(c.vertex >= 0 && c.vertex < int(d.positions.size()), "vertex index in range");
      check(c.texcoord >= -1 && c.texcoord < int(d.texcoords.size()), "texcoord index in range");
      check(c.normal >= -1 && c.normal < int(d.normals.size()), "normal index in range");
    }
  }
}

}  // namespace

void objReader(const std::uint8_t* data, std::size_t size) {
  const std::string path = scratchFolder() + "/input.obj";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    checkRead(readObj(path));
  } catch (const Error&) {
    // a refusal with a message: a clean outcome
  }
}

}  // namespace meshmend::fuzz
