#include "common/repair/holes/front.h"

#include <cmath>

#include <algorithm>
#include <memory>
#include <numeric>
#include <queue>
#include <unordered_set>

namespace meshmend::holes {

namespace {

// A count estimated from measures, clamped before converting: near the
// limits of double the measures overflow to infinity or NaN, which have no
// integer (NaN counts as none; the front's checks refuse such a hole).
std::size_t countOf(double estimate) {
  constexpr double kMost = 1e15;
  return estimate > 0 ? std::size_t(std::min(estimate, kMost)) : 0;
}

// The front of advanceFront (front.h): nodes in doubly linked loops, a
// heap of nodes by interior angle, and grids of the front's vertices and
// edges for the exact validity tests of each new triangle.
class AdvancingFront {
 public:
  using Settings = FrontSettings;

  std::vector<Vec2> uv;                    // boundary vertices first, then new ones
  std::vector<double> size;                // target edge length at each vertex
  std::vector<std::array<int, 2>> parent;  // new vertices: the front edge they were built on
  std::vector<Triangle> triangles;         // counter-clockwise in the plane

  AdvancingFront(const std::vector<Vec2>& boundary, const std::vector<double>& boundarySize,
                 const std::vector<std::pair<int, int>>& existingEdges, Settings settings)
      : uv(boundary), size(boundarySize), settings_(settings) {
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
    const std::size_t expected = countOf(area / (0.43 * cell * cell)) + n;
    points_ = std::make_unique<Grid>(lo, hi, cell, 2 * expected + 16);
    edgeGrid_ = std::make_unique<Grid>(lo, hi, cell, 2 * expected + 16);
    budget_ = std::min(8 * (countOf(area / (0.43 * minSize_ * minSize_)) + 4 * n) + 1000,
                       settings.maxTriangles);
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
  // Whether a grid entry still names a front edge / node (once gone, they
  // never come back: a node's edge that changes gets a new record).
  auto liveRecord() const {
    return [this](int id) { return liveEdge(edgeRecords_[std::size_t(id)]); };
  }
  auto liveNode() const {
    return [this](int n) { return nodes_[std::size_t(n)].alive; };
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
    edgeGrid_->queryLive(boxLo(pa, pb), boxHi(pa, pb), liveRecord(), [&](int id) {
      if (!clear) return;
      const EdgeRecord& r = edgeRecords_[std::size_t(id)];
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
    points_->queryLive(lo, hi, liveNode(), [&](int n) {
      if (!empty) return;
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
    if (!closesNext && (edges_.contains(edgeKey(b, c)) || !edgeIsClear(b, c))) return -1;
    if (!closesPrev && (edges_.contains(edgeKey(c, a)) || !edgeIsClear(c, a))) return -1;
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
    points_->queryLive(p - Vec2{radius, radius}, p + Vec2{radius, radius}, liveNode(), [&](int n) {
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
    edgeGrid_->queryLive(p - Vec2{limit, limit}, p + Vec2{limit, limit}, liveRecord(), [&](int id) {
      if (near) return;
      const EdgeRecord& r = edgeRecords_[std::size_t(id)];
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
  EdgeSet edges_;
  std::unique_ptr<Grid> points_, edgeGrid_;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap_;
};

}  // namespace

TrianglesAround::TrianglesAround(const std::vector<Triangle>& triangles, std::size_t vertexCount) {
  start_.assign(vertexCount + 1, 0);
  for (const Triangle& t : triangles)
    for (int v : t) ++start_[std::size_t(v) + 1];
  std::partial_sum(start_.begin(), start_.end(), start_.begin());
  triangles_.resize(std::size_t(start_.back()));
  std::vector<int> next(start_.begin(), start_.end() - 1);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t]) triangles_[std::size_t(next[std::size_t(v)]++)] = int(t);
}

namespace {

// A domain whose coordinates leave 1e-50..1e50 (nonzero) makes every
// orientation test of the front fall to GMP: such a domain is run centred
// and scaled to unit size (coordinates below 1e-40 of it taken as 0), and
// its new vertices mapped back. Other domains run as they are.
bool needsNormalising(const std::vector<Vec2>& uv) {
  for (const Vec2& p : uv)
    for (double c : {p.x, p.y}) {
      const double m = std::fabs(c);
      if (m != 0 && (m < 1e-50 || m > 1e50)) return true;
    }
  return false;
}

Front runFront(const std::vector<Vec2>& boundary, const std::vector<double>& sizes,
               const std::vector<std::pair<int, int>>& existingEdges,
               const FrontSettings& settings) {
  AdvancingFront front(boundary, sizes, existingEdges, settings);
  Front out;
  out.covered = front.run();
  out.uv = std::move(front.uv);
  out.size = std::move(front.size);
  out.parent = std::move(front.parent);
  out.triangles = std::move(front.triangles);
  return out;
}

}  // namespace

Front advanceFront(const std::vector<Vec2>& boundary, const std::vector<double>& sizes,
                   const std::vector<std::pair<int, int>>& existingEdges,
                   const FrontSettings& settings) {
  if (boundary.empty() || !needsNormalising(boundary))
    return runFront(boundary, sizes, existingEdges, settings);
  Vec2 lo = boundary[0], hi = boundary[0];
  for (const Vec2& p : boundary) lo = boxLo(lo, p), hi = boxHi(hi, p);
  const Vec2 centre = 0.5 * (lo + hi);
  const double extent = std::max(hi.x - lo.x, hi.y - lo.y);
  if (!(extent > 0) || !std::isfinite(extent))
    return runFront(boundary, sizes, existingEdges, settings);
  const double scale = 1 / extent, back = extent;
  auto local = [&](double c) { return std::fabs(c) < 1e-40 ? 0.0 : c; };
  std::vector<Vec2> uv;
  for (const Vec2& p : boundary)
    uv.push_back({local((p.x - centre.x) * scale), local((p.y - centre.y) * scale)});
  std::vector<double> localSizes;
  for (double s : sizes) localSizes.push_back(s * scale);
  FrontSettings localSettings = settings;
  localSettings.maxSize = std::min(settings.maxSize * scale, 1e300);
  Front out = runFront(uv, localSizes, existingEdges, localSettings);
  for (std::size_t v = 0; v < out.uv.size(); ++v)
    out.uv[v] = v < boundary.size() ? boundary[v] : centre + back * out.uv[v];
  for (double& s : out.size) s *= back;
  return out;
}

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

}  // namespace meshmend::holes
