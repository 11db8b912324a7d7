// The faces around the holes: all a hole's fill needs of the mesh (the fans
// of its border vertices, the rings its curvature is learnt from, the faces
// its patch is checked against) lie in a box around it, and one pass over
// the points and one over the faces collect the faces near every hole at
// once.
#pragma once

#include <vector>

#include "common/repair/holes/surface.h"

namespace meshmend::holes {

// For each region, the faces of `mesh` (as it has them) whose box overlaps
// it, and a few more whose box is near; ascending. `finite` tells whether
// every coordinate of the mesh is finite (the pass reads them all).
std::vector<std::vector<int>> inputFacesNear(const Mesh& mesh, const std::vector<Bounds>& regions,
                                             bool& finite);

}  // namespace meshmend::holes
