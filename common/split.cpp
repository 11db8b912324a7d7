#include "common/split.h"

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

#include "common/box_tree.h"
#include "common/errors.h"
#include "common/exact_point.h"
#include "common/huge_pages.h"
#include "common/parallel.h"
#include "common/predicates.h"
#include "common/retriangulate.h"
#include "common/split_detail.h"

namespace meshmend {

namespace split_detail {

// Sorts `pairs` (of values in [0, bound)) and removes the repeats, as
// std::sort and std::unique would. A split's curve edges are a few hundred
// to a hundred thousand pairs on as many vertices, and comparison sorting
// them took a tenth of a small split: when `bound` is not much larger than
// their number, a counting sort on the first value (each has the two or
// three curve edges of one curve vertex, ordered in place) takes linear time.
void sortUnique(std::vector<std::array<int, 2>>& pairs, std::size_t bound) {
  if (bound > 16 * pairs.size() + 4096) {  // sparse: the counts would cost more
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    return;
  }
  std::vector<int> start(bound + 1, 0);
  for (const auto& e : pairs) ++start[e[0] + 1];
  for (std::size_t v = 0; v < bound; ++v) start[v + 1] += start[v];
  std::vector<std::array<int, 2>> sorted(pairs.size());
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (const auto& e : pairs) sorted[next[e[0]]++] = e;
  }
  pairs.clear();
  for (std::size_t v = 0; v < bound; ++v) {
    const auto first = sorted.begin() + start[v], last = sorted.begin() + start[v + 1];
    for (auto i = first; i != last; ++i)  // insertion sort: a few per value
      for (auto j = i; j != first && (*j)[1] < (*(j - 1))[1]; --j) std::iter_swap(j, j - 1);
    for (auto i = first; i != last; ++i)
      if (i == first || (*i)[1] != (*(i - 1))[1]) pairs.push_back(*i);
  }
}

// Barycentric coordinates of p in triangle (a, b, c), from the rounded values.
Point3 barycentric(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  const Point3 n = (b - a) ^ (c - a);
  const double n2 = n.SquaredNorm();
  if (!(n2 > 0)) return {1, 0, 0};
  const double wa = (((c - b) ^ (p - b)) * n) / n2, wb = (((a - c) ^ (p - c)) * n) / n2;
  return {wa, wb, 1 - wa - wb};
}

// Closed and open components of a curve graph.
void countCurves(std::size_t vertices, const std::vector<std::array<int, 2>>& edges,
                 std::size_t& loops, std::size_t& open) {
  // Components of the curve graph (union-find with path halving); one is
  // open when it has an end point (a vertex of one curve edge). Curves may
  // branch without ending (three surfaces through one point, the outline of
  // a planar overlap meeting a crossing): a component is closed when none
  // of its vertices ends a curve.
  std::vector<int> parent(vertices), degree(vertices, 0);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& e : edges) {
    ++degree[e[0]], ++degree[e[1]];
    parent[find(e[0])] = find(e[1]);
  }
  enum : std::uint8_t { kNone, kClosed, kOpen };  // per component root
  std::vector<std::uint8_t> component(vertices, kNone);
  for (std::size_t v = 0; v < vertices; ++v) {
    if (degree[v] == 0) continue;
    std::uint8_t& c = component[find(int(v))];
    if (degree[v] == 1)
      c = kOpen;
    else if (c == kNone)
      c = kClosed;
  }
  loops = std::size_t(std::count(component.begin(), component.end(), kClosed));
  open = std::size_t(std::count(component.begin(), component.end(), kOpen));
}

}  // namespace split_detail

using namespace split_detail;

namespace {

using Clock = std::chrono::steady_clock;

// Lexicographic order on exact coordinates, to key the rare points made
// inside one face (crossings of two curves).
struct ExactLess {
  bool operator()(const RationalPoint& p, const RationalPoint& q) const {
    for (int k = 0; k < 3; ++k) {
      if (p.x[k] < q.x[k]) return true;
      if (q.x[k] < p.x[k]) return false;
    }
    return false;
  }
};

// Has the triangle an angle under 1°?
bool isSliver(const Point3& a, const Point3& b, const Point3& c) {
  static const double below = std::pow(std::sin(M_PI / 180), 2);
  return smallestAngleMeasure(a, b, c) < below;
}

// Is p certainly off the line through a and b, by its rounded value and
// error bound? A component of (p - a) x (b - a) is then non-zero: its value
// at the rounded point, less the rounding error of evaluating it and the
// most p's error can change it. False when that does not settle it.
bool visiblyOffLine(const ExactPoint& p, const Point3& a, const Point3& b) {
  constexpr double kEpsilon = std::numeric_limits<double>::epsilon() / 2;
  const Point3 &q = p.approx(), d = b - a, r = q - a;
  const double e = p.error();
  for (int k = 0; k < 3; ++k) {
    const int u = (k + 1) % 3, v = (k + 2) % 3;
    const double left = r[u] * d[v], right = r[v] * d[u];
    const double sum = std::fabs(left) + std::fabs(right);
    if (!(sum > 1e-250) || !std::isfinite(sum)) continue;  // underflow or overflow: no bound
    // Each difference and product rounds once, the subtraction once more
    // (a relative 4 ε of the sum covers them); p's error moves the value by
    // at most e (|d_u| + |d_v|), itself within a relative ε of its rounded form.
    const double bound =
        (4 * kEpsilon * sum + e * (std::fabs(d[u]) + std::fabs(d[v]))) * (1 + 8 * kEpsilon);
    if (std::fabs(left - right) > bound) return true;
  }
  return false;
}

// An input edge: mesh and its two vertices, smaller first.
struct EdgeRef {
  std::uint32_t mesh, u, v;
  bool operator==(const EdgeRef& o) const { return mesh == o.mesh && u == o.u && v == o.v; }
};
EdgeRef edgeRef(std::uint32_t mesh, int a, int b) {
  return {mesh, std::uint32_t(std::min(a, b)), std::uint32_t(std::max(a, b))};
}

// Every distinct curve point of all pairs, named by its defining input
// elements (an input vertex; an input edge crossing an input face; two
// coplanar input edges crossing), so that the pairs sharing a point find it
// without comparing coordinates. Points of different names that coincide
// exactly (degenerate inputs) are merged afterwards.
class CurvePoints {
 public:
  explicit CurvePoints(std::size_t expected) {
    points_.reserve(expected);
    names_.reserve(expected);
    std::size_t slots = 64;  // a power of two, at least twice the points
    while (slots < 2 * expected) slots *= 2;
    slots_.assign(slots, -1);
  }

  // The id of the point `tag` of the pair's contact (its ExactPoint `point`).
  int add(const ContactPoint& tag, const ExactPoint& point, const FaceRef faces[2],
          const std::vector<const std::vector<Triangle>*>& triangles) {
    const FaceRef& own = faces[tag.triangle];
    const Triangle& t = (*triangles[own.mesh])[own.face];
    Name name;
    switch (tag.kind) {
      case ContactPoint::Kind::kVertex:
        name.key = {0, own.mesh, std::uint32_t(t[tag.index]), 0, 0, 0, 0};
        name.vertex_mesh = own.mesh;
        name.vertex = t[tag.index];
        break;
      case ContactPoint::Kind::kEdgeFace: {
        const FaceRef& other = faces[1 - tag.triangle];
        const EdgeRef e = edgeRef(own.mesh, t[tag.index], t[(tag.index + 1) % 3]);
        name.key = {1, e.mesh, e.u, e.v, other.mesh, other.face, 0};
        name.edges[name.edge_count++] = e;
        break;
      }
      case ContactPoint::Kind::kEdgeEdge: {
        const Triangle& tb = (*triangles[faces[1].mesh])[faces[1].face];
        EdgeRef e = edgeRef(faces[0].mesh, t[tag.index], t[(tag.index + 1) % 3]);
        EdgeRef g = edgeRef(faces[1].mesh, tb[tag.other_index], tb[(tag.other_index + 1) % 3]);
        if (std::tie(g.mesh, g.u, g.v) < std::tie(e.mesh, e.u, e.v)) std::swap(e, g);
        name.key = {2, e.mesh, e.u, e.v, g.mesh, g.u, g.v};
        name.edges[name.edge_count++] = e;
        name.edges[name.edge_count++] = g;
        break;
      }
    }
    // Open addressing (linear probing): one lookup per contact point, no
    // allocation per point.
    std::size_t slot = hash(name.key) & (slots_.size() - 1);
    for (; slots_[slot] >= 0; slot = (slot + 1) & (slots_.size() - 1))
      if (names_[slots_[slot]].key == name.key) return slots_[slot];
    slots_[slot] = int(points_.size());
    points_.push_back(point);
    names_.push_back(name);
    if (2 * points_.size() > slots_.size()) rehash();
    return int(points_.size()) - 1;
  }

