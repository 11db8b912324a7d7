// Vertices whose faces are settled all at once for the self-intersection
// rule: their fan projects one-to-one onto a coordinate plane.
#pragma once

#include <vector>

#include "common/base/mesh.h"

namespace meshmend {

// For each vertex v, whether its faces form one closed, consistently
// oriented fan (v, w_0, w_1), (v, w_1, w_2), ..., (v, w_{k-1}, w_0) with
// distinct w_i, whose projection onto a coordinate plane has every face
// strictly counter-clockwise (or every face clockwise) and turns exactly
// once around v. The projected faces then lie in disjoint angular sectors
// that tile the plane once, and each face projects one-to-one, so two faces
// of the fan meet only in v (when they share v alone) or only along their
// common edge (consecutive faces). By the self-intersection rule
// (intersectBeyondShared), no two faces sharing v intersect.
//
// Exact: the signs come from orient2d and from comparisons of coordinates.
// False for vertices on a border, at a non-manifold or inconsistently
// oriented spot, on a degenerate face, or whose fan folds over in every
// projection tried (the projection along the fan's summed normal): their
// pairs are left to the full test. `points` must be finite.
std::vector<char> fansApartInProjection(const std::vector<Point3>& points,
                                        const std::vector<Triangle>& triangles);

}  // namespace meshmend
