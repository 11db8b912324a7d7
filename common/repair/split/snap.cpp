#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>

#include "common/base/errors.h"
#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "common/exact/box_tree.h"
#include "common/exact/exact_point.h"
#include "common/exact/predicates.h"
#include "common/exact/retriangulate.h"
#include "common/repair/split/detail.h"

namespace meshmend::split_detail {

namespace {

// Quality snapping (McLaurin 2012, §2.7). A curve point that lands very
// close to an input vertex, or very close to an input edge, leaves a sliver:
// a face with a tiny angle. With a tolerance τ > 0, scale-free (a fraction of
// the local edge length, as the paper's local tolerances are), two changes
// remove such slivers after the exact split:
//  - a new vertex v within τ·L of an input vertex w it shares an edge with
//    (L: the longest edge around v), or of the next new vertex w along its
//    curve, is merged into w; the curve then runs through w and the
//    surfaces bend by at most |vw| there;
//  - a face (v, a, b) whose new vertex v lies within τ·|ab| of its input
//    edge ab has ab split at v instead: the face across ab becomes two and
//    the sliver goes.
// A change is kept only if every surface stays manifold, no face flips or
// degenerates, the smallest angle there gets larger, and no face it touches
// crosses more faces than before (exact test). The curves stay shared by
// the meshes they separate.
// The faces around each vertex: one array for all vertices, built by
// counting; a vertex whose faces change gets a list of its own.
class FacesAroundVertices {
 public:
  FacesAroundVertices(const std::vector<Triangle>& T, std::size_t vertexCount)
      : first_(vertexCount + 1, 0), faces_(3 * T.size()) {
    for (const Triangle& t : T)
      for (int v : t) ++first_[v + 1];
    for (std::size_t v = 0; v < vertexCount; ++v) first_[v + 1] += first_[v];
    std::vector<std::uint32_t> next(first_.begin(), first_.end() - 1);
    for (std::size_t f = 0; f < T.size(); ++f)
      for (int v : T[f]) faces_[next[v]++] = std::uint32_t(f);
  }

  struct Range {
    const std::uint32_t *b, *e;
    const std::uint32_t* begin() const { return b; }
    const std::uint32_t* end() const { return e; }
  };
  Range operator[](int v) const {
    const auto own = changed_.find(v);
    if (own != changed_.end()) return {own->second.data(), own->second.data() + own->second.size()};
    return {faces_.data() + first_[v], faces_.data() + first_[v + 1]};
  }
  // The list of `v`, to change.
  std::vector<std::uint32_t>& edit(int v) {
    auto [own, added] = changed_.try_emplace(v);
    if (added) own->second.assign(faces_.begin() + first_[v], faces_.begin() + first_[v + 1]);
    return own->second;
  }

