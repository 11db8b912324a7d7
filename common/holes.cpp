#include "common/holes.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <numeric>
#include <optional>
#include <queue>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include "common/box_tree.h"
#include "common/errors.h"
#include "common/intersections.h"
#include "common/parallel.h"
#include "common/predicates.h"
#include "common/triangle_intersection.h"

namespace meshmend {

const char* toString(HoleFairing fairing) {
  switch (fairing) {
    case HoleFairing::Flat:
      return "flat";
    case HoleFairing::Harmonic:
      return "harmonic";
    case HoleFairing::Biharmonic:
      return "biharmonic";
    case HoleFairing::LaplacianRegression:
      return "laplacian_regression";
  }
  return "unknown";
}

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

std::uint64_t edgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

std::uint64_t directedKey(int from, int to) {
  return (std::uint64_t(std::uint32_t(from)) << 32) | std::uint32_t(to);
}

bool hasCorner(const Triangle& t, int v) {
  return t[0] == v || t[1] == v || t[2] == v;
}

// ---- Faces around vertices ------------------------------------------------------

// Faces around each vertex: a compressed table of the input faces plus the
// faces added or given a new corner since. Entries are checked on use: a
// split face loses a corner, so its entry at that corner goes stale.
class VertexFaces {
 public:
  // `cornerCounts`: per vertex, the faces that have it as a corner (as
  // often as they have it), then a 0; counted while the faces are copied,
  // so that the faces are read once for both.
  VertexFaces(const std::vector<Triangle>& triangles, std::vector<int> cornerCounts)
      : triangles_(triangles), tableVertices_(cornerCounts.size() - 1) {
    // Summed into each vertex's end, then filled from the last face
    // backwards: each end steps down to its start (and the last slot keeps
    // the total).
    start_ = std::move(cornerCounts);
    int* end = start_.data();
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    faces_.reset(new int[std::size_t(start_.back())]);
    corners_.reset(new std::uint8_t[std::size_t(start_.back())]);
    // All through locals: the byte stores could alias anything in memory.
    int* faces = faces_.get();
    std::uint8_t* corners = corners_.get();
    const Triangle* triangle = triangles.data();
    for (int f = int(triangles.size()) - 1; f >= 0; --f) {
      const Triangle& t = triangle[f];
      // A corner repeated in a degenerate face is its first one each time.
      int at = --end[t[2]];
      faces[at] = f;
      corners[at] = t[2] == t[0] ? 0 : t[2] == t[1] ? 1 : 2;
      at = --end[t[1]];
      faces[at] = f;
      corners[at] = t[1] == t[0] ? 0 : 1;
      at = --end[t[0]];
      faces[at] = f;
      corners[at] = 0;
    }
  }

  // The faces of the table at v as built (before any add or change), and
  // v's corner in each (its first, should a degenerate face repeat it).
  struct Fan {
    const int* faces;
    const std::uint8_t* corners;
    std::size_t count;
  };
  Fan initial(int v) const {
    return {faces_.get() + start_[v], corners_.get() + start_[v],
            std::size_t(start_[v + 1] - start_[v])};
  }

  // Face f is new, or has v as a new corner.
  void add(int v, int f) { extra_[v].push_back(f); }

  // Forgets what was added for vertices and faces beyond these counts (an
  // undone hole).
  void truncate(std::size_t vertexCount, std::size_t faceCount) {
    for (auto it = extra_.begin(); it != extra_.end();) {
      if (std::size_t(it->first) >= vertexCount) {
        it = extra_.erase(it);
        continue;
      }
      auto& list = it->second;
      list.erase(std::remove_if(list.begin(), list.end(),
                                [&](int f) { return std::size_t(f) >= faceCount; }),
                 list.end());
      ++it;
    }
  }

  template <class Visit>
  void forEach(int v, Visit&& visit) const {
    const auto current = [&](int f) {
      return std::size_t(f) < triangles_.size() && hasCorner(triangles_[f], v);
    };
    if (std::size_t(v) < tableVertices_)
      for (int i = start_[v]; i < start_[v + 1]; ++i)
        if (current(faces_[i])) visit(faces_[i]);
    const auto it = extra_.find(v);
    if (it != extra_.end())
      for (int f : it->second)
        if (current(f)) visit(f);
  }

 private:
  const std::vector<Triangle>& triangles_;
  std::size_t tableVertices_;
  std::vector<int> start_;
  std::unique_ptr<int[]> faces_;  // not value-initialised: every entry is written
  std::unique_ptr<std::uint8_t[]> corners_;
  std::unordered_map<int, std::vector<int>> extra_;
};

// ---- Border loops ------------------------------------------------------------------

struct BorderLoop {
  std::vector<int> vertices;  // mesh direction: a face runs vertices[i] -> vertices[i+1]
  std::vector<int> faces;     // faces[i]: the face of border edge vertices[i] -> vertices[i+1]
  bool closed = true;
  int brokenAt = -1;  // open loops: a vertex where the border cannot be followed
};

struct BorderEdge {
  int from, to, face;
};

struct BorderLoops {
  std::vector<BorderLoop> loops;
  std::unordered_set<int> pinched;  // boundary vertices with more than one border through them
};

Point3 faceNormal(const std::vector<Point3>& P, const Triangle& t) {
  return (P[t[1]] - P[t[0]]) ^ (P[t[2]] - P[t[0]]);
}

// Two unit vectors u, v with (u, v, n) right-handed and orthonormal, for a unit n.
std::pair<Point3, Point3> tangentFrame(const Point3& n) {
  Point3 u = std::abs(n[0]) < 0.9 ? Point3(1, 0, 0) ^ n : Point3(0, 1, 0) ^ n;
  u.Normalize();
  return {u, n ^ u};
}

// At a boundary vertex with several fans of faces (a bow-tie), decides which
// outgoing border edge follows each incoming one: the border leaving a fan
// continues along the next fan counter-clockwise around the vertex (the gap
// between them is the hole). Returns false when a fan is not a plain open
// fan (a non-manifold edge or inconsistent orientation around the vertex).
bool pairAtPinch(int v, const std::vector<Point3>& P, const std::vector<Triangle>& T,
                 const VertexFaces& adjacency, const std::vector<int>& ins,
                 const std::vector<int>& outs, const std::vector<BorderEdge>& edges,
                 std::unordered_map<int, int>& next) {
  std::vector<int> faces;
  adjacency.forEach(v, [&](int f) { faces.push_back(f); });
  // Faces sharing an edge through v that exactly two faces use are in one fan.
  std::vector<int> parent(faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> root = [&](int i) {
    return parent[i] == i ? i : parent[i] = root(parent[i]);
  };
  std::unordered_map<int, std::vector<int>> byNeighbour;
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (int c : T[faces[i]])
      if (c != v) byNeighbour[c].push_back(int(i));
  for (const auto& [neighbour, list] : byNeighbour)
    if (list.size() == 2) parent[root(list[0])] = root(list[1]);
  auto fanOf = [&](int face) {
    for (std::size_t i = 0; i < faces.size(); ++i)
      if (faces[i] == face) return root(int(i));
    return -1;
  };
  std::unordered_map<int, int> fanIn, fanOut;  // fan -> its border edge in / out
  for (int e : ins) {
    const int fan = fanOf(edges[e].face);
    if (fan < 0 || fanIn.count(fan)) return false;
    fanIn[fan] = e;
  }
  for (int e : outs) {
    const int fan = fanOf(edges[e].face);
    if (fan < 0 || fanOut.count(fan)) return false;
    fanOut[fan] = e;
  }
  if (fanIn.size() != fanOut.size()) return false;
  for (const auto& [fan, e] : fanIn)
    if (!fanOut.count(fan)) return false;
  // Angles of the border edges around the vertex's mean normal.
  Point3 n(0, 0, 0);
  for (int f : faces) n += faceNormal(P, T[f]);
  if (n.Norm() == 0) n = Point3(0, 0, 1);
  n.Normalize();
  const auto [u, w] = tangentFrame(n);
  auto angle = [&](int other) {
    const Point3 d = P[other] - P[v];
    return std::atan2(d * w, d * u);
  };
  for (const auto& [fan, in] : fanIn) {
    const double from = angle(edges[in].from);
    int best = -1;
    double bestTurn = 1e300;
    for (const auto& [otherFan, out] : fanOut) {
      if (otherFan == fan && fanOut.size() > 1) continue;
      double turn = angle(edges[out].to) - from;
      while (turn <= 0) turn += 2 * M_PI;
      if (turn < bestTurn) bestTurn = turn, best = out;
    }
    next[in] = best;
  }
  return true;
}

// A closed walk that passes a vertex twice is cut there into simple loops.
std::vector<BorderLoop> simpleLoops(const BorderLoop& walk) {
  std::vector<BorderLoop> out;
  BorderLoop stack;
  std::unordered_map<int, std::size_t> at;
  for (std::size_t i = 0; i < walk.vertices.size(); ++i) {
    const int v = walk.vertices[i];
    const auto it = at.find(v);
    if (it != at.end()) {
      const std::size_t k = it->second;
      BorderLoop part;
      part.vertices.assign(stack.vertices.begin() + std::ptrdiff_t(k), stack.vertices.end());
      part.faces.assign(stack.faces.begin() + std::ptrdiff_t(k), stack.faces.end());
      out.push_back(std::move(part));
      for (std::size_t j = k + 1; j < stack.vertices.size(); ++j) at.erase(stack.vertices[j]);
      stack.vertices.resize(k + 1);
      stack.faces.resize(k + 1);
      stack.faces[k] = walk.faces[i];  // the walk goes on from v along this edge
      continue;
    }
    at[v] = stack.vertices.size();
    stack.vertices.push_back(v);
    stack.faces.push_back(walk.faces[i]);
  }
  out.push_back(std::move(stack));
  return out;
}

BorderLoops findBorderLoops(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                            const VertexFaces& adjacency) {
  BorderLoops result;
  // An edge used by one face only: at its start vertex v, its end is the
  // next corner of that face and no other face at v has it as a corner.
  // Per vertex, over its own faces (a fan of a few): linear in the mesh,
  // no sorting, in parallel.
  std::vector<std::vector<BorderEdge>> found(workerCount());
  parallelChunks(P.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
    std::vector<int> after, before;  // the corners after / before v in each face
    for (std::size_t v = begin; v < end; ++v) {
      const int me = int(v);
      const VertexFaces::Fan fan = adjacency.initial(me);
      const std::size_t count = fan.count;
      if (after.size() < count) {
        after.resize(count);
        before.resize(count);
      }
      static constexpr int kNext[3] = {1, 2, 0}, kPrevious[3] = {2, 0, 1};
      for (std::size_t i = 0; i < count; ++i) {
        const Triangle& t = T[std::size_t(fan.faces[i])];
        after[i] = t[kNext[fan.corners[i]]];
        before[i] = t[kPrevious[fan.corners[i]]];
      }
      for (std::size_t i = 0; i < count; ++i) {
        const int b = after[i];
        // Inside a consistently oriented surface the twin face has b before v.
        std::size_t j = 0;
        while (j < count && before[j] != b) ++j;
        if (j < count) continue;
        bool once = true;
        for (j = 0; once && j < count; ++j) once = j == i || after[j] != b;
        if (once) found[worker].push_back({me, b, fan.faces[i]});
      }
    }
  });
  std::vector<BorderEdge> edges;
  for (const auto& part : found) edges.insert(edges.end(), part.begin(), part.end());
  if (edges.empty()) return result;
  std::unordered_map<int, std::vector<int>> outOf, inTo;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    outOf[edges[e].from].push_back(int(e));
    inTo[edges[e].to].push_back(int(e));
  }
  // The border edge that follows each border edge (-1: none can be chosen).
  std::unordered_map<int, int> pinchNext;
  std::unordered_set<int> broken;
  for (const auto& [v, outs] : outOf) {
    const auto in = inTo.find(v);
    const std::size_t ins = in == inTo.end() ? 0 : in->second.size();
    if (outs.size() == 1 && ins == 1) continue;
    if (outs.size() == ins && pairAtPinch(v, P, T, adjacency, in->second, outs, edges, pinchNext)) {
      result.pinched.insert(v);
      continue;
    }
    broken.insert(v);
  }
  for (const auto& [v, ins] : inTo)
    if (!outOf.count(v)) broken.insert(v);
  std::vector<int> next(edges.size(), -1), previous(edges.size(), -1);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const int to = edges[e].to;
    if (broken.count(to)) continue;
    if (result.pinched.count(to)) {
      const auto it = pinchNext.find(int(e));
      next[e] = it == pinchNext.end() ? -1 : it->second;
    } else {
      next[e] = outOf[to][0];
    }
    if (next[e] >= 0) previous[next[e]] = int(e);
  }
  // Open borders first from their start, so that each is followed whole.
  std::vector<int> starts;
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (previous[e] < 0) starts.push_back(int(e));
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (previous[e] >= 0) starts.push_back(int(e));
  std::vector<char> visited(edges.size(), 0);
  for (int start : starts) {
    if (visited[start]) continue;
    BorderLoop loop;
    int e = start;
    while (true) {
      visited[e] = 1;
      loop.vertices.push_back(edges[e].from);
      loop.faces.push_back(edges[e].face);
      const int n = next[e];
      if (n == start) break;
      if (n < 0 || visited[n]) {
        loop.closed = false;
        loop.vertices.push_back(edges[e].to);
        loop.brokenAt = edges[e].to;
        break;
      }
      e = n;
    }
    if (!loop.closed) {
      result.loops.push_back(std::move(loop));
      continue;
    }
    for (BorderLoop& part : simpleLoops(loop)) result.loops.push_back(std::move(part));
  }
  return result;
}

double loopDiameter(const std::vector<Point3>& P, const std::vector<int>& loop) {
  double best = 0;
  if (loop.size() <= 512) {
    for (std::size_t i = 0; i < loop.size(); ++i)
      for (std::size_t j = i + 1; j < loop.size(); ++j)
        best = std::max(best, (P[loop[i]] - P[loop[j]]).SquaredNorm());
    return std::sqrt(best);
  }
  // Large loops: repeated farthest-point sweeps (a lower bound, within a
  // few percent for the round and long shapes of holes).
  int from = loop[0];
  for (int sweep = 0; sweep < 4; ++sweep) {
    int far = from;
    for (int v : loop) {
      const double d = (P[v] - P[from]).SquaredNorm();
      if (d > best) best = d, far = v;
    }
    from = far;
  }
  return std::sqrt(best);
}

// ---- 2-D geometry of the patch domain ------------------------------------------

struct Vec2 {
  double x = 0, y = 0;
};
Vec2 operator+(Vec2 a, Vec2 b) {
  return {a.x + b.x, a.y + b.y};
}
Vec2 operator-(Vec2 a, Vec2 b) {
  return {a.x - b.x, a.y - b.y};
}
Vec2 operator*(double s, Vec2 a) {
  return {s * a.x, s * a.y};
}
double dot(Vec2 a, Vec2 b) {
  return a.x * b.x + a.y * b.y;
}
double cross(Vec2 a, Vec2 b) {
  return a.x * b.y - a.y * b.x;
}
double norm(Vec2 a) {
  return std::sqrt(dot(a, a));
}
Vec2 rotated(Vec2 a, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * a.x - s * a.y, s * a.x + c * a.y};
}

int orient(Vec2 a, Vec2 b, Vec2 c) {
  return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

// Exact: is r inside the bounding box of p and q (r collinear with them)?
bool withinBox(Vec2 p, Vec2 q, Vec2 r) {
  return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
         r.y <= std::max(p.y, q.y);
}

// Exact: do the closed segments ab and cd share a point?
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

// Exact: do segments sa and sb, which share the end point s, overlap beyond it?
bool overlapFromShared(Vec2 s, Vec2 a, Vec2 b) {
  return orient(s, a, b) == 0 && dot(a - s, b - s) > 0;
}

double pointSegmentDistance(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 ab = b - a;
  const double len2 = dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * ab));
}