  // Merges exactly coincident points; afterwards representative(id) names
  // each, and each representative lists its group (next_).
  void mergeCoincident() {
    std::vector<const ExactPoint*> all;
    all.reserve(points_.size());
    for (const ExactPoint& p : points_) all.push_back(&p);
    representative_ = coincidentGroups(all);
    next_.assign(points_.size(), -1);
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const int r = representative_[i];
      if (r == int(i)) continue;
      next_[i] = next_[r];  // the group after r: the later points first
      next_[r] = int(i);
    }
  }

  int representative(int id) const { return representative_[id]; }
  const ExactPoint& point(int id) const { return points_[id]; }
  std::size_t size() const { return points_.size(); }
  // Is the point (a representative) known to lie on input edge e (from the
  // names of its group)?
  bool knownOnEdge(int id, const EdgeRef& e) const {
    for (int q = id; q >= 0; q = next_[q])
      for (int k = 0; k < names_[q].edge_count; ++k)
        if (names_[q].edges[k] == e) return true;
    return false;
  }
  // The input vertex of `mesh` at this point (a representative), or -1;
  // of two coincident ones (duplicates left unwelded), the later.
  int inputVertex(std::uint32_t mesh, int id) const {
    for (int q = next_[id]; q >= 0; q = next_[q])
      if (names_[q].vertex >= 0 && names_[q].vertex_mesh == mesh) return names_[q].vertex;
    return names_[id].vertex >= 0 && names_[id].vertex_mesh == mesh ? names_[id].vertex : -1;
  }

 private:
  using Key = std::array<std::uint32_t, 7>;
  struct Name {
    Key key{};
    std::array<EdgeRef, 2> edges{};  // input edges the point lies on
    int edge_count = 0;
    std::uint32_t vertex_mesh = 0;
    int vertex = -1;  // the input vertex it is, or -1
  };
  static std::size_t hash(const Key& k) {
    std::size_t h = 0;
    for (std::uint32_t x : k) h = h * 0x9E3779B97F4A7C15ull + x;
    return h ^ (h >> 29);
  }
  void rehash() {
    slots_.assign(2 * slots_.size(), -1);
    for (std::size_t i = 0; i < names_.size(); ++i) {
      std::size_t slot = hash(names_[i].key) & (slots_.size() - 1);
      while (slots_[slot] >= 0) slot = (slot + 1) & (slots_.size() - 1);
      slots_[slot] = int(i);
    }
  }

  std::vector<ExactPoint> points_;
  std::vector<Name> names_;
  std::vector<int> slots_;  // hash table: point index or -1
  std::vector<int> representative_;
  std::vector<int> next_;  // the next point of the same group, or -1
};

// Where meshes (or one mesh and itself) overlap in a plane, the contact
// inserts the edges of each side into the other, so both re-triangulate the
// overlap alike and, welded, their faces there coincide: the same three
// vertices twice (either orientation). This keeps each such face once in
// `merged` (McLaurin 2012's result is free of duplicate geometry)
// and returns how many it removed. Only faces whose corners are all curve
// vertices (`onCurve`) can have a twin: other vertices belong to one mesh.
// A curve edge inside an overlap (all its faces were twins) is then an
// ordinary edge of the one surface left there and leaves `curves` (sorted):
// the overlap's outline stays.
std::size_t keepOverlapsOnce(OutputArrays& merged, std::vector<char>& newFace,
                             const std::vector<char>& onCurve,
                             std::vector<std::array<int, 2>>& curves, bool remove = true) {
  std::vector<std::pair<Triangle, std::uint32_t>> corners;  // sorted corners, face
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    Triangle t = merged.triangles[f];
    if (!onCurve[t[0]] || !onCurve[t[1]] || !onCurve[t[2]]) continue;
    std::sort(t.begin(), t.end());
    corners.push_back({t, std::uint32_t(f)});
  }
  std::sort(corners.begin(), corners.end());
  enum : char { kSingle, kTwinKept, kTwinRemoved };
  std::vector<char> twin(merged.triangles.size(), kSingle);
  std::size_t removed = 0;
  for (std::size_t k = 1, first = 0; k < corners.size(); ++k) {
    if (corners[k].first != corners[first].first) {
      first = k;
      continue;
    }
    twin[corners[first].second] = kTwinKept;
    twin[corners[k].second] = kTwinRemoved;
    ++removed;
  }
  if (removed == 0 || !remove) return removed;  // (only counted)
  // A curve edge stays one where a face that had no twin uses it (the
  // overlap's outline), or where more than two faces are left on it (a
  // crossing inside the overlap: the parts' own self-intersections there).
  std::vector<char> outline(curves.size(), 0);
  std::vector<int> facesLeft(curves.size(), 0);
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    const Triangle& t = merged.triangles[f];
    if (twin[f] == kTwinRemoved || int(onCurve[t[0]]) + onCurve[t[1]] + onCurve[t[2]] < 2) continue;
    for (int i = 0; i < 3; ++i) {
      const std::array<int, 2> e = {std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])};
      const auto at = std::lower_bound(curves.begin(), curves.end(), e);
      if (at == curves.end() || *at != e) continue;
      ++facesLeft[at - curves.begin()];
      if (twin[f] == kSingle) outline[at - curves.begin()] = 1;
    }
  }
  std::size_t keptEdges = 0;
  for (std::size_t k = 0; k < curves.size(); ++k)
    if (outline[k] || facesLeft[k] > 2) curves[keptEdges++] = curves[k];
  curves.resize(keptEdges);
  std::size_t kept = 0;
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    if (twin[f] == kTwinRemoved) continue;
    merged.triangles[kept] = merged.triangles[f];
    merged.face_origin[kept] = merged.face_origin[f];
    newFace[kept] = newFace[f];
    ++kept;
  }
  merged.triangles.resize(kept);
  merged.face_origin.resize(kept);
  newFace.resize(kept);
  return removed;
}

// The origin of the output vertex that is input vertex `vertex` of `layer`.
VertexOrigin inputOrigin(int layer, int vertex) {
  return {layer, vertex, -1, Point3(0, 0, 0)};  // (vcg leaves Point3{} unset)
}

