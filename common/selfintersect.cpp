#include "common/selfintersect.h"

#include <gmpxx.h>
#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <string>
#include <tuple>

#include "common/box_tree.h"
#include "common/errors.h"
#include "common/intersections.h"
#include "common/interval.h"
#include "common/output_stage.h"
#include "common/predicates.h"
#include "common/split.h"
#include "common/triangle_intersection.h"

namespace meshmend {

namespace {

constexpr double kPi = 3.14159265358979323846;

int find(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

Point3 normalOf(const Point3& a, const Point3& b, const Point3& c) {
  return (b - a) ^ (c - a);
}

TrianglePoints pointsOf(const std::vector<Point3>& P, const Triangle& t) {
  return {P[t[0]], P[t[1]], P[t[2]]};
}

// ---- Edges ----------------------------------------------------------------

// The edge uses of the faces (mesh.h), grouped by edge:
// uses[first[e]..first[e+1]) are the uses of edge e.
struct Edges {
  std::vector<EdgeUse> uses;
  std::vector<int> first;        // per edge: its first use; one extra at the end
  std::vector<int> edge_of_use;  // per face corner (3f + i): its edge

  explicit Edges(const std::vector<Triangle>& T) {
    uses = edgeUses(T);
    edge_of_use.resize(uses.size());
    first.reserve(uses.size() / 2 + 2);
    for (std::size_t k = 0; k < uses.size(); ++k) {
      if (k == 0 || uses[k].u != uses[k - 1].u || uses[k].v != uses[k - 1].v)
        first.push_back(int(k));
      edge_of_use[3 * uses[k].face + uses[k].corner] = int(first.size()) - 1;
    }
    first.push_back(int(uses.size()));
  }
  std::size_t count() const { return first.size() - 1; }
  int size(int e) const { return first[e + 1] - first[e]; }
  // Does the use run from the smaller vertex to the larger?
  static bool forward(const EdgeUse& use, const std::vector<Triangle>& T) {
    return T[use.face][use.corner] == use.u;
  }
  // Uses in each direction.
  std::pair<int, int> directions(int e, const std::vector<Triangle>& T) const {
    int fwd = 0;
    for (int k = first[e]; k < first[e + 1]; ++k) fwd += forward(uses[k], T);
    return {fwd, size(e) - fwd};
  }
  // An edge the surface simply continues across: two faces, opposite directions.
  bool manifold(int e, const std::vector<Triangle>& T) const {
    return size(e) == 2 && directions(e, T) == std::make_pair(1, 1);
  }
};

struct TopologyCounts {
  std::size_t border_edges = 0, non_manifold_edges = 0;
  std::size_t fin_edges = 0;  // used more than once, unequally in the two directions
  int components = 0;
  int genus = -1;
};

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

// ---- Radial order around an edge -----------------------------------------

// Signs of polynomials in the input doubles: first in interval arithmetic,
// then, when the interval holds 0, in rationals.
template <class N>
std::array<N, 3> normalIn(const TrianglePoints& t) {
  std::array<N, 3> u, v;
  for (int k = 0; k < 3; ++k) u[k] = N(t[1][k]) - N(t[0][k]), v[k] = N(t[2][k]) - N(t[0][k]);
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}

template <class N>
N normalsDet(const TrianglePoints& a, const TrianglePoints& b, const Point3& p, const Point3& q) {
  const auto na = normalIn<N>(a), nb = normalIn<N>(b);
  const N cx = na[1] * nb[2] - na[2] * nb[1], cy = na[2] * nb[0] - na[0] * nb[2],
          cz = na[0] * nb[1] - na[1] * nb[0];
  return cx * (N(q[0]) - N(p[0])) + cy * (N(q[1]) - N(p[1])) + cz * (N(q[2]) - N(p[2]));
}

template <class N>
N normalsDot(const TrianglePoints& a, const TrianglePoints& b) {
  const auto na = normalIn<N>(a), nb = normalIn<N>(b);
  return na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2];
}

int signOf(const Interval& x) {
  return x.positive() ? 1 : x.negative() ? -1 : 0;
}
int signOf(const mpq_class& x) {
  return sgn(x);
}

// sign det(n_a, n_b, q - p), n = a triangle's normal.
int signNormalsDet(const TrianglePoints& a, const TrianglePoints& b, const Point3& p,
                   const Point3& q) {
  // Pieces of one cut triangle meet at its curves all the time: their
  // normals are equal, the determinant is exactly 0 (no interval decides it).
  if (a == b) return 0;
  if (const int s = signOf(normalsDet<Interval>(a, b, p, q))) return s;
  return signOf(normalsDet<mpq_class>(a, b, p, q));
}

// sign (n_a . n_b).
int signNormalsDot(const TrianglePoints& a, const TrianglePoints& b) {
  if (a == b && !collinear(a[0], a[1], a[2])) return 1;  // a normal with itself
  if (const int s = signOf(normalsDot<Interval>(a, b))) return s;
  return signOf(normalsDot<mpq_class>(a, b));
}

// The faces around edge (p, q), seen from face f that runs from p to q:
// each face's half-plane is placed by its angle from f's, turning towards
// f's front (the side its normal points to). A face lies in the plane of
// the input triangle it was cut from (its birth triangle, with normal n),
// on the side w = e (n x d) of the edge, d = q - p and e = +1 if it runs
// from p to q, -1 otherwise. With the turn positive about d, w1 comes
// before w2 within a half turn when det(w1, w2, d) > 0, that is when
// e1 e2 det(n1, n2, d) > 0. Deciding on birth planes rather than on the
// cut faces' own corners keeps the order exact even for slivers whose
// corners are rounded curve points.
class RadialOrder {
 public:
  struct Sheet {
    const TrianglePoints* birth;
    int e;  // +1: runs p -> q
  };
  RadialOrder(const Point3& p, const Point3& q, Sheet f) : p_(p), q_(q), f_(f) {}