// Uniform grid over a rectangle: ids registered in the cells their box
// covers (points and boxes outside are clamped to the border cells). Each
// cell is a list threaded through one array of entries: no allocation per cell.
class Grid {
 public:
  Grid(Vec2 lo, Vec2 hi, double cell, std::size_t maxCells) : lo_(lo) {
    const double w = std::max(hi.x - lo.x, 1e-300), h = std::max(hi.y - lo.y, 1e-300);
    cell = std::max(cell, std::sqrt(w * h / double(std::max<std::size_t>(maxCells, 1))));
    inverse_ = 1 / cell;
    nx_ = std::max(1, std::min(4096, int(w * inverse_) + 1));
    ny_ = std::max(1, std::min(4096, int(h * inverse_) + 1));
    head_.assign(std::size_t(nx_) * std::size_t(ny_), -1);
    entries_.reserve(2 * head_.size());
  }
  void insert(int id, Vec2 lo, Vec2 hi) {
    const auto [x0, y0] = cellOf(lo);
    const auto [x1, y1] = cellOf(hi);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        int& head = head_[std::size_t(y) * nx_ + x];
        entries_.push_back({id, head});
        head = int(entries_.size() - 1);
      }
  }
  // Calls visit(id) for the ids in the cells the box covers (an id may come more than once).
  template <class Visit>
  void query(Vec2 lo, Vec2 hi, Visit&& visit) const {
    const auto [x0, y0] = cellOf(lo);
    const auto [x1, y1] = cellOf(hi);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        for (int e = head_[std::size_t(y) * nx_ + x]; e >= 0; e = entries_[std::size_t(e)].next)
          visit(entries_[std::size_t(e)].id);
  }

 private:
  struct Entry {
    int id, next;
  };
  std::pair<int, int> cellOf(Vec2 p) const {
    const double fx = (p.x - lo_.x) * inverse_, fy = (p.y - lo_.y) * inverse_;
    const int x = std::isfinite(fx) ? int(std::clamp(fx, 0.0, double(nx_ - 1))) : 0;
    const int y = std::isfinite(fy) ? int(std::clamp(fy, 0.0, double(ny_ - 1))) : 0;
    return {x, y};
  }
  Vec2 lo_;
  double inverse_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<int> head_;  // per cell: its last entry, or -1
  std::vector<Entry> entries_;
};

Vec2 boxLo(Vec2 a, Vec2 b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y)};
}
Vec2 boxHi(Vec2 a, Vec2 b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y)};
}

// Exact: is the closed polygon simple (no edge meets a non-adjacent edge,
// adjacent edges do not fold back, no edge has zero length)?
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
      const Vec2 c = poly[j], d = poly[(j + 1) % n];
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

double signedArea(const std::vector<Vec2>& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) a += cross(poly[i], poly[(i + 1) % poly.size()]);
  return a / 2;
}

// ---- Advancing front (§3.2) ----------------------------------------------------------

// Triangulates a simple counter-clockwise polygon of the plane with an
// advancing front: the front vertex with the smallest interior angle is
// treated first; below 75 degrees its two neighbours are joined, below 135
// one new vertex is put on its bisector, above that two (the three rules of
// §3.2); a new vertex closer than the merge distance to a front vertex is
// replaced by it, which splits the front in two. New triangles are added one
// at a time, each only after exact tests that it lies in the part still
// uncovered (orientation, no front edge crossing a new edge, no front vertex
// inside), so the front stays a set of simple polygons whatever happens;
// when no rule applies any more, the rest is cut into ears.
class AdvancingFront {
 public:
  struct Settings {
    double growth = 1.1;     // target size growth per front layer
    double maxSize = 1e300;  // cap on the target size
    double merge = 0.6;      // merge distance, relative to the target size
  };

  std::vector<Vec2> uv;                    // boundary vertices first, then new ones
  std::vector<double> size;                // target edge length at each vertex
  std::vector<std::array<int, 2>> parent;  // new vertices: the front edge they were built on
  std::vector<Triangle> triangles;         // counter-clockwise in the plane

  AdvancingFront(std::vector<Vec2> boundary, std::vector<double> boundarySize,
                 const std::vector<std::pair<int, int>>& existingEdges, Settings settings)
      : uv(std::move(boundary)), size(std::move(boundarySize)), settings_(settings) {
    const std::size_t n = uv.size();
    Vec2 lo = uv[0], hi = uv[0];
    double mean = 0;
    for (std::size_t i = 0; i < n; ++i) {
      lo = boxLo(lo, uv[i]);
      hi = boxHi(hi, uv[i]);
      mean += size[i];
    }
    mean /= double(n);
    minSize_ = std::max(*std::min_element(size.begin(), size.end()), 1e-3 * mean);
    const double area = std::abs(signedArea(uv));
    // Cells between the boundary edges' size and the largest triangles'
    // (geometric mean): few elements per cell near the border, few cells per
    // element inside.
    const double cell = std::sqrt(mean * std::min(settings.maxSize, 16 * mean));
    const std::size_t expected = std::size_t(area / (0.43 * cell * cell)) + n;
    points_ = std::make_unique<Grid>(lo, hi, cell, 2 * expected + 16);
    edgeGrid_ = std::make_unique<Grid>(lo, hi, cell, 2 * expected + 16);
    budget_ = 8 * (std::size_t(area / (0.43 * minSize_ * minSize_)) + 4 * n) + 1000;
    for (const auto& [a, b] : existingEdges) edges_.insert(edgeKey(a, b));
    for (std::size_t i = 0; i < n; ++i)
      nodes_.push_back({int(i), int((i + n - 1) % n), int((i + 1) % n)});
    alive_ = n;
    for (std::size_t i = 0; i < n; ++i) {
      points_->insert(int(i), uv[i], uv[i]);
      recordEdge(int(i));
    }
    for (std::size_t i = 0; i < n; ++i) push(int(i));
  }

  // Covers the polygon; false when it could not (no valid triangle left).
  bool run() {
    std::size_t failuresInARow = 0;
    while (!heap_.empty() && alive_ > 0) {
      const Entry top = heap_.top();
      heap_.pop();
      const Node& node = nodes_[top.node];
      if (!node.alive || node.stamp != top.stamp) continue;
      if (triangles.size() > budget_) break;
      if (advanceAt(top.node)) {
        failuresInARow = 0;
        continue;
      }
      // Try the others first; give up on the rules once every node failed.
      if (++failuresInARow > 2 * alive_ + 8) break;
      Node& failed = nodes_[top.node];
      ++failed.failures;
      heap_.push({angleAt(top.node) + 2 * M_PI * failed.failures, top.node, failed.stamp});
    }
    return clipEars();
  }

 private:
  struct Node {
    int vertex, prev, next;
    unsigned stamp = 0;
    bool alive = true;
    int failures = 0;
  };
  struct Entry {
    double key;
    int node;
    unsigned stamp;
    bool operator>(const Entry& o) const { return key > o.key; }
  };
  struct EdgeRecord {
    int node, from, to;
  };

  double angleAt(int n) const {
    const Node& node = nodes_[n];
    const Vec2 v = uv[node.vertex];
    const Vec2 toNext = uv[nodes_[node.next].vertex] - v, toPrev = uv[nodes_[node.prev].vertex] - v;
    double a = std::atan2(cross(toNext, toPrev), dot(toNext, toPrev));
    if (a < 0) a += 2 * M_PI;
    return a;
  }

  void push(int n) {
    Node& node = nodes_[n];
    ++node.stamp;
    node.failures = 0;
    heap_.push({angleAt(n), n, node.stamp});
  }

  void recordEdge(int n) {
    const Node& node = nodes_[n];
    const int from = node.vertex, to = nodes_[node.next].vertex;
    edgeRecords_.push_back({n, from, to});
    edgeGrid_->insert(int(edgeRecords_.size() - 1), boxLo(uv[from], uv[to]),
                      boxHi(uv[from], uv[to]));
  }

  bool liveEdge(const EdgeRecord& r) const {
    const Node& node = nodes_[r.node];
    return node.alive && node.vertex == r.from && nodes_[node.next].vertex == r.to;
  }

  void kill(int n) {
    if (!nodes_[n].alive) return;
    nodes_[n].alive = false;
    --alive_;
  }

  int newNode(int vertex) {
    nodes_.push_back({vertex, -1, -1});
    ++alive_;
    points_->insert(int(nodes_.size() - 1), uv[vertex], uv[vertex]);
    return int(nodes_.size() - 1);
  }

  // Exact: does the new edge ab (a, b vertices) stay clear of the front?
  bool edgeIsClear(int a, int b) const {
    const Vec2 pa = uv[a], pb = uv[b];
    bool clear = true;
    edgeGrid_->query(boxLo(pa, pb), boxHi(pa, pb), [&](int id) {
      if (!clear) return;
      const EdgeRecord& r = edgeRecords_[id];
      if (!liveEdge(r)) return;
      const int c = r.from, d = r.to;
      const Vec2 pc = uv[c], pd = uv[d];
      if (c == a && d == b) return;
      if (c == b && d == a) return;
      if (c == a || c == b || d == a || d == b) {
        const int shared = (c == a || c == b) ? c : d;
        const int mine = shared == a ? b : a, theirs = shared == c ? d : c;
        clear = !overlapFromShared(uv[shared], uv[mine], uv[theirs]);
        return;
      }
      clear = !segmentsMeet(pa, pb, pc, pd);
    });
    return clear;
  }

  // Exact: is no front vertex other than a, b, c in the closed triangle abc?
  bool triangleIsEmpty(int a, int b, int c) const {
    const Vec2 pa = uv[a], pb = uv[b], pc = uv[c];
    const Vec2 lo = boxLo(boxLo(pa, pb), pc), hi = boxHi(boxHi(pa, pb), pc);
    bool empty = true;
    points_->query(lo, hi, [&](int n) {
      if (!empty || !nodes_[n].alive) return;
      const int v = nodes_[n].vertex;
      if (v == a || v == b || v == c) return;
      const Vec2 p = uv[v];
      if (orient(pa, pb, p) >= 0 && orient(pb, pc, p) >= 0 && orient(pc, pa, p) >= 0) empty = false;
    });
    return empty;
  }

  // Adds triangle (a, b, c) on the front edge a->b that starts at node na,
  // with c a front vertex at node nc or a new vertex (nc < 0); updates the
  // front. Returns the node that now carries c (-1: the triangle is not valid).
  int advance(int na, int c, int nc) {
    const int nb = nodes_[na].next;
    const int a = nodes_[na].vertex, b = nodes_[nb].vertex;
    if (c == a || c == b) return -1;
    if (orient(uv[a], uv[b], uv[c]) <= 0) return -1;
    const bool closesNext = nc >= 0 && nc == nodes_[nb].next;
    const bool closesPrev = nc >= 0 && nc == nodes_[na].prev;
    if (!closesNext && (edges_.count(edgeKey(b, c)) || !edgeIsClear(b, c))) return -1;
    if (!closesPrev && (edges_.count(edgeKey(c, a)) || !edgeIsClear(c, a))) return -1;
    if (!triangleIsEmpty(a, b, c)) return -1;

    triangles.push_back({a, b, c});
    edges_.insert(edgeKey(b, c));
    edges_.insert(edgeKey(c, a));
    std::array<int, 5> touched{-1, -1, -1, -1, -1};
    int result = nc;
    if (nc < 0) {  // a -> c -> b
      const int nw = newNode(c);
      nodes_[nw].prev = na;
      nodes_[nw].next = nb;
      nodes_[na].next = nw;
      nodes_[nb].prev = nw;
      recordEdge(na);
      recordEdge(nw);
      touched = {na, nw, nb, -1, -1};
      result = nw;
    } else if (closesNext && closesPrev) {  // the last triangle of a loop
      kill(na);
      kill(nb);
      kill(nc);
      return nc;
    } else if (closesNext) {  // a -> c
      kill(nb);
      nodes_[na].next = nc;
      nodes_[nc].prev = na;
      recordEdge(na);
      touched = {na, nc, -1, -1, -1};
    } else if (closesPrev) {  // c -> b
      kill(na);
      nodes_[nc].next = nb;
      nodes_[nb].prev = nc;
      recordEdge(nc);
      touched = {nc, nb, -1, -1, -1};
    } else {  // the front splits: a -> c' -> (after c) ...  and  c -> b -> ...
      const int copy = newNode(c);
      const int after = nodes_[nc].next;
      nodes_[copy].prev = na;
      nodes_[copy].next = after;
      nodes_[after].prev = copy;
      nodes_[na].next = copy;
      nodes_[nc].next = nb;
      nodes_[nb].prev = nc;
      recordEdge(na);
      recordEdge(copy);
      recordEdge(nc);
      touched = {na, copy, after, nc, nb};
    }
    // A loop of two edges encloses nothing: both sides are covered.
    for (int n : touched)
      if (n >= 0 && nodes_[n].alive && nodes_[nodes_[n].next].next == n) {
        kill(nodes_[n].next);
        kill(n);
      }
    for (int n : touched)
      if (n >= 0 && nodes_[n].alive) push(n);
    return result;
  }

  int addVertex(Vec2 p, double s, int from, int to) {
    uv.push_back(p);
    size.push_back(s);
    parent.push_back({from, to});
    return int(uv.size() - 1);
  }
  void dropVertex() {
    uv.pop_back();
    size.pop_back();
    parent.pop_back();
  }

  // Front nodes (not at the excluded vertices) within `radius` of p, nearest first.
  std::vector<int> nodesNear(Vec2 p, double radius, std::initializer_list<int> exclude) const {
    std::vector<std::pair<double, int>> found;
    points_->query(p - Vec2{radius, radius}, p + Vec2{radius, radius}, [&](int n) {
      if (!nodes_[n].alive) return;
      const int v = nodes_[n].vertex;
      for (int x : exclude)
        if (v == x) return;
      const double d = norm(uv[v] - p);
      if (d < radius) found.push_back({d, n});
    });
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    std::vector<int> out;
    for (const auto& f : found) out.push_back(f.second);
    return out;
  }

  // Would a new vertex at p make thin triangles with a front edge close by
  // (one not at p's own neighbours)? Quality only, not validity.
  bool crowded(Vec2 p, double s, int pv, int iv, int qv) const {
    const double limit = 0.35 * s;
    bool near = false;
    edgeGrid_->query(p - Vec2{limit, limit}, p + Vec2{limit, limit}, [&](int id) {
      if (near) return;
      const EdgeRecord& r = edgeRecords_[id];
      if (!liveEdge(r)) return;
      for (int x : {pv, iv, qv})
        if (r.from == x || r.to == x) return;
      near = pointSegmentDistance(p, uv[r.from], uv[r.to]) < limit;
    });
    return near;
  }

  // Triangle (p, i, v) then (i, q, v) with v a front vertex at node nv (rule 2, merged).
  bool joinTo(int np, int ni, int nv) {
    const int at = advance(np, nodes_[nv].vertex, nv);
    if (at < 0) return false;
    if (nodes_[ni].alive && nodes_[ni].prev == nv) advance(ni, nodes_[nv].vertex, nv);
    return true;
  }

