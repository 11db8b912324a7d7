// Input checks, cleaning and the pre-treatment of self-intersection removal
// (TransforMesh §2.1): see stages.h.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <memory>
#include <numeric>
#include <string>

#include "common/base/errors.h"
#include "common/exact/box_tree.h"
#include "common/exact/predicates.h"
#include "common/exact/triangle_intersection.h"
#include "common/repair/selfintersect/stages.h"

namespace meshmend::selfintersect {

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- Pre-treatment (§2.1) -------------------------------------------------

class Pretreatment {
 public:
  Pretreatment(std::vector<Point3>& P, std::vector<Triangle>& T, std::vector<int>& faceOrigin,
               double angleDeg)
      : P_(P), T_(T), origin_(faceOrigin), minAngle_(angleDeg * kPi / 180) {}

  bool degenerate(int f) const {
    const Triangle& t = T_[f];
    return collinear(P_[t[0]], P_[t[1]], P_[t[2]]) ||
           smallestAngle(P_[t[0]], P_[t[1]], P_[t[2]]) < minAngle_;
  }

  std::size_t countDegenerate() const {
    std::size_t n = 0;
    for (std::size_t f = 0; f < T_.size(); ++f) n += !removed(int(f)) && degenerate(int(f));
    return n;
  }

  void run(std::size_t& collapses, std::size_t& flips) {
    removed_.assign(T_.size(), 0);
    for (int pass = 0; pass < 8; ++pass) {
      std::vector<int> bad;
      for (std::size_t f = 0; f < T_.size(); ++f)
        if (!removed(int(f)) && degenerate(int(f))) bad.push_back(int(f));
      if (bad.empty()) break;
      prepare();
      std::size_t done = 0;
      for (int f : bad) {
        if (removed(f) || !degenerate(f)) continue;
        if (collapseShortestEdge(f)) {
          ++collapses, ++done;
        } else if (flipLongestEdge(f)) {
          ++flips, ++done;
        }
      }
      if (done == 0) break;
    }
    // Compact the faces.
    std::size_t out = 0;
    for (std::size_t f = 0; f < T_.size(); ++f)
      if (!removed(int(f))) T_[out] = T_[f], origin_[out] = origin_[f], ++out;
    T_.resize(out);
    origin_.resize(out);
    removed_.assign(out, 0);
  }

  bool removed(int f) const { return !removed_.empty() && removed_[f]; }

 private:
  // Faces around each vertex and a box hierarchy of the faces as they are
  // at the start of a pass; faces changed during the pass are checked
  // against one by one (there are few).
  void prepare() {
    around_.assign(P_.size(), {});
    std::vector<Box> boxes(T_.size());
    for (std::size_t f = 0; f < T_.size(); ++f) {
      if (removed(int(f))) {
        boxes[f] = Box{{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}};
        continue;
      }
      for (int v : T_[f]) around_[v].push_back(int(f));
      boxes[f] = boxOf(P_[T_[f][0]], P_[T_[f][1]], P_[T_[f][2]]);
    }
    tree_ = std::make_unique<BoxTree>(std::move(boxes), BoxTree::Layout::kMorton);
    changed_.clear();
  }

  bool intersect(const Triangle& a, const Triangle& b) const {
    if (collinear(P_[a[0]], P_[a[1]], P_[a[2]]) || collinear(P_[b[0]], P_[b[1]], P_[b[2]]))
      return false;  // as in the intersection search: degenerate faces are never compared
    const SharedCorners s = sharedCorners(a, b);
    return intersectBeyondShared(pointsOf(P_, a), pointsOf(P_, b), s.count, s.ia, s.ib);
  }

  // Would the faces `fresh` (replacing `old`, same order) cross a face that
  // the face they replace did not cross? `skip`: faces being removed.
  bool createsIntersection(const std::vector<Triangle>& fresh, const std::vector<int>& old,
                           const std::vector<int>& skip) const {
    auto skipped = [&](int h) {
      return removed(h) || std::find(skip.begin(), skip.end(), h) != skip.end() ||
             std::find(old.begin(), old.end(), h) != old.end();
    };
    for (std::size_t i = 0; i < fresh.size(); ++i) {
      for (std::size_t j = i + 1; j < fresh.size(); ++j)
        if (intersect(fresh[i], fresh[j])) return true;
      const Triangle& t = fresh[i];
      bool crosses = false;
      auto test = [&](int h) {
        if (crosses || skipped(h)) return;
        if (intersect(t, T_[h]) && (old[i] < 0 || !intersect(T_[old[i]], T_[h]))) crosses = true;
      };
      tree_->query(boxOf(P_[t[0]], P_[t[1]], P_[t[2]]), 0, [&](std::uint32_t h, unsigned) {
        if (std::find(changed_.begin(), changed_.end(), int(h)) == changed_.end()) test(int(h));
      });
      for (int h : changed_) test(h);
      if (crosses) return true;
    }
    return false;
  }