 private:
  std::vector<std::uint32_t> first_, faces_;
  std::unordered_map<int, std::vector<std::uint32_t>> changed_;
};

class CurveSnapper {
 public:
  CurveSnapper(OutputArrays& mesh, std::set<std::array<int, 2>>& curves, std::vector<char>& newFace,
               double tolerance, double hostSteps, Scalar host)
      : P_(mesh.positions),
        T_(mesh.triangles),
        faceOrigin_(mesh.face_origin),
        vertexOrigin_(mesh.vertex_origin),
        curves_(curves),
        newFace_(newFace),
        tolerance_(tolerance),
        hostSteps_(hostSteps),
        host_(host),
        alive_(T_.size(), 1),
        snapped_(T_.size(), 0),
        around_(T_, P_.size()),
        snappedTo_(P_.size(), -1),
        fixed_(P_.size(), 0) {
    for (const auto& e : curves_) {
      curveNeighbours_[e[0]].push_back(e[1]);
      curveNeighbours_[e[1]].push_back(e[0]);
    }
    // Snapping reshapes only faces around new vertices, by moves shorter
    // than the tolerance times their longest edge: only faces near the new
    // faces go into the tree. A query that reaches past them (covers())
    // puts every face in.
    double longest = 0, farthest = 0;
    std::vector<Box> near;
    for (std::size_t f = 0; f < T_.size(); ++f)
      if (newFace_[f]) {
        near.push_back(boxOf(P_[T_[f][0]], P_[T_[f][1]], P_[T_[f][2]]));
        for (int i = 0; i < 3; ++i) {
          longest = std::max(longest, Distance(P_[T_[f][i]], P_[T_[f][(i + 1) % 3]]));
          farthest = std::max(farthest, hostReach(P_[T_[f][i]]));
        }
      }
    for (Box& b : near) b = grown(b, 2 * std::max(tolerance_ * longest, farthest));
    grid_ = std::make_unique<BoxGrid>(near);
    std::vector<Box> boxes;
    for (std::size_t f = 0; f < T_.size(); ++f) {
      const Box b = boxOf(P_[T_[f][0]], P_[T_[f][1]], P_[T_[f][2]]);
      if (!grid_->touches(b)) continue;
      boxes.push_back(b);
      treeFace_.push_back(std::uint32_t(f));
    }
    tree_ = std::make_unique<BoxTree>(std::move(boxes), BoxTree::Layout::kMorton);
    indexed_ = T_.size();
  }

  // Merges new vertices into nearby input vertices; returns how many.
  std::size_t snapVertices() {
    struct Candidate {
      double ratio;
      int v, w;
    };
    std::vector<Candidate> candidates;
    for (std::size_t v = 0; v < P_.size(); ++v) {
      if (vertexOrigin_[v].vertex >= 0) continue;  // input vertices never move
      double longest = 0;
      for (std::uint32_t f : around_[v])
        for (int i = 0; i < 3; ++i)
          longest = std::max(longest, Distance(P_[T_[f][i]], P_[T_[f][(i + 1) % 3]]));
      for (std::uint32_t f : around_[v])
        for (int w : T_[f]) {
          // Into an input vertex, or along the curve into another new vertex.
          if (w == int(v) || (vertexOrigin_[w].vertex < 0 && !isCurveEdge(int(v), w))) continue;
          const double d = Distance(P_[v], P_[w]);
          if (d < tolerance_ * longest || d < hostReach(P_[v]))
            candidates.push_back({d / longest, int(v), w});
        }
    }
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& x, const Candidate& y) { return x.ratio < y.ratio; });
    for (const Candidate& c : candidates) reach_ = std::max(reach_, Distance(P_[c.v], P_[c.w]));
    std::size_t snapped = 0;
    for (const Candidate& c : candidates)
      if (snappedTo_[c.v] < 0 && snappedTo_[c.w] < 0 && !fixed_[c.v] && collapse(c.v, c.w)) {
        fixed_[c.w] = 1;  // moves nothing more: every vertex moves once, by at most reach_
        ++snapped;
      }
    return snapped;
  }

  // Splits input edges at new vertices that lie almost on them; returns how many.
  std::size_t snapEdges() {
    std::size_t snapped = 0;
    const std::size_t faces = T_.size();
    for (std::size_t s = 0; s < faces; ++s) {
      if (!alive_[s] || !newFace_[s]) continue;
      for (int i = 0; i < 3; ++i) {
        const int v = T_[s][i], a = T_[s][(i + 1) % 3], b = T_[s][(i + 2) % 3];
        if (vertexOrigin_[v].vertex >= 0 || isCurveEdge(a, b)) continue;
        const Point3 ab = P_[b] - P_[a];
        const double t = ((P_[v] - P_[a]) * ab) / ab.SquaredNorm();
        if (!(t > 0 && t < 1)) continue;
        const double distance = (P_[v] - (P_[a] + ab * t)).Norm();
        if ((distance < tolerance_ * ab.Norm() || distance < hostReach(P_[v])) &&
            splitEdgeAt(std::uint32_t(s), v, a, b)) {
          ++snapped;
          break;
        }
      }
    }
    return snapped;
  }