  bool advanceAt(int ni) {
    const int np = nodes_[ni].prev, nq = nodes_[ni].next;
    const int i = nodes_[ni].vertex, p = nodes_[np].vertex, q = nodes_[nq].vertex;
    const double angle = angleAt(ni);
    const Vec2 pi = uv[i];
    const double target =
        std::min(settings_.maxSize, settings_.growth * (size[p] + size[i] + size[q]) / 3);
    auto close = [&] { return angle < M_PI && advance(np, q, nq) >= 0; };
    const double deg = 180 / M_PI;
    if (angle * deg < 75 && close()) return true;

    const Vec2 along = uv[q] - pi;
    const double alongLength = norm(along);
    if (alongLength == 0) return false;
    const Vec2 unit = (1 / alongLength) * along;

    if (angle * deg >= 135) {  // rule 3: two new vertices
      const Vec2 w1 = pi + target * rotated(unit, angle / 3);
      const Vec2 w2 = pi + target * rotated(unit, 2 * angle / 3);
      const double r = settings_.merge * target;
      if (nodesNear(w1, r, {i}).empty() && nodesNear(w2, r, {i}).empty() &&
          !crowded(w1, target, p, i, q) && !crowded(w2, target, p, i, q)) {
        const int v1 = addVertex(w1, target, i, q);
        const int n1 = advance(ni, v1, -1);
        if (n1 >= 0) {
          const int v2 = addVertex(w2, target, p, i);
          const int n2 = advance(np, v2, -1);
          if (n2 < 0) {
            dropVertex();
          } else if (nodes_[ni].alive && nodes_[n2].next == ni && nodes_[ni].next == n1) {
            advance(n2, v1, n1);
          }
          return true;
        }
        dropVertex();
      }
    }

    // Rule 2: one vertex on the bisector, or the front vertex close to it.
    const Vec2 w = pi + target * rotated(unit, angle / 2);
    for (double radius : {settings_.merge * target, 0.0}) {
      if (radius > 0) {
        const std::vector<int> near = nodesNear(w, radius, {i});
        if (!near.empty() && (nodes_[near[0]].vertex == p || nodes_[near[0]].vertex == q)) {
          if (close()) return true;
        }
        for (int nv : near) {
          const int v = nodes_[nv].vertex;
          if (v == p || v == q) continue;
          if (joinTo(np, ni, nv)) return true;
        }
        continue;
      }
      if (!crowded(w, target, p, i, q)) {
        const int v = addVertex(w, target, p, i);
        const int nw = advance(np, v, -1);
        if (nw >= 0) {
          if (nodes_[ni].alive && nodes_[ni].prev == nw) advance(ni, v, nw);
          return true;
        }
        dropVertex();
      }
    }
    // A wider search for a vertex to join, then closing.
    for (int nv : nodesNear(w, 1.5 * target, {i, p, q}))
      if (joinTo(np, ni, nv)) return true;
    return close();
  }

  // Cuts what is left of the front into ears (any valid triangle of two
  // consecutive front edges).
  bool clipEars() {
    bool progress = true;
    while (alive_ > 0 && progress) {
      progress = false;
      std::vector<std::pair<double, int>> order;
      for (std::size_t n = 0; n < nodes_.size(); ++n)
        if (nodes_[n].alive) order.push_back({angleAt(int(n)), int(n)});
      std::sort(order.begin(), order.end());
      for (const auto& [angle, n] : order) {
        if (!nodes_[n].alive || angle >= M_PI) continue;
        const int np = nodes_[n].prev, nq = nodes_[n].next;
        if (advance(np, nodes_[nq].vertex, nq) >= 0) progress = true;
      }
    }
    return alive_ == 0;
  }

  Settings settings_;
  std::size_t alive_ = 0, budget_ = 0;
  double minSize_ = 0;
  std::vector<Node> nodes_;
  std::vector<EdgeRecord> edgeRecords_;
  std::unordered_set<std::uint64_t> edges_;
  std::unique_ptr<Grid> points_, edgeGrid_;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap_;
};

// The triangles around each vertex of a patch, in one array (ascending).
class TrianglesAround {
 public:
  struct Range {
    const int *first, *last;
    const int* begin() const { return first; }
    const int* end() const { return last; }
  };
  TrianglesAround() = default;
  TrianglesAround(const std::vector<Triangle>& triangles, std::size_t vertexCount) {
    start_.assign(vertexCount + 1, 0);
    for (const Triangle& t : triangles)
      for (int v : t) ++start_[std::size_t(v) + 1];
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    triangles_.resize(std::size_t(start_.back()));
    std::vector<int> next(start_.begin(), start_.end() - 1);
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (int v : triangles[t]) triangles_[std::size_t(next[std::size_t(v)]++)] = int(t);
  }
  Range operator[](std::size_t v) const {
    return {triangles_.data() + start_[v], triangles_.data() + start_[v + 1]};
  }
  void swap(TrianglesAround& other) {
    start_.swap(other.start_);
    triangles_.swap(other.triangles_);
  }

 private:
  std::vector<int> start_, triangles_;
};

// Moves each new vertex towards the centroid of its neighbours (a few rounds)
// where no triangle around it turns over (exact): rounder triangles for the
// fairing's cotangent weights. `height` moves along.
void relaxInterior(std::vector<Vec2>& uv, std::vector<double>& height, std::size_t fixed,
                   const std::vector<Triangle>& triangles, int rounds) {
  const std::size_t n = uv.size();
  if (n == fixed) return;
  const TrianglesAround around(triangles, n);
  for (int round = 0; round < rounds; ++round)
    for (std::size_t v = fixed; v < n; ++v) {
      Vec2 centroid;
      double h = 0;
      int count = 0;
      for (int t : around[v])
        for (int c : triangles[t])
          if (std::size_t(c) != v) {
            centroid = centroid + uv[c];
            h += height[c];
            ++count;
          }
      if (count == 0) continue;
      const Vec2 old = uv[v];
      uv[v] = (1.0 / count) * centroid;
      bool valid = true;
      for (int t : around[v]) {
        const Triangle& tri = triangles[t];
        if (orient(uv[tri[0]], uv[tri[1]], uv[tri[2]]) <= 0) {
          valid = false;
          break;
        }
      }
      if (valid)
        height[v] = h / count;
      else
        uv[v] = old;
    }
}

// ---- Where the patch lies: the hole's plane, or a disk ---------------------------

struct Domain {
  std::vector<Vec2> uv;  // boundary vertices, front order
  bool planar = true;    // over a plane: a patch point is origin + u U + v V + h N
  Point3 origin, U, V, N;
  std::vector<double> height;  // boundary heights over the plane
};

bool projectOnPlane(const std::vector<Point3>& pts, Point3 origin, Point3 normal, Domain& d) {
  normal.Normalize();
  auto [u, v] = tangentFrame(normal);
  d.uv.clear();
  d.height.clear();
  for (const Point3& p : pts) {
    const Point3 r = p - origin;
    d.uv.push_back({r * u, r * v});
    d.height.push_back(r * normal);
  }
  if (signedArea(d.uv) < 0) {  // the front must run counter-clockwise
    v = -v;
    normal = -normal;
    for (Vec2& q : d.uv) q.y = -q.y;
    for (double& h : d.height) h = -h;
  }
  if (!isSimplePolygon(d.uv)) return false;
  d.planar = true;
  d.origin = origin;
  d.U = u;
  d.V = v;
  d.N = normal;
  return true;
}

// A circle with the boundary vertices spaced by arc length: a domain for
// any loop, where no plane gives a simple projection.
Domain diskDomain(const std::vector<Point3>& pts) {
  Domain d;
  d.planar = false;
  double perimeter = 0;
  std::vector<double> at;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    at.push_back(perimeter);
    perimeter += (pts[(i + 1) % pts.size()] - pts[i]).Norm();
  }
  const double radius = perimeter / (2 * M_PI);
  for (double s : at) {
    const double phi = 2 * M_PI * s / perimeter;
    d.uv.push_back({radius * std::cos(phi), radius * std::sin(phi)});
  }
  return d;
}

// The front's domains, in the order tried: the first plane the boundary
// projects onto as a simple polygon (its best-fit plane, the plane of the
// faces' mean normal, of its vector area, or one tilted around those), then
// the disk. A patch that does not fit over the plane gets a second chance
// over the disk.
std::vector<Domain> domainsOf(const std::vector<Point3>& pts, const Point3& meanFaceNormal) {
  Domain d;
  Point3 centroid(0, 0, 0);
  for (const Point3& p : pts) centroid += p;
  centroid /= double(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Point3& p : pts) {
    const Eigen::Vector3d r(p[0] - centroid[0], p[1] - centroid[1], p[2] - centroid[2]);
    cov += r * r.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov);
  const Eigen::Vector3d e = eigen.eigenvectors().col(0);
  const Point3 fitted(e[0], e[1], e[2]);
  if (projectOnPlane(pts, centroid, fitted, d)) return {d, diskDomain(pts)};
  if (meanFaceNormal.Norm() > 0 && projectOnPlane(pts, centroid, meanFaceNormal, d))
    return {d, diskDomain(pts)};
  // The boundary's vector area (half the sum of p_i x p_i+1): the direction
  // in which the loop encloses the most area, often simple where the
  // best-fit plane folds the loop over itself.
  Point3 area(0, 0, 0);
  for (std::size_t i = 0; i < pts.size(); ++i)
    area += (pts[i] - centroid) ^ (pts[(i + 1) % pts.size()] - centroid);
  if (area.Norm() > 0 && projectOnPlane(pts, centroid, area, d)) return {d, diskDomain(pts)};
  // Directions tilted around those by up to 60 degrees.
  for (const Point3& axis : {area, meanFaceNormal, fitted}) {
    if (!(axis.Norm() > 0)) continue;
    const Point3 n = axis / axis.Norm();
    const auto [u, v] = tangentFrame(n);
    for (double tilt : {15.0, 30.0, 45.0, 60.0})
      for (int k = 0; k < 8; ++k) {
        const double t = tilt * M_PI / 180, a = k * M_PI / 4;
        const Point3 dir = n * std::cos(t) + (u * std::cos(a) + v * std::sin(a)) * std::sin(t);
        if (projectOnPlane(pts, centroid, dir, d)) return {d, diskDomain(pts)};
      }
  }
  return {diskDomain(pts)};
}

// ---- Cotangent Laplacian rows --------------------------------------------------

// Cotangents of the angles at a, b and c (0 for a degenerate triangle).
std::array<double, 3> cotangents(const Point3& a, const Point3& b, const Point3& c) {
  auto cot = [](const Point3& u, const Point3& v) {
    const double s = (u ^ v).Norm();
    return s > 0 ? (u * v) / s : 0.0;
  };
  return {cot(b - a, c - a), cot(c - b, a - b), cot(a - c, b - c)};
}

// The membrane (harmonic) system, and the curvature samples of the
// regression, raise edge weights below this to it:
// obtuse triangles give negative cotangent sums, which would make its
// matrix indefinite. The least-squares systems (biharmonic, regression)
// are positive semi-definite whatever the signs and keep the true weights:
// raising them would bend a flat fan whose triangles are slivers (CAD
// meshes), where the true weights give it a zero Laplacian.
constexpr double kPositiveWeightFloor = 0.05;

// One vertex's Laplacian: neighbours (keys) with cotangent weights w_ij (Eq. 2-3).
struct LaplacianRow {
  std::vector<std::pair<int, double>> weights;  // key, omega (not normalised)
  double total = 0;
  double area = 0;  // the mixed Voronoi area of the vertex (A of Eq. 4)

  void add(int key, double omega) {
    for (auto& [k, w] : weights)
      if (k == key) {
        w += omega;
        return;
      }
    weights.push_back({key, omega});
  }
  // Sums the weights, raising those below `floor` to it first.
  void finish(double floor = -INFINITY) {
    total = 0;
    for (auto& [k, w] : weights) total += (w = std::max(w, floor));
  }
};

// Cotangents at the corners of a triangle, and the part of its area each
// corner's Laplacian counts (Meyer et al.'s mixed Voronoi area: the Voronoi
// part in a non-obtuse triangle, else half the area to the obtuse corner
// and a quarter to each other one).
struct TriangleWeights {
  std::array<double, 3> cot;
  std::array<double, 3> area;
};

TriangleWeights triangleWeights(const Point3& a, const Point3& b, const Point3& c) {
  TriangleWeights w{cotangents(a, b, c), {0, 0, 0}};
  const double area = ((b - a) ^ (c - a)).Norm() / 2;
  const std::array<Point3, 3> p{a, b, c};
  for (int k = 0; k < 3; ++k)
    if (w.cot[k] < 0) {  // obtuse at k
      for (int m = 0; m < 3; ++m) w.area[m] = m == k ? area / 2 : area / 4;
      return w;
    }
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3, l = (k + 2) % 3;
    w.area[k] =
        ((p[l] - p[k]).SquaredNorm() * w.cot[j] + (p[j] - p[k]).SquaredNorm() * w.cot[l]) / 8;
  }
  return w;
}

// Adds a triangle (keys k[0..2]) to the row of its corner `corner`.
void addTriangleToRow(LaplacianRow& row, const std::array<int, 3>& k, const TriangleWeights& w,
                      int corner) {
  const int j = (corner + 1) % 3, l = (corner + 2) % 3;
  row.add(k[j], w.cot[l]);
  row.add(k[l], w.cot[j]);
  row.area += w.area[corner];
}

void addTriangleToRow(LaplacianRow& row, const std::array<int, 3>& k,
                      const std::array<Point3, 3>& p, int corner) {
  addTriangleToRow(row, k, triangleWeights(p[0], p[1], p[2]), corner);
}

// ---- LS-SVM regression (§2.2) ----------------------------------------------------

// Least-squares SVM regression (Suykens) of a scalar over 3-D points with
// Wendland's compactly supported C2 kernel (positive definite in 3-D, no
// exponentials): solves [0 1^T; 1 Omega + I/gamma] [b; a] = [0; y] (Eq. 14)
// and predicts f(x) = sum a_i K(x, x_i) + b (Eq. 15).
class LsSvm {
 public:
  bool fit(const std::vector<Eigen::Vector3d>& x, const std::vector<double>& y, double support,
           double gamma) {
    const std::size_t n = x.size();
    if (n < 4) return false;
    centres_ = x;
    targets_ = y;
    inverseSupport_ = 1 / support;
    Eigen::MatrixXd K(n, n);
    for (std::size_t i = 0; i < n; ++i) {
      K(i, i) = 1 + 1 / gamma;
      for (std::size_t j = i + 1; j < n; ++j) K(i, j) = K(j, i) = kernel((x[i] - x[j]).norm());
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(K);
    if (llt.info() != Eigen::Success) return false;
    const Eigen::VectorXd eta = llt.solve(Eigen::VectorXd::Ones(Eigen::Index(n)));
    const Eigen::VectorXd nu =
        llt.solve(Eigen::Map<const Eigen::VectorXd>(y.data(), Eigen::Index(n)));
    const double s = eta.sum();
    if (!(std::abs(s) > 0)) return false;
    bias_ = nu.sum() / s;
    alpha_ = nu - bias_ * eta;
    return alpha_.allFinite() && std::isfinite(bias_);
  }

  const std::vector<double>& targets() const { return targets_; }

  double predict(const Eigen::Vector3d& p) const {
    double f = bias_;
    for (std::size_t i = 0; i < centres_.size(); ++i) {
      const double d2 = (p - centres_[i]).squaredNorm() * inverseSupport_ * inverseSupport_;
      if (d2 < 1) f += alpha_[Eigen::Index(i)] * wendland(std::sqrt(d2));
    }
    return f;
  }

 private:
  static double wendland(double r) {
    const double s = 1 - r;
    const double s2 = s * s;
    return s2 * s2 * (4 * r + 1);
  }
  double kernel(double d) const {
    const double r = d * inverseSupport_;
    return r < 1 ? wendland(r) : 0.0;
  }
  std::vector<Eigen::Vector3d> centres_;
  std::vector<double> targets_;
  Eigen::VectorXd alpha_;
  double bias_ = 0, inverseSupport_ = 1;
};

Eigen::Vector3d toEigen(const Point3& p) {
  return {p[0], p[1], p[2]};
}

// ---- The working surface ----------------------------------------------------------

// Where a vertex added by a split lies on the input: the input face and the
// barycentric coordinates in it.
struct SplitOrigin {
  int face = -1;
  Point3 barycentric{0, 0, 0};
};

struct Surface {
  std::vector<Point3> points;
  bool roundToFloat = false;  // new vertices take float coordinates (HoleFillOptions)
  // Where a new vertex at p is stored.
  Point3 stored(const Point3& p) const { return roundToFloat ? roundedToFloat(p) : p; }
  std::vector<Triangle> triangles;
  std::size_t inputVertices = 0, inputFaces = 0;
  std::unique_ptr<VertexFaces> adjacency;
  std::unordered_map<std::uint64_t, int> borderOwner;  // directed border edge -> its face
  std::unordered_map<int, SplitOrigin> splitOrigins;   // split vertex -> where it lies
  std::vector<int> inputFaceOf;  // per face beyond the input: the input face it is part of, or -1
  std::unordered_map<int, Triangle> inputCorners;  // input faces changed by splits: their corners
  std::vector<int> patchFaces, splitFaces;         // faces added by patches / by splits
  std::unique_ptr<BoxTree>
      inputTree;           // over the input faces' boxes (built once there are many holes)
  std::size_t checks = 0;  // patches checked so far

