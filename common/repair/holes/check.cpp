#include "common/repair/holes/check.h"

#include <algorithm>
#include <atomic>
#include <unordered_set>

#include "common/exact/box_tree.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"

namespace meshmend::holes {

std::size_t patchIntersections(const Surface& s, const std::vector<Triangle>& patch,
                               const std::vector<Point3>& newPoints, const std::vector<int>& own,
                               const std::vector<int>& near, std::size_t enough) {
  const std::size_t existing = s.vertexCount();
  auto point = [&](int v) -> const Point3& {
    return std::size_t(v) < existing ? s.point(v) : newPoints[std::size_t(v) - existing];
  };
  struct Checked {
    Triangle corners;
    TrianglePoints points;
  };
  std::vector<Checked> checked;  // the patch's faces, then the split ones
  checked.reserve(patch.size() + own.size());
  for (const Triangle& t : patch) {
    checked.push_back({t, {point(t[0]), point(t[1]), point(t[2])}});
    const TrianglePoints& p = checked.back().points;
    if (collinear(p[0], p[1], p[2])) return 1;
  }
  std::unordered_set<int> ownSet(own.begin(), own.end());
  for (int f : ownSet) {
    const Triangle t = s.corners(f);
    TrianglePoints p{point(t[0]), point(t[1]), point(t[2])};
    if (!collinear(p[0], p[1], p[2])) checked.push_back({t, p});
  }
  std::vector<Box> boxes;
  boxes.reserve(checked.size());
  Box bounds{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  Point3 lo(INFINITY, INFINITY, INFINITY), hi(-INFINITY, -INFINITY, -INFINITY);  // the points'
  for (const Checked& c : checked) {
    boxes.push_back(boxOf(c.points[0], c.points[1], c.points[2]));
    for (int k = 0; k < 3; ++k) {
      bounds.lo[k] = std::min(bounds.lo[k], boxes.back().lo[k]);
      bounds.hi[k] = std::max(bounds.hi[k], boxes.back().hi[k]);
      for (const Point3& q : c.points) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
    }
  }
  // A face with all its corners beyond one side of the checked faces'
  // points meets none of them (most of the faces near a hole): turned away
  // before its box is rounded out to float.
  auto beyond = [&](const TrianglePoints& p) {
    for (int k = 0; k < 3; ++k)
      if ((p[0][k] < lo[k] && p[1][k] < lo[k] && p[2][k] < lo[k]) ||
          (p[0][k] > hi[k] && p[1][k] > hi[k] && p[2][k] > hi[k]))
        return true;
    return false;
  };
  const BoxTree tree(boxes);
  std::atomic<std::size_t> pairs{0};
  tree.selfPairs([&](std::uint32_t i, std::uint32_t j, unsigned) {
    if (pairs < enough && facesIntersect(checked[i].corners, checked[i].points, checked[j].corners,
                                         checked[j].points))
      ++pairs;
  });
  for (int f : near) {
    if (pairs >= enough) break;
    if (ownSet.count(f)) continue;
    const Triangle t = s.corners(f);
    const TrianglePoints p{point(t[0]), point(t[1]), point(t[2])};
    if (beyond(p)) continue;
    const Box box = boxOf(p[0], p[1], p[2]);
    if (!overlap(box, bounds)) continue;
    tree.query(box, 0, [&](std::uint32_t i, unsigned) {
      if (pairs < enough && facesIntersect(checked[i].corners, checked[i].points, t, p)) ++pairs;
    });
  }
  return pairs;
}

}  // namespace meshmend::holes