  // The output without the faces and vertices snapping removed: `index`
  // receives each old vertex's new index (a snapped vertex: its target's).
  void compact(OutputArrays& mesh, std::vector<int>& index) {
    index.assign(P_.size(), -1);
    OutputArrays out;
    for (std::size_t v = 0; v < P_.size(); ++v) {
      if (snappedTo_[v] >= 0) continue;
      index[v] = int(out.positions.size());
      out.positions.push_back(P_[v]);
      out.vertex_origin.push_back(vertexOrigin_[v]);
    }
    for (std::size_t v = 0; v < P_.size(); ++v)
      if (snappedTo_[v] >= 0) index[v] = index[snappedTo_[v]];
    std::vector<char> newFace, snapped;
    for (std::size_t f = 0; f < T_.size(); ++f) {
      if (!alive_[f]) continue;
      out.triangles.push_back({index[T_[f][0]], index[T_[f][1]], index[T_[f][2]]});
      out.face_origin.push_back(faceOrigin_[f]);
      newFace.push_back(newFace_[f]);
      snapped.push_back(snapped_[f]);
    }
    snapped_ = std::move(snapped);
    std::set<std::array<int, 2>> curves;
    for (auto e : curves_) {
      e = {index[e[0]], index[e[1]]};
      if (e[0] > e[1]) std::swap(e[0], e[1]);
      curves.insert(e);
    }
    curves_ = std::move(curves);
    newFace_ = std::move(newFace);
    mesh = std::move(out);
  }

  const std::vector<int>& snappedTo() const { return snappedTo_; }
  // Per face (after compact()): did snapping reshape or make it? Such a face
  // may lie off the plane of the input face it was born from.
  const std::vector<char>& snappedFaces() const { return snapped_; }

 private:
  int mesh(std::uint32_t f) const { return faceOrigin_[f].layer; }

  bool isCurveEdge(int a, int b) const {
    return curves_.count({std::min(a, b), std::max(a, b)}) > 0;
  }

  // hostSteps_ steps of the host's scalar at `p`: closer than this, the
  // host can hardly tell points apart.
  double hostReach(const Point3& p) const {
    return hostSteps_ > 0 ? hostSteps_ * scalarStep(p, host_) : 0;
  }

  std::vector<std::uint32_t> facesAround(int v) const {
    std::vector<std::uint32_t> faces;
    for (std::uint32_t f : around_[v])
      if (alive_[f] && (T_[f][0] == v || T_[f][1] == v || T_[f][2] == v)) faces.push_back(f);
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    return faces;
  }

  TrianglePoints at(const Triangle& t) const { return {P_[t[0]], P_[t[1]], P_[t[2]]}; }

  static Point3 normalOf(const TrianglePoints& t) { return (t[1] - t[0]) ^ (t[2] - t[0]); }

  // `b` grown by `d` on every side, rounded outward.
  static Box grown(Box b, double d) {
    for (int k = 0; k < 3; ++k) {
      b.lo[k] = std::nextafter(float(double(b.lo[k]) - d), -INFINITY);
      b.hi[k] = std::nextafter(float(double(b.hi[k]) + d), INFINITY);
    }
    return b;
  }

  // The tree over every face, as they are now.
  void indexEveryFace() {
    std::vector<Box> boxes(T_.size());
    treeFace_.resize(T_.size());
    for (std::size_t f = 0; f < T_.size(); ++f) {
      boxes[f] = boxOf(P_[T_[f][0]], P_[T_[f][1]], P_[T_[f][2]]);
      treeFace_[f] = std::uint32_t(f);
    }
    tree_ = std::make_unique<BoxTree>(std::move(boxes), BoxTree::Layout::kMorton);
    indexed_ = T_.size();
    grid_.reset();
  }

