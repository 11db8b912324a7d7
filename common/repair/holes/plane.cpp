#include "common/repair/holes/plane.h"

#include <algorithm>

namespace meshmend::holes {

namespace {

// Exact: is r inside the bounding box of p and q (r collinear with them)?
bool withinBox(Vec2 p, Vec2 q, Vec2 r) {
  return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
         r.y <= std::max(p.y, q.y);
}

}  // namespace

bool segmentsMeet(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  // Closed boxes apart: no common point (compared exactly, most pairs end here).
  if (std::max(a.x, b.x) < std::min(c.x, d.x) || std::max(c.x, d.x) < std::min(a.x, b.x) ||
      std::max(a.y, b.y) < std::min(c.y, d.y) || std::max(c.y, d.y) < std::min(a.y, b.y))
    return false;
  const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  return (o1 == 0 && withinBox(a, b, c)) || (o2 == 0 && withinBox(a, b, d)) ||
         (o3 == 0 && withinBox(c, d, a)) || (o4 == 0 && withinBox(c, d, b));
}

bool overlapFromShared(Vec2 s, Vec2 a, Vec2 b) {
  return orient(s, a, b) == 0 && dot(a - s, b - s) > 0;
}

double pointSegmentDistance(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 ab = b - a;
  const double len2 = dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * ab));
}

double signedArea(const std::vector<Vec2>& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) a += cross(poly[i], poly[(i + 1) % poly.size()]);
  return a / 2;
}

bool isSimplePolygon(const std::vector<Vec2>& poly) {
  const std::size_t n = poly.size();
  if (n < 3) return false;
  Vec2 lo = poly[0], hi = poly[0];
  double length = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % n];
    if (a.x == b.x && a.y == b.y) return false;
    lo = boxLo(lo, a);
    hi = boxHi(hi, a);
    length += norm(b - a);
  }
  Grid grid(lo, hi, length / double(n), 4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % n];
    grid.insert(int(i), boxLo(a, b), boxHi(a, b));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % n];
    bool meets = false;
    grid.query(boxLo(a, b), boxHi(a, b), [&](int j) {
      if (meets || std::size_t(j) <= i) return;
      const Vec2 c = poly[std::size_t(j)], d = poly[(std::size_t(j) + 1) % n];
      if (std::size_t(j) == i + 1)
        meets = overlapFromShared(b, a, d);
      else if (i == 0 && std::size_t(j) == n - 1)
        meets = overlapFromShared(a, b, c);
      else
        meets = segmentsMeet(a, b, c, d);
    });
    if (meets) return false;
  }
  return true;
}

Grid::Grid(Vec2 lo, Vec2 hi, double cell, std::size_t maxCells) : lo_(lo) {
  const double w = std::max(hi.x - lo.x, 1e-300), h = std::max(hi.y - lo.y, 1e-300);
  cell = std::max(cell, std::sqrt(w * h / double(std::max<std::size_t>(maxCells, 1))));
  inverse_ = 1 / cell;
  // Clamped before converting: an extent near the double range makes the
  // counts infinite or NaN, which have no int (they take the most cells).
  auto cells = [](double extent) { return extent < 4095 ? int(extent) + 1 : 4096; };
  nx_ = cells(w * inverse_);
  ny_ = cells(h * inverse_);
  head_.assign(std::size_t(nx_) * std::size_t(ny_), -1);
  entries_.reserve(2 * head_.size());
}

void Grid::insert(int id, Vec2 lo, Vec2 hi) {
  const auto [x0, y0] = cellOf(lo);
  const auto [x1, y1] = cellOf(hi);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      int& head = head_[std::size_t(y) * std::size_t(nx_) + std::size_t(x)];
      entries_.push_back({id, head});
      head = int(entries_.size() - 1);
    }
}

std::pair<Point3, Point3> tangentFrame(const Point3& n) {
  Point3 u = std::abs(n[0]) < 0.9 ? Point3(1, 0, 0) ^ n : Point3(0, 1, 0) ^ n;
  u.Normalize();
  return {u, n ^ u};
}

}  // namespace meshmend::holes
