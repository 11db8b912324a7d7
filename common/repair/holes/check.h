// The exact check of a patch before it is kept: no face of the patch, or of
// the border faces its pre-treatment split, may meet another face beyond
// the corners they share (the self-intersection rule of facesIntersect,
// vertex identity = index).
#pragma once

#include <vector>

#include "common/repair/holes/surface.h"

namespace meshmend::holes {

// The pairs of faces that intersect among the patch's faces and `own` (the
// faces the hole's pre-treatment split, in the surface), and between those
// and `near` (faces of the surface around the patch; own ones among them
// are skipped): every face of the surface that may meet the patch must be
// in `own` or `near`. Patch corners from s.vertexCount() on are new
// vertices, at newPoints[corner - s.vertexCount()]. A patch face without
// area counts as a pair. The count stops at `enough` (a patch that fails
// is not looked at further).
std::size_t patchIntersections(const Surface& s, const std::vector<Triangle>& patch,
                               const std::vector<Point3>& newPoints, const std::vector<int>& own,
                               const std::vector<int>& near, std::size_t enough);

}  // namespace meshmend::holes