  // How many faces the triangle `t` (the new shape of face `self`) crosses,
  // leaving out the faces `ignore` (sorted).
  std::size_t crossings(const Triangle& t, std::uint32_t self,
                        const std::vector<std::uint32_t>& ignore) {
    const Box b = grown(boxOf(P_[t[0]], P_[t[1]], P_[t[2]]), reach_);
    if (grid_ && !grid_->covers(b)) indexEveryFace();
    std::size_t n = 0;
    const TrianglePoints a = at(t);
    auto test = [&](std::uint32_t g) {
      if (g == self || !alive_[g] || std::binary_search(ignore.begin(), ignore.end(), g)) return;
      if (collinear(P_[T_[g][0]], P_[T_[g][1]], P_[T_[g][2]])) return;
      const SharedCorners c = sharedCorners(t, T_[g]);
      n += intersectBeyondShared(a, at(T_[g]), c.count, c.ia, c.ib);
    };
    tree_->query(b, 0, [&](std::uint32_t i, unsigned) { test(treeFace_[i]); });
    for (std::size_t g = indexed_; g < T_.size(); ++g) {
      const Box gb = boxOf(P_[T_[g][0]], P_[T_[g][1]], P_[T_[g][2]]);
      if (overlap(b, gb)) test(std::uint32_t(g));
    }
    return n;
  }