  // 0: angle in [0, pi) (in front of f, or along f's own half-plane);
  // 1: angle in [pi, 2 pi) (behind f, or f's plane continued past the edge).
  int half(Sheet g) const {
    const int side = g.e * signNormalsDet(*f_.birth, *g.birth, p_, q_);
    if (side != 0) return side > 0 ? 0 : 1;
    return f_.e * g.e * signNormalsDot(*f_.birth, *g.birth) >= 0 ? 0 : 1;
  }

  // Does g1 come strictly before g2, turning from f towards its front?
  bool before(Sheet g1, int half1, Sheet g2, int half2) const {
    if (half1 != half2) return half1 < half2;
    return g1.e * g2.e * signNormalsDet(*g1.birth, *g2.birth, p_, q_) > 0;
  }

 private:
  Point3 p_, q_;
  Sheet f_;
};

// ---- Seeds -----------------------------------------------------------------

enum class RayVerdict { kOutside, kInside, kUndecided };

// ---- Region growing and stitching (§2.3, §2.4) ----------------------------

class ValidRegionGrowing {
 public:
  // `births`: per face, the input triangle it was cut from (itself if uncut).
  ValidRegionGrowing(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                     const std::vector<char>& newFace, std::vector<TrianglePoints> births)
      : P_(P), T_(T), newFace_(newFace), births_(std::move(births)), edges_(T) {
    boxes_.resize(T.size());
    bounds_ = boxes_.empty() ? Box{} : boxOf(P[T[0][0]], P[T[0][1]], P[T[0][2]]);
    for (std::size_t f = 0; f < T.size(); ++f) {
      boxes_[f] = boxOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]);
      for (int k = 0; k < 3; ++k) {
        bounds_.lo[k] = std::min(bounds_.lo[k], boxes_[f].lo[k]);
        bounds_.hi[k] = std::max(bounds_.hi[k], boxes_[f].hi[k]);
      }
    }
    // Regions the growing crosses freely (through manifold edges): a region
    // is kept or removed as a whole, so a seed test that proves one face of
    // it inside settles the others.
    region_.resize(T.size());
    std::iota(region_.begin(), region_.end(), 0);
    closed_ = true;
    for (std::size_t e = 0; e < edges_.count(); ++e) {
      const int first = edges_.first[e];
      const auto [fwd, bwd] = edges_.directions(int(e), T);
      if (fwd != bwd) closed_ = false;  // a border, or a fin: no winding number
      if (edges_.manifold(int(e), T))
        region_[find(region_, edges_.uses[first].face)] =
            find(region_, edges_.uses[first + 1].face);
    }
    for (std::size_t f = 0; f < T.size(); ++f) region_[f] = find(region_, int(f));
  }

  bool closed() const { return closed_; }
  std::size_t seeds = 0, rays = 0, conflicts = 0;