  int inputFace(int f) const {
    return std::size_t(f) < inputFaces ? f : inputFaceOf[std::size_t(f) - inputFaces];
  }
  Triangle originalCorners(int f0) const {
    const auto it = inputCorners.find(f0);
    return it == inputCorners.end() ? triangles[f0] : it->second;
  }
  Point3 barycentricIn(int v, int f0) const {
    const Triangle t = originalCorners(f0);
    for (int k = 0; k < 3; ++k)
      if (t[k] == v) {
        Point3 b(0, 0, 0);
        b[k] = 1;
        return b;
      }
    const auto it = splitOrigins.find(v);
    if (it != splitOrigins.end() && it->second.face == f0) return it->second.barycentric;
    return Point3(1.0 / 3, 1.0 / 3, 1.0 / 3);
  }
};

// What to restore when a hole is given up.
struct Checkpoint {
  std::size_t points = 0, triangles = 0, splitFaces = 0;
  std::vector<std::pair<int, Triangle>> changedFaces;   // in change order
  std::vector<std::pair<std::uint64_t, int>> ownerLog;  // key, previous owner (-1: none)
  std::vector<int> splitVertices;
  std::vector<int> newInputCorners;  // input faces first changed since the checkpoint
};

void setOwner(Surface& s, Checkpoint& undo, std::uint64_t key, int face) {
  const auto it = s.borderOwner.find(key);
  undo.ownerLog.push_back({key, it == s.borderOwner.end() ? -1 : it->second});
  if (face < 0)
    s.borderOwner.erase(key);
  else
    s.borderOwner[key] = face;
}

void restore(Surface& s, Checkpoint& undo) {
  for (auto it = undo.changedFaces.rbegin(); it != undo.changedFaces.rend(); ++it)
    s.triangles[it->first] = it->second;
  for (auto it = undo.ownerLog.rbegin(); it != undo.ownerLog.rend(); ++it) {
    if (it->second < 0)
      s.borderOwner.erase(it->first);
    else
      s.borderOwner[it->first] = it->second;
  }
  for (int v : undo.splitVertices) s.splitOrigins.erase(v);
  for (int f : undo.newInputCorners) s.inputCorners.erase(f);
  s.points.resize(undo.points);
  s.triangles.resize(undo.triangles);
  s.inputFaceOf.resize(undo.triangles - s.inputFaces);
  s.splitFaces.resize(undo.splitFaces);
  s.adjacency->truncate(undo.points, undo.triangles);
}

// §3.1: halves the border edges longer than `factor` x the loop's mean edge
// length (the mean taken again after each pass) together with the face each
// borders, until none is. `loop` (mesh direction) gets the new vertices.
std::size_t splitLongEdges(Surface& s, std::vector<int>& loop, double factor, Checkpoint& undo) {
  if (factor <= 0) return 0;
  std::size_t splits = 0;
  for (int pass = 0; pass < 64; ++pass) {
    double total = 0;
    for (std::size_t i = 0; i < loop.size(); ++i)
      total += (s.points[loop[(i + 1) % loop.size()]] - s.points[loop[i]]).Norm();
    const double limit = factor * total / double(loop.size());
    std::vector<int> out;
    bool any = false;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      out.push_back(a);
      if (!((s.points[b] - s.points[a]).Norm() > limit)) continue;
      const auto owner = s.borderOwner.find(directedKey(a, b));
      if (owner == s.borderOwner.end()) continue;
      const int f = owner->second;
      Triangle t = s.triangles[f];
      int k = 0;
      while (k < 3 && !(t[k] == a && t[(k + 1) % 3] == b)) ++k;
      if (k == 3) continue;
      const int c = t[(k + 2) % 3];
      const int m = int(s.points.size());
      const int f0 = s.inputFace(f);
      if (std::size_t(f) < s.inputFaces && !s.inputCorners.count(f)) {
        s.inputCorners[f] = t;
        undo.newInputCorners.push_back(f);
      }
      s.points.push_back(s.stored((s.points[a] + s.points[b]) / 2));
      s.splitOrigins[m] = {f0, (s.barycentricIn(a, f0) + s.barycentricIn(b, f0)) / 2};
      undo.splitVertices.push_back(m);
      undo.changedFaces.push_back({f, t});
      t[(k + 1) % 3] = m;  // f = (a, m, c)
      s.triangles[f] = t;
      const int g = int(s.triangles.size());
      s.triangles.push_back({m, b, c});
      s.inputFaceOf.push_back(f0);
      s.splitFaces.push_back(g);
      s.adjacency->add(m, f);
      for (int v : {m, b, c}) s.adjacency->add(v, g);
      setOwner(s, undo, directedKey(a, b), -1);
      setOwner(s, undo, directedKey(a, m), f);
      setOwner(s, undo, directedKey(m, b), g);
      const auto bc = s.borderOwner.find(directedKey(b, c));
      if (bc != s.borderOwner.end() && bc->second == f) setOwner(s, undo, directedKey(b, c), g);
      out.push_back(m);
      any = true;
      ++splits;
    }
    loop = std::move(out);
    if (!any) break;
  }
  return splits;
}

// ---- Exact check of a patch ----------------------------------------------------------

// Counts the pairs of faces that intersect (the self-intersection rule,
// vertex identity = index; facesIntersect of intersections.h) that involve
// the patch or `own` (the faces the hole's pre-treatment split, already in
// the surface), among themselves or with the rest of the surface. The
// patch's new vertices are numbered from s.points.size() on: they are
// positions[firstNew...]. The patch is appended to the surface for the
// check and taken out again. A patch face without area counts as a pair.
std::size_t patchIntersections(Surface& s, const std::vector<Triangle>& patch,
                               const std::vector<Point3>& positions, std::size_t firstNew,
                               const std::vector<int>& own) {
  const std::size_t points = s.points.size(), faces = s.triangles.size();
  s.points.insert(s.points.end(), positions.begin() + std::ptrdiff_t(firstNew), positions.end());
  s.triangles.insert(s.triangles.end(), patch.begin(), patch.end());
  struct Undo {
    Surface& s;
    std::size_t points, faces;
    ~Undo() {
      s.points.resize(points);
      s.triangles.resize(faces);
    }
  } undo{s, points, faces};
  const std::vector<Point3>& P = s.points;
  const std::vector<Triangle>& T = s.triangles;
  auto degenerate = [&](int f) { return collinear(P[T[f][0]], P[T[f][1]], P[T[f][2]]); };
  auto boxOfFace = [&](int f) { return boxOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]); };
  std::vector<int> checked;  // patch faces, then the split ones
  checked.reserve(patch.size() + own.size());
  for (std::size_t f = faces; f < T.size(); ++f) {
    if (degenerate(int(f))) return 1;
    checked.push_back(int(f));
  }
  std::unordered_set<int> ownSet;
  for (int f : own)
    if (ownSet.insert(f).second && !degenerate(f)) checked.push_back(f);
  std::vector<Box> boxes;
  boxes.reserve(checked.size());
  Box bounds{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  for (int f : checked) {
    boxes.push_back(boxOfFace(f));
    for (int k = 0; k < 3; ++k) {
      bounds.lo[k] = std::min(bounds.lo[k], boxes.back().lo[k]);
      bounds.hi[k] = std::max(bounds.hi[k], boxes.back().hi[k]);
    }
  }
  auto intersect = [&](int f, int g) {
    return facesIntersect(P, T, std::uint32_t(f), std::uint32_t(g));
  };
  const BoxTree tree(boxes);
  std::atomic<std::size_t> pairs{0};
  tree.selfPairs([&](std::uint32_t i, std::uint32_t j, unsigned) {
    if (intersect(checked[i], checked[j])) ++pairs;
  });
  // The input faces as they came (a split face's halves lie within it, the
  // later half being checked below).
  auto inputCorners = [&](std::size_t f) {
    return s.inputCorners.empty() ? T[f] : s.originalCorners(int(f));
  };
  // A few holes scan the input faces; many pay for a hierarchy of their boxes once.
  if (!s.inputTree && ++s.checks > 8) {
    std::vector<Box> inputBoxes(s.inputFaces);
    parallelChunks(s.inputFaces, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t f = begin; f < end; ++f) {
        const Triangle t = inputCorners(f);
        inputBoxes[f] = boxOf(P[t[0]], P[t[1]], P[t[2]]);
      }
    });
    s.inputTree = std::make_unique<BoxTree>(std::move(inputBoxes));
  }
  // The rest of the surface: faces before the patch that are not split ones
  // (facesIntersect skips degenerate faces).
  auto other = [&](std::size_t f) { return !ownSet.count(int(f)); };
  // Input faces, then later faces.
  if (s.inputTree) {
    parallelChunks(
        checked.size(),
        [&](std::size_t begin, std::size_t end, unsigned worker) {
          for (std::size_t i = begin; i < end; ++i)
            s.inputTree->query(boxes[i], worker, [&](std::uint32_t f, unsigned) {
              if (other(f) && intersect(checked[i], int(f))) ++pairs;
            });
        },
        64);
  } else {
    // Beyond which sides of the patch's bounds (rounded outwards) each
    // point lies, a bit per side and axis: a face whose corners share a bit
    // is away from the patch, as most of a large mesh is. (A face split
    // since lies within its input face: its current corners decide that.)
    std::vector<std::uint8_t> beyond(P.size());
    parallelChunks(P.size(), [&](std::size_t begin, std::size_t end, unsigned) {
      // In locals: the byte stores could alias anything in memory.
      const double lo0 = bounds.lo[0], lo1 = bounds.lo[1], lo2 = bounds.lo[2];
      const double hi0 = bounds.hi[0], hi1 = bounds.hi[1], hi2 = bounds.hi[2];
      const Point3* point = P.data();
      std::uint8_t* code = beyond.data();
      for (std::size_t v = begin; v < end; ++v) {
        const double x = point[v][0], y = point[v][1], z = point[v][2];
        code[v] =
            std::uint8_t(unsigned(x < lo0) | unsigned(y < lo1) << 1 | unsigned(z < lo2) << 2 |
                         unsigned(x > hi0) << 3 | unsigned(y > hi1) << 4 | unsigned(z > hi2) << 5);
      }
    });
    parallelChunks(s.inputFaces, [&](std::size_t begin, std::size_t end, unsigned worker) {
      for (std::size_t f = begin; f < end; ++f) {
        const Triangle& current = T[f];
        if (beyond[std::size_t(current[0])] & beyond[std::size_t(current[1])] &
            beyond[std::size_t(current[2])])
          continue;
        if (!other(f)) continue;
        const Triangle t = inputCorners(f);
        tree.query(boxOf(P[t[0]], P[t[1]], P[t[2]]), worker, [&](std::uint32_t i, unsigned) {
          if (intersect(checked[i], int(f))) ++pairs;
        });
      }
    });
  }
  for (std::size_t f = s.inputFaces; f < faces; ++f) {
    const Box box = boxOfFace(int(f));
    if (!overlap(box, bounds) || !other(f)) continue;
    tree.query(box, 0, [&](std::uint32_t i, unsigned) {
      if (intersect(checked[i], int(f))) ++pairs;
    });
  }
  return pairs;
}

// ---- One hole ----------------------------------------------------------------------

struct PatchShape {
  std::vector<Point3> positions;  // local: boundary (front order) then new vertices
  HoleFairing fairing = HoleFairing::Flat;
  double residual = 0;
};

class HoleFiller {
 public:
  HoleFiller(Surface& s, const HoleFillOptions& options, const std::unordered_set<int>& pinched,
             HoleFillResult::StageTimes& times)
      : s_(s), options_(options), pinched_(pinched), times_(times) {}

