// The checks and counts trimming, stitching and gap closing share.
#include <sstream>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/repair/stitch/detail.h"

namespace meshmend::stitch_detail {

std::string describeVertex(const Mesh& mesh, int v) {
  std::ostringstream s;
  s.precision(6);
  const Point3& p = mesh.vert[v].cP();
  s << "vertex " << v << " (" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return s.str();
}

void requireCompact(const Mesh& mesh) {
  if (std::size_t(mesh.vn) != mesh.vert.size() || std::size_t(mesh.fn) != mesh.face.size())
    throw InvalidInputError(
        "the mesh has deleted vertices or faces: compact it first (vcg::tri::Allocator::Compact)");
}

void requireVertex(const Mesh& mesh, int v, const std::string& what) {
  if (v < 0 || std::size_t(v) >= mesh.vert.size())
    throw InvalidInputError(what + " refers to vertex " + std::to_string(v) +
                            ", but the mesh has only " + std::to_string(mesh.vert.size()) +
                            " vertices");
}

std::size_t borderEdgesOf(const std::vector<Triangle>& triangles) {
  const std::vector<EdgeUse> uses = edgeUses(triangles);
  std::size_t border = 0;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    if (j - i == 1) ++border;
    i = j;
  }
  return border;
}

}  // namespace meshmend::stitch_detail