  // Marks the valid faces: the outer loop of §2.3 over seed faces.
  std::vector<char> grow() {
    valid_.assign(T_.size(), 0);
    std::vector<char> settled(T_.size(), 0);  // per region: proved inside, or gave up
    std::vector<int> tries(T_.size(), 0);
    // Faces without intersections are the paper's seed candidates; faces cut
    // by a curve come second (a region made only of those has no other).
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t f = 0; f < T_.size(); ++f) {
        if (valid_[f] || settled[region_[f]] || (pass == 0) == bool(newFace_[f])) continue;
        const RayVerdict verdict = castRay(int(f));
        ++rays;
        if (verdict == RayVerdict::kOutside) {
          ++seeds;
          growFrom(int(f));
        } else if (verdict == RayVerdict::kInside || ++tries[region_[f]] >= kMaxTries) {
          settled[region_[f]] = 1;
        }
      }
    return valid_;
  }

  // Stitches the valid faces (§2.4): a face is joined across each edge to
  // the face next() continues the surface with (the neighbour across a
  // manifold edge); a vertex becomes one output vertex per fan of faces
  // joined around it, so singular vertices and edges come out duplicated.
  struct Stitched {
    std::vector<int> vertex_of_corner;  // per valid face corner (3f + i): output vertex
    std::vector<int> source_vertex;     // per output vertex: its vertex in the input arrays
    std::size_t edges_duplicated = 0;   // edges with more than two valid faces
  };
  Stitched stitch(const std::vector<char>& valid) {
    Stitched s = stitchOnce(valid);
    // Where a vertex's faces form one fan that meets an edge of more than
    // two valid faces twice, copying the vertex cannot separate the sheets
    // on that edge: pairing its faces the other way round (across the
    // material instead of across the outside) splits the fan in two.
    std::vector<int> rest = overloadedEdges(valid, s);
    if (!rest.empty()) {
      alternate_.assign(edges_.count(), 0);
      for (int e : rest) alternate_[e] = 1;
      s = stitchOnce(valid);
      alternate_.clear();
    }
    return s;
  }

 private:
  Stitched stitchOnce(const std::vector<char>& valid) {
    std::vector<int> corner(3 * T_.size());
    std::iota(corner.begin(), corner.end(), 0);
    Stitched s;
    const std::size_t conflictsWhileGrowing = conflicts;
    for (std::size_t f = 0; f < T_.size(); ++f) {
      if (!valid[f]) continue;
      for (int i = 0; i < 3; ++i) {
        const int g = next(int(f), i);
        if (g < 0 || !valid[g]) continue;
        const int p = T_[f][i], q = T_[f][(i + 1) % 3];
        for (int j = 0; j < 3; ++j)
          if (T_[g][j] == q && T_[g][(j + 1) % 3] == p) {
            corner[find(corner, int(3 * f) + i)] = find(corner, 3 * g + (j + 1) % 3);
            corner[find(corner, int(3 * f) + (i + 1) % 3)] = find(corner, 3 * g + j);
          }
      }
    }
    conflicts = conflictsWhileGrowing;
    for (std::size_t e = 0; e < edges_.count(); ++e) {
      int kept = 0;
      for (int k = edges_.first[e]; k < edges_.first[e + 1]; ++k)
        kept += valid[edges_.uses[k].face];
      s.edges_duplicated += kept > 2;
    }
    s.vertex_of_corner.assign(3 * T_.size(), -1);
    std::vector<int> outOfRoot(3 * T_.size(), -1);
    for (std::size_t f = 0; f < T_.size(); ++f) {
      if (!valid[f]) continue;
      for (int i = 0; i < 3; ++i) {
        const int root = find(corner, int(3 * f) + i);
        if (outOfRoot[root] < 0) {
          outOfRoot[root] = int(s.source_vertex.size());
          s.source_vertex.push_back(T_[f][i]);
        }
        s.vertex_of_corner[3 * f + i] = outOfRoot[root];
      }
    }
    return s;
  }

  // Edges (of the cut mesh) that come out with more than two faces.
  std::vector<int> overloadedEdges(const std::vector<char>& valid, const Stitched& s) const {
    std::vector<int> faces;
    std::vector<Triangle> stitched;
    for (std::size_t f = 0; f < T_.size(); ++f)
      if (valid[f]) {
        faces.push_back(int(f));
        stitched.push_back({s.vertex_of_corner[3 * f], s.vertex_of_corner[3 * f + 1],
                            s.vertex_of_corner[3 * f + 2]});
      }
    const std::vector<EdgeUse> uses = edgeUses(stitched);
    std::vector<int> out;
    for (std::size_t i = 0; i < uses.size();) {
      std::size_t j = i + 1;
      while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
      if (j - i > 2) out.push_back(edges_.edge_of_use[3 * faces[uses[i].face] + uses[i].corner]);
      i = j;
    }
    return out;
  }

  static constexpr int kMaxTries = 32;

  RadialOrder::Sheet sheet(const EdgeUse& use, int p) const {
    return {&births_[use.face], T_[use.face][use.corner] == p ? 1 : -1};
  }

  // The face across f's edge i where the surface goes on (§2.3, Figure 4).
  // Across a manifold edge, the neighbour. Where sheets meet (a curve, or an
  // edge the input already had more faces on), the faces are visited in
  // turn from f towards its front, counting the winding number of the
  // wedges between them relative to the one in front of f: a face running
  // the edge as f does is crossed from its back to its front (-1), one
  // running it the other way from front to back (+1). The surface goes on
  // at the first face where the count rises from f's front level (0) to its
  // back level (1). With two sheets crossing this is the paper's rule (the
  // two faces, folded on the edge, have opposing normals); with more, it
  // passes over inverted pockets (a fold turned inside out, where the
  // winding number drops below the outside's) instead of entering them.
  // -1 at a border, or where no face continues the surface (counted).
  int next(int f, int i) {
    const int e = edges_.edge_of_use[3 * f + i];
    const int first = edges_.first[e], n = edges_.size(e);
    if (n == 1) return -1;
    const Triangle& t = T_[f];
    const int p = t[i], q = t[(i + 1) % 3];
    if (n == 2) {
      const EdgeUse& other =
          edges_.uses[first].face == f ? edges_.uses[first + 1] : edges_.uses[first];
      return T_[other.face][other.corner] == q ? other.face : -1;
    }
    const RadialOrder order(P_[p], P_[q], {&births_[f], 1});
    struct Around {
      int face;
      RadialOrder::Sheet sheet;
      int half;
    };
    std::vector<Around> around;
    for (int k = first; k < first + n; ++k) {
      const EdgeUse& use = edges_.uses[k];
      if (use.face == f) continue;
      const RadialOrder::Sheet g = sheet(use, p);
      around.push_back({use.face, g, order.half(g)});
    }
    std::sort(around.begin(), around.end(), [&](const Around& x, const Around& y) {
      return order.before(x.sheet, x.half, y.sheet, y.half);
    });
    if (!alternate_.empty() && alternate_[e]) {
      // Stitching the other way round: the first face met turning from f
      // towards its back that runs the edge the other way.
      for (auto a = around.rbegin(); a != around.rend(); ++a)
        if (a->sheet.e < 0) return a->face;
      return -1;
    }
    int level = 0;
    for (const Around& a : around) {
      if (a.sheet.e < 0 && level == 0) return a.face;
      level += a.sheet.e < 0 ? 1 : -1;
    }
    ++conflicts;
    return -1;
  }

  // The valid and partially valid queues of §2.3. Faces of the split mesh
  // that no curve cut are the paper's valid triangles (V); the pieces of
  // cut ones (P) are the sub-triangles of its in-plane constrained
  // triangulation, which split.h made once for all: the fill traversal
  // inside a cut triangle is the walk across its pieces, stopped at the
  // constraint (curve) edges, where the side choice of next() applies.
  void growFrom(int seed) {
    std::vector<int> V{seed}, Pq;
    valid_[seed] = 1;
    while (!V.empty() || !Pq.empty()) {
      std::vector<int>& queue = !V.empty() ? V : Pq;
      const int f = queue.back();
      queue.pop_back();
      for (int i = 0; i < 3; ++i) {
        const int g = next(f, i);
        if (g < 0 || valid_[g]) continue;
        valid_[g] = 1;
        (newFace_[g] ? Pq : V).push_back(g);
      }
    }
  }

  // Calls visit(face) for every face whose box overlaps `query`. Most
  // meshes need a few rays: those scan the boxes; many rays get a tree.
  template <class Visit>
  void facesOverlapping(const Box& query, Visit&& visit) const {
    if (!tree_ && ++scans_ > kRaysBeforeTree)
      tree_ = std::make_unique<BoxTree>(boxes_, BoxTree::Layout::kMorton);
    if (tree_) {
      tree_->query(query, 0, [&](std::uint32_t h, unsigned) { visit(h); });
      return;
    }
    for (std::size_t h = 0; h < boxes_.size(); ++h)
      if (overlap(query, boxes_[h])) visit(std::uint32_t(h));
  }

  // Seed test (§2.3): is the space just in front of face f outside the
  // surface? A ray from f's centroid along the coordinate axis closest to
  // its normal (so it leaves f on its front) is tested exactly against
  // every face. On a closed mesh the faces it enters and leaves must
  // balance: the winding number in front of f is 0 (which also keeps the
  // inner walls of hollow parts). On a mesh with borders the winding
  // number is not defined: the ray must meet nothing, the paper's rule.
  // A ray through an edge or vertex decides nothing.
  RayVerdict castRay(int f) const {
    const Triangle& t = T_[f];
    const Point3 n = normalOf(P_[t[0]], P_[t[1]], P_[t[2]]);
    int k = 0;
    for (int j = 1; j < 3; ++j)
      if (std::abs(n[j]) > std::abs(n[k])) k = j;
    if (!(std::abs(n[k]) > 0)) return RayVerdict::kUndecided;
    const Point3 o = (P_[t[0]] + P_[t[1]] + P_[t[2]]) / 3.0;
    Point3 end = o;
    const double extent = double(bounds_.hi[k]) - double(bounds_.lo[k]) + 1;
    end[k] = n[k] > 0 ? double(bounds_.hi[k]) + extent : double(bounds_.lo[k]) - extent;
    int winding = 0, hits = 0;
    bool undecided = false;
    facesOverlapping(boxOf(o, end, end), [&](std::uint32_t h) {
      if (undecided || int(h) == f) return;
      const Triangle& s = T_[h];
      const Point3 &a = P_[s[0]], &b = P_[s[1]], &c = P_[s[2]];
      if (collinear(a, b, c)) return;
      const int so = orient3d(a, b, c, o), se = orient3d(a, b, c, end);
      if (so == se && so != 0) return;
      if (so == 0 || se == 0) {
        if (segmentIntersectsTriangle(o, end, {a, b, c})) undecided = true;
        return;
      }
      const int e1 = orient3d(o, end, a, b), e2 = orient3d(o, end, b, c),
                e3 = orient3d(o, end, c, a);
      if ((e1 > 0 || e2 > 0 || e3 > 0) && (e1 < 0 || e2 < 0 || e3 < 0)) return;  // misses
      if (e1 == 0 || e2 == 0 || e3 == 0) {
        undecided = true;  // through an edge or a vertex
        return;
      }
      ++hits;
      winding += so < 0 ? 1 : -1;  // leaving a face through its front lowers the winding number
    });
    if (undecided) return RayVerdict::kUndecided;
    if (!closed_) return hits == 0 ? RayVerdict::kOutside : RayVerdict::kUndecided;
    return winding == 0 ? RayVerdict::kOutside : RayVerdict::kInside;
  }

  const std::vector<Point3>& P_;
  const std::vector<Triangle>& T_;
  const std::vector<char>& newFace_;
  std::vector<TrianglePoints> births_;
  Edges edges_;
  std::vector<Box> boxes_;  // per face
  Box bounds_;
  static constexpr int kRaysBeforeTree = 8;
  mutable int scans_ = 0;
  mutable std::unique_ptr<BoxTree> tree_;  // over boxes_, once the rays are many
  std::vector<int> region_;
  std::vector<char> valid_;
  std::vector<char> alternate_;  // per edge: stitch across the material (see stitch())
  bool closed_ = true;
};

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
      ") neighbouring faces run the same way, so inside and outside are undefined there. Run "
      "Filters > Normals, Curvatures and Orientation > \"Re-Orient all faces coherently\" first.");
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