  // Fills the hole bounded by `loop` (mesh direction, after splitting) in
  // the working surface; false (with the reason) when it could not be.
  bool fill(const std::vector<int>& loop, const std::vector<int>& splitFaces, HoleReport& report) {
    n_ = loop.size();
    front_.assign(loop.rbegin(), loop.rend());
    local_.clear();
    for (std::size_t k = 0; k < n_; ++k) local_[front_[k]] = int(k);
    std::vector<Point3> boundary;
    meanEdge_ = 0;
    Point3 faceNormals(0, 0, 0);
    std::vector<Point3> borderNormals;  // unit normals of the faces along the border
    for (std::size_t k = 0; k < n_; ++k) {
      boundary.push_back(s_.points[front_[k]]);
      meanEdge_ += (s_.points[front_[(k + 1) % n_]] - s_.points[front_[k]]).Norm();
      const auto owner = s_.borderOwner.find(directedKey(front_[(k + 1) % n_], front_[k]));
      if (owner != s_.borderOwner.end()) {
        const Point3 n = faceNormal(s_.points, s_.triangles[owner->second]);
        faceNormals += n;
        if (n.Norm() > 0) borderNormals.push_back(n / n.Norm());
      }
    }
    meanEdge_ /= double(n_);
    if (!(meanEdge_ > 0)) {
      report.reason = "the hole's border has zero length";
      return false;
    }

    std::vector<HoleFairing> modes;
    for (HoleFairing m :
         {options_.fairing, HoleFairing::Biharmonic, HoleFairing::Harmonic, HoleFairing::Flat})
      if (int(m) <= int(options_.fairing) &&
          std::find(modes.begin(), modes.end(), m) == modes.end())
        modes.push_back(m);
    // Asked for the smoothest shape and none down to flat fits: the
    // regression's, which bends with the curvature around the hole instead,
    // may clear what they hit; it is tried before the hole is left open.
    if (options_.fairing == HoleFairing::Biharmonic)
      modes.push_back(HoleFairing::LaplacianRegression);
    // Each domain's patch, shaped in the first mode. The plane's is kept
    // when its triangles come out round in space; where the plane squeezes
    // part of the hole (the surface turns away from it), the disk's patch
    // competes and the rounder of the two is tried first. The disk's is
    // made on a second thread meanwhile (the machine's other core), by a
    // filler of its own: both only read the surface.
    std::vector<Domain> domains = domainsOf(boundary, faceNormals);
    // Where the surface along the border turns more than 45 degrees away
    // from the plane on average (a cap, a tube's end), the plane squeezes
    // the patch next to the border: the disk's patch is tried first, alone
    // and in the first mode, and both domains compete as below only when it
    // does not fit.
    if (domains.size() == 2 && !borderNormals.empty()) {
      double cosine = 0;
      for (const Point3& n : borderNormals) cosine += std::abs(n * domains[0].N);
      if (cosine < kSteepCosine * double(borderNormals.size())) {
        Candidate c;
        std::string problem, failed;
        HoleReport trial = report;
        shapeOver(domains[1], modes[0], trial, c, problem);
        if (problem.empty()) {
          swapState(c.state);
          const bool filled = fillAs(modes[0], modes[0], c, splitFaces, trial, failed);
          swapState(c.state);
          if (filled) {
            report = std::move(trial);
            if (report.fairing != modes[0])
              report.reason = "fell back to biharmonic: " + report.reason;
            else
              report.reason.clear();
            return true;
          }
        }
      }
    }
    std::vector<Candidate> made(domains.size());
    std::vector<std::string> problem(domains.size());
    HoleFillResult::StageTimes twinTimes;
    std::exception_ptr twinError;
    if (domains.size() == 2) {
      // The stage times stay wall times of this thread: the time spent
      // waiting for the disk's patch counts as fairing.
      const auto parallelStart = Clock::now();
      const double triangulateBefore = times_.triangulate, fairBefore = times_.fair;
      HoleFiller twin(s_, options_, pinched_, twinTimes);
      twin.n_ = n_;
      twin.front_ = front_;
      twin.local_ = local_;
      twin.meanEdge_ = meanEdge_;
      TaskAlongside disk([&] {
        try {
          HoleReport scratch;
          twin.shapeOver(domains[1], modes[0], scratch, made[1], problem[1]);
        } catch (...) {
          twinError = std::current_exception();
        }
      });
      shapeOver(domains[0], modes[0], report, made[0], problem[0]);
      disk.wait();
      if (twinError) std::rethrow_exception(twinError);
      times_.fair = fairBefore + msSince(parallelStart) - (times_.triangulate - triangulateBefore);
    } else {
      for (std::size_t i = 0; i < domains.size(); ++i)
        shapeOver(domains[i], modes[0], report, made[i], problem[i]);
    }
    std::string problems;
    std::vector<Candidate> candidates;
    for (std::size_t i = 0; i < domains.size(); ++i) {
      if (!problem[i].empty()) {
        problems += (problems.empty() ? "" : "; ") + where(domains[i]) + problem[i];
        continue;
      }
      candidates.push_back(std::move(made[i]));
      if (domains[i].planar && candidates.back().quality >= kRoundPatchQuality) break;
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.quality > b.quality; });
    // A smoother shape over either domain before a flatter one.
    std::string failed;
    for (HoleFairing mode : modes)
      for (Candidate& c : candidates) {
        swapState(c.state);
        const bool filled = fillAs(mode, modes[0], c, splitFaces, report, failed);
        swapState(c.state);
        if (!filled) continue;
        if (!problems.empty()) failed = problems + (failed.empty() ? "" : "; ") + failed;
        if (mode != options_.fairing || !problems.empty())
          report.reason = "fell back: " + failed;
        else if (report.fairing != mode)
          report.reason = "fell back to biharmonic: " + report.reason;
        else
          report.reason.clear();
        return true;
      }
    report.reason = problems + (problems.empty() || failed.empty() ? "" : "; ") + failed;
    return false;
  }

 private:
  // A patch of at least this mean shape quality (1 = equilateral triangles)
  // over the hole's plane is used without trying the disk.
  static constexpr double kRoundPatchQuality = 0.85;
  // Mean |cos| between the border's faces and the hole's plane below which
  // the disk is tried first: 45 degrees, where projecting onto the plane
  // shortens the patch's first layer by more than a factor 1 / sqrt(2).
  static constexpr double kSteepCosine = 0.70710678118654752;
  // Patch edges that the shape stretches beyond this factor of their length
  // in the domain are split (refineStretched): twice the size the front meant.
  static constexpr double kMaxStretch = 2;
  static constexpr int kRefinePasses = 3;
  static constexpr int kFlipPasses = 4;
  static constexpr const char* kNoMembrane = "the membrane over the disk could not be solved";

  // The triangulated patch over one domain (what prepare() leaves in the members).
  struct PatchState {
    std::vector<Vec2> uv;
    std::vector<double> height;
    std::vector<Triangle> localTriangles, patchTriangles;
    TrianglesAround localAround;
    std::vector<int> rowVertex;
    std::vector<LaplacianRow> outsideRows;
    std::vector<char> hasOutsideRow;
  };
  struct Candidate {
    Domain domain;
    PatchState state;
    // The boundary, and the flat placement of the new vertices once known
    // (over a disk it takes a solve of its own, made only when needed).
    std::vector<Point3> flat;
    bool flatPlaced = false;
    PatchShape first;  // shaped in the first mode
    bool firstShaped = false;
    double quality = -1;
    std::size_t trainingSamples = 0;
    std::string firstNote;  // what shaping in the first mode reported
  };

  void swapState(PatchState& p) {
    uv_.swap(p.uv);
    height_.swap(p.height);
    localTriangles_.swap(p.localTriangles);
    patchTriangles_.swap(p.patchTriangles);
    localAround_.swap(p.localAround);
    rowVertex_.swap(p.rowVertex);
    outsideRows_.swap(p.outsideRows);
    hasOutsideRow_.swap(p.hasOutsideRow);
  }

  static std::string where(const Domain& domain) {
    return domain.planar ? "over its plane: " : "over a disk: ";
  }

  // Mean over the patch's triangles of 4 sqrt(3) area / (sum of squared
  // edge lengths): 1 for equilateral ones, 0 for slivers.
  double meanShapeQuality(const std::vector<Point3>& x) const {
    if (localTriangles_.empty()) return 0;
    double sum = 0;
    for (const Triangle& t : localTriangles_) {
      const Point3 &a = x[t[0]], &b = x[t[1]], &c = x[t[2]];
      const double squares = (b - a).SquaredNorm() + (c - b).SquaredNorm() + (a - c).SquaredNorm();
      if (squares > 0) sum += 2 * std::sqrt(3.0) * ((b - a) ^ (c - a)).Norm() / squares;
    }
    return sum / double(localTriangles_.size());
  }

  // The candidate patch over `domain`, shaped in `mode` (state swapped out
  // into c); `problem` says why there is none.
  void shapeOver(const Domain& domain, HoleFairing mode, HoleReport& report, Candidate& c,
                 std::string& problem) {
    c.domain = domain;
    report.reason.clear();
    c.flatPlaced = domain.planar || mode == HoleFairing::Flat;
    if (!prepare(domain, report, c.flat, c.flatPlaced)) {
      problem = report.reason.empty() ? "no patch" : report.reason;
      return;
    }
    c.first.positions = c.flat;
    c.first.fairing = mode;
    const auto clock = Clock::now();
    c.firstShaped = mode == HoleFairing::Flat || fair(mode, c.first, report);
    // The domain sized the triangles; where the shape in space stretches
    // them far beyond that (the plane foreshortens a part of the hole that
    // turns away from it), the patch is refined there and shaped again,
    // starting from where it is.
    if (c.firstShaped && smoothWithTangents(mode) && refineStretched(c.first.positions, c.flat) > 0)
      c.firstShaped = fair(mode, c.first, report, true);
    times_.fair += msSince(clock);
    c.quality = c.firstShaped ? meanShapeQuality(c.first.positions) : -1;
    c.trainingSamples = report.training_samples;
    c.firstNote = report.reason;
    swapState(c.state);
  }

  // Triangulates the hole over `domain` into the members; `flat` gets the
  // boundary and, with `placeFlat`, the flat placement of the new vertices.
  // False (reason in the report) when it cannot.
  bool prepare(const Domain& domain, HoleReport& report, std::vector<Point3>& flat,
               bool placeFlat) {
    auto clock = Clock::now();
    const bool covered = triangulate(domain, report);
    times_.triangulate += msSince(clock);
    if (!covered) return false;
    numberPatch();
    if (!placeFlat) {
      flat.assign(uv_.size(), Point3(0, 0, 0));
      for (std::size_t k = 0; k < n_; ++k) flat[k] = s_.points[front_[k]];
      return true;
    }
    clock = Clock::now();
    const bool placed = flatPositions(domain, flat);
    times_.fair += msSince(clock);
    if (!placed) report.reason = kNoMembrane;
    return placed;
  }

  // Patch faces in mesh numbering (new vertices follow the surface's) and
  // the Laplacian rows.
  void numberPatch() {
    const std::size_t base = s_.points.size();
    patchTriangles_.clear();
    for (const Triangle& t : localTriangles_) {
      Triangle g;
      for (int k = 0; k < 3; ++k)
        g[k] = std::size_t(t[k]) < n_ ? front_[t[k]] : int(base + std::size_t(t[k]) - n_);
      patchTriangles_.push_back(g);
    }
    buildRows();
  }

  static bool smoothWithTangents(HoleFairing mode) {
    return mode == HoleFairing::Biharmonic || mode == HoleFairing::LaplacianRegression;
  }

  // The corner k of `t` whose edge to corner k + 1 has `key` (t has that edge).
  static int cornerBefore(const Triangle& t, std::uint64_t key) {
    int k = 0;
    while (edgeKey(t[k], t[(k + 1) % 3]) != key) ++k;
    return k;
  }

  // The patch's inner edges (local key) and the two triangles on each.
  std::unordered_map<std::uint64_t, std::pair<int, int>> innerEdgeSides() const {
    std::unordered_map<std::uint64_t, std::pair<int, int>> sides;
    sides.reserve(localTriangles_.size() * 2);
    for (std::size_t t = 0; t < localTriangles_.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int a = localTriangles_[t][k], b = localTriangles_[t][(k + 1) % 3];
        auto [it, added] = sides.try_emplace(edgeKey(a, b), int(t), -1);
        if (!added) it->second.second = int(t);
      }
    for (auto it = sides.begin(); it != sides.end();)
      it = it->second.second < 0 ? sides.erase(it) : std::next(it);
    return sides;
  }

  // Splits, at their midpoints in the domain and in space, the patch's
  // inner edges that the shape `x` made longer than kMaxStretch times their
  // length in the domain and than the boundary's mean edge (longest first,
  // each triangle once per pass, a few passes). A half keeps its edge's
  // stretch, so the pieces are split again until they are no longer than
  // the boundary's mean edge or the passes run out: where the domain
  // foreshortened the patch, its triangles in space come down towards the
  // border's size. Then flips the
  // edges the splits left non-Delaunay in space. `flat` (the flat placement,
  // as far as known) follows. Returns the number of edges split; with any,
  // the patch is renumbered and its rows rebuilt.
  std::size_t refineStretched(std::vector<Point3>& x, std::vector<Point3>& flat) {
    auto isStretched = [&](int a, int b, double& length) {
      length = (x[a] - x[b]).Norm();
      return length > meanEdge_ && length > kMaxStretch * norm(uv_[a] - uv_[b]);
    };
    // Most patches have no such edge: a plain scan finds that out.
    bool any = false;
    double length = 0;
    for (const Triangle& t : localTriangles_)
      for (int k = 0; k < 3 && !any; ++k) any = isStretched(t[k], t[(k + 1) % 3], length);
    if (!any) return 0;
    std::size_t splits = 0;
    for (int pass = 0; pass < kRefinePasses; ++pass) {
      struct Edge {
        double length;
        int first, second, a, b;
      };
      std::vector<Edge> stretched;
      for (const auto& [key, side] : innerEdgeSides()) {
        const Triangle& t = localTriangles_[std::size_t(side.first)];
        const int k = cornerBefore(t, key);
        const int a = t[k], b = t[(k + 1) % 3];
        if (isStretched(a, b, length)) stretched.push_back({length, side.first, side.second, a, b});
      }
      if (stretched.empty()) break;
      std::sort(stretched.begin(), stretched.end(), [](const Edge& p, const Edge& q) {
        if (p.length != q.length) return p.length > q.length;
        return std::tie(p.first, p.a, p.b) < std::tie(q.first, q.a, q.b);
      });
      std::vector<char> touched(localTriangles_.size(), 0);
      for (const Edge& e : stretched) {
        if (touched[std::size_t(e.first)] || touched[std::size_t(e.second)]) continue;
        touched[std::size_t(e.first)] = touched[std::size_t(e.second)] = 1;
        const int m = int(uv_.size());
        uv_.push_back(0.5 * (uv_[e.a] + uv_[e.b]));
        height_.push_back((height_[e.a] + height_[e.b]) / 2);
        x.push_back((x[e.a] + x[e.b]) / 2);
        flat.push_back((flat[e.a] + flat[e.b]) / 2);
        // (from, to, apex) -> (from, m, apex) + (m, to, apex), in both triangles:
        // m lies on the edge in the domain, so both halves keep their orientation.
        for (const int t : {e.first, e.second}) {
          Triangle& tri = localTriangles_[std::size_t(t)];
          const int k = cornerBefore(tri, edgeKey(e.a, e.b));
          const int from = tri[k], to = tri[(k + 1) % 3], apex = tri[(k + 2) % 3];
          tri = {from, m, apex};
          localTriangles_.push_back({m, to, apex});
        }
        ++splits;
      }
    }
    if (splits > 0) {
      flipToDelaunay(x);
      localAround_ = TrianglesAround(localTriangles_, uv_.size());
      numberPatch();
    }
    return splits;
  }

  // Whether local vertices c and d are border vertices joined by an edge of
  // the mesh (the patch must not add such an edge again: the front avoids
  // them, and so must a flip).
  bool isMeshChord(int c, int d) const {
    if (std::size_t(c) >= n_ || std::size_t(d) >= n_) return false;
    bool found = false;
    s_.adjacency->forEach(front_[std::size_t(c)], [&](int f) {
      for (int corner : s_.triangles[std::size_t(f)])
        found = found || corner == front_[std::size_t(d)];
    });
    return found;
  }

  // Flips the patch's inner edges whose opposite angles at x add up to more
  // than pi (Delaunay in space: rounder triangles, positive cotangent
  // weights), where the flipped pair stays counter-clockwise in the domain
  // and the new edge is not there yet. A few passes.
  void flipToDelaunay(const std::vector<Point3>& x) {
    auto angleAt = [&](int apex, int a, int b) {
      const Point3 u = x[a] - x[apex], v = x[b] - x[apex];
      return std::atan2((u ^ v).Norm(), u * v);
    };
    for (int pass = 0; pass < kFlipPasses; ++pass) {
      const auto sides = innerEdgeSides();
      // In key order, so that the result does not depend on the hash table's.
      std::vector<std::pair<std::uint64_t, std::pair<int, int>>> edges(sides.begin(), sides.end());
      std::sort(edges.begin(), edges.end());
      std::vector<char> touched(localTriangles_.size(), 0);
      std::size_t flips = 0;
      for (const auto& [key, side] : edges) {
        if (touched[std::size_t(side.first)] || touched[std::size_t(side.second)]) continue;
        Triangle& t1 = localTriangles_[std::size_t(side.first)];
        Triangle& t2 = localTriangles_[std::size_t(side.second)];
        const int k = cornerBefore(t1, key);
        const int a = t1[k], b = t1[(k + 1) % 3], c = t1[(k + 2) % 3];
        int j = 0;
        while (t2[j] == a || t2[j] == b) ++j;
        const int d = t2[j];
        if (c == d || sides.count(edgeKey(c, d)) || isMeshChord(c, d)) continue;
        if (angleAt(c, a, b) + angleAt(d, b, a) <= M_PI) continue;
        // (a, b, c) + (b, a, d) -> (a, d, c) + (d, b, c).
        if (orient(uv_[a], uv_[d], uv_[c]) <= 0 || orient(uv_[d], uv_[b], uv_[c]) <= 0) continue;
        t1 = {a, d, c};
        t2 = {d, b, c};
        touched[std::size_t(side.first)] = touched[std::size_t(side.second)] = 1;
        ++flips;
      }
      if (flips == 0) break;
    }
  }

  // Shapes the candidate's patch (its state swapped in) in `mode` and
  // commits it when it passes the exact check; else says why in `failed`.
  bool fillAs(HoleFairing mode, HoleFairing firstMode, Candidate& c,
              const std::vector<int>& splitFaces, HoleReport& report, std::string& failed) {
    auto fail = [&](const std::string& why) {
      failed += (failed.empty() ? "" : "; ") + where(c.domain) + toString(mode) + why;
      return false;
    };
    PatchShape shape;
    bool faired = true;
    if (mode == firstMode) {
      shape = c.first;
      faired = c.firstShaped;
      report.reason = c.firstNote;
      report.training_samples = c.trainingSamples;
    } else {
      const auto clock = Clock::now();
      if (mode == HoleFairing::Flat && !c.flatPlaced) {
        if (!flatPositions(c.domain, c.flat)) return fail(std::string(": ") + kNoMembrane);
        c.flatPlaced = true;
      }
      shape.positions = c.flat;
      shape.fairing = mode;
      faired = mode == HoleFairing::Flat || fair(mode, shape, report);
      times_.fair += msSince(clock);
    }
    if (!faired) return fail(": solver failed");
    for (std::size_t v = n_; v < shape.positions.size(); ++v)
      shape.positions[v] = s_.stored(shape.positions[v]);
    if (options_.check_intersections) {
      const auto clock = Clock::now();
      const std::size_t pairs =
          patchIntersections(s_, patchTriangles_, shape.positions, n_, splitFaces);
      times_.check += msSince(clock);
      if (pairs > 0)
        return fail(" patch would intersect itself or the mesh (" + std::to_string(pairs) +
                    " pairs)");
    }
    report.planar_domain = c.domain.planar;
    commit(shape, report);
    return true;
  }

  bool triangulate(const Domain& domain, HoleReport& report) {
    std::vector<double> sizes(n_);
    for (std::size_t k = 0; k < n_; ++k) {
      const Vec2 here = domain.uv[k];
      sizes[k] =
          (norm(domain.uv[(k + 1) % n_] - here) + norm(domain.uv[(k + n_ - 1) % n_] - here)) / 2;
    }
    double meanDomainEdge = 0;
    for (std::size_t k = 0; k < n_; ++k)
      meanDomainEdge += norm(domain.uv[(k + 1) % n_] - domain.uv[k]);
    meanDomainEdge /= double(n_);
    // Mesh edges between boundary vertices (the border's own among them):
    // the patch must not add any of them again.
    std::vector<std::pair<int, int>> existing;
    for (std::size_t k = 0; k < n_; ++k)
      s_.adjacency->forEach(front_[k], [&](int f) {
        for (int c : s_.triangles[f]) {
          const auto it = local_.find(c);
          if (it != local_.end() && it->second > int(k)) existing.push_back({int(k), it->second});
        }
      });
    AdvancingFront::Settings settings;
    const double uniformFaces =
        std::abs(signedArea(domain.uv)) / (0.433 * meanDomainEdge * meanDomainEdge);
    if (uniformFaces > double(options_.uniform_face_limit)) {
      settings.growth = options_.size_growth;
      settings.maxSize = options_.max_size_factor * meanDomainEdge;
    } else {
      settings.growth = 1;
      settings.maxSize = meanDomainEdge * 4;
    }
    settings.merge = options_.merge_distance;
    AdvancingFront front(domain.uv, sizes, existing, settings);
    if (!front.run()) {
      report.reason = "the advancing front could not cover the hole (its border is too tangled)";
      return false;
    }
    uv_ = front.uv;
    localTriangles_ = front.triangles;
    height_.assign(uv_.size(), 0);
    if (domain.planar) {
      for (std::size_t k = 0; k < n_; ++k) height_[k] = domain.height[k];
      for (std::size_t v = n_; v < uv_.size(); ++v) {
        const auto [a, b] = front.parent[v - n_];
        height_[v] = (height_[a] + height_[b]) / 2;
      }
    }
    relaxInterior(uv_, height_, n_, localTriangles_, 3);
    localAround_ = TrianglesAround(localTriangles_, uv_.size());
    return true;
  }

  // Local index of a patch vertex, or -(global + 1) for a vertex outside the patch.
  int keyOf(int global) const {
    const auto it = local_.find(global);
    return it == local_.end() ? -(global + 1) : it->second;
  }

  // Laplacian rows: every new vertex, and the boundary vertices whose faces
  // form one fan (their outside part is fixed; the patch part is added per solve).
  void buildRows() {
    rowVertex_.clear();
    outsideRows_.assign(n_, {});
    hasOutsideRow_.assign(n_, 0);
    for (std::size_t v = n_; v < uv_.size(); ++v) rowVertex_.push_back(int(v));
    for (std::size_t k = 0; k < n_; ++k) {
      if (pinched_.count(front_[k])) continue;
      LaplacianRow row;
      s_.adjacency->forEach(front_[k], [&](int f) {
        const Triangle& t = s_.triangles[f];
        int corner = 0;
        while (t[corner] != front_[k]) ++corner;
        addTriangleToRow(row, {keyOf(t[0]), keyOf(t[1]), keyOf(t[2])},
                         {s_.points[t[0]], s_.points[t[1]], s_.points[t[2]]}, corner);
      });
      if (row.weights.empty()) continue;
      rowVertex_.push_back(int(k));
      outsideRows_[k] = row;
      hasOutsideRow_[k] = 1;
    }
  }

  const Point3& fixedPosition(int key, const std::vector<Point3>& x) const {
    return key >= 0 ? x[key] : s_.points[-key - 1];
  }

  // Cotangent weights of the patch's triangles at positions x, or in the plane (`planar`).
  std::vector<TriangleWeights> patchWeights(const std::vector<Point3>& x, bool planar) const {
    std::vector<TriangleWeights> w(localTriangles_.size());
    for (std::size_t t = 0; t < localTriangles_.size(); ++t) {
      const Triangle& tri = localTriangles_[t];
      if (planar) {
        auto at = [&](int k) { return Point3(uv_[tri[k]].x, uv_[tri[k]].y, 0); };
        w[t] = triangleWeights(at(0), at(1), at(2));
      } else {
        w[t] = triangleWeights(x[tri[0]], x[tri[1]], x[tri[2]]);
      }
    }
    return w;
  }

  // The Laplacian row of local vertex v (into `row`, reusing its storage).
  // Weights below `floor` are raised to it.
  void rowOf(int v, const std::vector<TriangleWeights>& weights, LaplacianRow& row,
             double floor = -INFINITY) const {
    row.weights.clear();
    row.area = 0;
    if (std::size_t(v) < n_ && hasOutsideRow_[v]) {
      const LaplacianRow& outside = outsideRows_[v];
      row.weights.assign(outside.weights.begin(), outside.weights.end());
      row.area = outside.area;
    }
    for (int t : localAround_[v]) {
      const Triangle& tri = localTriangles_[t];
      int corner = 0;
      while (tri[corner] != v) ++corner;
      addTriangleToRow(row, {tri[0], tri[1], tri[2]}, weights[t], corner);
    }
    row.finish(floor);
  }

  // Flat: the front's own placement (heights carried inward from the
  // boundary) over the plane, or a uniform membrane over a disk domain.
  bool flatPositions(const Domain& domain, std::vector<Point3>& x) const {
    x.assign(uv_.size(), Point3(0, 0, 0));
    for (std::size_t k = 0; k < n_; ++k) x[k] = s_.points[front_[k]];
    if (domain.planar) {
      for (std::size_t v = n_; v < uv_.size(); ++v)
        x[v] = domain.origin + domain.U * uv_[v].x + domain.V * uv_[v].y + domain.N * height_[v];
      return true;
    }
    double residual = 0;
    Membrane m;
    return membrane(m, x, MembraneWeights::Uniform, residual);
  }

  // Normal (area weighted) and a third of the area of the faces around local vertex v.
  std::pair<Point3, double> normalAndArea(int v, const std::vector<Point3>& x) const {
    Point3 n(0, 0, 0);
    for (int t : localAround_[v]) {
      const Triangle& tri = localTriangles_[t];
      n += (x[tri[1]] - x[tri[0]]) ^ (x[tri[2]] - x[tri[0]]);
    }
    if (std::size_t(v) < n_)
      s_.adjacency->forEach(front_[v], [&](int f) { n += faceNormal(s_.points, s_.triangles[f]); });
    const double twiceArea = n.Norm();  // faces around a vertex are nearly coplanar
    double area = 0;
    for (int t : localAround_[v]) {
      const Triangle& tri = localTriangles_[t];
      area += ((x[tri[1]] - x[tri[0]]) ^ (x[tri[2]] - x[tri[0]])).Norm() / 6;
    }
    if (std::size_t(v) < n_)
      s_.adjacency->forEach(
          front_[v], [&](int f) { area += faceNormal(s_.points, s_.triangles[f]).Norm() / 6; });
    return {twiceArea > 0 ? n / twiceArea : n, area};
  }

  // Least squares over the rows: sum_r A_r |(L x)_r - delta_r|^2 over the
  // new vertices (unknowns), with (L x)_r = (1 / 2 A_r) sum_j omega_rj (x_j -
  // x_r) the cotangent Laplacian (Eq. 1-3 with Eq. 4's area): the sum
  // discretises the integral of |Laplacian|^2 whatever the local triangle
  // size. The rows' vertices, the pattern of the normal equations and its
  // ordering follow from the triangulation alone: they are worked out at the
  // first weight set, and each later one only refills the numbers and
  // factorises again.
  struct System {
    // Row r's entries are [start[r], start[r + 1]): a key (local vertex, or
    // -(global + 1) outside the patch) and its coefficient, omega_rj times
    // the row's weight; the row's own vertex comes first.
    std::vector<int> start, key;
    std::vector<double> coefficient;
    // Per row, from pairStart[r]: where the product of each pair (i <= j)
    // of its unknown entries goes in the values of normal.
    std::vector<int> pairStart, pairSlot;
    Eigen::SparseMatrix<double> normal;  // A^T A, lower triangle
    Eigen::MatrixXd fixedPart;           // rows x 3: the fixed vertices' contribution
    Eigen::VectorXd rowWeight;           // 1 / (2 sqrt(A_r))
    std::vector<double> rowLength;       // sum_j |omega_rj|: turns a row's residual into a length
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
    bool analysed = false, ok = false;
  };

  // The lower triangle of a symmetric pattern over `size` unknowns, from
  // the pairs (row >= column) it holds (repeats allowed): bucketed by
  // column, each column's few rows then sorted.
  static Eigen::SparseMatrix<double> lowerPattern(std::size_t size,
                                                  const std::vector<std::pair<int, int>>& pairs) {
    std::vector<int> start(size + 1, 0);
    for (const auto& [row, column] : pairs) ++start[std::size_t(column) + 1];
    for (std::size_t c = 0; c < size; ++c) start[c + 1] += start[c];
    std::vector<int> rows(pairs.size());
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (const auto& [row, column] : pairs) rows[std::size_t(fill[std::size_t(column)]++)] = row;
    }
    Eigen::SparseMatrix<double> m(static_cast<Eigen::Index>(size), static_cast<Eigen::Index>(size));
    m.resizeNonZeros(Eigen::Index(pairs.size()));
    int* outer = m.outerIndexPtr();
    int* inner = m.innerIndexPtr();
    int count = 0;
    outer[0] = 0;
    for (std::size_t c = 0; c < size; ++c) {
      int* begin = rows.data() + start[c];
      int* end = rows.data() + start[c + 1];
      std::sort(begin, end);
      end = std::unique(begin, end);
      for (const int* r = begin; r != end; ++r) inner[count++] = *r;
      outer[c + 1] = count;
    }
    m.resizeNonZeros(count);
    std::fill(m.valuePtr(), m.valuePtr() + count, 0.0);
    return m;
  }

  // Where entry (row, column), row >= column, is in the values of a compressed lower pattern.
  static int slotOf(const Eigen::SparseMatrix<double>& m, int row, int column) {
    const int* begin = m.innerIndexPtr() + m.outerIndexPtr()[column];
    const int* end = m.innerIndexPtr() + m.outerIndexPtr()[column + 1];
    return int(std::lower_bound(begin, end, row) - m.innerIndexPtr());
  }

  void assemble(System& sys, const std::vector<int>& rows, const std::vector<Point3>& x,
                bool planarWeights) const {
    const std::size_t unknowns = uv_.size() - n_;
    const int first = int(n_);
    sys.fixedPart = Eigen::MatrixXd::Zero(Eigen::Index(rows.size()), 3);
    sys.rowLength.assign(rows.size(), 0);
    sys.rowWeight.resize(Eigen::Index(rows.size()));
    const std::vector<TriangleWeights> weights = patchWeights(x, planarWeights);
    const bool symbolic = !sys.analysed;
    if (symbolic) {
      sys.start.assign(1, 0);
      sys.key.clear();
      sys.coefficient.clear();
    }
    LaplacianRow row;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const int v = rows[r];
      rowOf(v, weights, row);
      const double weight = row.area > 0 ? 1 / (2 * std::sqrt(row.area)) : 1.0;
      sys.rowWeight[Eigen::Index(r)] = weight;
      if (symbolic) {
        sys.key.push_back(v);
        for (const auto& [key, w] : row.weights) sys.key.push_back(key);
        sys.start.push_back(int(sys.key.size()));
        sys.coefficient.resize(sys.key.size());
      }
      int at = sys.start[r];
      auto put = [&](int key, double coefficient) {
        coefficient *= weight;
        sys.coefficient[std::size_t(at++)] = coefficient;
        if (key < first) {
          const Point3& p = fixedPosition(key, x);
          for (int d = 0; d < 3; ++d) sys.fixedPart(Eigen::Index(r), d) += coefficient * p[d];
        }
      };
      put(v, -row.total);
      for (const auto& [key, w] : row.weights) {
        put(key, w);
        sys.rowLength[r] += std::abs(w);
      }
    }
    if (symbolic) {
      // The pattern of A^T A: every pair of unknowns that share a row.
      std::vector<std::pair<int, int>> pairs;
      for (std::size_t r = 0; r < rows.size(); ++r)
        for (int i = sys.start[r]; i < sys.start[r + 1]; ++i)
          for (int j = sys.start[r]; j < sys.start[r + 1]; ++j)
            if (sys.key[i] >= first && sys.key[j] >= sys.key[i])
              pairs.push_back({sys.key[j] - first, sys.key[i] - first});
      sys.normal = lowerPattern(unknowns, pairs);
      sys.pairStart.assign(1, 0);
      sys.pairSlot.clear();
      for (std::size_t r = 0; r < rows.size(); ++r) {
        for (int i = sys.start[r]; i < sys.start[r + 1]; ++i)
          for (int j = sys.start[r]; j < sys.start[r + 1]; ++j)
            if (sys.key[i] >= first && sys.key[j] >= first)
              sys.pairSlot.push_back(
                  sys.key[j] >= sys.key[i]
                      ? slotOf(sys.normal, sys.key[j] - first, sys.key[i] - first)
                      : -1);
        sys.pairStart.push_back(int(sys.pairSlot.size()));
      }
    }
    // A^T A, row by row.
    double* values = sys.normal.valuePtr();
    std::fill(values, values + sys.normal.nonZeros(), 0.0);
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const int* slot = sys.pairSlot.data() + sys.pairStart[r];
      for (int i = sys.start[r]; i < sys.start[r + 1]; ++i) {
        if (sys.key[i] < first) continue;
        for (int j = sys.start[r]; j < sys.start[r + 1]; ++j) {
          if (sys.key[j] < first) continue;
          const int s = *slot++;
          if (s >= 0) values[s] += sys.coefficient[i] * sys.coefficient[j];
        }
      }
    }
    if (symbolic) {
      sys.solver.analyzePattern(sys.normal);
      sys.analysed = true;
    }
    sys.solver.factorize(sys.normal);
    sys.ok = sys.solver.info() == Eigen::Success;
  }

  // Solves for the new vertices given the target Laplacians delta (rows x 3,
  // sum_j omega_rj (x_j - x_r)); returns the RMS residual as a length, or -1.
  double solve(System& sys, const Eigen::MatrixXd& delta, std::vector<Point3>& x) const {
    const int first = int(n_);
    const Eigen::Index rows = Eigen::Index(sys.start.size() - 1);
    // The rows' targets less what the fixed vertices give, weighted as the rows.
    const Eigen::MatrixXd target = sys.rowWeight.asDiagonal() * delta - sys.fixedPart;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(Eigen::Index(uv_.size() - n_), 3);
    for (Eigen::Index r = 0; r < rows; ++r)
      for (int i = sys.start[r]; i < sys.start[r + 1]; ++i)
        if (sys.key[i] >= first) rhs.row(sys.key[i] - first) += sys.coefficient[i] * target.row(r);
    const Eigen::MatrixXd sol = sys.solver.solve(rhs);
    if (sys.solver.info() != Eigen::Success || !sol.allFinite()) return -1;
    for (std::size_t v = n_; v < uv_.size(); ++v)
      for (int d = 0; d < 3; ++d) x[v][d] = sol(Eigen::Index(v - n_), d);
    double sum = 0;
    for (Eigen::Index r = 0; r < rows; ++r) {
      Eigen::RowVector3d residual = -target.row(r);
      for (int i = sys.start[r]; i < sys.start[r + 1]; ++i)
        if (sys.key[i] >= first) residual += sys.coefficient[i] * sol.row(sys.key[i] - first);
      const double length = sys.rowLength[std::size_t(r)] * sys.rowWeight[r];
      if (length > 0) sum += residual.squaredNorm() / (length * length);
    }
    return std::sqrt(sum / double(std::max<Eigen::Index>(1, rows)));
  }

  enum class MembraneWeights {
    Uniform,  // every edge 1 (a Tutte embedding: where nothing better is known)
    Domain,   // cotangents of the patch in its plane
    Shape,    // cotangents of the patch at the positions given
  };

  // The membrane L x = 0 over the new vertices, boundary fixed (symmetric
  // form, weights raised to kPositiveWeightFloor): the harmonic shape, and
  // the flat placement over a disk. Its rows are those of the new vertices
  // alone: the membrane does not see the surface beyond the boundary. Its
  // pattern is the patch's edges between new vertices, ordered once for
  // every weight set.
  struct Membrane {
    Eigen::SparseMatrix<double> matrix;  // lower triangle
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
    bool analysed = false;
  };

  bool membrane(Membrane& m, std::vector<Point3>& x, MembraneWeights kind, double& residual) const {
    const std::size_t unknowns = uv_.size() - n_;
    if (unknowns == 0) return true;
    const int first = int(n_);
    if (!m.analysed) {
      std::vector<std::pair<int, int>> pairs;
      for (std::size_t r = 0; r < unknowns; ++r) {
        const int v = int(n_ + r);
        pairs.push_back({int(r), int(r)});
        for (int t : localAround_[v])
          for (int c : localTriangles_[t])
            if (c > v) pairs.push_back({c - first, int(r)});
      }
      m.matrix = lowerPattern(unknowns, pairs);
    }
    double* values = m.matrix.valuePtr();
    std::fill(values, values + m.matrix.nonZeros(), 0.0);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(Eigen::Index(unknowns), 3);
    std::vector<TriangleWeights> weights;
    if (kind != MembraneWeights::Uniform)
      weights = patchWeights(x, kind == MembraneWeights::Domain);
    LaplacianRow row;
    double diagonal = 0;
    for (std::size_t r = 0; r < unknowns; ++r) {
      const int v = int(n_ + r);
      if (kind == MembraneWeights::Uniform) {
        row.weights.clear();
        for (int t : localAround_[v])
          for (int c : localTriangles_[t])
            if (c != v) row.add(c, 0.5);  // each neighbour on two faces around v: 1
        row.finish();
      } else {
        rowOf(v, weights, row, kPositiveWeightFloor);
      }
      values[slotOf(m.matrix, int(r), int(r))] = row.total;
      diagonal += row.total;
      for (const auto& [key, w] : row.weights) {
        if (key > v)
          values[slotOf(m.matrix, key - first, int(r))] -= w;
        else if (key < first)
          for (int d = 0; d < 3; ++d) rhs(Eigen::Index(r), d) += w * x[key][d];
      }
    }
    if (!m.analysed) {
      m.solver.analyzePattern(m.matrix);
      m.analysed = true;
    }
    m.solver.factorize(m.matrix);
    if (m.solver.info() != Eigen::Success) return false;
    const Eigen::MatrixXd sol = m.solver.solve(rhs);
    if (m.solver.info() != Eigen::Success || !sol.allFinite()) return false;
    for (std::size_t v = n_; v < uv_.size(); ++v)
      for (int d = 0; d < 3; ++d) x[v][d] = sol(Eigen::Index(v - n_), d);
    const Eigen::MatrixXd res = m.matrix.selfadjointView<Eigen::Lower>() * sol - rhs;
    residual = std::sqrt(res.squaredNorm() / double(unknowns)) /
               std::max(1e-300, diagonal / double(unknowns));
    return true;
  }

  // Mean curvature from the rings around the hole, learnt by LS-SVM (§3.3).
  // The samples are H at each ring vertex, from its cotangent Laplacian:
  // sum_j omega_ij (x_j - x_i) = -4 A_i H_i n_i (Meyer et al.).
  bool learnCurvature(LsSvm& model, Eigen::Vector3d& centre, double& scale,
                      HoleReport& report) const {
    centre.setZero();
    for (int g : front_) centre += toEigen(s_.points[g]);
    centre /= double(n_);
    scale = 0;
    for (int g : front_) scale += (toEigen(s_.points[g]) - centre).squaredNorm();
    scale = std::sqrt(scale / double(n_));
    if (!(scale > 0)) return false;
    std::unordered_set<int> seen(front_.begin(), front_.end());
    std::vector<int> ring(front_.begin(), front_.end()), samples;
    for (int level = 0; level < options_.regression_rings; ++level) {
      std::vector<int> nextRing;
      for (int v : ring)
        s_.adjacency->forEach(v, [&](int f) {
          for (int c : s_.triangles[f])
            if (seen.insert(c).second) nextRing.push_back(c);
        });
      samples.insert(samples.end(), nextRing.begin(), nextRing.end());
      ring = std::move(nextRing);
    }
    std::vector<Eigen::Vector3d> xs;
    std::vector<double> ys;
    const std::size_t stride = std::max<std::size_t>(
        1, (samples.size() + std::size_t(options_.regression_max_samples) - 1) /
               std::size_t(options_.regression_max_samples));
    for (std::size_t i = 0; i < samples.size(); i += stride) {
      const int v = samples[i];
      // Only vertices inside the surface (a closed fan: each neighbour on two faces).
      std::unordered_map<int, int> count;
      LaplacianRow row;
      Point3 n(0, 0, 0);
      double area = 0;
      s_.adjacency->forEach(v, [&](int f) {
        const Triangle& t = s_.triangles[f];
        int corner = 0;
        while (t[corner] != v) ++corner;
        for (int c : t)
          if (c != v) ++count[c];
        addTriangleToRow(row, {t[0], t[1], t[2]},
                         {s_.points[t[0]], s_.points[t[1]], s_.points[t[2]]}, corner);
        const Point3 fn = faceNormal(s_.points, t);
        n += fn;
        area += fn.Norm() / 6;
      });
      bool closedFan = !count.empty();
      for (const auto& [c, k] : count) closedFan = closedFan && k == 2;
      if (!closedFan || !(area > 0) || !(n.Norm() > 0)) continue;
      // Raised weights: one sliver in a scan's ring must not make its
      // vertex's curvature sample an outlier the regression then spreads.
      row.finish(kPositiveWeightFloor);
      Point3 sum(0, 0, 0);
      for (const auto& [c, w] : row.weights) sum += (s_.points[c] - s_.points[v]) * w;
      n.Normalize();
      const double H = -(sum * n) / (4 * area);
      if (!std::isfinite(H)) continue;
      xs.push_back((toEigen(s_.points[v]) - centre) / scale);
      ys.push_back(H * scale);
    }
    report.training_samples = xs.size();
    return model.fit(xs, ys, 2.5, options_.regression_gamma);
  }

  // `fromShape`: the positions given are already near the shape (the first
  // weights come from them, not from the domain).
  bool fair(HoleFairing mode, PatchShape& shape, HoleReport& report, bool fromShape = false) {
    std::vector<Point3>& x = shape.positions;
    if (uv_.size() == n_) return true;  // nothing to place
    if (mode == HoleFairing::Harmonic) {
      double residual = 0;
      Membrane m;
      if (!membrane(m, x, MembraneWeights::Domain, residual)) return false;
      // Weights from the membrane's own shape, then solved again.
      if (!membrane(m, x, MembraneWeights::Shape, residual)) return false;
      shape.residual = residual;
      return true;
    }
    // First weights from the patch in its domain (or from the shape given), then from the shape.
    System sys;
    assemble(sys, rowVertex_, x, !fromShape);
    if (!sys.ok) return false;
    Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(Eigen::Index(rowVertex_.size()), 3);
    if (solve(sys, zero, x) < 0) return false;
    assemble(sys, rowVertex_, x, false);
    if (!sys.ok) return false;
    double residual = solve(sys, zero, x);
    if (residual < 0) return false;
    if (mode == HoleFairing::LaplacianRegression) {
      LsSvm model;
      Eigen::Vector3d centre;
      double scale = 1;
      if (learnCurvature(model, centre, scale, report)) {
        // Predictions stay within the curvatures seen around the hole (the
        // 5th to 95th percentile): scan noise learned near the border must
        // not extrapolate into a balloon in the middle of a large hole.
        std::vector<double> seen = model.targets();
        std::sort(seen.begin(), seen.end());
        const double low = seen[seen.size() / 20] / scale,
                     high = seen[seen.size() - 1 - seen.size() / 20] / scale;
        std::vector<double> curvature(rowVertex_.size());
        for (std::size_t r = 0; r < rowVertex_.size(); ++r)
          curvature[r] = std::clamp(
              model.predict((toEigen(x[rowVertex_[r]]) - centre) / scale) / scale, low, high);
        Eigen::MatrixXd delta(Eigen::Index(rowVertex_.size()), 3);
        for (int iteration = 0; iteration < 3; ++iteration) {
          for (std::size_t r = 0; r < rowVertex_.size(); ++r) {
            const auto [n, area] = normalAndArea(rowVertex_[r], x);
            const Point3 d = n * (-4 * area * curvature[r]);
            for (int k = 0; k < 3; ++k) delta(Eigen::Index(r), k) = d[k];
          }
          std::vector<Point3> trial = x;
          const double res = solve(sys, delta, trial);
          if (res < 0) break;
          x = std::move(trial);
          residual = res;
        }
      } else {
        report.reason = "too few surface vertices around the hole to learn its curvature from";
        shape.fairing = HoleFairing::Biharmonic;
      }
    }
    shape.residual = residual / meanEdge_;
    return true;
  }

  void commit(const PatchShape& shape, HoleReport& report) {
    for (std::size_t v = n_; v < shape.positions.size(); ++v)
      s_.points.push_back(shape.positions[v]);
    for (const Triangle& t : patchTriangles_) {
      const int f = int(s_.triangles.size());
      s_.triangles.push_back(t);
      s_.inputFaceOf.push_back(-1);
      s_.patchFaces.push_back(f);
      for (int v : t) s_.adjacency->add(v, f);
    }
    for (std::size_t k = 0; k < n_; ++k)
      s_.borderOwner.erase(directedKey(front_[(k + 1) % n_], front_[k]));
    report.faces_added = patchTriangles_.size();
    report.vertices_added += shape.positions.size() - n_;
    report.fairing = shape.fairing;
    report.fairing_residual = shape.residual;
  }

  Surface& s_;
  const HoleFillOptions& options_;
  const std::unordered_set<int>& pinched_;
  HoleFillResult::StageTimes& times_;
  std::size_t n_ = 0;
  double meanEdge_ = 0;
  std::vector<int> front_;                 // boundary vertices (mesh indices), front order
  std::unordered_map<int, int> local_;     // boundary vertex -> local index
  std::vector<Vec2> uv_;                   // patch vertices in the domain
  std::vector<double> height_;             // over the plane (planar domains)
  std::vector<Triangle> localTriangles_;   // patch faces, local indices
  std::vector<Triangle> patchTriangles_;   // the same in mesh numbering
  TrianglesAround localAround_;            // patch faces around each local vertex
  std::vector<int> rowVertex_;             // Laplacian rows: new vertices, then boundary ones
  std::vector<LaplacianRow> outsideRows_;  // boundary rows' mesh part
  std::vector<char> hasOutsideRow_;
};

