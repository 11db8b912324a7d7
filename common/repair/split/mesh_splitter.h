// One input's split (McLaurin 2012, §2.3–2.4): its faces receive the
// curve points and segments of their contacts, are re-triangulated with the
// curves as constraints, and the output is written as arrays or as the mesh
// itself. Used by the split's stages only (split.cpp).
#pragma once

#include "common/repair/split/curve_points.h"

namespace meshmend::split_detail {

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
inline bool isSliver(const Point3& a, const Point3& b, const Point3& c) {
  static const double below = std::pow(std::sin(M_PI / 180), 2);
  return smallestAngleMeasure(a, b, c) < below;
}

// Is p certainly off the line through a and b, by its rounded value and
// error bound? A component of (p - a) x (b - a) is then non-zero: its value
// at the rounded point, less the rounding error of evaluating it and the
// most p's error can change it. False when that does not settle it.
inline bool visiblyOffLine(const ExactPoint& p, const Point3& a, const Point3& b) {
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

// The origin of the output vertex that is input vertex `vertex` of `layer`.
inline VertexOrigin inputOrigin(int layer, int vertex) {
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
      auto isProper = [&, &w = w, f = f] {  // asked once, if needed
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

}  // namespace meshmend::split_detail