// Copies of one vertex (singular vertices and edges split by stitching)
// still coincide, so their fans touch: by the self-intersection rule they
// intersect. Each copy moves into its own side by kSeparation of its fan's
// size: towards the centroid of its fan, or else against its fan's normal,
// each tried at full, quarter and sixteenth length; a move is kept only if
// the copy's faces then cross nothing (exact), else the copy goes back.
// With `asFloat` the moved positions are rounded to float (as stored).
// Returns the copies left moved.
std::size_t separateCopies(std::vector<Point3>& P, const std::vector<Triangle>& T,
                           const std::vector<int>& source, bool asFloat) {
  constexpr double kSeparation = 1e-3;
  std::vector<int> copies(*std::max_element(source.begin(), source.end()) + 1, 0);
  for (int s : source) ++copies[s];
  std::vector<Point3> normal(P.size(), Point3(0, 0, 0)), centroid(P.size(), Point3(0, 0, 0));
  std::vector<double> length(P.size(), 0);
  std::vector<int> count(P.size(), 0);
  for (const Triangle& t : T)
    for (int i = 0; i < 3; ++i) {
      const int v = t[i];
      if (copies[source[v]] < 2) continue;
      normal[v] += normalOf(P[t[0]], P[t[1]], P[t[2]]);
      centroid[v] += P[t[(i + 1) % 3]] + P[t[(i + 2) % 3]];
      length[v] += (P[t[(i + 1) % 3]] - P[v]).Norm();
      ++count[v];
    }
  auto stored = [asFloat](const Point3& p) { return asFloat ? roundedToFloat(p) : p; };
  // Candidate positions per copy, in the order tried; the last is home.
  std::vector<int> moving;
  std::vector<std::vector<Point3>> steps(P.size());
  for (std::size_t v = 0; v < P.size(); ++v) {
    if (count[v] == 0) continue;
    const Point3 towardsFan = (centroid[v] / (2.0 * count[v]) - P[v]) * kSeparation;
    const double n = normal[v].Norm();
    const Point3 inward =
        n > 0 ? normal[v] * (-kSeparation * length[v] / count[v] / n) : Point3(0, 0, 0);
    for (double scale : {1.0, 0.25, 0.0625}) {
      steps[v].push_back(stored(P[v] + towardsFan * scale));
      steps[v].push_back(stored(P[v] + inward * scale));
    }
    steps[v].push_back(P[v]);
    moving.push_back(int(v));
  }
  if (moving.empty()) return 0;
  // Candidate pairs of faces around moving copies, from boxes that hold
  // every position their corners may take.
  std::vector<char> isMoving(P.size(), 0), aroundMoving(T.size(), 0);
  for (int v : moving) isMoving[v] = 1;
  std::vector<Box> reach;
  std::vector<int> reachIndex(T.size(), -1);
  for (std::size_t f = 0; f < T.size(); ++f) {
    for (int v : T[f]) aroundMoving[f] |= isMoving[v];
    if (!aroundMoving[f]) continue;
    Box b = boxOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]);
    for (int v : T[f])
      for (const Point3& q : steps[v]) {
        const Box c = boxOf(q, q, q);
        for (int k = 0; k < 3; ++k)
          b.lo[k] = std::min(b.lo[k], c.lo[k]), b.hi[k] = std::max(b.hi[k], c.hi[k]);
      }
    reachIndex[f] = int(reach.size());
    reach.push_back(b);
  }
  std::vector<std::vector<std::uint32_t>> others(reach.size());
  for (const auto& [f, g] : pairsWithChangedBoxes(P, T, aroundMoving, reach)) {
    others[reachIndex[f]].push_back(g);
    if (reachIndex[g] >= 0) others[reachIndex[g]].push_back(f);
  }
  std::vector<std::vector<std::uint32_t>> around(P.size());
  for (std::size_t f = 0; f < T.size(); ++f)
    if (aroundMoving[f])
      for (int v : T[f])
        if (isMoving[v]) around[v].push_back(std::uint32_t(f));
  auto crossings = [&](int v) {
    std::size_t n = 0;
    for (std::uint32_t f : around[v])
      for (std::uint32_t g : others[reachIndex[f]]) n += facesIntersect(P, T, f, g);
    return n;
  };
  // One copy at a time, against the others where they are now: the first
  // step that leaves its faces crossing nothing, else the one that crosses
  // least if it beats home. Two sweeps: a copy that had to stay home may
  // move once its twin has.
  for (int sweep = 0; sweep < 2; ++sweep)
    for (int v : moving) {
      const Point3 home = steps[v].back();
      if (sweep == 1 && !(P[v] == home)) continue;
      P[v] = home;
      Point3 best = home;
      std::size_t fewest = crossings(v);
      if (fewest == 0) continue;
      for (const Point3& q : steps[v]) {
        P[v] = q;
        const std::size_t n = crossings(v);
        if (n < fewest) best = q, fewest = n;
        if (n == 0) break;
      }
      P[v] = best;
    }
  std::size_t moved = 0;
  for (int v : moving) moved += !(P[v] == steps[v].back());
  return moved;
}

}  // namespace