  bool acceptable(const Triangle& now, const Triangle& before) const {
    const Point3 &a = P_[now[0]], &b = P_[now[1]], &c = P_[now[2]];
    if (collinear(a, b, c)) return false;
    const double angle = smallestAngle(a, b, c);
    const Triangle& o = before;
    const double oldAngle = smallestAngle(P_[o[0]], P_[o[1]], P_[o[2]]);
    if (angle < std::min(minAngle_, oldAngle)) return false;
    return normalOf(a, b, c) * normalOf(P_[o[0]], P_[o[1]], P_[o[2]]) > 0;  // does not turn over
  }

  void replaceAround(int v, int f, bool add) {
    auto& list = around_[v];
    if (add)
      list.push_back(f);
    else
      list.erase(std::remove(list.begin(), list.end(), f), list.end());
  }

  // Collapses the shortest edge of f into one of its end points (no new
  // coordinates), if the link condition holds and the faces it moves stay
  // acceptable and cross nothing new.
  bool collapseShortestEdge(int f) {
    const Triangle& t = T_[f];
    int k = 0;
    double best = INFINITY;
    for (int i = 0; i < 3; ++i) {
      const double len = (P_[t[(i + 1) % 3]] - P_[t[i]]).SquaredNorm();
      if (len < best) best = len, k = i;
    }
    const int a = t[k], b = t[(k + 1) % 3];
    return collapse(b, a) || collapse(a, b);
  }

  bool collapse(int from, int into) {
    std::vector<int> shared, moved;
    for (int g : around_[from]) {
      const Triangle& t = T_[g];
      (std::find(t.begin(), t.end(), into) != t.end() ? shared : moved).push_back(g);
    }
    if (shared.empty() || shared.size() > 2) return false;
    // Link condition: the vertices next to both are exactly the apexes of the shared faces.
    std::vector<int> apexes, nextFrom, nextInto;
    for (int g : shared)
      for (int v : T_[g])
        if (v != from && v != into) apexes.push_back(v);
    for (int g : around_[from])
      for (int v : T_[g])
        if (v != from) nextFrom.push_back(v);
    for (int g : around_[into])
      for (int v : T_[g])
        if (v != into) nextInto.push_back(v);
    for (auto* list : {&apexes, &nextFrom, &nextInto}) {
      std::sort(list->begin(), list->end());
      list->erase(std::unique(list->begin(), list->end()), list->end());
    }
    std::vector<int> common;
    std::set_intersection(nextFrom.begin(), nextFrom.end(), nextInto.begin(), nextInto.end(),
                          std::back_inserter(common));
    if (common != apexes) return false;
    std::vector<Triangle> fresh;
    for (int g : moved) {
      Triangle t = T_[g];
      for (int& v : t)
        if (v == from) v = into;
      if (!acceptable(t, T_[g])) return false;
      fresh.push_back(t);
    }
    if (createsIntersection(fresh, moved, shared)) return false;
    for (int g : shared) {
      removed_[g] = 1;
      for (int v : T_[g]) replaceAround(v, g, false);
    }
    for (std::size_t i = 0; i < moved.size(); ++i) {
      T_[moved[i]] = fresh[i];
      replaceAround(into, moved[i], true);
      changed_.push_back(moved[i]);
    }
    around_[from].clear();
    return true;
  }