// Where MeshSplitter::build writes a mesh's output: the input's vertices
// (with their origins) and kept faces first, then the new vertices and
// faces. ArraysOutput fills OutputArrays, which the merged output and
// snapping work on; MeshOutput fills the output mesh itself, when that is
// all that is asked for, so that the output is written once (a second copy
// of it was a third of the memory a split touched, and on a virtual
// machine memory first touched costs more than the copy).
class ArraysOutput {
 public:
  explicit ArraysOutput(OutputArrays& out) : out_(out) {}
  // Room for `vertices` and `faces` in all; the input's vertices, and its
  // kept faces to be written by index (a third fewer instructions than a
  // push_back each).
  void begin(const std::vector<Point3>& points, int layer, const std::vector<int>& pointOrigins,
             std::size_t keptFaces, std::size_t vertices, std::size_t faces) {
    reserveInHugePages(out_.positions, vertices);
    out_.positions.assign(points.begin(), points.end());
    reserveInHugePages(out_.vertex_origin, vertices);
    out_.vertex_origin.resize(points.size());
    for (std::size_t v = 0; v < points.size(); ++v)
      out_.vertex_origin[v] = inputOrigin(layer, pointOrigins[v]);
    reserveInHugePages(out_.triangles, faces);
    out_.triangles.resize(keptFaces);
    reserveInHugePages(out_.face_origin, faces);
    out_.face_origin.resize(keptFaces);
  }
  void keptFace(std::size_t k, const Triangle& t, const FaceOrigin& origin) {
    out_.triangles[k] = t;
    out_.face_origin[k] = origin;
  }
  int addVertex(const Point3& p, const VertexOrigin& origin) {
    out_.positions.push_back(p);
    out_.vertex_origin.push_back(origin);
    return int(out_.positions.size()) - 1;
  }
  void addFace(const Triangle& t, const FaceOrigin& origin) {
    out_.triangles.push_back(t);
    out_.face_origin.push_back(origin);
  }
  const Point3& position(int v) const { return out_.positions[v]; }
  std::size_t vertices() const { return out_.positions.size(); }
  std::size_t faces() const { return out_.triangles.size(); }
  void end() {}

 private:
  OutputArrays& out_;
};

class MeshOutput {
 public:
  explicit MeshOutput(Mesh& mesh) : mesh_(mesh) {}
  // `vertices` must bound the vertices added: faces point into the vertex
  // array, which must not move.
  void begin(const std::vector<Point3>& points, int layer, const std::vector<int>& pointOrigins,
             std::size_t keptFaces, std::size_t vertices, std::size_t faces) {
    startMesh(mesh_, vertices, faces, vo_, fo_);
    mesh_.vert.resize(points.size());
    for (std::size_t v = 0; v < points.size(); ++v) mesh_.vert[v].P() = points[v];
    vo_._handle->data.resize(points.size());
    for (std::size_t v = 0; v < points.size(); ++v) vo_[v] = inputOrigin(layer, pointOrigins[v]);
    mesh_.face.resize(keptFaces);
    fo_._handle->data.resize(keptFaces);
  }
  void keptFace(std::size_t k, const Triangle& t, const FaceOrigin& origin) {
    Face& f = mesh_.face[k];
    for (int i = 0; i < 3; ++i) f.V(i) = &mesh_.vert[t[i]];
    fo_[k] = origin;
  }
  int addVertex(const Point3& p, const VertexOrigin& origin) {
    if (mesh_.vert.size() == mesh_.vert.capacity())
      throw std::logic_error("split output: more new vertices than its patches have");
    mesh_.vert.emplace_back().P() = p;
    vo_._handle->data.push_back(origin);
    return int(mesh_.vert.size()) - 1;
  }
  void addFace(const Triangle& t, const FaceOrigin& origin) {
    Face& f = mesh_.face.emplace_back();
    for (int i = 0; i < 3; ++i) f.V(i) = &mesh_.vert[t[i]];
    fo_._handle->data.push_back(origin);
  }
  Point3 position(int v) const { return mesh_.vert[v].cP(); }
  std::size_t vertices() const { return mesh_.vert.size(); }
  std::size_t faces() const { return mesh_.face.size(); }
  void end() {
    mesh_.vn = int(mesh_.vert.size());
    mesh_.fn = int(mesh_.face.size());
  }

 private:
  Mesh& mesh_;
  VertexOriginHandle vo_;
  FaceOriginHandle fo_;
};

// A list that keeps its first N elements in place and only a longer one on
// the heap: a crossed face receives a few points and segments, and an
// allocation for each would cost more than the rest of its bookkeeping.
template <class T, std::size_t N>
class SmallList {
 public:
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T* begin() { return size_ <= N ? local_.data() : heap_.data(); }
  T* end() { return begin() + size_; }
  const T* begin() const { return size_ <= N ? local_.data() : heap_.data(); }
  const T* end() const { return begin() + size_; }
  T& operator[](std::size_t i) { return begin()[i]; }
  const T& operator[](std::size_t i) const { return begin()[i]; }
  void push_back(const T& x) {
    if (size_ < N) {
      local_[size_++] = x;
      return;
    }
    if (size_ == N) heap_.assign(local_.begin(), local_.end());
    heap_.push_back(x);
    ++size_;
  }

 private:
  std::array<T, N> local_{};
  std::vector<T> heap_;  // all elements once there are more than N
  std::size_t size_ = 0;
};

// The curve points and segments one face receives (representative ids).
struct FaceWork {
  // Beside the edge bits: the point is known to lie strictly inside the
  // face (so on none of its edges).
  static constexpr std::uint8_t kInside = 1 << 3;
  static constexpr std::uint8_t kEdgeBits = 7;

  SmallList<int, 6> points;
  // Per point: the face's edges it lies inside (bit i: edge i), or kInside.
  SmallList<std::uint8_t, 6> edges;
  SmallList<std::array<int, 2>, 6> segments;  // indices into points
  std::int8_t proper = -1;  // is the face a proper triangle (not collinear)? -1: not asked yet

  int add(int id, std::uint8_t onEdges = 0) {
    for (std::size_t i = 0; i < points.size(); ++i)
      if (points[i] == id) {
        edges[i] |= onEdges;
        return int(i);
      }
    points.push_back(id);
    edges.push_back(onEdges);
    return int(points.size()) - 1;
  }
};

// The work of the faces that receive points, in the order they first do,
// found by face index: a slot per face of the mesh, as a hash map's node
// per face would cost more.
class FaceWorkTable {
 public:
  using Entry = std::pair<std::uint32_t, FaceWork>;
  explicit FaceWorkTable(std::size_t faces) : slot_(faces, -1) {}
  FaceWork& operator[](std::uint32_t f) {  // added when missing
    int& slot = slot_[f];
    if (slot < 0) {
      slot = int(entries_.size());
      entries_.emplace_back(f, FaceWork{});
    }
    return entries_[slot].second;
  }
  const FaceWork& at(std::uint32_t f) const { return entries_[slot_[f]].second; }
  std::size_t size() const { return entries_.size(); }
  std::vector<Entry>::iterator begin() { return entries_.begin(); }
  std::vector<Entry>::iterator end() { return entries_.end(); }
  std::vector<Entry>::const_iterator begin() const { return entries_.begin(); }
  std::vector<Entry>::const_iterator end() const { return entries_.end(); }

 private:
  std::vector<int> slot_;  // per face: its entry, or -1
  std::vector<Entry> entries_;
};

class MeshSplitter {
 public:
  MeshSplitter(WeldedArrays&& input, std::uint32_t index)
      : index_(index),
        points_(std::move(input.mesh.points)),
        triangles_(std::move(input.mesh.triangles)),
        vertexOrigin_(std::move(input.vertex_origin)),
        faceOrigin_(std::move(input.face_origin)),
        work_(triangles_.size()) {}

  const std::vector<Triangle>& triangles() const { return triangles_; }

  TrianglePoints at(std::uint32_t f) const {
    return {points_[triangles_[f][0]], points_[triangles_[f][1]], points_[triangles_[f][2]]};
  }

  // A pair's contact (n curve point ids), seen from this mesh's face f;
  // `inside[i] & insideBit` when point i is known to lie strictly inside f.
  void addContact(std::uint32_t f, const int* contact, const std::uint8_t* inside,
                  std::uint8_t insideBit, std::size_t n) {
    FaceWork& w = work_[f];
    int ids[6];  // a contact has at most six points (two coplanar triangles' overlap)
    for (std::size_t i = 0; i < n; ++i)
      ids[i] = w.add(contact[i], inside[i] & insideBit ? FaceWork::kInside : 0);
    if (n == 2 && ids[0] != ids[1]) w.segments.push_back({ids[0], ids[1]});
    if (n > 2)
      for (std::size_t i = 0; i < n; ++i)
        if (ids[i] != ids[(i + 1) % n]) w.segments.push_back({ids[i], ids[(i + 1) % n]});
  }

