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
#include "common/split/detail.h"

namespace meshmend {

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

namespace {

// The inputs as arrays, with their seams closed when asked; each keeps the
// input index of its vertices and faces. Meshes side by side; an error
// names the first mesh at fault.
std::vector<WeldedArrays> prepareInputs(const std::vector<const Mesh*>& meshes,
                                        const SplitOptions& options, SplitResult& r) {
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
  return inputs;
}

// The crossing pairs with their contacts, within the work bound on the
// triple points of one face.
FindIntersectionsResult findCrossings(const std::vector<WeldedArrays>& inputs,
                                      const SplitOptions& options, SplitResult& r) {
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
  const std::size_t bound = options.max_triple_points_per_face;
  if (bound == 0) return found;
  std::vector<std::size_t> faces;
  for (const MeshArrays* a : arrays) faces.push_back(a->triangles.size());
  const TriplePoints most = mostTriplePoints(found.pairs, faces, bound);
  if (most.count > bound)
    throw WorkLimitError(
        "in face " + std::to_string(most.face.face) + " of mesh " + std::to_string(most.face.mesh) +
        " more than " + std::to_string(bound) +
        " pairs of the faces crossing it cross each other too (max_triple_points_per_face): "
        "the surfaces pass many times through nearly one point there, as the meridians of a "
        "spindle torus do near its axis, and cutting it would take the exact arithmetic "
        "minutes. Nothing was changed. Remove the faces around that point (select them, "
        "Filters > Selection > Delete Selected Faces) and close the hole with MeshMend: Fill "
        "Holes, then split again");
  return found;
}

// Every pair's contact as curve point ids of one table, handed to the faces
// of both meshes; the contacts' exact points move into the table.
void distributeContacts(FindIntersectionsResult& found, std::vector<MeshSplitter>& splitters,
                        CurvePoints& table) {
  std::vector<const std::vector<Triangle>*> triangles;
  for (const MeshSplitter& s : splitters) triangles.push_back(&s.triangles());
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
      splitters.size(),
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
}

// What re-triangulating the meshes made: each input's output, as arrays or
// (`direct`: when each input's mesh is all that is asked for, no merged
// output, no snapping) written into the result's meshes, and its new
// vertices' exact points.
struct SplitMeshes {
  bool direct = false;
  std::vector<OutputArrays> outputs;
  std::vector<std::vector<ExactPoint>> exactNew;
};

// Each mesh's split reads only the finished curve point table (and copies
// the points it asks exact questions of), so meshes can be split side by
// side: a second thread takes meshes from the same counter as this one,
// and each mesh's faces are re-triangulated on its thread alone (both
// cores are busy already). Only when the work (points and segments
// received, not faces: a coarse mesh's faces receive many each) is shared
// fairly evenly (as between two meshes that cross, where every curve
// segment goes into both) and there is enough of it to be worth sharing
// (a few dozen faces); otherwise one mesh after the other, each on every
// core. With more than two cores, each mesh still re-triangulates on several.
SplitMeshes splitEachMesh(std::vector<MeshSplitter>& splitters, const CurvePoints& table,
                          const SplitOptions& options, SplitResult& r) {
  const std::size_t n = splitters.size();
  SplitMeshes out;
  out.direct = options.separate_meshes && !options.merged_output && !snaps(options);
  out.outputs.resize(n);
  out.exactNew.resize(n);
  r.curve_edges.resize(n);
  if (out.direct) r.meshes.resize(n);
  std::atomic<std::size_t> nextMesh{0};
  std::vector<std::size_t> facesAdded(n, 0);
  bool sideBySide = false;
  auto splitMeshes = [&] {
    for (std::size_t m; (m = nextMesh++) < n;) {
      MeshSplitter& s = splitters[m];
      s.shareEdgePoints(table);
      s.retriangulateFaces(table, !sideBySide || workerCount() > 2);
      if (out.direct)
        s.build(table, MeshOutput(r.meshes[m]), r.curve_edges[m], out.exactNew[m], facesAdded[m]);
      else
        s.build(table, ArraysOutput(out.outputs[m]), r.curve_edges[m], out.exactNew[m],
                facesAdded[m]);
      s.releaseWorkingMemory();
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
        nextMesh = n;  // the other thread takes no more
      }
    });
    try {
      splitMeshes();
    } catch (...) {
      nextMesh = n;
      throw;
    }
    aside.wait();
    if (asideError) std::rethrow_exception(asideError);
  } else {
    splitMeshes();
  }
  for (std::size_t m = 0; m < n; ++m) {
    r.faces_added += facesAdded[m];
    r.faces_split += splitters[m].facesSplit();
    r.degenerate_faces_kept += splitters[m].degenerateKept();
    r.new_vertices += out.exactNew[m].size();
    if (splitters[m].facesSplit() > 0)
      r.smallest_new_angle_deg =
          std::min(r.smallest_new_angle_deg, splitters[m].smallestAngle() * 180 / M_PI);
  }
  return out;
}

