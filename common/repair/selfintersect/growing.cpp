// Region growing and stitching of self-intersection removal (TransforMesh
// §2.3-2.4), and the separation of the copies stitching makes: see
// stages.h.
#include <gmpxx.h>
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>

#include "common/exact/box_tree.h"
#include "common/exact/intersections.h"
#include "common/exact/interval.h"
#include "common/exact/predicates.h"
#include "common/exact/triangle_intersection.h"
#include "common/repair/selfintersect/stages.h"

namespace meshmend::selfintersect {

namespace {

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
    // Near the double range the centre or the ray's end overflow: a ray
    // from or to infinity has no exact predicate, so it decides nothing.
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(o[j]) || !std::isfinite(end[j])) return RayVerdict::kUndecided;
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

}  // namespace

namespace {
// Thrown inside separateCopies when its exact tests reach their bound.
struct SeparationBoundReached {};
// The bound: about a second of exact tests where the moving copies' faces
// lie among many others (the real meshes take a few thousand).
constexpr std::size_t kMaxSeparationTests = 2000000;
}  // namespace

Grown growAndStitch(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                    const std::vector<char>& newFace, std::vector<TrianglePoints> births,
                    const Progress& progress) {
  ValidRegionGrowing growing(P, T, newFace, std::move(births));
  Grown g;
  g.valid = growing.grow();
  reportProgress(progress, 80, "stitching");
  g.stitched = growing.stitch(g.valid);
  g.seeds = growing.seeds;
  g.rays = growing.rays;
  g.conflicts = growing.conflicts;
  return g;
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
                           const std::vector<int>& source, bool asFloat, const Progress& progress,
                           bool* boundReached) {
  constexpr double kSeparation = 1e-3;
  *boundReached = false;
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
  // The crossings of v's faces, counted up to `limit` (a position that
  // reaches the best so far is out), against the work bound.
  std::size_t tests = 0;
  auto crossings = [&](int v, std::size_t limit) {
    std::size_t n = 0;
    for (std::uint32_t f : around[v])
      for (std::uint32_t g : others[reachIndex[f]]) {
        if (n >= limit) return n;
        if (++tests > kMaxSeparationTests) throw SeparationBoundReached();
        n += facesIntersect(P, T, f, g);
      }
    return n;
  };
  // One copy at a time, against the others where they are now: the first
  // step that leaves its faces crossing nothing, else the one that crosses
  // least if it beats home. Two sweeps: a copy that had to stay home may
  // move once its twin has. Past the work bound, the copies not yet tried
  // stay home (the contract check counts what they touch).
  ProgressSpan span(progress, 84, 88, 2 * moving.size(), "separating touching sheets");
  int current = -1;  // the copy being placed, and its best position so far
  Point3 best(0, 0, 0);
  try {
    for (int sweep = 0; sweep < 2; ++sweep)
      for (std::size_t i = 0; i < moving.size(); ++i) {
        span.step(sweep * moving.size() + i);
        const int v = current = moving[i];
        const Point3 home = steps[v].back();
        if (sweep == 1 && !(P[v] == home)) continue;
        P[v] = best = home;
        std::size_t fewest = crossings(v, SIZE_MAX);
        if (fewest == 0) continue;
        for (const Point3& q : steps[v]) {
          P[v] = q;
          const std::size_t n = crossings(v, fewest);
          if (n < fewest) best = q, fewest = n;
          if (n == 0) break;
        }
        P[v] = best;
      }
  } catch (const SeparationBoundReached&) {
    P[current] = best;  // the moves made stay
    *boundReached = true;
  }
  std::size_t moved = 0;
  for (int v : moving) moved += !(P[v] == steps[v].back());
  return moved;
}

}  // namespace meshmend::selfintersect