namespace {

SelfIntersectionResult removeOnce(const Mesh& input, const SelfIntersectionOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto lap = start;
  // Milliseconds since the previous lap.
  auto elapsed = [&lap] {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - lap).count();
    lap = now;
    return ms;
  };
  requireFacesAndFiniteCoordinates(input, "the mesh");
  if (!(options.degenerate_angle_deg >= 0 && options.degenerate_angle_deg < 60))
    throw InvalidInputError("the degenerate face angle must be between 0 and 60 degrees");
  if (!(options.snap_tolerance >= 0 && options.snap_tolerance < 0.5))
    throw InvalidInputError("the snapping tolerance must be between 0 and 0.5");
  SelfIntersectionResult r;
  r.faces_in = std::size_t(input.fn);
  reportProgress(options.progress, 0, "checking the input");

  // The mesh as arrays, welded; each vertex and face remembers its input index.
  MeshArrays arrays = arraysOf(input);
  // Output in float is decided on float: the input as it will be stored
  // too (MeshLab's already is), so only new and moved vertices change later.
  if (options.round_to_float)
    for (Point3& p : arrays.points) p = roundedToFloat(p);
  std::vector<int> vertexOrigin(arrays.points.size()), faceOrigin(arrays.triangles.size());
  std::iota(vertexOrigin.begin(), vertexOrigin.end(), 0);
  std::iota(faceOrigin.begin(), faceOrigin.end(), 0);
  if (options.weld_duplicates) {
    WeldedArrays w = weldCoincident(arrays);
    r.vertices_welded = w.vertices_merged;
    arrays = std::move(w.mesh);
    vertexOrigin = std::move(w.vertex_origin);
    faceOrigin = std::move(w.face_origin);
  }
  std::vector<Point3>& P = arrays.points;
  std::vector<Triangle>& T = arrays.triangles;
  r.duplicate_faces_removed = removeDuplicateFaces(T, faceOrigin);
  if (T.empty()) throw InvalidInputError("the mesh has no faces left after welding");
  {
    const Edges edges(T);
    requireConsistentOrientation(edges, T);
    const TopologyCounts before = topologyOf(edges, T, P.size());
    r.components_before = before.components;
    r.genus_before = before.genus;
    r.border_edges_before = before.border_edges;
    r.non_manifold_edges_before = before.non_manifold_edges;
    r.fin_edges_before = before.fin_edges;
    r.input_closed = before.border_edges == 0;
  }
  // A closed mesh with negative volume is inside out: the region growing
  // keeps what is outside with respect to the orientation, which would be
  // nothing. It runs on the mesh turned over, and the result is turned back.
  r.inside_out = signedVolume(P, T) < 0;
  if (r.inside_out)
    for (Triangle& t : T) std::swap(t[1], t[2]);