  // Crossings of the faces `faces`, shaped as `triangles`, with all other
  // faces (the normal checks keep a fan from folding onto itself).
  std::size_t crossingsOf(const std::vector<std::uint32_t>& faces,
                          const std::vector<Triangle>& triangles) {
    std::size_t n = 0;
    std::vector<std::uint32_t> sorted = faces;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t i = 0; i < faces.size(); ++i) n += crossings(triangles[i], faces[i], sorted);
    return n;
  }

  double smallestAngle(const std::vector<Triangle>& triangles) const {
    double smallest = M_PI;
    for (const Triangle& t : triangles)
      smallest = std::min(smallest, meshmend::smallestAngle(P_[t[0]], P_[t[1]], P_[t[2]]));
    return smallest;
  }

  // With `faces` (of `meshes`) the faces around w after v collapsed into
  // it: is every edge at w in at most two faces of one mesh, and in faces
  // of several meshes only where it is (or comes from) a curve edge?
  bool edgesStayManifold(int v, int w, const std::vector<Triangle>& faces,
                         const std::vector<int>& meshes) const {
    std::map<int, std::map<int, int>> count;  // other end -> mesh -> faces
    for (std::size_t i = 0; i < faces.size(); ++i)
      for (int k = 0; k < 3; ++k)
        if (faces[i][k] == w) {
          ++count[faces[i][(k + 1) % 3]][meshes[i]];
          ++count[faces[i][(k + 2) % 3]][meshes[i]];
        }
    for (const auto& [x, perMesh] : count) {
      const bool curve = isCurveEdge(w, x) || isCurveEdge(v, x);
      if (perMesh.size() > 1 && !curve) return false;
      for (const auto& [m, n] : perMesh)
        if (n > 2 && !curve) return false;  // (a mesh's own curves join four of its faces)
    }
    return true;
  }

  std::size_t facesOfMesh(const std::vector<std::uint32_t>& faces, int m) const {
    return std::size_t(
        std::count_if(faces.begin(), faces.end(), [&](std::uint32_t f) { return mesh(f) == m; }));
  }

  // Is v (with `faces` around it) on the border of mesh m: an edge at v in one face of m only?
  bool onBorder(int v, const std::vector<std::uint32_t>& faces, int m) const {
    std::map<int, int> count;
    for (std::uint32_t f : faces)
      if (mesh(f) == m)
        for (int x : T_[f])
          if (x != v) ++count[x];
    for (const auto& [x, n] : count)
      if (n == 1) return true;
    return false;
  }

  // Merges new vertex v into input vertex w (an edge collapse), if allowed.
  bool collapse(int v, int w) {
    if (curveNeighbours_.count(w) && !isCurveEdge(v, w)) return false;  // would join two curves
    const std::vector<std::uint32_t> fv = facesAround(v);
    std::vector<std::uint32_t> removed, moved;
    for (std::uint32_t f : fv)
      (T_[f][0] == w || T_[f][1] == w || T_[f][2] == w ? removed : moved).push_back(f);
    if (removed.empty()) return false;
    // Per mesh, the link condition: the common neighbours of v and w are
    // the apexes of the faces on vw; and no border pinches.
    std::map<int, std::map<int, int>> neighbours;  // mesh -> vertex -> bits (1: of v, 2: of w)
    const std::vector<std::uint32_t> fw = facesAround(w);
    for (std::uint32_t f : fv)
      for (int x : T_[f]) neighbours[mesh(f)][x] |= 1;
    for (std::uint32_t f : fw)
      for (int x : T_[f]) neighbours[mesh(f)][x] |= 2;
    for (auto& [m, marks] : neighbours) {
      if (onBorder(v, fv, m) && onBorder(w, fw, m) && facesOfMesh(removed, m) != 1)
        return false;  // both on the border, joined inside: the border would pinch
      std::set<int> apexes;
      for (std::uint32_t f : removed)
        if (mesh(f) == int(m))
          for (int x : T_[f])
            if (x != v && x != w) apexes.insert(x);
      for (const auto& [x, bits] : marks)
        if (bits == 3 && x != v && x != w && !apexes.count(x)) return false;
    }
    // Geometry after the move.
    std::vector<Triangle> after;
    std::vector<int> meshes;
    for (std::uint32_t f : moved) {
      Triangle t = T_[f];
      for (int& x : t)
        if (x == v) x = w;
      const TrianglePoints p = at(t);
      if (collinear(p[0], p[1], p[2]) || normalOf(p) * normalOf(at(T_[f])) <= 0) return false;
      after.push_back(t);
      meshes.push_back(mesh(f));
    }
    {
      std::vector<Triangle> all = after;
      std::vector<int> allMeshes = meshes;
      for (std::uint32_t f : fw)
        if (!std::count(removed.begin(), removed.end(), f)) {
          all.push_back(T_[f]);
          allMeshes.push_back(mesh(f));
        }
      if (!edgesStayManifold(v, w, all, allMeshes)) return false;
    }
    std::vector<Triangle> before;
    for (std::uint32_t f : fv) before.push_back(T_[f]);
    if (smallestAngle(after) <= smallestAngle(before)) return false;
    // Exact: no face crosses more than it did. The faces removed are
    // ignored in the count after.
    const std::size_t crossedBefore = crossingsOf(fv, before);
    for (std::uint32_t f : removed) alive_[f] = 0;
    const std::size_t crossedAfter = crossingsOf(moved, after);
    if (crossedAfter > crossedBefore) {
      for (std::uint32_t f : removed) alive_[f] = 1;
      return false;
    }
    for (std::size_t i = 0; i < moved.size(); ++i) {
      T_[moved[i]] = after[i];
      newFace_[moved[i]] = 1;
      snapped_[moved[i]] = 1;
      around_.edit(w).push_back(moved[i]);
    }
    around_.edit(v).clear();
    const auto curve = curveNeighbours_.find(v);
    if (curve != curveNeighbours_.end()) {
      for (int x : curve->second) {
        curves_.erase({std::min(v, x), std::max(v, x)});
        auto& back = curveNeighbours_[x];
        back.erase(std::remove(back.begin(), back.end(), v), back.end());
        if (x == w) continue;
        if (curves_.insert({std::min(w, x), std::max(w, x)}).second) {
          curveNeighbours_[w].push_back(x);
          back.push_back(w);
        }
      }
      curveNeighbours_.erase(v);
    }
    P_[v] = P_[w];
    snappedTo_[v] = w;
    return true;
  }

  // Removes the sliver s = (v, a, b) by splitting the face across ab at v.
  bool splitEdgeAt(std::uint32_t s, int v, int a, int b) {
    std::vector<std::uint32_t> across;
    for (std::uint32_t f : facesAround(a))
      if (f != s && (T_[f][0] == b || T_[f][1] == b || T_[f][2] == b)) across.push_back(f);
    if (across.size() != 1 || mesh(across[0]) != mesh(s)) return false;
    const std::uint32_t g = across[0];
    int k = 0;
    while (T_[g][k] != b) ++k;
    if (T_[g][(k + 1) % 3] != a) return false;  // inconsistently oriented
    const int c = T_[g][(k + 2) % 3];
    if (c == v) return false;
    // vc an edge already: of this mesh, it would be in four faces; of
    // another (v and c both curve points), the meshes would share an edge
    // that is no curve.
    for (std::uint32_t f : facesAround(v))
      if (T_[f][0] == c || T_[f][1] == c || T_[f][2] == c) return false;
    const std::vector<Triangle> after{{b, v, c}, {v, a, c}};
    const Point3 n = normalOf(at(T_[g]));
    for (const Triangle& t : after) {
      const TrianglePoints p = at(t);
      if (collinear(p[0], p[1], p[2]) || normalOf(p) * n <= 0) return false;
    }
    const std::vector<Triangle> before{T_[s], T_[g]};
    if (smallestAngle(after) <= smallestAngle(before)) return false;
    const std::size_t crossedBefore = crossingsOf({s, g}, before);
    alive_[s] = 0;
    T_.push_back(after[1]);  // so that the count sees both new faces
    alive_.push_back(1);
    const Triangle old = T_[g];
    T_[g] = after[0];
    const std::uint32_t added = std::uint32_t(T_.size() - 1);
    const std::size_t crossedAfter = crossingsOf({g, added}, after);
    if (crossedAfter > crossedBefore) {
      T_[g] = old;
      T_.pop_back();
      alive_.pop_back();
      alive_[s] = 1;
      return false;
    }
    faceOrigin_.push_back(faceOrigin_[g]);
    newFace_.push_back(1);
    newFace_[g] = 1;
    snapped_.push_back(1);
    snapped_[g] = 1;
    for (int x : {v, a, c}) around_.edit(x).push_back(added);
    around_.edit(v).push_back(g);
    return true;
  }

  std::vector<Point3>& P_;
  std::vector<Triangle>& T_;
  std::vector<FaceOrigin>& faceOrigin_;
  std::vector<VertexOrigin>& vertexOrigin_;
  std::set<std::array<int, 2>>& curves_;
  std::vector<char>& newFace_;
  double tolerance_;
  double hostSteps_;  // SplitOptions::snap_host_steps
  Scalar host_;       // SplitOptions::host
  std::vector<char> alive_;
  std::vector<char> snapped_;  // per face: reshaped or made by snapping
  FacesAroundVertices around_;
  std::vector<int> snappedTo_;
  std::vector<char> fixed_;  // snapping targets
  std::unordered_map<int, std::vector<int>> curveNeighbours_;
  std::unique_ptr<BoxGrid> grid_;        // where the tree holds every face (null: everywhere)
  std::unique_ptr<BoxTree> tree_;        // over the faces treeFace_ as they were when built
  std::vector<std::uint32_t> treeFace_;  // tree primitive -> face
  std::size_t indexed_ = 0;              // faces from here on were added later: tested one by one
  double reach_ = 0;  // the largest distance a vertex moved: boxes grow by at most this
};