// Everything but the coordinates, which fillHoles checks as it copies them
// (and reports first, through requireFacesAndFiniteCoordinates, when one is
// not finite).
void validateCompactnessAndOptions(const Mesh& mesh, const HoleFillOptions& o) {
  if (std::size_t(mesh.vn) != mesh.vert.size() || std::size_t(mesh.fn) != mesh.face.size())
    throw InvalidInputError(
        "the mesh has deleted vertices or faces; compact it first (MeshLab does when saving, or "
        "run \"Remove Unreferenced Vertices\")");
  auto bad = [](const std::string& what) { throw InvalidInputError("fill holes: " + what); };
  if (!(o.max_diameter >= 0)) bad("max_diameter must be 0 (no limit) or positive");
  if (!(o.long_edge_factor == 0 || o.long_edge_factor > 1))
    bad("long_edge_factor must be 0 (off) or greater than 1");
  if (!(o.size_growth >= 1 && o.size_growth <= 4)) bad("size_growth must be between 1 and 4");
  if (!(o.max_size_factor >= 1)) bad("max_size_factor must be at least 1");
  if (!(o.merge_distance > 0 && o.merge_distance < 1)) bad("merge_distance must be in (0, 1)");
  if (o.regression_rings < 1) bad("regression_rings must be at least 1");
  if (!(o.regression_gamma > 0)) bad("regression_gamma must be positive");
  if (o.regression_max_samples < 8) bad("regression_max_samples must be at least 8");
  if (!o.selected_vertices.empty() && o.selected_vertices.size() != mesh.vert.size())
    bad("selected_vertices has " + std::to_string(o.selected_vertices.size()) +
        " flags but the mesh has " + std::to_string(mesh.vert.size()) + " vertices");
  for (int v : o.selected_vertex_indices)
    if (v < 0 || std::size_t(v) >= mesh.vert.size())
      bad("selected vertex " + std::to_string(v) + " is not a vertex of the mesh");
}

}  // namespace