  // Points on an edge of a face also split that edge in the faces across it.
  void shareEdgePoints(const CurvePoints& table) {
    struct Shared {
      std::uint32_t face;
      int id;
      std::uint8_t edges;
    };
    // The faces around the corners of the faces that received points
    // (compressed rows), where rows for every vertex would write three
    // entries per face of the whole mesh.
    std::vector<int> row(points_.size(), -1);
    int rows = 0;
    for (const auto& [f, w] : work_)
      for (int v : triangles_[f])
        if (row[v] < 0) row[v] = rows++;
    // One pass over all faces finds the few that touch such a corner (-1 in
    // all three rows: none); the rows are made from those.
    std::vector<std::uint32_t> near;
    for (std::size_t f = 0; f < triangles_.size(); ++f) {
      const Triangle& t = triangles_[f];
      if ((row[t[0]] & row[t[1]] & row[t[2]]) != -1) near.push_back(std::uint32_t(f));
    }
    std::vector<std::uint32_t> offsets(std::size_t(rows) + 1, 0), faces;
    for (std::uint32_t f : near)
      for (int v : triangles_[f])
        if (row[v] >= 0) ++offsets[row[v] + 1];
    for (int r = 0; r < rows; ++r) offsets[r + 1] += offsets[r];
    faces.resize(offsets.back());
    {
      std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
      for (std::uint32_t f : near)
        for (int v : triangles_[f])
          if (row[v] >= 0) faces[next[row[v]]++] = f;
    }
    std::vector<Shared> shared;
    for (auto& [f, w] : work_) {
      const Triangle& t = triangles_[f];
      auto isProper = [&, &w = w] {  // asked once, if needed
        if (w.proper < 0) w.proper = !collinear(at(f)[0], at(f)[1], at(f)[2]);
        return w.proper == 1;
      };
      for (std::size_t p = 0; p < w.points.size(); ++p) {
        if (w.edges[p] & FaceWork::kInside) continue;
        // A point known to lie inside one edge of a proper triangle lies on
        // no other (two edges share only a corner): the other tests are spared.
        std::uint8_t edges = 0;
        for (int i = 0; i < 3; ++i)
          if (table.knownOnEdge(w.points[p], edgeRef(index_, t[i], t[(i + 1) % 3])))
            edges |= std::uint8_t(1 << i);
        if (edges == 0 || !isProper())
          for (int i = 0; i < 3; ++i)
            if (!(edges & (1 << i)) && onEdge(table, w.points[p], t[i], t[(i + 1) % 3]))
              edges |= std::uint8_t(1 << i);
        for (int i = 0; i < 3; ++i) {
          if (!(edges & (1 << i))) continue;
          const int a = t[i], b = t[(i + 1) % 3];
          w.edges[p] |= std::uint8_t(1 << i);
          for (std::uint32_t k = offsets[row[a]]; k < offsets[row[a] + 1]; ++k) {
            const std::uint32_t g = faces[k];
            if (g == f) continue;
            const Triangle& u = triangles_[g];
            for (int j = 0; j < 3; ++j)
              if ((u[j] == b && u[(j + 1) % 3] == a) || (u[j] == a && u[(j + 1) % 3] == b))
                shared.push_back({g, w.points[p], std::uint8_t(1 << j)});
          }
        }
      }
    }
    for (const Shared& x : shared) work_[x.face].add(x.id, x.edges);
  }