  // Flips the edge opposite f's largest angle (a cap's long edge), if the
  // face across it is its only neighbour there and the two new faces are
  // better, turn no normal over and cross nothing new.
  bool flipLongestEdge(int f) {
    const Triangle t = T_[f];
    int k = 0;
    double best = -1;
    for (int i = 0; i < 3; ++i) {
      const double len = (P_[t[(i + 1) % 3]] - P_[t[i]]).SquaredNorm();
      if (len > best) best = len, k = i;
    }
    const int u = t[k], v = t[(k + 1) % 3], w = t[(k + 2) % 3];
    int g = -1, across = 0;
    for (int h : around_[u]) {
      if (h == f) continue;
      const Triangle& s = T_[h];
      for (int i = 0; i < 3; ++i)
        if ((s[i] == u && s[(i + 1) % 3] == v) || (s[i] == v && s[(i + 1) % 3] == u)) {
          ++across;
          if (s[i] == v) g = h;
        }
    }
    if (across != 1 || g < 0) return false;
    int x = -1;
    for (int vv : T_[g])
      if (vv != u && vv != v) x = vv;
    if (x == w) return false;
    for (int h : around_[w])
      for (int vv : T_[h])
        if (vv == x) return false;  // edge wx exists already
    const Triangle f2{u, x, w}, g2{v, w, x};
    const Point3 before =
        normalOf(P_[t[0]], P_[t[1]], P_[t[2]]) + normalOf(P_[T_[g][0]], P_[T_[g][1]], P_[T_[g][2]]);
    for (const Triangle& n : {f2, g2}) {
      const Point3 &a = P_[n[0]], &b = P_[n[1]], &c = P_[n[2]];
      if (collinear(a, b, c) || normalOf(a, b, c) * before <= 0) return false;
    }
    const double oldAngle = std::min(smallestAngle(P_[t[0]], P_[t[1]], P_[t[2]]),
                                     smallestAngle(P_[T_[g][0]], P_[T_[g][1]], P_[T_[g][2]]));
    const double newAngle =
        std::min(smallestAngle(P_[u], P_[x], P_[w]), smallestAngle(P_[v], P_[w], P_[x]));
    if (newAngle <= oldAngle) return false;
    if (createsIntersection({f2, g2}, {f, g}, {})) return false;
    for (int h : {f, g})
      for (int vv : T_[h]) replaceAround(vv, h, false);
    T_[f] = f2;
    T_[g] = g2;
    for (int h : {f, g}) {
      for (int vv : T_[h]) replaceAround(vv, h, true);
      changed_.push_back(h);
    }
    return true;
  }

  std::vector<Point3>& P_;
  std::vector<Triangle>& T_;
  std::vector<int>& origin_;
  double minAngle_;
  std::vector<char> removed_;
  std::vector<std::vector<int>> around_;
  std::unique_ptr<BoxTree> tree_;
  std::vector<int> changed_;
};

}  // namespace

TopologyCounts topologyOf(const Edges& edges, const std::vector<Triangle>& T,
                          std::size_t vertexCount) {
  TopologyCounts c;
  std::vector<int> parent(T.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t e = 0; e < edges.count(); ++e) {
    const int n = edges.size(int(e));
    if (n == 1) ++c.border_edges;
    if (n > 2) ++c.non_manifold_edges;
    if (n > 1) {
      const auto [forward, backward] = edges.directions(int(e), T);
      c.fin_edges += forward != backward;
    }
    for (int k = edges.first[e] + 1; k < edges.first[e + 1]; ++k)
      parent[find(parent, edges.uses[k].face)] = find(parent, edges.uses[edges.first[e]].face);
  }
  for (std::size_t f = 0; f < T.size(); ++f) c.components += find(parent, int(f)) == int(f);
  if (c.border_edges == 0 && c.non_manifold_edges == 0) {
    std::vector<char> used(vertexCount, 0);
    long vertices = 0;
    for (const Triangle& t : T)
      for (int v : t) vertices += !used[v], used[v] = 1;
    const long euler = vertices - long(edges.count()) + long(T.size());
    c.genus = int((2L * c.components - euler) / 2);
  }
  return c;
}

PretreatmentCounts pretreat(std::vector<Point3>& P, std::vector<Triangle>& T,
                            std::vector<int>& faceOrigin, double angleDeg, bool apply,
                            const Progress& progress) {
  PretreatmentCounts c;
  Pretreatment pre(P, T, faceOrigin, angleDeg);
  c.degenerate_before = pre.countDegenerate();
  if (apply && c.degenerate_before > 0) {
    reportProgress(progress, 5, "removing degenerate faces");
    pre.run(c.collapses, c.flips);
  }
  c.degenerate_left = c.degenerate_before > 0 ? pre.countDegenerate() : 0;
  return c;
}

// ---- Input checks ---------------------------------------------------------

