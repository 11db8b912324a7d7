// The mesh being filled: the input, read in place (never copied: a hole
// needs only the faces around it), and what the holes add to it: vertices,
// faces, and new corners for input faces that a border split changed.
// Indices continue the input's. Changes are undone to a checkpoint when a
// hole is given up, and written into the mesh once at the end.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "common/base/mesh.h"
#include "common/repair/holes/holes.h"

namespace meshmend::holes {

// An axis-aligned box in double.
struct Bounds {
  Point3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  void add(const Point3& p) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  void add(const Bounds& b) {
    add(b.lo);
    add(b.hi);
  }
  bool contains(const Bounds& b) const {
    for (int k = 0; k < 3; ++k)
      if (b.lo[k] < lo[k] || b.hi[k] > hi[k]) return false;
    return true;
  }
  bool overlaps(const Bounds& b) const {
    for (int k = 0; k < 3; ++k)
      if (b.hi[k] < lo[k] || hi[k] < b.lo[k]) return false;
    return true;
  }
  Bounds grown(double by) const {
    Bounds b = *this;
    for (int k = 0; k < 3; ++k) b.lo[k] -= by, b.hi[k] += by;
    return b;
  }
};

// Where a vertex added by a split lies on the input: the input face and the
// barycentric coordinates in it.
struct SplitOrigin {
  int face = -1;
  Point3 barycentric{0, 0, 0};
};

std::uint64_t directedKey(int from, int to);

// A vertex's position, by reference (vcglib's cP() returns a copy).
inline const Point3& positionOf(const Vertex& v) {
  return const_cast<Vertex&>(v).P();
}

class Surface {
 public:
  // What to restore when a hole is given up.
  struct Checkpoint {
    std::size_t points = 0, faces = 0, splitFaces = 0, log = 0;
  };

  Surface(const Mesh& mesh, bool roundToFloat);

  std::size_t inputVertices() const { return nv_; }
  std::size_t inputFaces() const { return nf_; }
  std::size_t vertexCount() const { return nv_ + points_.size(); }
  std::size_t faceCount() const { return nf_ + triangles_.size(); }

  // Moves a new vertex (v >= inputVertices()): the output stage re-rounds it.
  void setNewPoint(int v, const Point3& p) { points_[std::size_t(v) - nv_] = p; }
  const Point3& point(int v) const {
    return std::size_t(v) < nv_ ? positionOf(vert_[v]) : points_[std::size_t(v) - nv_];
  }
  // The face's corners now (a split changes an input face's).
  Triangle corners(int f) const {
    if (std::size_t(f) >= nf_) return triangles_[std::size_t(f) - nf_];
    if (!changed_.empty()) {
      const auto it = changed_.find(f);
      if (it != changed_.end()) return it->second;
    }
    return inputCorners(f);
  }
  // An input face's corners as the input has them.
  Triangle inputCorners(int f) const {
    const Face& face = face_[f];
    return {int(face.cV(0) - vert_), int(face.cV(1) - vert_), int(face.cV(2) - vert_)};
  }
  Bounds boundsOf(int f) const;
  // Where a new vertex at p is stored (in float when the host stores float).
  Point3 stored(const Point3& p) const { return roundToFloat_ ? roundedToFloat(p) : p; }

  // The face of a directed border edge (from the loops, kept up to date by
  // splits and patches), or -1.
  int borderFace(int from, int to) const;
  void setBorderFace(int from, int to, int face);  // face -1: no longer a border edge

  Checkpoint checkpoint() const;
  void restore(const Checkpoint& c);

  // §3.1 pre-treatment: splits border edge a -> b at its midpoint, with the
  // face it borders; returns the new vertex (-1 when the edge has no face).
  int splitBorderEdge(int a, int b);
  // Appends a patch: its new vertices (numbered from vertexCount() on) and faces.
  void addPatch(const std::vector<Point3>& newPoints, const std::vector<Triangle>& faces);

  // Faces added so far (split halves, then patches, in order), and input
  // faces whose corners a split changed.
  const std::vector<int>& splitFaces() const { return splitFaces_; }
  const std::vector<int>& patchFaces() const { return patchFaces_; }
  std::vector<int> changedInputFaces() const;

  // Writes what was added into `mesh` (the mesh this surface reads): new
  // vertices and faces appended, split faces given their new corners, with
  // their provenance; new_faces and new_vertices of the result.
  void writeInto(Mesh& mesh, HoleFillResult& result) const;

 private:
  Point3 barycentricIn(int v, int inputFace) const;
  int inputFaceOf(int f) const {
    return std::size_t(f) < nf_ ? f : inputFaceOf_[std::size_t(f) - nf_];
  }
  void setCorners(int f, const Triangle& t);

  const Vertex* vert_;
  const Face* face_;
  std::size_t nv_, nf_;
  bool roundToFloat_;
  std::vector<Point3> points_;       // added vertices
  std::vector<Triangle> triangles_;  // added faces
  std::vector<int> inputFaceOf_;     // per added face: the input face it is part of, or -1
  std::unordered_map<int, Triangle> changed_;  // input faces with new corners
  std::unordered_map<int, SplitOrigin> splitOrigins_;
  std::unordered_map<std::uint64_t, int> borderFace_;
  std::vector<int> splitFaces_, patchFaces_;
  // Undo log: what changed since the start, in order.
  struct Change {
    enum Kind { kCorners, kBorderFace, kSplitOrigin } kind;
    std::uint64_t key;  // face, directed edge or vertex
    bool existed;       // had an entry before
    Triangle corners;   // kCorners: the corners before
    int face;           // kBorderFace: the face before
  };
  std::vector<Change> log_;
};

}  // namespace meshmend::holes
