// Plane geometry of a hole's domain (where its patch is triangulated):
// points, exact orientation and segment tests, a bucket grid, and the
// simple-polygon test that decides whether a projection of the border can
// be triangulated.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "common/base/mesh.h"
#include "common/exact/predicates.h"

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
  // The same, taking out of the grid, as it passes them, the ids that
  // `live` says are gone for good: the cells a moving front crossed keep
  // only what is still there.
  template <class Live, class Visit>
  void queryLive(Vec2 lo, Vec2 hi, Live&& live, Visit&& visit) {
    const auto [x0, y0] = cellOf(lo);
    const auto [x1, y1] = cellOf(hi);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        for (int* link = &head_[std::size_t(y) * std::size_t(nx_) + std::size_t(x)]; *link >= 0;) {
          Entry& entry = entries_[std::size_t(*link)];
          if (!live(entry.id)) {
            *link = entry.next;
            continue;
          }
          visit(entry.id);
          link = &entry.next;
        }
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

// An undirected edge, as one number (lower vertex in the high half).
inline std::uint64_t edgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

// A set of edge keys (never 0 nor ~0: edgeKey of two vertices >= 0 is
// neither unless both are 0), open addressing with linear probing.
class EdgeSet {
 public:
  explicit EdgeSet(std::size_t expected = 16) {
    std::size_t size = 16;
    while (size < 2 * expected) size *= 2;
    slots_.assign(size, kEmpty);
  }
  bool contains(std::uint64_t key) const {
    for (std::size_t i = slot(key);; i = (i + 1) & (slots_.size() - 1)) {
      if (slots_[i] == key) return true;
      if (slots_[i] == kEmpty) return false;
    }
  }
  void insert(std::uint64_t key) {
    if (2 * (count_ + 1) > slots_.size()) grow();
    std::size_t i = slot(key);
    while (slots_[i] != kEmpty && slots_[i] != key) i = (i + 1) & (slots_.size() - 1);
    if (slots_[i] == kEmpty) slots_[i] = key, ++count_;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
  std::size_t slot(std::uint64_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ull) >> 20) & (slots_.size() - 1);
  }
  void grow() {
    std::vector<std::uint64_t> old(2 * slots_.size(), kEmpty);
    old.swap(slots_);
    count_ = 0;
    for (std::uint64_t key : old)
      if (key != kEmpty) insert(key);
  }
  std::vector<std::uint64_t> slots_;
  std::size_t count_ = 0;
};

}  // namespace meshmend::holes