// Two or more faces on an edge, all running it the same way: some faces are
// turned over (the usual inconsistent orientation). Other unbalanced edges
// (a fin: three faces on an edge) are left to the growing, as borders.
void requireConsistentOrientation(const Edges& edges, const std::vector<Triangle>& T) {
  std::size_t bad = 0;
  int example = -1;
  for (std::size_t e = 0; e < edges.count(); ++e) {
    const auto [fwd, bwd] = edges.directions(int(e), T);
    if (fwd + bwd >= 2 && (fwd == 0 || bwd == 0)) {
      if (bad++ == 0) example = int(e);
    }
  }
  if (bad == 0) return;
  const EdgeUse& use = edges.uses[edges.first[example]];
  throw TopologyError(
      "the mesh is not consistently oriented: on " + std::to_string(bad) +
      " edges (e.g. between vertices " + std::to_string(use.u) + " and " + std::to_string(use.v) +
      ") neighbouring faces run the same way, so inside and outside are undefined there; the "
      "layer is unchanged. Orient the faces first: MeshMend: Close Gaps Between Borders does it "
      "('Orient faces consistently', on by default, turns closed parts outward), as does Filters > "
      "Normals, Curvatures and Orientation > \"Re-Orient all faces coherently\".");
}

double signedVolume(const std::vector<Point3>& P, const std::vector<Triangle>& T) {
  double v = 0;
  for (const Triangle& t : T) v += P[t[0]] * (P[t[1]] ^ P[t[2]]);
  return v / 6;
}

// Removes faces repeating another face's three vertices (after welding): the
// same surface twice. Of a group, one face stays if they all run alike; two
// opposite copies bound nothing and both go.
std::size_t removeDuplicateFaces(std::vector<Triangle>& T, std::vector<int>& origin) {
  // Faces on the same vertices share their smallest vertex: a counting sort
  // by it, then a small sort within each vertex's faces, puts them together.
  std::vector<Triangle> keys(T.size());
  int vertexCount = 0;
  for (std::size_t f = 0; f < T.size(); ++f) {
    keys[f] = T[f];
    std::sort(keys[f].begin(), keys[f].end());
    vertexCount = std::max(vertexCount, keys[f][2] + 1);
  }
  std::vector<int> start(std::size_t(vertexCount) + 1, 0);
  for (const Triangle& k : keys) ++start[k[0] + 1];
  for (int v = 0; v < vertexCount; ++v) start[v + 1] += start[v];
  std::vector<int> order(T.size());
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < T.size(); ++f) order[next[keys[f][0]]++] = int(f);
  }
  auto byKey = [&](int a, int b) { return keys[a] < keys[b] || (keys[a] == keys[b] && a < b); };
  for (int v = 0; v < vertexCount; ++v)
    if (start[v + 1] - start[v] > 1)
      std::sort(order.begin() + start[v], order.begin() + start[v + 1], byKey);
  auto key = [&](int f) -> const Triangle& { return keys[f]; };
  std::vector<char> drop(T.size(), 0);
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i + 1;
    while (j < order.size() && key(order[j]) == key(order[i])) ++j;
    if (j - i > 1) {
      // A face's direction: is its corner sequence an even rotation of the sorted one?
      auto even = [&](int f) {
        const Triangle& s = key(f);
        const Triangle& t = T[f];
        for (int r = 0; r < 3; ++r)
          if (t[r] == s[0]) return t[(r + 1) % 3] == s[1];
        return true;
      };
      int up = 0, down = 0;
      for (std::size_t k = i; k < j; ++k) (even(order[k]) ? up : down)++;
      // Keep |up - down| copies of the majority direction: opposite pairs cancel.
      int keepUp = std::max(0, up - down), keepDown = std::max(0, down - up);
      keepUp = std::min(keepUp, 1), keepDown = std::min(keepDown, 1);
      for (std::size_t k = i; k < j; ++k) {
        int& budget = even(order[k]) ? keepUp : keepDown;
        if (budget > 0)
          --budget;
        else
          drop[order[k]] = 1;
      }
    }
    i = j;
  }
  std::size_t out = 0, dropped = 0;
  for (std::size_t f = 0; f < T.size(); ++f) {
    if (drop[f]) {
      ++dropped;
      continue;
    }
    T[out] = T[f], origin[out] = origin[f], ++out;
  }
  T.resize(out);
  origin.resize(out);
  return dropped;
}

}  // namespace meshmend::selfintersect