HoleFillResult fillHoles(Mesh& mesh, const HoleFillOptions& options) {
  const auto start = Clock::now();
  // A mesh without faces or with deleted elements is refused before
  // anything is read from its faces.
  if (mesh.fn == 0 || std::size_t(mesh.vn) != mesh.vert.size() ||
      std::size_t(mesh.fn) != mesh.face.size()) {
    requireFacesAndFiniteCoordinates(mesh, "the mesh");
    validateCompactnessAndOptions(mesh, options);
  }
  HoleFillResult result;
  reportProgress(options.progress, 0, "Finding holes");

  Surface s;
  s.roundToFloat = options.round_to_float;
  // The copy of the mesh, with room for the patches (each is appended for
  // its check, and a reallocation would copy the whole mesh); one pass over
  // the points also checks them, one over the faces also counts the faces
  // at each vertex. (Copying on two cores gains nothing: both threads
  // wait on the page faults of the fresh arrays.)
  s.points.reserve(mesh.vert.size() + mesh.vert.size() / 8 + 4096);
  s.triangles.reserve(mesh.face.size() + mesh.face.size() / 8 + 8192);
  double notFinite = 0;  // x - x is 0 for a finite x, NaN otherwise: the sum stays 0 if all are
  s.points.resize(mesh.vert.size());
  Point3* toPoint = s.points.data();
  for (const Vertex& v : mesh.vert) {
    const Point3& p = v.cP();
    notFinite += (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]);
    *toPoint++ = p;
  }
  s.triangles.resize(mesh.face.size());
  Triangle* toTriangle = s.triangles.data();
  const Vertex* firstVertex = mesh.vert.data();
  std::vector<int> cornerCounts(mesh.vert.size() + 1, 0);
  int* count = cornerCounts.data();
  for (const Face& face : mesh.face) {
    const Triangle t = {int(face.cV(0) - firstVertex), int(face.cV(1) - firstVertex),
                        int(face.cV(2) - firstVertex)};
    *toTriangle++ = t;
    ++count[t[0]];
    ++count[t[1]];
    ++count[t[2]];
  }
  s.adjacency = std::make_unique<VertexFaces>(s.triangles, std::move(cornerCounts));
  if (notFinite != 0) requireFacesAndFiniteCoordinates(mesh, "the mesh");  // throws, naming it
  validateCompactnessAndOptions(mesh, options);
  s.inputVertices = s.points.size();
  s.inputFaces = s.triangles.size();
  const BorderLoops found = findBorderLoops(s.points, s.triangles, *s.adjacency);
  result.holes_found = found.loops.size();
  if (found.loops.empty()) {
    reportProgress(options.progress, 100, "Done");
    result.verified = true;  // nothing new
    if (options.verify) {
      result.remaining_intersecting_pairs =
          storedIntersectingPairs(MeshArrays{s.points, s.triangles},
                                  options.round_to_float ? Scalar::kFloat : Scalar::kDouble);
      result.remaining_counted = true;
    }
    result.time_ms = msSince(start);
    return result;
  }
  for (const BorderLoop& loop : found.loops) {
    const std::size_t count = loop.vertices.size();
    for (std::size_t i = 0; i < loop.faces.size(); ++i)
      s.borderOwner[directedKey(loop.vertices[i], loop.vertices[(i + 1) % count])] = loop.faces[i];
  }
  // Which holes to fill (the bounding box and the selection only when a limit needs them).
  double diagonal = 0;
  if (options.max_diameter > 0) {
    Point3 lo = s.points[0], hi = s.points[0];
    for (const Point3& p : s.points)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    diagonal = (hi - lo).Norm();
  }
  const bool bySelection =
      !options.selected_vertices.empty() || !options.selected_vertex_indices.empty();
  std::vector<char> selected(bySelection ? s.points.size() : 0, 0);
  for (std::size_t v = 0; v < options.selected_vertices.size(); ++v)
    if (options.selected_vertices[v]) selected[v] = 1;
  for (int v : options.selected_vertex_indices) selected[v] = 1;

  std::vector<std::vector<int>> loops;
  std::vector<std::size_t> toFill;
  for (const BorderLoop& loop : found.loops) {
    HoleReport report;
    report.boundary = loop.vertices;
    report.boundary_edges = loop.closed ? loop.vertices.size() : loop.vertices.size() - 1;
    report.diameter = loopDiameter(s.points, loop.vertices);
    const std::size_t index = result.holes.size();
    if (!loop.closed)
      report.reason = "its border is not a closed loop: at vertex " +
                      std::to_string(loop.brokenAt) +
                      " the faces are non-manifold or inconsistently oriented (repair them first)";
    else if (loop.vertices.size() < 3)
      report.reason = "a border of two edges (a slit between two faces): weld or stitch it instead";
    else if (options.max_boundary_edges > 0 && report.boundary_edges > options.max_boundary_edges)
      report.reason = "larger than the limit: " + std::to_string(report.boundary_edges) + " > " +
                      std::to_string(options.max_boundary_edges) + " boundary edges";
    else if (options.max_diameter > 0 && report.diameter > options.max_diameter * diagonal)
      report.reason = "wider than the limit: diameter " +
                      std::to_string(report.diameter / diagonal) + " > " +
                      std::to_string(options.max_diameter) + " of the bounding box diagonal";
    else if (bySelection && std::none_of(loop.vertices.begin(), loop.vertices.end(),
                                         [&](int v) { return selected[v]; }))
      report.reason = "not selected (no selected vertex on its border)";
    else
      toFill.push_back(index);
    result.holes.push_back(std::move(report));
    loops.push_back(loop.vertices);
  }

  result.stage_ms.find = msSince(start);
  HoleFiller filler(s, options, found.pinched, result.stage_ms);
  for (std::size_t i = 0; i < toFill.size(); ++i) {
    reportProgress(options.progress, int(5 + 85 * i / toFill.size()), "Filling holes");
    const auto holeStart = Clock::now();
    HoleReport& report = result.holes[toFill[i]];
    std::vector<int> loop = loops[toFill[i]];
    Checkpoint undo;
    undo.points = s.points.size();
    undo.triangles = s.triangles.size();
    undo.splitFaces = s.splitFaces.size();
    const auto splitStart = Clock::now();
    report.edges_split = splitLongEdges(s, loop, options.long_edge_factor, undo);
    result.stage_ms.split += msSince(splitStart);
    report.vertices_added = report.edges_split;
    std::vector<int> splitFaces(s.splitFaces.begin() + std::ptrdiff_t(undo.splitFaces),
                                s.splitFaces.end());
    for (const auto& [f, corners] : undo.changedFaces) splitFaces.push_back(f);
    if (filler.fill(loop, splitFaces, report)) {
      report.filled = true;
      if (report.fairing != options.fairing) ++result.fallbacks;
    } else {
      restore(s, undo);
      report.edges_split = 0;
      report.vertices_added = 0;
      report.faces_added = 0;
    }
    report.time_ms = msSince(holeStart);
  }

  for (const HoleReport& r : result.holes) {
    if (r.filled) {
      ++result.holes_filled;
      result.faces_added += r.faces_added;
      result.vertices_added += r.vertices_added;
      result.edges_split += r.edges_split;
    } else {
      ++result.holes_skipped;
    }
  }
  // The output stage (output_stage.h): the new vertices as the host
  // stores them, every pair with a patch or split face checked exactly on
  // those values, re-rounded where rounding made one cross (the patches'
  // own checks ran on the stored values: nothing to do, as a rule).
  {
    reportProgress(options.progress, 92, "Checking the stored result");
    const auto verifyStart = Clock::now();
    std::vector<char> movable(s.points.size(), 0), isChanged(s.triangles.size(), 0);
    for (std::size_t v = s.inputVertices; v < s.points.size(); ++v) movable[v] = 1;
    for (int f : s.patchFaces) isChanged[std::size_t(f)] = 1;
    for (int f : s.splitFaces) isChanged[std::size_t(f)] = 1;
    for (const auto& [f, corners] : s.inputCorners) isChanged[std::size_t(f)] = 1;
    OutputStageOptions stage;
    stage.scalar = options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
    stage.progress = progressWithin(options.progress, 92, 96);
    result.stored = storeNewPoints(s.points, s.triangles, movable, isChanged, stage);
    result.new_intersecting_pairs = result.stored.crossing;
    result.verified = true;
    if (options.verify) {  // the whole result, by the checker's rule
      result.remaining_intersecting_pairs =
          storedIntersectingPairs(MeshArrays{s.points, s.triangles}, stage.scalar);
      result.remaining_counted = true;
    }
    result.stage_ms.verify = msSince(verifyStart);
  }

  // Write back: split faces change corners, new vertices and faces are appended.
  reportProgress(options.progress, 97, "Writing");
  const auto writeStart = Clock::now();
  if (s.points.size() > s.inputVertices || s.triangles.size() > s.inputFaces) {
    VertexOriginHandle vo = vertexOrigins(mesh);
    FaceOriginHandle fo = faceOrigins(mesh);
    const int layer = mesh.vert.empty() ? 0 : std::max(0, vo[0].layer);
    // Origins of the input faces that split vertices and faces come from,
    // read before adding elements moves the attribute's storage.
    std::unordered_map<int, FaceOrigin> inputOrigins;
    for (const auto& [v, origin] : s.splitOrigins)
      inputOrigins.emplace(origin.face, fo[origin.face]);
    for (int f : s.inputFaceOf)
      if (f >= 0) inputOrigins.emplace(f, fo[f]);
    const std::size_t newVertices = s.points.size() - s.inputVertices;
    const std::size_t newFaces = s.triangles.size() - s.inputFaces;
    // Each array grows here, once, to its final size: a move of the whole
    // mesh into fresh memory, as costly as the rest of the write together,
    // so the faces with their origins move on this core and the vertices
    // with theirs on the other. (Grown by AddVertices, the vertex array
    // would move with vcglib correcting every face's corner pointers one by
    // one; instead the faces' corners are set afresh, in parallel, from the
    // indices held below.)
    // The faces' corners are pointers: once the vertex array has moved,
    // every input face is pointed at its input corners in the new array,
    // before anything else can fail, so that an error in the reserves or
    // later leaves the faces as they were.
    const Vertex* before = mesh.vert.data();
    auto pointFacesAtInputCorners = [&] {
      Vertex* const first = mesh.vert.data();
      if (first == before) return;
      Face* const faces = mesh.face.data();
      const Triangle* const corners = s.triangles.data();
      auto repoint = [&](std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f < end; ++f) {
          const Triangle& t = corners[f];
          Face& face = faces[f];
          face.V(0) = first + t[0];
          face.V(1) = first + t[1];
          face.V(2) = first + t[2];
        }
      };
      try {
        parallelChunks(s.inputFaces,
                       [&](std::size_t begin, std::size_t end, unsigned) { repoint(begin, end); });
      } catch (...) {  // no memory for the workers' bookkeeping: the plain loop cannot fail
        repoint(0, s.inputFaces);
      }
      // Faces a split changed keep their input corners until the new vertices exist.
      for (const auto& [f, input] : s.inputCorners)
        for (int k = 0; k < 3; ++k) faces[f].V(k) = first + input[k];
      before = first;
    };
    try {
      parallelChunks(
          2,
          [&](std::size_t begin, std::size_t end, unsigned) {
            for (std::size_t part = begin; part < end; ++part)
              if (part == 0) {
                mesh.face.reserve(s.triangles.size());
                fo._handle->data.reserve(s.triangles.size());
              } else {
                mesh.vert.reserve(s.points.size());
                vo._handle->data.reserve(s.points.size());
              }
          },
          1);
    } catch (...) {
      pointFacesAtInputCorners();
      throw;
    }
    pointFacesAtInputCorners();
    if (newVertices > 0) {
      auto vi = vcg::tri::Allocator<Mesh>::AddVertices(mesh, newVertices);
      for (std::size_t v = s.inputVertices; v < s.points.size(); ++v, ++vi) {
        vi->P() = s.points[v];
        const auto split = s.splitOrigins.find(int(v));
        if (split != s.splitOrigins.end()) {
          const FaceOrigin& of = inputOrigins.at(split->second.face);
          vo[v] = VertexOrigin{of.layer, -1, of.face, split->second.barycentric};
        } else {
          vo[v] = VertexOrigin{layer, -1, -1, {0, 0, 0}};
        }
        result.new_vertices.push_back(int(v));
      }
      // A patch vertex takes the origin of the border vertex nearest to it
      // along the patch's edges: colours, quality and texture coordinates
      // then continue into the patch instead of leaving it blank.
      auto inPatch = [&](int v) {
        return std::size_t(v) >= s.inputVertices && !s.splitOrigins.count(v);
      };
      std::vector<std::vector<int>> neighbours(newVertices);
      for (int f : s.patchFaces)
        for (int k = 0; k < 3; ++k) {
          const int a = s.triangles[f][k], b = s.triangles[f][(k + 1) % 3];
          if (inPatch(a)) neighbours[std::size_t(a) - s.inputVertices].push_back(b);
          if (inPatch(b)) neighbours[std::size_t(b) - s.inputVertices].push_back(a);
        }
      std::vector<int> border(newVertices, -1), queue;
      for (std::size_t i = 0; i < newVertices; ++i)
        for (int w : neighbours[i])
          if (!inPatch(w)) {
            border[i] = w;
            queue.push_back(int(i));
            break;
          }
      for (std::size_t head = 0; head < queue.size(); ++head) {
        const int i = queue[head];
        for (int w : neighbours[std::size_t(i)])
          if (inPatch(w) && border[std::size_t(w) - s.inputVertices] < 0) {
            border[std::size_t(w) - s.inputVertices] = border[std::size_t(i)];
            queue.push_back(int(std::size_t(w) - s.inputVertices));
          }
      }
      for (std::size_t i = 0; i < newVertices; ++i)
        if (border[i] >= 0 && inPatch(int(s.inputVertices + i)))
          vo[s.inputVertices + i] = vo[border[i]];
    }
    // The faces a split changed take their new corners (the vertex array
    // no longer moves: it was reserved above).
    for (const auto& [f, corners] : s.inputCorners)
      for (int k = 0; k < 3; ++k) mesh.face[f].V(k) = &mesh.vert[s.triangles[f][k]];
    if (newFaces > 0) {
      auto fi = vcg::tri::Allocator<Mesh>::AddFaces(mesh, newFaces);
      for (std::size_t f = s.inputFaces; f < s.triangles.size(); ++f, ++fi) {
        for (int k = 0; k < 3; ++k) fi->V(k) = &mesh.vert[s.triangles[f][k]];
        const int from = s.inputFaceOf[f - s.inputFaces];
        fo[f] = from >= 0 ? inputOrigins.at(from) : FaceOrigin{layer, -1};
      }
    }
    result.new_faces = s.patchFaces;
  }
  result.stage_ms.write = msSince(writeStart);
  reportProgress(options.progress, 100, "Done");
  result.time_ms = msSince(start);
  return result;
}