// Each mesh's own output again after snapping, from the (compacted) merged
// faces of that mesh: `index` maps old merged vertices to new ones (a
// snapped vertex to its target). A snapped vertex of a mesh that has no
// vertex at its target keeps its place in that mesh, moved to the target.
void rebuildSeparate(const OutputArrays& merged, const std::vector<int>& index,
                     const std::vector<int>& snappedTo, const std::set<std::array<int, 2>>& curves,
                     std::vector<OutputArrays>& outputs,
                     std::vector<std::vector<int>>& mergedVertex,
                     std::vector<std::vector<std::array<int, 2>>>& curveEdges) {
  for (std::size_t m = 0; m < outputs.size(); ++m) {
    const OutputArrays& old = outputs[m];
    const std::vector<int>& globalOf = mergedVertex[m];
    std::unordered_map<int, int> localOf;  // new merged vertex -> old local vertex kept for it
    for (std::size_t u = 0; u < globalOf.size(); ++u)
      if (snappedTo[globalOf[u]] < 0) localOf.emplace(index[globalOf[u]], int(u));
    for (std::size_t u = 0; u < globalOf.size(); ++u)
      if (snappedTo[globalOf[u]] >= 0) localOf.emplace(index[globalOf[u]], int(u));
    std::vector<int> renumbered(globalOf.size(), -1);
    OutputArrays out;
    std::vector<int> newGlobalOf;
    for (std::size_t u = 0; u < globalOf.size(); ++u) {
      const int g = index[globalOf[u]];
      if (localOf.at(g) != int(u)) continue;
      renumbered[u] = int(out.positions.size());
      out.positions.push_back(merged.positions[g]);
      out.vertex_origin.push_back(old.vertex_origin[u]);
      newGlobalOf.push_back(g);
    }
    std::set<std::array<int, 2>> meshCurves;
    for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
      if (merged.face_origin[f].layer != int(m)) continue;
      const Triangle& t = merged.triangles[f];
      Triangle local;
      for (int k = 0; k < 3; ++k) local[k] = renumbered[localOf.at(t[k])];
      out.triangles.push_back(local);
      out.face_origin.push_back(merged.face_origin[f]);
      for (int k = 0; k < 3; ++k)
        if (curves.count({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}))
          meshCurves.insert(
              {std::min(local[k], local[(k + 1) % 3]), std::max(local[k], local[(k + 1) % 3])});
    }
    outputs[m] = std::move(out);
    mergedVertex[m] = std::move(newGlobalOf);
    curveEdges[m].assign(meshCurves.begin(), meshCurves.end());
  }
}

}  // namespace