// The separate meshes, when they come from arrays and snapping does not
// rebuild them: their vcglib meshes built in parts (MeshBuilder: vertices,
// faces and their origins, new memory whose page faults cost more than the
// copy) that a second thread takes one after the other, the largest first,
// while this one merges or counts the curves, then takes the parts left.
// Only once there are enough faces to be worth handing to a helper (a few
// thousand faces take a few hundred microseconds). The helper is waited
// for also when the merged output throws.
class SeparateMeshes {
 public:
  SeparateMeshes(SplitMeshes& split, const SplitOptions& options, SplitResult& r)
      : split_(split), options_(options), r_(r) {
    std::size_t outputFaces = 0;
    for (const OutputArrays& out : split.outputs) outputFaces += out.triangles.size();
    if (split.direct || !options.separate_meshes || snaps(options) || outputFaces < 4096) return;
    const std::size_t n = split.outputs.size();
    r.meshes.resize(n);
    builders_.reserve(n);
    for (std::size_t m = 0; m < n; ++m) {
      const OutputArrays& out = split.outputs[m];
      builders_.emplace_back(r.meshes[m], out.positions, out.triangles, out.vertex_origin,
                             out.face_origin);
      const std::size_t nv = out.positions.size(), nf = out.triangles.size();
      parts_.push_back({m, MeshBuilder::kVertices, nv * sizeof(Vertex)});
      parts_.push_back({m, MeshBuilder::kVertexOrigins, nv * sizeof(VertexOrigin)});
      parts_.push_back({m, MeshBuilder::kFaces, nf * sizeof(Face)});
      parts_.push_back({m, MeshBuilder::kFaceOrigins, nf * sizeof(FaceOrigin)});
    }
    std::sort(parts_.begin(), parts_.end(),
              [](const Part& a, const Part& b) { return a.bytes > b.bytes; });
    helper_.emplace([this] { buildSomeParts(); });
  }
  SeparateMeshes(const SeparateMeshes&) = delete;
  SeparateMeshes& operator=(const SeparateMeshes&) = delete;

  // The parts no helper took, then their faces' corners; or every mesh
  // here, from the arrays as snapping left them.
  void finish() {
    if (helper_) {
      buildSomeParts();
      helper_->wait();
      for (MeshBuilder& b : builders_) b.link();
    } else if (options_.separate_meshes && !split_.direct) {
      r_.meshes.resize(split_.outputs.size());
      for (std::size_t m = 0; m < split_.outputs.size(); ++m)
        split_.outputs[m].toMesh(r_.meshes[m]);
    }
  }

 private:
  struct Part {
    std::size_t mesh;
    MeshBuilder::Part part;
    std::size_t bytes;  // what it writes
  };
  void buildSomeParts() {
    for (std::size_t k; (k = next_++) < parts_.size();)
      builders_[parts_[k].mesh].build(parts_[k].part);
  }

  SplitMeshes& split_;
  const SplitOptions& options_;
  SplitResult& r_;
  std::vector<MeshBuilder> builders_;
  std::vector<Part> parts_;
  std::atomic<std::size_t> next_{0};
  std::optional<TaskAlongside> helper_;  // last: destroyed (waited for) first
};

// The curve vertices of every output as exact points, by reference (each
// copied would cost more than the rest of this stage): one per curve point
// id used, then the others (an input vertex on a curve without an id is
// kept in `inputPoints`), and those at one exact position welded: at one
// curve point by its id, the others (crossings of two curves inside a
// face) by comparing exactly.
struct CurveWelding {
  std::vector<const ExactPoint*> points;
  std::deque<ExactPoint> inputPoints;
  std::vector<std::vector<int>> index;  // per mesh vertex: into points, or -1
  std::vector<int> weldedTo;            // per point: its representative
};