JsonObject toJson(const HoleFillResult& r) {
  std::vector<JsonObject> skipped, holes;
  for (std::size_t i = 0; i < r.holes.size(); ++i) {
    const HoleReport& h = r.holes[i];
    JsonObject j;
    j.set("hole", i)
        .set("boundary_vertices", h.boundary.size())
        .set("boundary_edges", h.boundary_edges)
        .set("diameter", h.diameter)
        .set("filled", h.filled);
    if (h.filled)
      j.set("edges_split", h.edges_split)
          .set("faces_added", h.faces_added)
          .set("vertices_added", h.vertices_added)
          .set("fairing", toString(h.fairing))
          .set("planar_domain", h.planar_domain)
          .set("fairing_residual", h.fairing_residual)
          .set("training_samples", h.training_samples);
    if (!h.reason.empty()) j.set("reason", h.reason);
    j.set("time_ms", h.time_ms);
    holes.push_back(j);
    if (!h.filled)
      skipped.push_back(JsonObject()
                            .set("hole", i)
                            .set("boundary_edges", h.boundary_edges)
                            .set("reason", h.reason));
  }
  JsonObject j;
  j.set("holes_found", r.holes_found)
      .set("holes_filled", r.holes_filled)
      .set("holes_skipped", r.holes_skipped)
      .set("skipped", skipped)
      .set("faces_added", r.faces_added)
      .set("vertices_added", r.vertices_added)
      .set("edges_split", r.edges_split)
      .set("fallbacks", r.fallbacks);
  if (r.verified)
    j.set("new_intersecting_pairs", r.new_intersecting_pairs);
  else
    j.setNull("new_intersecting_pairs");
  if (r.remaining_counted) j.set("remaining_intersecting_pairs", r.remaining_intersecting_pairs);
  const auto& t = r.stage_ms;
  j.set("time_ms", r.time_ms)
      .set("stage_ms", JsonObject()
                           .set("find", t.find)
                           .set("split", t.split)
                           .set("triangulate", t.triangulate)
                           .set("fair", t.fair)
                           .set("check", t.check)
                           .set("verify", t.verify)
                           .set("write", t.write))
      .set("holes", holes);
  return j;
}

}  // namespace meshmend