void snapCurves(OutputArrays& merged, std::vector<std::array<int, 2>>& curves,
                std::vector<OutputArrays>& outputs, const SplitOptions& options, SplitResult& r) {
  const std::size_t facesBefore = merged.triangles.size();              // edge snaps add faces
  std::set<std::array<int, 2>> curveSet(curves.begin(), curves.end());  // snapping edits it
  CurveSnapper snapper(merged, curveSet, r.merged_new_face, options.snap_tolerance,
                       options.snap_host_steps, options.host);
  r.vertices_snapped = snapper.snapVertices();
  r.edges_snapped = snapper.snapEdges();
  const std::vector<int> snappedTo = snapper.snappedTo();
  std::vector<int> index;
  snapper.compact(merged, index);
  r.merged_snapped_face = snapper.snappedFaces();
  if (options.separate_meshes) {
    rebuildSeparate(merged, index, snappedTo, curveSet, outputs, r.merged_vertex, r.curve_edges);
  } else {
    // No per-mesh outputs to rebuild: only where each input vertex went.
    for (std::vector<int>& global : r.merged_vertex)
      for (int& g : global) g = index[g];
  }
  r.new_vertices -= r.vertices_snapped;
  r.faces_added = r.faces_added + merged.triangles.size() - facesBefore;
  double smallest = M_PI;
  for (std::size_t f = 0; f < merged.triangles.size(); ++f)
    if (r.merged_new_face[f]) {
      const Triangle& t = merged.triangles[f];
      smallest =
          std::min(smallest, meshmend::smallestAngle(merged.positions[t[0]], merged.positions[t[1]],
                                                     merged.positions[t[2]]));
    }
  r.smallest_new_angle_deg = smallest * 180 / M_PI;
  curves.assign(curveSet.begin(), curveSet.end());
}

}  // namespace meshmend::split_detail