  // §2.1 Pre-treatment.
  elapsed();
  {
    Pretreatment pre(P, T, faceOrigin, options.degenerate_angle_deg);
    r.degenerate_faces_before = pre.countDegenerate();
    if (options.pretreat && r.degenerate_faces_before > 0) {
      reportProgress(options.progress, 5, "removing degenerate faces");
      pre.run(r.collapses, r.flips);
    }
    r.degenerate_faces_left = r.degenerate_faces_before > 0 ? pre.countDegenerate() : 0;
  }
  r.stage_ms.pretreat = elapsed();

  // §2.2 Self-intersections, cut into the faces (split.h).
  reportProgress(options.progress, 10, "splitting along the self-intersections");
  Mesh work;
  buildMesh(work, P, T);
  SplitOptions so;
  so.between_meshes = false;
  so.self = true;
  so.separate_meshes = false;
  so.snap_tolerance = options.snap_tolerance;
  SplitResult split = splitAlongIntersections({&work}, so);
  // The cut as the host stores it (output_stage.h): the region growing
  // decides on those coordinates, so that its decisions hold for the result.
  OutputStageOptions stage;
  stage.scalar = options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
  stage.progress = progressWithin(options.progress, 10, 59);
  r.stored = storeForHost(split, {&work}, so, stage);
  r.intersecting_pairs_before = split.intersecting_pairs;
  r.faces_split = split.faces_split;
  const MeshArrays cut = arraysOf(split.merged);
  r.faces_after_split = cut.triangles.size();
  r.stage_ms.split = elapsed();