  // Re-triangulates every face that received points (in parallel if asked).
  void retriangulateFaces(const CurvePoints& table, bool parallel) {
    order_.clear();
    for (const auto& [f, w] : work_) order_.push_back(f);
    std::sort(order_.begin(), order_.end());
    patches_.resize(order_.size());
    parallelChunks(
        order_.size(),
        [&](std::size_t begin, std::size_t end, unsigned) {
          PatchInput in;  // one for the chunk: its storage serves every face
          for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t f = order_[i];
            const FaceWork& w = work_.at(f);
            const TrianglePoints t = at(f);
            if (w.proper == 0 || (w.proper < 0 && collinear(t[0], t[1], t[2])))
              continue;  // degenerate: kept as it is (empty patch)
            for (int k = 0; k < 3; ++k) in.corners[k] = ExactPoint(t[k]);
            in.points.clear();
            for (int id : w.points) in.points.push_back(table.point(id));
            in.on_edges.resize(w.edges.size());
            for (std::size_t p = 0; p < w.edges.size(); ++p)
              in.on_edges[p] = w.edges[p] & FaceWork::kEdgeBits;
            in.segments.clear();
            for (const auto& s : w.segments) in.segments.push_back({3 + s[0], 3 + s[1]});
            patches_[i] = retriangulate(in);
          }
        },
        parallel ? 16 : order_.size() + 1);
  }

  // Builds the output mesh (into `out`, an ArraysOutput or a MeshOutput)
  // and its curve edges; `exactNew` receives the exact positions of the new
  // vertices.
  template <class Output>
  void build(const CurvePoints& table, Output&& out, std::vector<std::array<int, 2>>& curves,
             std::vector<ExactPoint>& exactNew, std::size_t& facesAdded) {
    slivers_ = 0;
    // The output's exact face count, and a bound on its vertices: each new
    // vertex is a point or crossing of one of the patches.
    std::vector<char> split(triangles_.size(), 0);
    std::size_t splitCount = 0, newFaces = 0, newVerticesAtMost = 0;
    for (std::size_t i = 0; i < order_.size(); ++i) {
      const RetriangulatedPatch& patch = patches_[i];
      split[order_[i]] = !patch.triangles.empty();
      if (patch.triangles.empty()) continue;
      ++splitCount;
      newFaces += patch.triangles.size();
      newVerticesAtMost += patch.vertices.size() - 3;
    }
    keptFaces_ = triangles_.size() - splitCount;
    out.begin(points_, int(index_), vertexOrigin_, keptFaces_, points_.size() + newVerticesAtMost,
              keptFaces_ + newFaces);
    for (std::size_t f = 0, k = 0; f < triangles_.size(); ++f)
      if (!split[f]) out.keptFace(k++, triangles_[f], {int(index_), faceOrigin_[f]});
    std::vector<int> vertexOfPoint(table.size(), -1);        // curve point id -> output vertex
    std::vector<std::array<int, 2>> pointOfVertex;           // (output vertex, curve point id)
    std::map<RationalPoint, int, ExactLess> crossingPoints;  // made inside one face
    exactNew.reserve(exactNew.size() + 2 * order_.size());
    auto newVertex = [&](const ExactPoint& p, std::uint32_t f) {
      exactNew.push_back(p);
      const TrianglePoints t = at(f);
      return out.addVertex(
          p.approx(), {int(index_), -1, faceOrigin_[f], barycentric(p.approx(), t[0], t[1], t[2])});
    };
    curves.clear();
    std::vector<int> global;             // per patch vertex: its output vertex
    std::array<Point3, 3> smallestFace;  // the new face with the smallest angle
    double smallestSine = 2;             // its measure (smallestAngleMeasure)
    for (std::size_t i = 0; i < order_.size(); ++i) {
      const std::uint32_t f = order_[i];
      const RetriangulatedPatch& patch = patches_[i];
      if (patch.triangles.empty()) {
        ++degenerateKept_;
        continue;
      }
      const SmallList<int, 6>& ids = work_.at(f).points;
      global.assign(patch.vertices.size(), -1);
      for (int k = 0; k < 3; ++k) global[k] = triangles_[f][k];
      for (std::size_t j = 0; j < ids.size(); ++j) {
        const int v = patch.vertex_of_input[3 + j];
        const int id = ids[j];
        if (global[v] < 0) {
          int& vertex = vertexOfPoint[id];
          if (vertex < 0) {
            const int input = table.inputVertex(index_, id);
            vertex = input >= 0 ? input : newVertex(table.point(id), f);
          }
          global[v] = vertex;
        }
        pointOfVertex.push_back({global[v], id});
      }
      for (std::size_t v = 3; v < patch.vertices.size(); ++v) {
        if (global[v] >= 0) continue;
        const auto [it, added] = crossingPoints.emplace(patch.vertices[v].exact(), -1);
        if (added) it->second = newVertex(patch.vertices[v], f);
        global[v] = it->second;
      }
      // Every contact point is a place where meshes meet, curve or not (a
      // touching corner): the merged output welds them.
      for (std::size_t j = 3; j < patch.vertex_of_input.size(); ++j)
        contactVertices_.push_back(global[patch.vertex_of_input[j]]);
      for (const auto& t : patch.triangles) {
        const Point3 &a = patch.vertices[t[0]].approx(), &b = patch.vertices[t[1]].approx(),
                     &c = patch.vertices[t[2]].approx();
        const double sine = smallestAngleMeasure(a, b, c);
        if (sine < smallestSine) smallestSine = sine, smallestFace = {a, b, c};
        out.addFace({global[t[0]], global[t[1]], global[t[2]]}, {int(index_), faceOrigin_[f]});
        slivers_ += isSliver(out.position(global[t[0]]), out.position(global[t[1]]),
                             out.position(global[t[2]]));
      }
      for (const auto& e : patch.constrained_edges)
        curves.push_back(
            {std::min(global[e[0]], global[e[1]]), std::max(global[e[0]], global[e[1]])});
    }
    sortUnique(curves, out.vertices());
    if (smallestSine < 2)  // one angle computed, not one per face
      smallestAngle_ = meshmend::smallestAngle(smallestFace[0], smallestFace[1], smallestFace[2]);
    // Later entries win, as each curve point is met again in every face it is in.
    pointOfVertex_.assign(out.vertices(), -1);
    for (const auto& [vertex, id] : pointOfVertex) pointOfVertex_[vertex] = id;
    facesAdded += out.faces() - triangles_.size();
    out.end();
  }

  // Frees what only the split itself needs (the faces' work, the patches,
  // the input faces) on the thread that split the mesh, side by side with
  // the other meshes, where freeing everything at the end took a serial
  // tenth of a small split.
  void releaseWorkingMemory() {
    std::vector<RetriangulatedPatch>().swap(patches_);
    work_ = FaceWorkTable(0);
    std::vector<Triangle>().swap(triangles_);
  }

  std::size_t facesWithPoints() const { return work_.size(); }
  // The re-triangulation's work, roughly: the points and segments received.
  std::size_t pointsAndSegments() const {
    std::size_t n = 0;
    for (const auto& [f, w] : work_) n += w.points.size() + w.segments.size();
    return n;
  }
  std::size_t facesSplit() const { return order_.size() - degenerateKept_; }
  std::size_t keptFaces() const { return keptFaces_; }     // output faces before the new ones
  double smallestAngle() const { return smallestAngle_; }  // of the new faces, radians
  // New faces with an angle under 1°, positions as built (the merged
  // output's too, unless snapping moves them).
  std::size_t slivers() const { return slivers_; }
  const std::vector<int>& contactVertices() const { return contactVertices_; }
  // Per output vertex: the curve point id at it, or -1.
  const std::vector<int>& pointOfVertex() const { return pointOfVertex_; }
  std::size_t degenerateKept() const { return degenerateKept_; }
  const std::vector<Point3>& points() const { return points_; }

 private:
  // Is curve point `id` inside the input edge (a, b) of this mesh? (Its
  // name, which may say so, is asked by the caller.)
  bool onEdge(const CurvePoints& table, int id, int a, int b) const {
    const ExactPoint& p = table.point(id);
    if (p.isInputPoint() && (p.approx() == points_[a] || p.approx() == points_[b]))
      return false;                                               // a corner: not inside the edge
    if (visiblyOffLine(p, points_[a], points_[b])) return false;  // most points, cheaply
    // On a copy: the exact value is computed (and kept) per copy, and other
    // meshes' threads read the table's points at the same time.
    return onSegment(ExactPoint(p), ExactPoint(points_[a]), ExactPoint(points_[b]));
  }

  std::uint32_t index_;
  std::vector<Point3> points_;
  std::vector<Triangle> triangles_;
  std::vector<int> vertexOrigin_, faceOrigin_;  // input index of each vertex and face
  FaceWorkTable work_;
  std::vector<std::uint32_t> order_;
  std::vector<RetriangulatedPatch> patches_;
  std::size_t degenerateKept_ = 0;
  std::size_t keptFaces_ = 0;
  double smallestAngle_ = M_PI;
  std::size_t slivers_ = 0;
  std::vector<int> contactVertices_;  // output vertices at contact points
  std::vector<int> pointOfVertex_;
};

// Quality snapping (intersection paper §2.7). A curve point that lands very
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

// Removes faces with the same three vertices as an earlier face (in any
// order): the same surface twice, which would intersect itself everywhere.
std::size_t removeDuplicateFaces(WeldedArrays& in) {
  const std::vector<Triangle>& triangles = in.mesh.triangles;
  auto sorted = [&](std::uint32_t f) {
    Triangle t = triangles[f];
    std::sort(t.begin(), t.end());
    return t;
  };
  // Faces with the same vertices share their smallest: the faces are listed
  // by it (counting, in face order), and each is compared with the earlier
  // faces kept in its list, a few at most. (A table keyed by the vertex set
  // cost four times as much on a large mesh: every probe read another face
  // from anywhere in memory.)
  auto smallest = [&](const Triangle& t) { return std::size_t(std::min({t[0], t[1], t[2]})); };
  std::vector<std::uint32_t> first(in.mesh.points.size() + 1, 0);
  for (const Triangle& t : triangles) ++first[smallest(t) + 1];
  for (std::size_t v = 1; v < first.size(); ++v) first[v] += first[v - 1];
  std::vector<std::uint32_t> byCorner(triangles.size());
  {
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for (std::size_t f = 0; f < triangles.size(); ++f)
      byCorner[next[smallest(triangles[f])]++] = std::uint32_t(f);
  }
  std::vector<char> drop(triangles.size(), 0);
  for (std::size_t v = 0; v + 1 < first.size(); ++v)
    for (std::uint32_t i = first[v] + 1; i < first[v + 1]; ++i) {
      const Triangle key = sorted(byCorner[i]);
      for (std::uint32_t j = first[v]; j < i && !drop[byCorner[i]]; ++j)
        if (!drop[byCorner[j]] && sorted(byCorner[j]) == key) drop[byCorner[i]] = 1;
    }
  std::size_t kept = 0;
  for (std::size_t f = 0; f < drop.size(); ++f)
    if (!drop[f]) {
      in.mesh.triangles[kept] = in.mesh.triangles[f];
      in.face_origin[kept] = in.face_origin[f];
      ++kept;
    }
  const std::size_t removed = drop.size() - kept;
  in.mesh.triangles.resize(kept);
  in.face_origin.resize(kept);
  return removed;
}

// Does the split snap curve points (quality snapping, or within float steps)?
bool snaps(const SplitOptions& o) {
  return o.snap_tolerance > 0 || o.snap_host_steps > 0;
}

}  // namespace