void weldCurvePoints(const CurvePoints& table, const std::vector<MeshSplitter>& splitters,
                     const SplitMeshes& split, const SplitResult& r, CurveWelding& w) {
  std::vector<int> pointOfId(table.size(), -1);
  std::size_t notAtCurvePoints = 0;  // curve vertices without an id: crossings made in a face
  w.index.resize(splitters.size());
  for (std::size_t m = 0; m < splitters.size(); ++m) {
    std::vector<int>& index = w.index[m];
    index.assign(split.direct ? r.meshes[m].vert.size() : split.outputs[m].positions.size(), -1);
    const auto& pointOfVertex = splitters[m].pointOfVertex();
    auto mark = [&](int v) {
      if (index[v] >= 0) return;
      const int id = pointOfVertex[v];
      if (id >= 0) {
        int& point = pointOfId[id];
        if (point < 0) {
          point = int(w.points.size());
          w.points.push_back(&table.point(id));
        }
        index[v] = point;
        return;
      }
      ++notAtCurvePoints;
      index[v] = int(w.points.size());
      const std::size_t inputVertices = splitters[m].points().size();
      if (std::size_t(v) < inputVertices) {
        w.inputPoints.emplace_back(split.direct ? r.meshes[m].vert[v].cP()
                                                : split.outputs[m].positions[v]);
        w.points.push_back(&w.inputPoints.back());
      } else {
        w.points.push_back(&split.exactNew[m][v - inputVertices]);
      }
    };
    for (const auto& e : r.curve_edges[m]) mark(e[0]), mark(e[1]);
    for (int v : splitters[m].contactVertices()) mark(v);
  }
  // Distinct curve points never coincide (the table merged those): only
  // points made inside a face can coincide with another.
  w.weldedTo.resize(w.points.size());
  if (notAtCurvePoints > 0)
    w.weldedTo = coincidentGroups(w.points);
  else
    std::iota(w.weldedTo.begin(), w.weldedTo.end(), 0);
}

// Without a merged output: only what it would tell, its slivers (the new
// faces of each mesh, counted as each was built) and its curves, a graph on
// the welded curve points.
void countWithoutMerging(const CurveWelding& w, const std::vector<MeshSplitter>& splitters,
                         SplitResult& r) {
  std::size_t slivers = 0;
  for (const MeshSplitter& s : splitters) slivers += s.slivers();
  r.new_faces_below_1deg = r.new_faces_below_1deg_unsnapped = slivers;
  std::vector<std::array<int, 2>> curves;
  std::size_t curveEdges = 0;
  for (const auto& edges : r.curve_edges) curveEdges += edges.size();
  curves.reserve(curveEdges);
  for (std::size_t m = 0; m < splitters.size(); ++m)
    for (const auto& e : r.curve_edges[m]) {
      const int a = w.weldedTo[w.index[m][e[0]]], b = w.weldedTo[w.index[m][e[1]]];
      curves.push_back({std::min(a, b), std::max(a, b)});
    }
  sortUnique(curves, w.points.size());
  r.curve_edges_welded = curves.size();
  countCurves(w.points.size(), curves, r.curve_loops, r.open_curves);
}