  // §2.3 Valid region growing.
  reportProgress(options.progress, 60, "growing the valid region");
  // The planes the radial order decides on: each face's birth face, or its
  // own, where snapping moved it off that plane (deciding on the birth plane
  // there let the growing pass from the outer surface into the inner one).
  std::vector<TrianglePoints> births(cut.triangles.size());
  {
    FaceOriginHandle birth = faceOrigins(split.merged);
    const std::vector<char>& snapped = split.merged_snapped_face;
    for (std::size_t f = 0; f < births.size(); ++f)
      births[f] = f < snapped.size() && snapped[f] ? pointsOf(cut.points, cut.triangles[f])
                                                   : pointsOf(P, T[birth[f].face]);
  }
  ValidRegionGrowing growing(cut.points, cut.triangles, split.merged_new_face, std::move(births));
  const std::vector<char> valid = growing.grow();
  r.seeds = growing.seeds;
  r.rays = growing.rays;
  r.side_conflicts = growing.conflicts;
  for (char v : valid) r.faces_kept += v;
  r.faces_removed = valid.size() - r.faces_kept;
  r.stage_ms.growing = elapsed();

  // §2.4 Stitching.
  reportProgress(options.progress, 80, "stitching");
  const auto stitched = growing.stitch(valid);
  r.edges_duplicated = stitched.edges_duplicated;
  {
    std::vector<char> seen(cut.points.size(), 0);
    std::size_t distinct = 0;
    for (int v : stitched.source_vertex) distinct += !seen[v], seen[v] = 1;
    r.vertices_duplicated = stitched.source_vertex.size() - distinct;
  }
  std::vector<Point3> outPoints;
  outPoints.reserve(stitched.source_vertex.size());
  for (int v : stitched.source_vertex) outPoints.push_back(cut.points[v]);
  std::vector<Triangle> outTriangles;
  std::vector<int> outFace;
  for (std::size_t f = 0; f < valid.size(); ++f)
    if (valid[f]) {
      outTriangles.push_back({stitched.vertex_of_corner[3 * f],
                              stitched.vertex_of_corner[3 * f + 1],
                              stitched.vertex_of_corner[3 * f + 2]});
      outFace.push_back(int(f));
    }
  r.stage_ms.stitching = elapsed();
  if (options.separate_touching)
    r.vertices_separated =
        separateCopies(outPoints, outTriangles, stitched.source_vertex, options.round_to_float);
  r.stage_ms.separation = elapsed();
  if (r.inside_out)
    for (Triangle& t : outTriangles) std::swap(t[1], t[2]);
  buildMesh(r.mesh, outPoints, outTriangles);

  // Provenance back to the caller's mesh: the split names the vertices and
  // faces of the welded, pre-treated arrays.
  VertexOriginHandle cutVertex = vertexOrigins(split.merged);
  FaceOriginHandle cutFace = faceOrigins(split.merged);
  auto inputVertex = [&](int v) {
    VertexOrigin o = cutVertex[v];
    o.layer = 0;
    if (o.vertex >= 0) o.vertex = vertexOrigin[o.vertex];
    if (o.face >= 0) o.face = faceOrigin[o.face];
    return o;
  };
  auto inputFace = [&](int f) { return FaceOrigin{0, faceOrigin[cutFace[f].face]}; };
  {
    VertexOriginHandle vo = vertexOrigins(r.mesh);
    FaceOriginHandle fo = faceOrigins(r.mesh);
    for (std::size_t v = 0; v < stitched.source_vertex.size(); ++v)
      vo[v] = inputVertex(stitched.source_vertex[v]);
    for (std::size_t f = 0; f < outFace.size(); ++f) fo[f] = inputFace(outFace[f]);
  }
  if (options.keep_removed && r.faces_removed > 0) {
    std::vector<int> index(cut.points.size(), -1);
    std::vector<Point3> points;
    std::vector<int> source;
    std::vector<Triangle> triangles;
    std::vector<int> faces;
    for (std::size_t f = 0; f < valid.size(); ++f) {
      if (valid[f]) continue;
      Triangle t = cut.triangles[f];
      for (int& v : t) {
        if (index[v] < 0)
          index[v] = int(points.size()), points.push_back(cut.points[v]), source.push_back(v);
        v = index[v];
      }
      if (r.inside_out) std::swap(t[1], t[2]);
      triangles.push_back(t);
      faces.push_back(int(f));
    }
    buildMesh(r.removed, points, triangles);
    VertexOriginHandle vo = vertexOrigins(r.removed);
    FaceOriginHandle fo = faceOrigins(r.removed);
    for (std::size_t v = 0; v < source.size(); ++v) vo[v] = inputVertex(source[v]);
    for (std::size_t f = 0; f < faces.size(); ++f) fo[f] = inputFace(faces[f]);
  }

