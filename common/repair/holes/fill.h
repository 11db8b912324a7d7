// One hole's fill, in the stages of the paper (Xu, Li, Tan 2013, §3):
// the border and the surface around it are read; the hole is triangulated
// over a domain (its plane, else a disk) by the advancing front and refined
// where the placement stretches it; the patch is faired; the result is
// checked exactly against the surface near it; and committed, or a flatter
// shape (or the other domain) is tried, or the hole is left open.
#pragma once

#include <functional>
#include <vector>

#include "common/repair/holes/holes.h"
#include "common/repair/holes/surface.h"

namespace meshmend::holes {

struct HoleContext {
  Surface& surface;
  const HoleFillOptions& options;
  const std::vector<int>& pinched;  // sorted: vertices where several borders pass
  HoleFillResult::StageTimes& times;
  // The faces of the surface whose box may overlap `bounds` (every face
  // whose box does, and some more): the fans of the hole's border and the
  // faces its patch is checked against.
  std::function<std::vector<int>(const Bounds& bounds)> facesNear;
};

// Fills the hole bounded by `loop` (in the faces' direction, after the
// pre-treatment split its long edges; `sizes`: per loop edge, the length of
// the input edge it is part of, which the patch's triangles take there;
// `splitFaces`: the faces that split changed or added). False, with the
// reason in the report, when no patch fits; the surface is then as it was.
bool fillHole(HoleContext& context, const std::vector<int>& loop, const std::vector<double>& sizes,
              const std::vector<int>& splitFaces, HoleReport& report);

}  // namespace meshmend::holes
