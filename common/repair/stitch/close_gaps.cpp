// Closing gaps between borders: border vertices within a distance merged,
// then the remaining gaps stitched, each checked before it is applied.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <future>
#include <memory>
#include <numeric>
#include <queue>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "common/base/border_loops.h"
#include "common/base/errors.h"
#include "common/exact/box_tree.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"
#include "common/repair/stitch/detail.h"

namespace meshmend {

using namespace stitch_detail;

namespace {

// Points within a distance of a query: a uniform grid (cell = the
// distance), or exact coordinate buckets for distance 0.
class NearPoints {
 public:
  NearPoints(const std::vector<Point3>& points, const std::vector<int>& ids, double radius)
      : points_(points), radius_(radius) {
    for (int id : ids) cells_[keyOf(points[id])].push_back(id);
  }
  template <class Visit>
  void near(const Point3& q, Visit&& visit) const {
    if (radius_ <= 0) {
      const auto it = cells_.find(keyOf(q));
      if (it != cells_.end())
        for (int id : it->second)
          if (points_[id] == q) visit(id);
      return;
    }
    const auto c = cellOf(q);
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(hash({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (int id : it->second)
            if ((points_[id] - q).SquaredNorm() <= radius_ * radius_) visit(id);
        }
  }
  // Points within `radius` of q, which may exceed the cell (a few cells
  // further; a cell may be visited twice where two hash alike).
  template <class Visit>
  void near(const Point3& q, double radius, Visit&& visit) const {
    const long reach = std::max(1L, cellIndex(std::ceil(radius / radius_)));
    const auto c = cellOf(q);
    for (long dx = -reach; dx <= reach; ++dx)
      for (long dy = -reach; dy <= reach; ++dy)
        for (long dz = -reach; dz <= reach; ++dz) {
          const auto it = cells_.find(hash({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (int id : it->second)
            if ((points_[id] - q).SquaredNorm() <= radius * radius) visit(id);
        }
  }

 private:
  // A coordinate's cell, clamped to what a long holds (a coordinate over
  // the radius may overflow to infinity, and converting that is undefined).
  static long cellIndex(double x) {
    return x == x ? long(std::clamp(std::floor(x), -4e18, 4e18)) : 0;
  }
  std::array<long, 3> cellOf(const Point3& p) const {
    return {cellIndex(p[0] / radius_), cellIndex(p[1] / radius_), cellIndex(p[2] / radius_)};
  }
  static std::uint64_t hash(const std::array<long, 3>& c) {
    std::uint64_t h = 0;
    for (long x : c) h = (h ^ std::uint64_t(x)) * 0x9E3779B97F4A7C15ull, h ^= h >> 29;
    return h;
  }
  std::uint64_t keyOf(const Point3& p) const {
    if (radius_ > 0) return hash(cellOf(p));
    std::uint64_t h = 0;
    for (int k = 0; k < 3; ++k) {
      const double x = p[k] == 0 ? 0.0 : p[k];
      std::uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      h = (h ^ bits) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 32;
    }
    return h;
  }
  const std::vector<Point3>& points_;
  double radius_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

struct BorderEdge {
  int from, to, face;
};

std::vector<BorderEdge> borderEdgesDirected(const std::vector<Triangle>& T) {
  const std::vector<EdgeUse> uses = edgeUses(T);
  std::vector<BorderEdge> out;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    if (j - i == 1) {
      const Triangle& t = T[uses[i].face];
      out.push_back({t[uses[i].corner], t[(uses[i].corner + 1) % 3], uses[i].face});
    }
    i = j;
  }
  return out;
}

// Union-find over indices, with path halving.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int root(int v) {
    while (parent_[v] != v) v = parent_[v] = parent_[parent_[v]];
    return v;
  }
  void join(int from, int into) { parent_[root(from)] = root(into); }

 private:
  std::vector<int> parent_;
};

// Border vertices that coincide (exactly, or within the tolerance, through
// chains of such pairs) share a class: classOf[v] is its representative,
// v itself for a vertex on no border edge.
std::vector<int> coincidenceClasses(const std::vector<Point3>& P,
                                    const std::vector<BorderEdge>& border, double tolerance) {
  const int n = int(P.size());
  std::vector<int> borderVertices;
  {
    std::vector<char> on(n, 0);
    for (const BorderEdge& e : border) on[e.from] = on[e.to] = 1;
    for (int v = 0; v < n; ++v)
      if (on[v]) borderVertices.push_back(v);
  }
  DisjointSets sets(P.size());
  const NearPoints near(P, borderVertices, tolerance);
  for (int v : borderVertices) near.near(P[v], [&](int w) { sets.join(w, v); });
  std::vector<int> classOf(n);
  for (int v = 0; v < n; ++v) classOf[v] = sets.root(v);
  return classOf;
}

// Faces flipped so that faces meeting at an edge run it opposite ways,
// where "meeting" counts coincident border vertices as one: the facets of a
// soup whose neighbours face the other way (some CAD exports) can then be
// merged. Only edges with exactly two faces propagate the orientation. A
// connected part that needed no flip is left as it is; one that did keeps,
// if it is closed (every edge has a second face), the orientation whose
// signed volume is positive (outward), else the orientation of most of its
// area as given.
void orientConsistently(const std::vector<Point3>& P, std::vector<Triangle>& T,
                        const std::vector<int>& classOf, CloseGapsResult& r) {
  const std::size_t m = T.size();
  std::vector<Triangle> G(m);
  for (std::size_t f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) G[f][k] = classOf[T[f][k]];
  const std::vector<EdgeUse> uses = edgeUses(G);
  // Neighbours across two-face edges: (face, same direction?).
  std::vector<int> start(m + 1, 0);
  std::vector<char> open(m, 0);  // has an edge with one face
  auto forEachPair = [&](auto&& visit) {
    for (std::size_t i = 0; i < uses.size();) {
      std::size_t j = i + 1;
      while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
      if (uses[i].u != uses[i].v) {
        if (j - i == 1) open[uses[i].face] = 1;
        if (j - i == 2 && uses[i].face != uses[i + 1].face) {
          const bool same = (G[uses[i].face][uses[i].corner] == uses[i].u) ==
                            (G[uses[i + 1].face][uses[i + 1].corner] == uses[i + 1].u);
          visit(uses[i].face, uses[i + 1].face, same);
        }
      }
      i = j;
    }
  };
  forEachPair([&](int f, int g, bool) { ++start[f + 1], ++start[g + 1]; });
  for (std::size_t f = 0; f < m; ++f) start[f + 1] += start[f];
  std::vector<std::pair<int, bool>> next(start.back());
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    forEachPair([&](int f, int g, bool same) {
      next[fill[f]++] = {g, same};
      next[fill[g]++] = {f, same};
    });
  }
  std::vector<char> flip(m, 0), seen(m, 0);
  std::vector<int> part;
  for (std::size_t seed = 0; seed < m; ++seed) {
    if (seen[seed]) continue;
    part.assign(1, int(seed));
    seen[seed] = 1;
    for (std::size_t k = 0; k < part.size(); ++k) {
      const int f = part[k];
      for (int i = start[f]; i < start[f + 1]; ++i) {
        const auto [g, same] = next[i];
        const char want = char(flip[f] ^ char(same));
        if (!seen[g]) {
          seen[g] = 1;
          flip[g] = want;
          part.push_back(g);
        } else if (flip[g] != want && f < g) {
          ++r.orientation_conflicts;
        }
      }
    }
    if (std::none_of(part.begin(), part.end(), [&](int f) { return flip[f]; })) continue;
    bool closed = true;
    double keptArea = 0, flippedArea = 0, volume = 0;
    const Point3 centre = P[T[part[0]][0]];
    for (int f : part) {
      const Point3 a = P[T[f][0]] - centre, b = P[T[f][1]] - centre, c = P[T[f][2]] - centre;
      const double area = ((b - a) ^ (c - a)).Norm();
      (flip[f] ? flippedArea : keptArea) += area;
      const double v = a * (b ^ c);
      volume += flip[f] ? -v : v;
      closed = closed && !open[f];
    }
    const bool turn = closed ? volume < 0 : flippedArea > keptArea;
    for (int f : part) flip[f] ^= char(turn);
  }
  for (std::size_t f = 0; f < m; ++f)
    if (flip[f]) {
      std::swap(T[f][1], T[f][2]);
      ++r.faces_flipped;
    }
}

// Around an edge where more than two border edges coincide (from class lo
// to class hi): each use's face apex at an angle; a face running lo -> hi
// faces towards larger angles, so its inside is its predecessor, which must
// run hi -> lo. `uses` are the border edges there.
void requestsAround(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                    const std::vector<int>& classOf, const std::vector<BorderEdge>& border, int lo,
                    const std::vector<int>& uses, std::vector<std::array<int, 2>>& requests) {
  const BorderEdge& first = border[uses[0]];
  const Point3 origin = P[classOf[first.from] == lo ? first.from : first.to];
  Point3 axis = P[classOf[first.from] == lo ? first.to : first.from] - origin;
  axis.Normalize();
  Point3 u = std::abs(axis[0]) < 0.9 ? Point3(1, 0, 0) ^ axis : Point3(0, 1, 0) ^ axis;
  u.Normalize();
  const Point3 w = axis ^ u;
  struct Around {
    double angle;
    int edge;
    bool forward;
  };
  std::vector<Around> around;
  for (int edge : uses) {
    const BorderEdge& e = border[edge];
    const Triangle& t = T[e.face];
    const int apex = t[0] != e.from && t[0] != e.to   ? t[0]
                     : t[1] != e.from && t[1] != e.to ? t[1]
                                                      : t[2];
    const Point3 d = P[apex] - origin;
    around.push_back({std::atan2(d * w, d * u), edge, classOf[e.from] == lo});
  }
  std::sort(around.begin(), around.end(),
            [](const Around& x, const Around& y) { return x.angle < y.angle; });
  for (std::size_t k = 0; k < around.size(); ++k) {
    const Around& behind = around[(k + around.size() - 1) % around.size()];
    if (around[k].forward && !behind.forward) requests.push_back({around[k].edge, behind.edge});
  }
}

// The merges to try: pairs of border edges between the same two classes
// running opposite ways, or one edge to collapse (second -1).
std::vector<std::array<int, 2>> mergeRequests(const std::vector<Point3>& P,
                                              const std::vector<Triangle>& T,
                                              const std::vector<int>& classOf,
                                              const std::vector<BorderEdge>& border) {
  std::vector<std::array<int, 2>> requests;
  for (std::size_t e = 0; e < border.size(); ++e)
    if (classOf[border[e].from] == classOf[border[e].to]) requests.push_back({int(e), -1});
  std::vector<std::pair<std::uint64_t, int>> byKey;
  for (std::size_t e = 0; e < border.size(); ++e) {
    const int a = classOf[border[e].from], b = classOf[border[e].to];
    if (a != b) byKey.push_back({undirectedKey(a, b), int(e)});
  }
  std::sort(byKey.begin(), byKey.end());
  for (std::size_t i = 0; i < byKey.size();) {
    std::size_t j = i + 1;
    while (j < byKey.size() && byKey[j].first == byKey[i].first) ++j;
    if (j - i == 2) {
      const BorderEdge &x = border[byKey[i].second], &y = border[byKey[i + 1].second];
      if (classOf[x.from] == classOf[y.to])
        requests.push_back({byKey[i].second, byKey[i + 1].second});
    } else if (j - i > 2) {
      std::vector<int> uses;
      for (std::size_t k = i; k < j; ++k) uses.push_back(byKey[k].second);
      requestsAround(P, T, classOf, border, int(byKey[i].first >> 32), uses, requests);
    }
    i = j;
  }
  return requests;
}

// Step 1: border edges that coincide (within the tolerance) and run
// opposite ways become one edge, and border edges whose ends coincide
// collapse (their face, of zero area within the tolerance, goes). Where
// more than two border edges coincide (solids that touch along an edge),
// each is paired with the next one around the edge behind its face, so
// that each solid closes on its own. Merge by merge, each is kept only if
// it leaves every edge it touches with at most two faces running it
// opposite ways. Vertices merge only through these edges: coincident
// vertices whose faces do not join stay apart (a vertex split).
void mergeCoincidentBorders(const std::vector<Point3>& P, std::vector<Triangle>& T,
                            const std::vector<int>& classOf, std::vector<char>& removedFace,
                            std::vector<int>& target, CloseGapsResult& r) {
  const int n = int(P.size());
  target.resize(n);
  std::iota(target.begin(), target.end(), 0);
  removedFace.assign(T.size(), 0);
  const std::vector<BorderEdge> border = borderEdgesDirected(T);
  const std::vector<std::array<int, 2>> requests = mergeRequests(P, T, classOf, border);
  if (requests.empty()) return;

  // Faces per vertex (a merged vertex's go to the vertex it joins).
  std::vector<std::vector<int>> facesOf(n);
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int v : T[f]) facesOf[v].push_back(int(f));
  DisjointSets sets(P.size());
  std::vector<int> affected;
  std::vector<Triangle> changed;
  std::vector<char> collapses;
  for (const auto& [e1, e2] : requests) {
    // e1 = a -> b, e2 = c -> d: d joins a, c joins b; a collapse: b joins a.
    const int a = sets.root(border[e1].from), b = sets.root(border[e1].to);
    int from[2], to[2], joins = 0;
    auto join = [&](int x, int y) {
      if (x != y) from[joins] = x, to[joins++] = y;
    };
    if (e2 < 0) {
      join(b, a);
    } else {
      join(sets.root(border[e2].to), a);
      join(sets.root(border[e2].from), b);
      if (joins == 2 && from[0] == to[1] && from[1] == to[0]) continue;  // crossed: a <-> b
    }
    if (joins == 0) {  // done by the merges before
      if (e2 >= 0) ++r.edges_merged;
      continue;
    }
    auto mapped = [&](int v) {  // at most two steps (c -> b -> a)
      for (int step = 0; step < 2; ++step)
        for (int k = 0; k < joins; ++k)
          if (v == from[k]) {
            v = to[k];
            break;
          }
      return v;
    };
    affected.clear();
    for (int k = 0; k < joins; ++k)
      for (int f : facesOf[from[k]])
        if (!removedFace[f]) affected.push_back(f);
    std::sort(affected.begin(), affected.end());
    affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
    changed.clear();
    collapses.clear();
    for (int f : affected) {
      const Triangle t{mapped(T[f][0]), mapped(T[f][1]), mapped(T[f][2])};
      changed.push_back(t);
      collapses.push_back(t[0] == t[1] || t[1] == t[2] || t[2] == t[0]);
    }
    // Every edge of a changed face, with the faces it has after the merge:
    // those of its first end and of the vertices joining that end.
    auto faceAfter = [&](int f, const Triangle*& t) {
      const auto it = std::lower_bound(affected.begin(), affected.end(), f);
      if (it == affected.end() || *it != f) {
        t = &T[f];
        return true;
      }
      const std::size_t k = std::size_t(it - affected.begin());
      t = &changed[k];
      return !collapses[k];
    };
    auto usesOf = [&](int u, int v, int& forward, int& backward) {
      forward = backward = 0;
      auto visit = [&](const std::vector<int>& faces) {
        for (int f : faces) {
          const Triangle* t = nullptr;
          if (removedFace[f] || !faceAfter(f, t)) continue;
          for (int i = 0; i < 3; ++i) {
            if ((*t)[i] == u && (*t)[(i + 1) % 3] == v) ++forward;
            if ((*t)[i] == v && (*t)[(i + 1) % 3] == u) ++backward;
          }
        }
      };
      visit(facesOf[u]);
      for (int k = 0; k < joins; ++k)
        if (mapped(from[k]) == u) visit(facesOf[from[k]]);
    };
    bool ok = true;
    for (std::size_t k = 0; k < changed.size() && ok; ++k) {
      if (collapses[k]) continue;
      for (int i = 0; i < 3 && ok; ++i) {
        int forward, backward;
        usesOf(changed[k][i], changed[k][(i + 1) % 3], forward, backward);
        ok = forward <= 1 && forward + backward <= 2;
      }
    }
    if (!ok) {
      ++r.merges_skipped;
      continue;
    }
    for (std::size_t k = 0; k < affected.size(); ++k) {
      T[affected[k]] = changed[k];
      if (collapses[k]) {
        removedFace[affected[k]] = 1;
        ++r.degenerate_faces_removed;
      }
    }
    for (int k = 0; k < joins; ++k) {
      const int into = mapped(from[k]);
      sets.join(from[k], into);
      facesOf[into].insert(facesOf[into].end(), facesOf[from[k]].begin(), facesOf[from[k]].end());
      facesOf[from[k]].clear();
      ++r.vertices_merged;
    }
    if (e2 >= 0) ++r.edges_merged;
  }
  for (int v = 0; v < n; ++v) target[v] = sets.root(v);
}

// Step 2: runs of border vertices facing another run within the bound. A
// border vertex's partner is its nearest border vertex within the bound
// that lies in front of it (away from its faces, within about 100 degrees
// of the direction across its border) and is on another border loop, or
// far along its own loop (the two sides of a crack: at least twice as far
// along the loop as straight across, more than between any two points of a
// convex hole's border, where it is at most pi/2). Runs of consecutive vertices
// of one loop whose partners are on one loop face the run there holding
// most of those partners. On one loop, two runs whose ends meet at a crack's
// tip (the same vertex, or the two ends of one border edge) are extended
// to it, so that stitching them closes the crack. Pairs with a path of
// fewer than minPathVertices vertices are left out.
// The bound: `bound`, or, between two vertices of one part (joined by
// faces: a slit or crack, not a gap between separate parts), localFactor x
// the mean length of the border edges at either vertex, whichever is
// smaller (at most four times the typical local bound: a few long border
// edges do not widen the search everywhere).
// The border loops with what the search for facing runs needs per vertex:
// its loop and place there, the arc length along each loop, the direction
// across the border (away from its faces, in their planes) and the mean
// length of its border edges.
struct BorderGeometry {
  BorderLoops found;
  std::vector<int> loopOf, positionOf;
  std::vector<int> ids;                  // border vertices, each once
  std::vector<std::vector<double>> arc;  // per loop: arc length from its start
  std::vector<Point3> outward;
  std::vector<double> borderLength;
  std::vector<int> borderEdges;