TriplePoints mostTriplePoints(const std::vector<IntersectingPair>& pairs,
                              const std::vector<std::size_t>& faces, std::size_t bound) {
  std::vector<std::size_t> first(faces.size() + 1, 0);  // each mesh's first global face
  for (std::size_t m = 0; m < faces.size(); ++m) first[m + 1] = first[m] + faces[m];
  auto global = [&](const FaceRef& f) { return first[f.mesh] + f.face; };
  std::vector<std::vector<std::size_t>> crossing(first.back());
  for (const IntersectingPair& p : pairs) {
    crossing[global(p.a)].push_back(global(p.b));
    crossing[global(p.b)].push_back(global(p.a));
  }
  for (auto& list : crossing) std::sort(list.begin(), list.end());
  auto cross = [&](std::size_t g, std::size_t h) {
    return std::binary_search(crossing[g].begin(), crossing[g].end(), h);
  };
  std::size_t most = 0, at = 0;
  for (std::size_t f = 0; f < crossing.size() && most <= bound; ++f) {
    const auto& list = crossing[f];
    std::size_t triples = 0;
    for (std::size_t i = 0; i < list.size() && triples <= bound; ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) triples += cross(list[i], list[j]);
    if (triples > most) most = triples, at = f;
  }
  TriplePoints r;
  r.count = most;
  const std::size_t mesh = std::upper_bound(first.begin(), first.end(), at) - first.begin() - 1;
  r.face = {std::uint32_t(mesh), std::uint32_t(at - first[mesh])};
  return r;
}

