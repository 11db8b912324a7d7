#include "common/repair/holes/surface.h"

#include <algorithm>

#include "common/base/parallel.h"

namespace meshmend::holes {

std::uint64_t directedKey(int from, int to) {
  return (std::uint64_t(std::uint32_t(from)) << 32) | std::uint32_t(to);
}

Surface::Surface(const Mesh& mesh, bool roundToFloat)
    : vert_(mesh.vert.data()),
      face_(mesh.face.data()),
      nv_(mesh.vert.size()),
      nf_(mesh.face.size()),
      roundToFloat_(roundToFloat) {}

Bounds Surface::boundsOf(int f) const {
  const Triangle t = corners(f);
  Bounds b;
  for (int v : t) b.add(point(v));
  return b;
}

int Surface::borderFace(int from, int to) const {
  const auto it = borderFace_.find(directedKey(from, to));
  return it == borderFace_.end() ? -1 : it->second;
}

void Surface::setBorderFace(int from, int to, int face) {
  const std::uint64_t key = directedKey(from, to);
  const auto it = borderFace_.find(key);
  log_.push_back({Change::kBorderFace,
                  key,
                  it != borderFace_.end(),
                  {},
                  it == borderFace_.end() ? -1 : it->second});
  if (face < 0) {
    if (it != borderFace_.end()) borderFace_.erase(it);
  } else {
    borderFace_[key] = face;
  }
}

void Surface::setCorners(int f, const Triangle& t) {
  if (std::size_t(f) < nf_) {
    const auto it = changed_.find(f);
    log_.push_back({Change::kCorners, std::uint64_t(f), it != changed_.end(),
                    it != changed_.end() ? it->second : Triangle{}, -1});
    changed_[f] = t;
  } else {
    Triangle& at = triangles_[std::size_t(f) - nf_];
    log_.push_back({Change::kCorners, std::uint64_t(f), true, at, -1});
    at = t;
  }
}

Surface::Checkpoint Surface::checkpoint() const {
  return {points_.size(), triangles_.size(), splitFaces_.size(), log_.size()};
}

void Surface::restore(const Checkpoint& c) {
  while (log_.size() > c.log) {
    const Change& change = log_.back();
    switch (change.kind) {
      case Change::kCorners: {
        const int f = int(change.key);
        if (std::size_t(f) < nf_) {
          if (change.existed)
            changed_[f] = change.corners;
          else
            changed_.erase(f);
        } else if (std::size_t(f) - nf_ < triangles_.size()) {
          triangles_[std::size_t(f) - nf_] = change.corners;
        }
        break;
      }
      case Change::kBorderFace:
        if (change.existed)
          borderFace_[change.key] = change.face;
        else
          borderFace_.erase(change.key);
        break;
      case Change::kSplitOrigin:
        splitOrigins_.erase(int(change.key));
        break;
    }
    log_.pop_back();
  }
  points_.resize(c.points);
  triangles_.resize(c.faces);
  inputFaceOf_.resize(c.faces);
  splitFaces_.resize(c.splitFaces);
  while (!patchFaces_.empty() && std::size_t(patchFaces_.back()) >= nf_ + c.faces)
    patchFaces_.pop_back();
}

Point3 Surface::barycentricIn(int v, int f0) const {
  const Triangle t = inputCorners(f0);
  for (int k = 0; k < 3; ++k)
    if (t[k] == v) {
      Point3 b(0, 0, 0);
      b[k] = 1;
      return b;
    }
  const auto it = splitOrigins_.find(v);
  if (it != splitOrigins_.end() && it->second.face == f0) return it->second.barycentric;
  return Point3(1.0 / 3, 1.0 / 3, 1.0 / 3);
}

int Surface::splitBorderEdge(int a, int b) {
  const int f = borderFace(a, b);
  if (f < 0) return -1;
  Triangle t = corners(f);
  int k = 0;
  while (k < 3 && !(t[k] == a && t[(k + 1) % 3] == b)) ++k;
  if (k == 3) return -1;
  const int c = t[(k + 2) % 3];
  const int m = int(vertexCount());
  const int f0 = inputFaceOf(f);
  points_.push_back(stored((point(a) + point(b)) / 2));
  splitOrigins_[m] = {f0, (barycentricIn(a, f0) + barycentricIn(b, f0)) / 2};
  log_.push_back({Change::kSplitOrigin, std::uint64_t(m), false, {}, -1});
  t[(k + 1) % 3] = m;  // f = (a, m, c)
  setCorners(f, t);
  const int g = int(faceCount());
  triangles_.push_back({m, b, c});
  inputFaceOf_.push_back(f0);
  splitFaces_.push_back(g);
  setBorderFace(a, b, -1);
  setBorderFace(a, m, f);
  setBorderFace(m, b, g);
  if (borderFace(b, c) == f) setBorderFace(b, c, g);
  return m;
}

void Surface::addPatch(const std::vector<Point3>& newPoints, const std::vector<Triangle>& faces) {
  points_.insert(points_.end(), newPoints.begin(), newPoints.end());
  for (const Triangle& t : faces) {
    patchFaces_.push_back(int(faceCount()));
    triangles_.push_back(t);
    inputFaceOf_.push_back(-1);
  }
}

std::vector<int> Surface::changedInputFaces() const {
  std::vector<int> out;
  for (const auto& [f, corners] : changed_) out.push_back(f);
  std::sort(out.begin(), out.end());
  return out;
}

void Surface::writeInto(Mesh& mesh, HoleFillResult& result) const {
  if (points_.empty() && triangles_.empty()) return;
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);
  const int layer = mesh.vert.empty() ? 0 : std::max(0, vo[0].layer);
  // Origins of the input faces that split vertices and faces come from.
  std::unordered_map<int, FaceOrigin> inputOrigins;
  for (const auto& [v, origin] : splitOrigins_) inputOrigins.emplace(origin.face, fo[origin.face]);
  for (int f : inputFaceOf_)
    if (f >= 0) inputOrigins.emplace(f, fo[f]);
  const std::size_t vertices = vertexCount(), faces = faceCount();
  // Room first. The mesh keeps room to grow (mesh.h), so this moves
  // nothing as a rule; where it must move the vertex array, every input
  // face is pointed at its corners in the new one (their indices read
  // before, while the old array is still there).
  if (mesh.vert.capacity() < vertices) {
    std::vector<Triangle> inputCorners(nf_);
    parallelChunks(nf_, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t f = begin; f < end; ++f) inputCorners[f] = this->inputCorners(int(f));
    });
    mesh.vert.reserve(vertices);
    Vertex* const first = mesh.vert.data();
    parallelChunks(nf_, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t f = begin; f < end; ++f)
        for (int k = 0; k < 3; ++k) mesh.face[f].V(k) = first + inputCorners[f][k];
    });
  }
  mesh.face.reserve(faces);
  vo._handle->data.reserve(vertices);
  fo._handle->data.reserve(faces);
  // From here on nothing moves.
  if (!points_.empty()) {
    auto vi = vcg::tri::Allocator<Mesh>::AddVertices(mesh, points_.size());
    for (std::size_t v = nv_; v < vertices; ++v, ++vi) {
      vi->P() = points_[v - nv_];
      const auto split = splitOrigins_.find(int(v));
      if (split != splitOrigins_.end()) {
        const FaceOrigin& of = inputOrigins.at(split->second.face);
        vo[v] = VertexOrigin{of.layer, -1, of.face, split->second.barycentric};
      } else {
        vo[v] = VertexOrigin{layer, -1, -1, {0, 0, 0}};
      }
      result.new_vertices.push_back(int(v));
    }
    // A patch vertex takes the origin of the border vertex nearest to it
    // along the patch's edges: colours, quality and texture coordinates
    // then continue into the patch instead of leaving it blank.
    auto inPatch = [&](int v) { return std::size_t(v) >= nv_ && !splitOrigins_.count(v); };
    std::vector<std::vector<int>> neighbours(points_.size());
    for (int f : patchFaces_) {
      const Triangle& t = triangles_[std::size_t(f) - nf_];
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3];
        if (inPatch(a)) neighbours[std::size_t(a) - nv_].push_back(b);
        if (inPatch(b)) neighbours[std::size_t(b) - nv_].push_back(a);
      }
    }
    std::vector<int> border(points_.size(), -1), queue;
    for (std::size_t i = 0; i < points_.size(); ++i)
      for (int w : neighbours[i])
        if (!inPatch(w)) {
          border[i] = w;
          queue.push_back(int(i));
          break;
        }
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int i = queue[head];
      for (int w : neighbours[std::size_t(i)])
        if (inPatch(w) && border[std::size_t(w) - nv_] < 0) {
          border[std::size_t(w) - nv_] = border[std::size_t(i)];
          queue.push_back(int(std::size_t(w) - nv_));
        }
    }
    for (std::size_t i = 0; i < points_.size(); ++i)
      if (border[i] >= 0 && inPatch(int(nv_ + i))) vo[nv_ + i] = vo[border[i]];
  }
  for (const auto& [f, corners] : changed_)
    for (int k = 0; k < 3; ++k)
      mesh.face[std::size_t(f)].V(k) = &mesh.vert[std::size_t(corners[k])];
  if (!triangles_.empty()) {
    auto fi = vcg::tri::Allocator<Mesh>::AddFaces(mesh, triangles_.size());
    for (std::size_t f = nf_; f < faces; ++f, ++fi) {
      for (int k = 0; k < 3; ++k) fi->V(k) = &mesh.vert[std::size_t(triangles_[f - nf_][k])];
      const int from = inputFaceOf_[f - nf_];
      fo[f] = from >= 0 ? inputOrigins.at(from) : FaceOrigin{layer, -1};
    }
  }
  result.new_faces = patchFaces_;
}

}  // namespace meshmend::holes