  const std::vector<BorderLoop>& loops() const { return found.loops; }
  double alongLoop(int l, int i, int j) const {
    const double d = std::abs(arc[l][i] - arc[l][j]);
    return found.loops[l].closed ? std::min(d, arc[l].back() - d) : d;
  }
  double localBound(int v, double factor) const {
    return borderEdges[v] > 0 ? factor * borderLength[v] / borderEdges[v] : 0.0;
  }
};

BorderGeometry borderGeometry(const std::vector<Point3>& P, const std::vector<Triangle>& T) {
  BorderGeometry b;
  b.found = findBorderLoops(P, T);
  const std::vector<BorderLoop>& loops = b.found.loops;
  const std::size_t n = P.size();
  b.loopOf.assign(n, -1);
  b.positionOf.assign(n, -1);
  b.arc.resize(loops.size());
  for (std::size_t l = 0; l < loops.size(); ++l) {
    const std::vector<int>& loop = loops[l].vertices;
    b.arc[l].assign(loop.size() + 1, 0);
    for (std::size_t k = 0; k < loop.size(); ++k) {
      if (b.loopOf[loop[k]] < 0) {
        b.loopOf[loop[k]] = int(l);
        b.positionOf[loop[k]] = int(k);
        b.ids.push_back(loop[k]);
      }
      const int next = loop[(k + 1) % loop.size()];
      const bool wraps = k + 1 == loop.size();
      b.arc[l][k + 1] =
          b.arc[l][k] + (wraps && !loops[l].closed ? 0.0 : (P[next] - P[loop[k]]).Norm());
    }
  }
  b.outward.assign(n, Point3(0, 0, 0));
  b.borderLength.assign(n, 0);
  b.borderEdges.assign(n, 0);
  for (const BorderEdge& e : borderEdgesDirected(T)) {
    const double edgeLength = (P[e.to] - P[e.from]).Norm();
    for (const int v : {e.from, e.to}) {
      b.borderLength[v] += edgeLength;
      ++b.borderEdges[v];
    }
    const Triangle& t = T[e.face];
    const Point3 normal = (P[t[1]] - P[t[0]]) ^ (P[t[2]] - P[t[0]]);
    Point3 across = (P[e.to] - P[e.from]) ^ normal;
    const double length = across.Norm();
    if (length > 0) {
      across /= length;
      b.outward[e.from] += across;
      b.outward[e.to] += across;
    }
  }
  return b;
}

// Each border vertex's partner (-1: none): its nearest border vertex within
// the bound in front of it, on another loop or far along its own.
std::vector<int> partnersOf(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                            const BorderGeometry& b, double bound, double localFactor) {
  const std::size_t n = P.size();
  // Parts: vertices joined through faces.
  std::vector<int> part(n);
  std::iota(part.begin(), part.end(), 0);
  auto partOf = [&](int v) {
    while (part[v] != v) v = part[v] = part[part[v]];
    return v;
  };
  for (const Triangle& t : T)
    for (int k = 1; k < 3; ++k) part[partOf(t[k])] = partOf(t[0]);
  // The grid's cell: the bound, or the typical (median) local bound if larger.
  double cell = bound;
  if (localFactor > 0 && !b.ids.empty()) {
    std::vector<double> locals;
    for (int v : b.ids) locals.push_back(b.localBound(v, localFactor));
    std::nth_element(locals.begin(), locals.begin() + locals.size() / 2, locals.end());
    cell = std::max(cell, locals[locals.size() / 2]);
  }
  std::vector<int> partnerOf(n, -1);
  if (!(cell > 0)) return partnerOf;
  const NearPoints near(P, b.ids, cell);
  for (int v : b.ids) {
    double best = INFINITY;
    const int l = b.loopOf[v];
    const double localV = b.localBound(v, localFactor);
    const double radius = std::min(std::max(bound, localV), 4 * cell);
    near.near(P[v], radius, [&](int w) {
      if (w == v) return;
      const Point3 d = P[w] - P[v];
      const double distance = d.Norm();
      if (distance > bound &&
          (partOf(v) != partOf(w) || distance > std::min(localV, b.localBound(w, localFactor))))
        return;
      if (b.loopOf[w] == l) {
        const double along = b.alongLoop(l, b.positionOf[v], b.positionOf[w]);
        if (along <= 0 || along < 2 * distance) return;
      }
      const double facing = d * b.outward[v];
      if (facing < -0.2 * distance * b.outward[v].Norm()) return;
      if (distance < best) best = distance, partnerOf[v] = w;
    });
  }
  return partnerOf;
}

// Runs of loop l whose partners are on loop `other`, in the loop's order.
std::vector<std::vector<int>> runsFacing(const BorderGeometry& b, const std::vector<int>& partnerOf,
                                         int l, int other) {
  std::vector<std::vector<int>> runs;
  const BorderLoop& loop = b.loops()[l];
  const std::size_t m = loop.vertices.size();
  auto facing = [&](std::size_t k) {
    const int w = partnerOf[loop.vertices[k % m]];
    return w >= 0 && b.loopOf[w] == other;
  };
  std::size_t first = 0;
  if (loop.closed) {
    while (first < m && facing(first)) ++first;
    if (first == m) return {loop.vertices};  // the whole loop
  }
  const std::size_t end = loop.closed ? first + m : m;
  for (std::size_t k = first; k < end; ++k) {
    if (!facing(k)) continue;
    std::vector<int> run;
    while (k < end && facing(k)) run.push_back(loop.vertices[k++ % m]);
    runs.push_back(run);
  }
  return runs;
}

// On one closed loop, a runs forward beside b running backward: a's start
// meets b's end, a's end meets b's start. Where they end one vertex or one
// border edge short of a crack's tip, both are extended to it.
void extendToCrackTips(const BorderGeometry& b, int l, GapReport& g) {
  const std::vector<int>& loop = b.loops()[l].vertices;
  const int m = int(loop.size());
  auto at = [&](int k) { return loop[((k % m) + m) % m]; };
  std::unordered_set<int> used(g.path_a.begin(), g.path_a.end());
  used.insert(g.path_b.begin(), g.path_b.end());
  const int p = at(b.positionOf[g.path_a.front()] - 1), q = at(b.positionOf[g.path_b.back()] + 1);
  if (!used.count(p) && !used.count(q) && (p == q || at(b.positionOf[q] + 1) == p)) {
    g.path_a.insert(g.path_a.begin(), p);
    g.path_b.push_back(q);
    used.insert(p);
    used.insert(q);
  }
  const int s = at(b.positionOf[g.path_a.back()] + 1), t = at(b.positionOf[g.path_b.front()] - 1);
  if (!used.count(s) && !used.count(t) && (s == t || at(b.positionOf[s] + 1) == t)) {
    g.path_a.push_back(s);
    g.path_b.insert(g.path_b.begin(), t);
  }
}

// The gaps between loops l1 and l2 (the same loop for a crack): each run
// of l1 faces the run of l2 holding most of its partners.
void gapsBetween(const std::vector<Point3>& P, const BorderGeometry& b,
                 const std::vector<int>& partnerOf, int l1, int l2, int minPathVertices,
                 std::vector<GapReport>& gaps) {
  const auto runs1 = runsFacing(b, partnerOf, l1, l2);
  const auto runs2 = l1 == l2 ? runs1 : runsFacing(b, partnerOf, l2, l1);
  const bool whole1 = runs1.size() == 1 && runs1[0].size() == b.loops()[l1].vertices.size();
  const bool whole2 = runs2.size() == 1 && runs2[0].size() == b.loops()[l2].vertices.size();
  std::unordered_map<int, int> runOf2;
  for (std::size_t k = 0; k < runs2.size(); ++k)
    for (int v : runs2[k]) runOf2[v] = int(k);
  std::vector<char> taken(runs2.size(), 0);
  for (std::size_t k1 = 0; k1 < runs1.size(); ++k1) {
    if (l1 == l2 && taken[k1]) continue;
    const std::vector<int>& run = runs1[k1];
    std::vector<int> votes(runs2.size(), 0);
    for (int v : run) {
      const auto it = runOf2.find(partnerOf[v]);
      if (it != runOf2.end()) ++votes[it->second];
    }
    if (l1 == l2) votes[k1] = 0;  // a run does not face itself
    if (votes.empty()) continue;
    const int k2 = int(std::max_element(votes.begin(), votes.end()) - votes.begin());
    if (votes[k2] == 0 || taken[k2]) continue;
    taken[k2] = 1;
    if (l1 == l2) taken[k1] = 1;
    GapReport g;
    g.closed = l1 != l2 && whole1 && whole2;
    g.path_a = run;
    g.path_b = runs2[k2];
    for (int v : g.path_a)
      if (partnerOf[v] >= 0) g.gap = std::max(g.gap, (P[partnerOf[v]] - P[v]).Norm());
    if (l1 != l2 && (whole1 || whole2) && !g.closed)
      g.reason = "a whole border loop faces only part of another loop";
    auto onLoop = [&](int v) { return b.loopOf[v] == l1; };
    if (l1 == l2 && b.loops()[l1].closed && onLoop(g.path_a.front()) && onLoop(g.path_a.back()) &&
        onLoop(g.path_b.front()) && onLoop(g.path_b.back()))
      extendToCrackTips(b, l1, g);
    if (int(std::min(g.path_a.size(), g.path_b.size())) < minPathVertices) continue;
    gaps.push_back(g);
  }
}

std::vector<GapReport> facingBorders(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                                     double bound, double localFactor, int minPathVertices) {
  const BorderGeometry b = borderGeometry(P, T);
  const std::vector<int> partnerOf = partnersOf(P, T, b, bound, localFactor);
  std::vector<std::array<int, 2>> loopPairs;
  std::set<std::array<int, 2>> seen;
  for (int v : b.ids)
    if (const int w = partnerOf[v]; w >= 0) {
      const std::array<int, 2> key{std::min(b.loopOf[v], b.loopOf[w]),
                                   std::max(b.loopOf[v], b.loopOf[w])};
      if (seen.insert(key).second) loopPairs.push_back(key);
    }
  std::vector<GapReport> gaps;
  for (const auto& [l1, l2] : loopPairs)
    gapsBetween(P, b, partnerOf, l1, l2, minPathVertices, gaps);
  return gaps;
}

}  // namespace

CloseGapsResult closeGaps(Mesh& mesh, const CloseGapsOptions& options) {
  const auto start = Clock::now();
  requireFacesAndFiniteCoordinates(mesh, "the mesh");
  requireCompact(mesh);
  if (!(options.merge_tolerance >= 0) || !(options.max_gap >= 0) ||
      !(options.local_gap_factor >= 0) || !(options.max_aspect_ratio >= 0))
    throw InvalidInputError(
        "merge_tolerance, max_gap, local_gap_factor and max_aspect_ratio must not be negative");
  CloseGapsResult r;
  std::vector<Point3> P = positionsOf(mesh);
  std::vector<Triangle> T = trianglesOf(mesh);
  r.border_edges_before = borderEdgesOf(T);
  double scale = 1;
  if (!options.absolute_distances) {
    vcg::Box3d box;
    for (const Point3& p : P) box.Add(p);
    scale = box.Diag();
  }
  r.merge_tolerance = options.merge_tolerance * scale;
  r.max_gap = options.max_gap * scale;

  // ---- Step 1: orient, merge coincident borders.
  reportProgress(options.progress, 0, "Merging coincident borders");
  const std::vector<int> classOf = coincidenceClasses(P, borderEdgesDirected(T), r.merge_tolerance);
  if (options.orient_faces) orientConsistently(P, T, classOf, r);
  std::vector<char> removedFace;
  std::vector<int> target;
  mergeCoincidentBorders(P, T, classOf, removedFace, target, r);
  const int n = int(P.size());
  r.vertex_index.assign(n, -1);
  std::vector<char> changedFace(T.size(), 0);  // corners merged (for the check)
  if (r.vertices_merged > 0 || r.faces_flipped > 0) {
    VertexOriginHandle vo = vertexOrigins(mesh);
    FaceOriginHandle fo = faceOrigins(mesh);
    std::vector<Point3> points;
    std::vector<VertexOrigin> vorig;
    for (int v = 0; v < n; ++v)
      if (target[v] == v) {
        r.vertex_index[v] = int(points.size());
        points.push_back(P[v]);
        vorig.push_back(vo[v]);
      }
    for (int v = 0; v < n; ++v) r.vertex_index[v] = r.vertex_index[target[v]];
    std::vector<Triangle> kept;
    std::vector<FaceOrigin> forig;
    std::vector<char> keptChanged;
    const std::vector<Triangle> input = trianglesOf(mesh);
    for (std::size_t f = 0; f < T.size(); ++f) {
      if (removedFace[f]) continue;
      bool merged = false;
      for (int k = 0; k < 3; ++k) merged = merged || target[input[f][k]] != input[f][k];
      kept.push_back({r.vertex_index[T[f][0]], r.vertex_index[T[f][1]], r.vertex_index[T[f][2]]});
      forig.push_back(fo[f]);
      keptChanged.push_back(merged);
    }
    buildMesh(mesh, points, kept, vorig, forig);
    P = points;
    T = kept;
    changedFace = keptChanged;
  } else {
    std::iota(r.vertex_index.begin(), r.vertex_index.end(), 0);
  }
  r.border_edges_after_merge = borderEdgesOf(T);
  r.border_edges_after = r.border_edges_after_merge;
  const std::size_t verticesAfterMerge = mesh.vert.size();

  // ---- Step 2: facing borders, in rounds: a stitch can leave borders that
  // face each other anew (the rest of an L-shaped slit), so they are looked
  // for again until a round stitches nothing.
  if (r.max_gap > 0) {
    constexpr int kRounds = 8;
    std::set<std::pair<std::vector<int>, std::vector<int>>> reported;
    for (int round = 0; round < kRounds; ++round) {
      reportProgress(options.progress, 30 + 60 * round / kRounds, "Finding facing borders");
      std::vector<GapReport> gaps =
          facingBorders(positionsOf(mesh), trianglesOf(mesh), r.max_gap, options.local_gap_factor,
                        options.min_path_vertices);
      std::size_t stitched = 0;
      // Stitch each pair on the current mesh (earlier stitches change borders).
      for (GapReport& g : gaps) {
        if (!reported.insert({g.path_a, g.path_b}).second) continue;  // left open before
        ++r.gaps_found;
        if (g.reason.empty()) {
          StitchOptions so;
          so.a = {g.path_a, g.closed ? BorderPath::Shape::Closed : BorderPath::Shape::Open};
          so.b = {g.path_b, g.closed ? BorderPath::Shape::Closed : BorderPath::Shape::Open};
          so.max_aspect_ratio = options.max_aspect_ratio;
          so.round_to_float = options.round_to_float;
          try {
            const StitchPlan plan = planStitch(mesh, so);
            if (plan.conflicts > 0) {
              g.reason = "the two sides are inconsistently oriented";
            } else if (options.check_intersections && newIntersections(mesh, plan) > 0) {
              g.reason = "the stitch would intersect the mesh";
            } else {
              StitchResult sr;
              applyPlan(mesh, plan, sr);
              g.stitched = true;
              g.faces_added = sr.faces_added;
              r.faces_added += sr.faces_added;
              r.vertices_added += sr.vertices_added;
              r.border_edges_after = std::size_t(long(r.border_edges_after) + plan.borderDelta);
              ++r.gaps_stitched;
              ++stitched;
            }
          } catch (const Error& e) {
            g.reason = e.what();
          }
        }
        r.gaps.push_back(std::move(g));
      }
      if (stitched == 0) break;
    }
  }
  // ---- The output stage: new vertices (subdivided strips) as stored.
  r.stored = storeStitched(mesh, verticesAfterMerge, changedFace, options.round_to_float);
  // ---- The output's intersecting pairs: those that involve a merged or new
  // face, and all of them by the checker's rule.
  if (options.verify) {
    reportProgress(options.progress, 90, "Checking the result");
    changedFace.resize(mesh.face.size(), 1);
    const std::vector<Point3> points = positionsOf(mesh);
    const std::vector<Triangle> triangles = trianglesOf(mesh);
    r.new_intersecting_pairs =
        intersectingOf(points, triangles, pairsWithChangedFaces(points, triangles, changedFace))
            .size();
    r.remaining_intersecting_pairs =
        storedIntersectingPairs(MeshArrays{points, triangles}, r.stored.scalar);
    r.verified = true;
  }
  reportProgress(options.progress, 100, "Done");
  r.time_ms = msSince(start);
  return r;
}

}  // namespace meshmend