SplitResult splitAlongIntersections(const std::vector<const Mesh*>& meshes,
                                    const SplitOptions& options) {
  const auto start = Clock::now();
  if (!options.separate_meshes && !options.merged_output)
    throw InvalidInputError(
        "nothing to output: ask for the separate meshes, the merged mesh or both");
  SplitResult r;
  // The inputs as arrays, with their seams closed when asked; each keeps
  // the input index of its vertices and faces. Meshes side by side; an
  // error names the first mesh at fault.
  std::vector<WeldedArrays> inputs(meshes.size());
  std::vector<std::size_t> duplicateFaces(meshes.size(), 0);
  parallelChunks(
      meshes.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t m = begin; m < end; ++m) {
          requireFacesAndFiniteCoordinates(*meshes[m], "mesh " + std::to_string(m));
          WeldedArrays& in = inputs[m];
          if (options.weld_duplicates) {
            in = weldCoincident(arraysOf(*meshes[m]));
          } else {
            in.mesh = arraysOf(*meshes[m]);
            in.vertex_origin.resize(in.mesh.points.size());
            std::iota(in.vertex_origin.begin(), in.vertex_origin.end(), 0);
            in.face_origin.resize(in.mesh.triangles.size());
            std::iota(in.face_origin.begin(), in.face_origin.end(), 0);
          }
          if (options.remove_duplicate_faces) duplicateFaces[m] = removeDuplicateFaces(in);
        }
      },
      1);
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    if (inputs[m].mesh.triangles.empty())
      throw InvalidInputError(
          "mesh " + std::to_string(m) +
          " has no face left once its coincident vertices are welded: every face had two "
          "corners at one position (as where coordinates are very large for the mesh's size, "
          "stored in float); move the mesh near the origin first, or do not weld");
    r.vertices_welded += inputs[m].vertices_merged;
    r.duplicate_faces_removed += duplicateFaces[m];
  }
  std::vector<const MeshArrays*> arrays;
  for (const WeldedArrays& in : inputs) arrays.push_back(&in.mesh);
  FindIntersectionsOptions find;
  find.self = options.self;
  find.cross = options.between_meshes;
  find.contacts = true;
  find.same_vertices = false;
  find.progress = [&](int percent, const char* stage) {
    return !options.progress || options.progress(percent * 4 / 10, stage);
  };
  FindIntersectionsResult found = findIntersectionsInArrays(arrays, find);
  r.intersecting_pairs = found.pairs.size();
  if (options.max_triple_points_per_face > 0) {
    std::vector<std::size_t> faces;
    for (const MeshArrays* a : arrays) faces.push_back(a->triangles.size());
    const TriplePoints most =
        mostTriplePoints(found.pairs, faces, options.max_triple_points_per_face);
    if (most.count > options.max_triple_points_per_face)
      throw WorkLimitError(
          "in face " + std::to_string(most.face.face) + " of mesh " +
          std::to_string(most.face.mesh) + " more than " +
          std::to_string(options.max_triple_points_per_face) +
          " pairs of the faces crossing it cross each other too (max_triple_points_per_face): "
          "the surfaces pass many times through nearly one point there, as the meridians of a "
          "spindle torus do near its axis, and cutting it would take the exact arithmetic "
          "minutes. Nothing was changed. Remove the faces around that point (select them, "
          "Filters > Selection > Delete Selected Faces) and close the hole with MeshMend: Fill "
          "Holes, then split again");
  }
  r.complete = options.self && (options.between_meshes || meshes.size() == 1);

  reportProgress(options.progress, 40, "Collecting curve points");
  std::vector<MeshSplitter> splitters;
  splitters.reserve(meshes.size());
  for (std::size_t m = 0; m < meshes.size(); ++m)
    splitters.emplace_back(std::move(inputs[m]), std::uint32_t(m));
  std::vector<const std::vector<Triangle>*> triangles;
  for (const MeshSplitter& s : splitters) triangles.push_back(&s.triangles());
  CurvePoints table(2 * found.pairs.size());
  // Each pair's contact as curve point ids, all pairs in one array, and
  // per point the face of the pair it is known to lie strictly inside
  // (FaceWork::kInside: bit 0 the pair's first face, bit 1 its second).
  std::vector<int> contactIds;
  std::vector<std::uint8_t> contactInside;
  std::vector<std::size_t> contactStart(found.pairs.size() + 1, 0);
  contactIds.reserve(2 * found.pairs.size());
  contactInside.reserve(2 * found.pairs.size());
  for (std::size_t i = 0; i < found.pairs.size(); ++i) {
    const FaceRef faces[2] = {found.pairs[i].a, found.pairs[i].b};
    const TriangleContact& c = found.contacts[i];
    if (c.points.size() > 6) throw std::logic_error("a contact of more than six points");
    for (std::size_t k = 0; k < c.points.size(); ++k) {
      contactIds.push_back(table.add(c.points[k], c.exact[k], faces, triangles));
      const ContactPoint& p = c.points[k];
      contactInside.push_back(p.inside_other ? std::uint8_t(1 << (1 - p.triangle)) : 0);
    }
    contactStart[i + 1] = contactIds.size();
  }
  // The contacts' exact points are in the table now: their memory (a third
  // of a small split's) goes back before the outputs are made.
  std::vector<TriangleContact>().swap(found.contacts);
  table.mergeCoincident();
  for (int& id : contactIds) id = table.representative(id);
  // Each mesh's faces receive their contacts on their own thread, in the
  // pairs' order.
  parallelChunks(
      meshes.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t m = begin; m < end; ++m)
          for (std::size_t i = 0; i < found.pairs.size(); ++i) {
            const int* ids = contactIds.data() + contactStart[i];
            const std::uint8_t* inside = contactInside.data() + contactStart[i];
            const std::size_t n = contactStart[i + 1] - contactStart[i];
            const IntersectingPair& pair = found.pairs[i];
            if (pair.a.mesh == m) splitters[m].addContact(pair.a.face, ids, inside, 1, n);
            if (pair.b.mesh == m) splitters[m].addContact(pair.b.face, ids, inside, 2, n);
          }
      },
      1);
  reportProgress(options.progress, 55, "Re-triangulating crossed faces");
  std::vector<std::vector<ExactPoint>> exactNew(meshes.size());
  std::vector<OutputArrays> outputs(meshes.size());
  r.curve_edges.resize(meshes.size());
  // Each mesh's split reads only the finished curve point table (and copies
  // the points it asks exact questions of), so meshes can be split side by
  // side: a second thread takes meshes from the same counter as this one,
  // and each mesh's faces are re-triangulated on its thread alone (both
  // cores are busy already). Only when the work (points and segments
  // received, not faces: a coarse mesh's faces receive many each) is shared
  // fairly evenly (as between two meshes that cross, where every curve
  // segment goes into both) and there is enough of it to be worth sharing
  // (a few dozen faces); otherwise one mesh after the other, each on every core. With
  // more than two cores, each mesh still re-triangulates on several.
  // When each input's mesh is all that is asked for (no merged output, no
  // snapping), the split writes it directly; otherwise into arrays first.
  const bool directMeshes = options.separate_meshes && !options.merged_output && !snaps(options);
  if (directMeshes) r.meshes.resize(meshes.size());
  std::atomic<std::size_t> nextMesh{0};
  std::vector<std::size_t> facesAdded(meshes.size(), 0);
  bool sideBySide = false;
  auto splitMeshes = [&] {
    for (std::size_t m; (m = nextMesh++) < meshes.size();) {
      splitters[m].shareEdgePoints(table);
      splitters[m].retriangulateFaces(table, !sideBySide || workerCount() > 2);
      if (directMeshes)
        splitters[m].build(table, MeshOutput(r.meshes[m]), r.curve_edges[m], exactNew[m],
                           facesAdded[m]);
      else
        splitters[m].build(table, ArraysOutput(outputs[m]), r.curve_edges[m], exactNew[m],
                           facesAdded[m]);
      splitters[m].releaseWorkingMemory();
    }
  };
  std::size_t facesWithPoints = 0, work = 0, mostWork = 0;
  for (const MeshSplitter& s : splitters) {
    facesWithPoints += s.facesWithPoints();
    work += s.pointsAndSegments();
    mostWork = std::max(mostWork, s.pointsAndSegments());
  }
  if (facesWithPoints >= 32 && 3 * mostWork <= 2 * work) {
    sideBySide = true;
    std::exception_ptr asideError;
    TaskAlongside aside([&] {
      try {
        splitMeshes();
      } catch (...) {
        asideError = std::current_exception();
        nextMesh = meshes.size();  // the other thread takes no more
      }
    });
    try {
      splitMeshes();
    } catch (...) {
      nextMesh = meshes.size();
      throw;
    }
    aside.wait();
    if (asideError) std::rethrow_exception(asideError);
  } else {
    splitMeshes();
  }
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    r.faces_added += facesAdded[m];
    r.faces_split += splitters[m].facesSplit();
    r.degenerate_faces_kept += splitters[m].degenerateKept();
    r.new_vertices += exactNew[m].size();
    if (splitters[m].facesSplit() > 0)
      r.smallest_new_angle_deg =
          std::min(r.smallest_new_angle_deg, splitters[m].smallestAngle() * 180 / M_PI);
  }

  reportProgress(options.progress, 90, "Welding along the curves");
  // Snapping works on the merged arrays (and rebuilds each input's output
  // from them), so it needs them even when the merged mesh is not asked for.
  const bool snapping = snaps(options) && r.faces_split > 0;
  const bool mergedArrays = options.merged_output || snapping;
  // Without snapping, each input's output is final here: unless the split
  // wrote it directly, its vcglib mesh is built in parts (MeshBuilder: vertices, faces and their
  // origins, new memory whose page faults cost more than the copy) that a second thread takes one
  // after the other, the largest first, while this one makes the merged mesh or counts the curves,
  // then takes the parts left. Once there are enough faces to be worth handing to a helper (a few
  // thousand faces take a few hundred microseconds).
  std::size_t outputFaces = 0;
  for (const OutputArrays& out : outputs) outputFaces += out.triangles.size();
  std::vector<MeshBuilder> builders;
  struct BuildPart {
    std::size_t mesh;
    MeshBuilder::Part part;
    std::size_t bytes;  // what it writes
  };
  std::vector<BuildPart> buildParts;
  std::atomic<std::size_t> nextBuildPart{0};
  auto buildSomeParts = [&] {
    for (std::size_t k; (k = nextBuildPart++) < buildParts.size();)
      builders[buildParts[k].mesh].build(buildParts[k].part);
  };
  std::optional<TaskAlongside>
      separateBuilder;  // destroyed (waited for) also when the merged output throws
  if (!directMeshes && options.separate_meshes && !snaps(options) && outputFaces >= 4096) {
    r.meshes.resize(meshes.size());
    builders.reserve(meshes.size());
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      const OutputArrays& out = outputs[m];
      builders.emplace_back(r.meshes[m], out.positions, out.triangles, out.vertex_origin,
                            out.face_origin);
      const std::size_t nv = out.positions.size(), nf = out.triangles.size();
      buildParts.push_back({m, MeshBuilder::kVertices, nv * sizeof(Vertex)});
      buildParts.push_back({m, MeshBuilder::kVertexOrigins, nv * sizeof(VertexOrigin)});
      buildParts.push_back({m, MeshBuilder::kFaces, nf * sizeof(Face)});
      buildParts.push_back({m, MeshBuilder::kFaceOrigins, nf * sizeof(FaceOrigin)});
    }
    std::sort(buildParts.begin(), buildParts.end(),
              [](const BuildPart& a, const BuildPart& b) { return a.bytes > b.bytes; });
    separateBuilder.emplace(buildSomeParts);
  }
  // The separate meshes: the parts no helper took, then their faces'
  // corners; or all of them here, when snapping rebuilt their arrays.
  auto finishSeparate = [&] {
    if (separateBuilder) {
      buildSomeParts();
      separateBuilder->wait();
      for (MeshBuilder& b : builders) b.link();
    } else if (options.separate_meshes && !directMeshes) {
      r.meshes.resize(meshes.size());
      for (std::size_t m = 0; m < meshes.size(); ++m) outputs[m].toMesh(r.meshes[m]);
    }
  };
  {
    // All meshes in one; curve vertices with the same exact position merge:
    // those at one curve point by its id, the others (crossings of two
    // curves inside a face) by comparing exactly.
    // One per curve point id used, then the others, by reference (each
    // copied would cost more than the rest of this stage); an input vertex
    // on a curve without an id is kept in `inputCurvePoints`.
    std::vector<const ExactPoint*> curvePoints;
    std::deque<ExactPoint> inputCurvePoints;
    std::vector<int> curvePointOfId(table.size(), -1);
    std::size_t notAtCurvePoints = 0;  // curve vertices without an id: crossings made in a face
    std::vector<std::vector<int>> curveIndex(meshes.size());  // per mesh vertex: into curvePoints
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      std::vector<int>& index = curveIndex[m];
      index.assign(directMeshes ? r.meshes[m].vert.size() : outputs[m].positions.size(), -1);
      const auto& pointOfVertex = splitters[m].pointOfVertex();
      auto mark = [&](int v) {
        if (index[v] >= 0) return;
        const int id = pointOfVertex[v];
        if (id >= 0) {
          int& point = curvePointOfId[id];
          if (point < 0) {
            point = int(curvePoints.size());
            curvePoints.push_back(&table.point(id));
          }
          index[v] = point;
          return;
        }
        ++notAtCurvePoints;
        index[v] = int(curvePoints.size());
        const std::size_t inputVertices = splitters[m].points().size();
        if (std::size_t(v) < inputVertices) {
          inputCurvePoints.emplace_back(directMeshes ? r.meshes[m].vert[v].cP()
                                                     : outputs[m].positions[v]);
          curvePoints.push_back(&inputCurvePoints.back());
        } else {
          curvePoints.push_back(&exactNew[m][v - inputVertices]);
        }
      };
      for (const auto& e : r.curve_edges[m]) mark(e[0]), mark(e[1]);
      for (int v : splitters[m].contactVertices()) mark(v);
    }
    // Distinct curve points never coincide (the table merged those): only
    // points made inside a face can coincide with another.
    std::vector<int> weldedTo(curvePoints.size());
    if (notAtCurvePoints > 0)
      weldedTo = coincidentGroups(curvePoints);
    else
      std::iota(weldedTo.begin(), weldedTo.end(), 0);
    r.smallest_new_angle_deg_unsnapped = r.smallest_new_angle_deg;
    if (!mergedArrays) {
      // Only what the merged output would tell: its slivers (the new faces
      // of each mesh, positions as they are there) and its curves, a graph
      // on the welded curve points (the merged output's curve vertices).
      std::size_t slivers = 0;  // counted as each mesh was built
      for (const MeshSplitter& s : splitters) slivers += s.slivers();
      r.new_faces_below_1deg = r.new_faces_below_1deg_unsnapped = slivers;
      std::vector<std::array<int, 2>> curves;
      std::size_t curveEdges = 0;
      for (const auto& edges : r.curve_edges) curveEdges += edges.size();
      curves.reserve(curveEdges);
      for (std::size_t m = 0; m < meshes.size(); ++m)
        for (const auto& e : r.curve_edges[m]) {
          const int a = weldedTo[curveIndex[m][e[0]]], b = weldedTo[curveIndex[m][e[1]]];
          curves.push_back({std::min(a, b), std::max(a, b)});
        }
      sortUnique(curves, curvePoints.size());
      r.curve_edges_welded = curves.size();
      countCurves(curvePoints.size(), curves, r.curve_loops, r.open_curves);
      finishSeparate();
      if (!options.separate_meshes) r.curve_edges.assign(meshes.size(), {});
      reportProgress(options.progress, 100, "Done");
      r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      return r;
    }
    std::vector<int> mergedOfCurvePoint(curvePoints.size(), -1);
    OutputArrays merged;
    std::vector<Point3>& positions = merged.positions;
    {
      std::size_t vertices = 0, faces = 0;
      for (const OutputArrays& mesh : outputs)
        vertices += mesh.positions.size(), faces += mesh.triangles.size();
      reserveInHugePages(positions, vertices);
      reserveInHugePages(merged.vertex_origin, vertices);
      reserveInHugePages(merged.triangles, faces);
      reserveInHugePages(merged.face_origin, faces);
      r.merged_new_face.reserve(faces);
    }
    std::vector<std::array<int, 2>>& curves = r.merged_curve_edges;  // sorted, each once
    std::vector<char> onCurve;                                       // per merged vertex
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      const OutputArrays& mesh = outputs[m];
      std::vector<int>& global = r.merged_vertex.emplace_back(mesh.positions.size());
      for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        const int c = curveIndex[m][v];
        if (c >= 0) {
          int& target = mergedOfCurvePoint[weldedTo[c]];
          if (target >= 0) {
            global[v] = target;
            continue;
          }
          target = int(positions.size());
        }
        global[v] = int(positions.size());
        positions.push_back(mesh.positions[v]);
        merged.vertex_origin.push_back(mesh.vertex_origin[v]);
        onCurve.push_back(c >= 0);
      }
      for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Triangle& t = mesh.triangles[f];
        const Triangle g = {global[t[0]], global[t[1]], global[t[2]]};
        // Two corners welded into one (they lie at one exact position, as
        // rounded output split again can have them): no area left.
        if (g[0] == g[1] || g[1] == g[2] || g[2] == g[0]) {
          ++r.collapsed_faces_removed;
          continue;
        }
        merged.triangles.push_back(g);
        merged.face_origin.push_back(mesh.face_origin[f]);
        r.merged_new_face.push_back(f >= splitters[m].keptFaces());
      }
      for (const auto& e : r.curve_edges[m])
        if (global[e[0]] != global[e[1]])
          curves.push_back(
              {std::min(global[e[0]], global[e[1]]), std::max(global[e[0]], global[e[1]])});
    }
    sortUnique(curves, positions.size());
    r.coincident_faces =
        keepOverlapsOnce(merged, r.merged_new_face, onCurve, curves, options.overlaps_once);
    if (options.overlaps_once) r.coincident_faces_removed = r.coincident_faces;
    // The quality of the new faces: their smallest angle, and the slivers.
    auto slivers = [&] {
      std::size_t n = 0;
      for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
        const Triangle& t = merged.triangles[f];
        n += r.merged_new_face[f] &&
             isSliver(merged.positions[t[0]], merged.positions[t[1]], merged.positions[t[2]]);
      }
      return n;
    };
    r.new_faces_below_1deg = r.new_faces_below_1deg_unsnapped = slivers();
    if (snapping) {
      reportProgress(options.progress, 95, "Snapping curve points");
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
        rebuildSeparate(merged, index, snappedTo, curveSet, outputs, r.merged_vertex,
                        r.curve_edges);
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
          smallest = std::min(
              smallest, meshmend::smallestAngle(merged.positions[t[0]], merged.positions[t[1]],
                                                merged.positions[t[2]]));
        }
      r.smallest_new_angle_deg = smallest * 180 / M_PI;
      r.new_faces_below_1deg = slivers();
      curves.assign(curveSet.begin(), curveSet.end());
    }
    if (options.merged_output) merged.toMesh(r.merged);
    finishSeparate();
    if (!options.separate_meshes) r.curve_edges.assign(meshes.size(), {});  // they go with `meshes`
    r.curve_edges_welded = curves.size();
    countCurves(positions.size(), r.merged_curve_edges, r.curve_loops, r.open_curves);
    if (!options.merged_output) {  // made for snapping only
      r.merged_curve_edges.clear();
      r.merged_vertex.clear();
      r.merged_new_face.clear();
      r.merged_snapped_face.clear();
    }
  }
  reportProgress(options.progress, 100, "Done");
  r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  return r;
}

