// Where a hole's patch is triangulated: the hole's plane, when the border
// projects onto one as a simple polygon, or a disk (any border does).
#pragma once

#include <vector>

#include "common/repair/holes/plane.h"

namespace meshmend::holes {

struct Domain {
  std::vector<Vec2> uv;  // the boundary vertices, front order (counter-clockwise)
  bool planar = true;    // over a plane: a patch point is origin + u U + v V + h N
  Point3 origin, U, V, N;
  std::vector<double> height;  // planar: the boundary's heights over the plane
};

// The plane the border `points` (front order) projects onto as a simple
// polygon: its best-fit plane, the plane of the faces' mean normal
// `meanFaceNormal`, of its vector area, or one tilted around those by up
// to 60 degrees. False when none does.
bool planeDomain(const std::vector<Point3>& points, const Point3& meanFaceNormal, Domain& plane);

// A circle with the boundary vertices spaced by arc length: a domain for
// any border.
Domain diskDomain(const std::vector<Point3>& points);

}  // namespace meshmend::holes