  const TopologyCounts after = topologyOf(Edges(outTriangles), outTriangles, outPoints.size());
  r.components_after = outTriangles.empty() ? 0 : after.components;
  r.genus_after = after.genus;
  r.border_edges_after = after.border_edges;
  r.non_manifold_edges_after = after.non_manifold_edges;
  r.output_closed = !outTriangles.empty() && after.border_edges == 0;

  elapsed();
  if (options.verify && !outTriangles.empty()) {
    reportProgress(options.progress, 90, "verifying");
    // By the checker's rule, on the whole result as stored: the count a
    // user gets from any tool (output_stage.h).
    MeshArrays stored{outPoints, outTriangles};
    r.remaining_intersecting_pairs = storedIntersectingPairs(stored, stage.scalar);
    r.verified = true;
  }
  r.stage_ms.verify = elapsed();
  r.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  reportProgress(options.progress, 100, "done");
  return r;
}

// How far a result falls short of a valid outer surface: intersecting
// pairs left, non-manifold edges made. (A closed input with fins may open
// at them either way: see fin_edges_before.)
std::array<std::size_t, 2> shortfall(const SelfIntersectionResult& r) {
  return {r.verified ? r.remaining_intersecting_pairs : 0,
          r.non_manifold_edges_after > r.non_manifold_edges_before
              ? r.non_manifold_edges_after - r.non_manifold_edges_before
              : 0};
}

}  // namespace

SelfIntersectionResult removeSelfIntersections(const Mesh& input,
                                               const SelfIntersectionOptions& options) {
  SelfIntersectionResult r = removeOnce(input, options);
  // Snapping moves the surface near the curves by up to its tolerance:
  // where two sheets lie closer than that (nearly coincident scans), it can
  // carry one through the other, and the growing then passes into the inner
  // sheet. Without snapping every decision is exact: such a result is made
  // again without it, and returned instead where it falls short less.
  if (options.snap_tolerance > 0 && shortfall(r) != std::array<std::size_t, 2>{}) {
    SelfIntersectionOptions exact = options;
    exact.snap_tolerance = 0;
    SelfIntersectionResult again = removeOnce(input, exact);
    if (shortfall(again) < shortfall(r)) {
      again.snapping_dropped = true;
      again.time_ms += r.time_ms;
      return again;
    }
  }
  return r;
}

JsonObject toJson(const SelfIntersectionResult& r) {
  JsonObject j;
  j.set("faces_in", r.faces_in)
      .set("faces_kept", r.faces_kept)
      .set("faces_removed", r.faces_removed)
      .set("faces_out", std::size_t(r.mesh.fn))
      .set("intersecting_pairs_before", r.intersecting_pairs_before)
      .set("faces_split", r.faces_split)
      .set("components_before", r.components_before)
      .set("components_after", r.components_after)
      .set("genus_before", r.genus_before)
      .set("genus_after", r.genus_after)
      .set("input_closed", r.input_closed)
      .set("output_closed", r.output_closed)
      .set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("non_manifold_edges_before", r.non_manifold_edges_before)
      .set("fin_edges_before", r.fin_edges_before)
      .set("non_manifold_edges_after", r.non_manifold_edges_after)
      .set("degenerate_faces_before", r.degenerate_faces_before)
      .set("collapses", r.collapses)
      .set("flips", r.flips)
      .set("degenerate_faces_left", r.degenerate_faces_left)
      .set("vertices_welded", r.vertices_welded)
      .set("duplicate_faces_removed", r.duplicate_faces_removed)
      .set("seeds", r.seeds)
      .set("rays", r.rays)
      .set("side_conflicts", r.side_conflicts)
      .set("inside_out", r.inside_out)
      .set("vertices_duplicated", r.vertices_duplicated)
      .set("vertices_separated", r.vertices_separated)
      .set("edges_duplicated", r.edges_duplicated)
      .set("snapping_dropped", r.snapping_dropped);
  if (r.verified) j.set("remaining_intersecting_pairs", r.remaining_intersecting_pairs);
  j.set("time_ms", r.time_ms);
  const auto& t = r.stage_ms;
  j.set("stage_ms", JsonObject()
                        .set("pretreat", t.pretreat)
                        .set("split", t.split)
                        .set("growing", t.growing)
                        .set("stitching", t.stitching)
                        .set("separation", t.separation)
                        .set("verify", t.verify));
  return j;
}

}  // namespace meshmend