std::vector<std::uint8_t> curveEdgeFlags(const Mesh& mesh,
                                         const std::vector<std::array<int, 2>>& curveEdges) {
  std::set<std::array<int, 2>> curves;
  for (auto e : curveEdges) {
    if (e[0] > e[1]) std::swap(e[0], e[1]);
    curves.insert(e);
  }
  const std::vector<Triangle> triangles = trianglesOf(mesh);
  std::vector<std::uint8_t> flags(triangles.size(), 0);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      std::array<int, 2> e{triangles[f][i], triangles[f][(i + 1) % 3]};
      if (e[0] > e[1]) std::swap(e[0], e[1]);
      if (curves.count(e)) flags[f] |= std::uint8_t(1 << i);
    }
  return flags;
}

JsonObject toJson(const SplitResult& r) {
  JsonObject j;
  j.set("intersecting_pairs", r.intersecting_pairs)
      .set("curve_edges", r.curve_edges_welded)
      .set("curve_loops", r.curve_loops)
      .set("open_curves", r.open_curves)
      .set("faces_split", r.faces_split)
      .set("faces_added", r.faces_added)
      .set("new_vertices", r.new_vertices)
      .set("degenerate_faces_kept", r.degenerate_faces_kept)
      .set("vertices_welded", r.vertices_welded)
      .set("duplicate_faces_removed", r.duplicate_faces_removed)
      .set("coincident_faces", r.coincident_faces)
      .set("coincident_faces_removed", r.coincident_faces_removed)
      .set("pairs_split_after_rounding", r.pairs_split_after_rounding)
      .set("collapsed_faces_removed", r.collapsed_faces_removed)
      .set("smallest_new_angle_deg", r.faces_split ? r.smallest_new_angle_deg : 0.0)
      .set("smallest_new_angle_deg_unsnapped",
           r.faces_split ? r.smallest_new_angle_deg_unsnapped : 0.0)
      .set("new_faces_below_1deg", r.new_faces_below_1deg)
      .set("new_faces_below_1deg_unsnapped", r.new_faces_below_1deg_unsnapped)
      .set("vertices_snapped", r.vertices_snapped)
      .set("edges_snapped", r.edges_snapped)
      .set("time_ms", r.time_ms);
  return j;
}

}  // namespace meshmend
