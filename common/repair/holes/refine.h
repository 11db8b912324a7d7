// Refining a patch where its shape in space stretches the triangles the
// domain gave it (a plane foreshortens the part of a hole that turns away
// from it; a bulging shape stretches the middle), and flipping its edges
// towards Delaunay triangles in space.
#pragma once

#include <functional>
#include <vector>

#include "common/repair/holes/fairing.h"

namespace meshmend::holes {

// Splits, at their midpoints in the domain and in space, the patch's inner
// edges that the positions `x` make longer than `maxStretch` times their
// length in the domain and than `size` (longest first, each triangle once
// per pass, a few passes). A half keeps its edge's stretch, so the pieces
// are split again until they are no longer than `size` or the passes run
// out: where the domain foreshortened the patch, its triangles in space
// come down towards the border's size. Then flips the edges the splits left
// non-Delaunay in space. `flat` (another placement) follows the splits.
// Edges that `forbidden` names (local corners) are never made by a flip.
// Returns the number of edges split; with any, patch.around is rebuilt.
std::size_t refineStretched(Patch& patch, std::vector<Point3>& x, std::vector<Point3>& flat,
                            double size, double maxStretch,
                            const std::function<bool(int, int)>& forbidden);

// Mean over the patch's triangles of 4 sqrt(3) area / (sum of squared edge
// lengths) at x: 1 for equilateral ones, 0 for slivers.
double meanShapeQuality(const Patch& patch, const std::vector<Point3>& x);

}  // namespace meshmend::holes