// All meshes in one, the welded curve points once: the merged arrays, and
// in the result where each mesh's vertices went (merged_vertex), which
// faces are new and the curve edges (sorted, each once). `onCurve` marks
// the merged curve vertices.
OutputArrays mergeOutputs(const CurveWelding& w, const SplitMeshes& split,
                          const std::vector<MeshSplitter>& splitters, SplitResult& r,
                          std::vector<char>& onCurve) {
  std::vector<int> mergedOfPoint(w.points.size(), -1);
  OutputArrays merged;
  std::vector<Point3>& positions = merged.positions;
  std::size_t vertices = 0, faces = 0;
  for (const OutputArrays& mesh : split.outputs)
    vertices += mesh.positions.size(), faces += mesh.triangles.size();
  reserveInHugePages(positions, vertices);
  reserveInHugePages(merged.vertex_origin, vertices);
  reserveInHugePages(merged.triangles, faces);
  reserveInHugePages(merged.face_origin, faces);
  r.merged_new_face.reserve(faces);
  std::vector<std::array<int, 2>>& curves = r.merged_curve_edges;
  for (std::size_t m = 0; m < split.outputs.size(); ++m) {
    const OutputArrays& mesh = split.outputs[m];
    std::vector<int>& global = r.merged_vertex.emplace_back(mesh.positions.size());
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const int c = w.index[m][v];
      if (c >= 0) {
        int& target = mergedOfPoint[w.weldedTo[c]];
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
  return merged;
}

// The new faces of `merged` with an angle under 1°.
std::size_t newSlivers(const OutputArrays& merged, const std::vector<char>& newFace) {
  std::size_t n = 0;
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    const Triangle& t = merged.triangles[f];
    n += newFace[f] &&
         isSliver(merged.positions[t[0]], merged.positions[t[1]], merged.positions[t[2]]);
  }
  return n;
}

// The merged output: coincident faces kept once, quality snapping, the
// curves counted; the merged mesh built when asked for.
void mergeAndSnap(const CurveWelding& w, SplitMeshes& split,
                  const std::vector<MeshSplitter>& splitters, const SplitOptions& options,
                  SplitResult& r) {
  std::vector<char> onCurve;  // per merged vertex
  OutputArrays merged = mergeOutputs(w, split, splitters, r, onCurve);
  std::vector<std::array<int, 2>>& curves = r.merged_curve_edges;
  r.coincident_faces =
      keepOverlapsOnce(merged, r.merged_new_face, onCurve, curves, options.overlaps_once);
  if (options.overlaps_once) r.coincident_faces_removed = r.coincident_faces;
  r.new_faces_below_1deg = r.new_faces_below_1deg_unsnapped = newSlivers(merged, r.merged_new_face);
  if (snaps(options) && r.faces_split > 0) {
    reportProgress(options.progress, 95, "Snapping curve points");
    snapCurves(merged, curves, split.outputs, options, r);
    r.new_faces_below_1deg = newSlivers(merged, r.merged_new_face);
  }
  if (options.merged_output) merged.toMesh(r.merged);
  r.curve_edges_welded = curves.size();
  countCurves(merged.positions.size(), curves, r.curve_loops, r.open_curves);
}

}  // namespace

SplitResult splitAlongIntersections(const std::vector<const Mesh*>& meshes,
                                    const SplitOptions& options) {
  const auto start = Clock::now();
  if (!options.separate_meshes && !options.merged_output)
    throw InvalidInputError(
        "nothing to output: ask for the separate meshes, the merged mesh or both");
  SplitResult r;
  std::vector<WeldedArrays> inputs = prepareInputs(meshes, options, r);
  FindIntersectionsResult found = findCrossings(inputs, options, r);
  r.complete = options.self && (options.between_meshes || meshes.size() == 1);

  reportProgress(options.progress, 40, "Collecting curve points");
  std::vector<MeshSplitter> splitters;
  splitters.reserve(meshes.size());
  for (std::size_t m = 0; m < meshes.size(); ++m)
    splitters.emplace_back(std::move(inputs[m]), std::uint32_t(m));
  CurvePoints table(2 * found.pairs.size());
  distributeContacts(found, splitters, table);

  reportProgress(options.progress, 55, "Re-triangulating crossed faces");
  SplitMeshes split = splitEachMesh(splitters, table, options, r);

  reportProgress(options.progress, 90, "Welding along the curves");
  SeparateMeshes separate(split, options, r);
  CurveWelding welding;
  weldCurvePoints(table, splitters, split, r, welding);
  r.smallest_new_angle_deg_unsnapped = r.smallest_new_angle_deg;
  // Snapping works on the merged arrays (and rebuilds each input's output
  // from them), so it needs them even when the merged mesh is not asked for.
  const bool mergedArrays = options.merged_output || (snaps(options) && r.faces_split > 0);
  if (mergedArrays)
    mergeAndSnap(welding, split, splitters, options, r);
  else
    countWithoutMerging(welding, splitters, r);
  separate.finish();
  if (!options.separate_meshes) r.curve_edges.assign(meshes.size(), {});  // they go with `meshes`
  if (!options.merged_output) {                                           // made for snapping only
    r.merged_curve_edges.clear();
    r.merged_vertex.clear();
    r.merged_new_face.clear();
    r.merged_snapped_face.clear();
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
