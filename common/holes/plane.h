// Plane geometry of a hole's domain (where its patch is triangulated):
// points, exact orientation and segment tests, a bucket grid, and the
// simple-polygon test that decides whether a projection of the border can
// be triangulated.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "common/mesh.h"
#include "common/predicates.h"

namespace meshmend::holes {

struct Vec2 {
  double x = 0, y = 0;
};
inline Vec2 operator+(Vec2 a, Vec2 b) {
  return {a.x + b.x, a.y + b.y};
}
inline Vec2 operator-(Vec2 a, Vec2 b) {
  return {a.x - b.x, a.y - b.y};
}
inline Vec2 operator*(double s, Vec2 a) {
  return {s * a.x, s * a.y};
}
inline double dot(Vec2 a, Vec2 b) {
  return a.x * b.x + a.y * b.y;
}
inline double cross(Vec2 a, Vec2 b) {
  return a.x * b.y - a.y * b.x;
}
inline double norm(Vec2 a) {
  return std::sqrt(dot(a, a));
}
inline Vec2 rotated(Vec2 a, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * a.x - s * a.y, s * a.x + c * a.y};
}
inline Vec2 boxLo(Vec2 a, Vec2 b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y)};
}
inline Vec2 boxHi(Vec2 a, Vec2 b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y)};
}

// Exact orientation of c with respect to the line ab: +1 left, -1 right, 0 on it.
inline int orient(Vec2 a, Vec2 b, Vec2 c) {
  return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

// Exact: do the closed segments ab and cd share a point?
bool segmentsMeet(Vec2 a, Vec2 b, Vec2 c, Vec2 d);

// Exact: do segments sa and sb, which share the end point s, overlap beyond it?
bool overlapFromShared(Vec2 s, Vec2 a, Vec2 b);

double pointSegmentDistance(Vec2 p, Vec2 a, Vec2 b);

double signedArea(const std::vector<Vec2>& polygon);

// Exact: is the closed polygon simple (no edge meets a non-adjacent edge,
// adjacent edges do not fold back, no edge has zero length)?
bool isSimplePolygon(const std::vector<Vec2>& polygon);

// Uniform grid over a rectangle: ids registered in the cells their box
// covers (points and boxes outside are clamped to the border cells). Each
// cell is a list threaded through one array of entries: no allocation per cell.
class Grid {
 public:
  Grid(Vec2 lo, Vec2 hi, double cell, std::size_t maxCells);
  void insert(int id, Vec2 lo, Vec2 hi);
  // Calls visit(id) for the ids in the cells the box covers (an id may come more than once).
  template <class Visit>
  void query(Vec2 lo, Vec2 hi, Visit&& visit) const {
    const auto [x0, y0] = cellOf(lo);
    const auto [x1, y1] = cellOf(hi);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        for (int e = head_[std::size_t(y) * std::size_t(nx_) + std::size_t(x)]; e >= 0;
             e = entries_[std::size_t(e)].next)
          visit(entries_[std::size_t(e)].id);
  }

 private:
  struct Entry {
    int id, next;
  };
  std::pair<int, int> cellOf(Vec2 p) const {
    const double fx = (p.x - lo_.x) * inverse_, fy = (p.y - lo_.y) * inverse_;
    const int x = std::isfinite(fx) ? int(std::min(std::max(fx, 0.0), double(nx_ - 1))) : 0;
    const int y = std::isfinite(fy) ? int(std::min(std::max(fy, 0.0), double(ny_ - 1))) : 0;
    return {x, y};
  }
  Vec2 lo_;
  double inverse_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<int> head_;  // per cell: its last entry, or -1
  std::vector<Entry> entries_;
};

// Two unit vectors u, v with (u, v, n) right-handed and orthonormal, for a unit n.
std::pair<Point3, Point3> tangentFrame(const Point3& n);

std::uint64_t edgeKey(int a, int b);  // an undirected edge, as one number

}  // namespace meshmend::holes
