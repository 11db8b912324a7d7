// Ingestion and validation of a mesh (makeMesh, the finiteness check,
// welding, inspect): any arrays, NaN and infinities included, are taken or
// refused with InvalidInputError, and the counts agree with each other.
#include <cmath>

#include "common/base/errors.h"
#include "common/base/mesh.h"
#include "common/exact/intersections.h"
#include "common/repair/inspect/inspect.h"
#include "fuzz/fuzz_input.h"

namespace meshmend::fuzz {

namespace {

bool allFinite(const std::vector<Point3>& points) {
  for (const Point3& p : points)
    if (!isFinite(p)) return false;
  return true;
}

void checkInspection(const Mesh& mesh, const InspectResult& r, bool finite) {
  check(r.faces == std::size_t(mesh.fn) && r.vertices == std::size_t(mesh.vn), "element counts");
  check(r.face_defects.size() == r.faces && r.vertex_defects.size() == r.vertices,
        "one defect mark per element");
  check(r.is_closed == (r.border_edges == 0 && r.faces > 0), "closed means no border edge");
  check(r.consistently_oriented == (r.orientation_inconsistent_edges == 0), "orientation flag");
  check(r.border_loops <= r.border_edges, "at most one loop per border edge");
  check(finite == (r.non_finite_vertices == 0), "non-finite vertices counted");
  check(r.coordinate_binades == magnitudesOf(positionsOf(mesh), trianglesOf(mesh)).binades(),
        "the span of the faces' coordinates");
  if (finite && mesh.fn > 0 && r.coordinate_binades <= kMaxCoordinateBinades) {
    check(r.self_intersecting_pairs.has_value(), "pairs counted on finite faces");
    check(*r.self_intersecting_pairs == selfIntersectingPairs(mesh),
          "inspect and selfIntersectingPairs count the same pairs");
  }
  (void)toJson(r).str();
  (void)summarize(r);
}

}  // namespace

void meshValidation(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const DecodedMesh d = decodeMesh(in, 256, 512);
  const bool finite = allFinite(d.points);
  Mesh mesh;
  try {
    mesh = makeMesh(d.points, d.triangles);
  } catch (const InvalidInputError&) {
    check(false, "indices in range are taken");
  }
  bool refused = false;
  try {
    requireFacesAndFiniteCoordinates(mesh, "the fuzz mesh");
  } catch (const InvalidInputError&) {
    refused = true;
  }
  const bool wide = finite && magnitudesOf(d.points, d.triangles).binades() > kMaxCoordinateBinades;
  check(refused == (d.triangles.empty() || !finite || wide),
        "a mesh is refused exactly when it has no face, a non-finite coordinate or "
        "coordinates spanning more than kMaxCoordinateBinades");
  InspectOptions options;
  options.mark_defects = true;
  options.self_intersections = true;
  checkInspection(mesh, inspect(mesh, options), finite);
  if (!finite) return;
  Mesh welded = mesh;
  std::size_t removedFaces = 0;
  const std::size_t merged = weldCoincidentVertices(welded, &removedFaces);
  check(std::size_t(welded.vn) + merged <= std::size_t(mesh.vn), "welding merges vertices away");
  check(std::size_t(welded.fn) + removedFaces == std::size_t(mesh.fn), "welding removes faces");
  const InspectResult after = inspect(welded, options);
  check(after.duplicate_points == 0, "no duplicate point is left after welding");
  const WeldedArrays arrays = weldCoincident(arraysOf(mesh));
  check(arrays.mesh.triangles.size() == std::size_t(welded.fn), "welding arrays and meshes agree");
}

}  // namespace meshmend::fuzz
