#include "common/base/mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "common/base/errors.h"
#include "common/base/huge_pages.h"
#include "common/base/parallel.h"

namespace meshmend {

void Mesh::copyFrom(const Mesh& other) {
  using Allocator = vcg::tri::Allocator<Mesh>;
  Mesh& source = const_cast<Mesh&>(other);  // vcglib 2020.09's Append takes non-const meshes
  Clear();
  ClearAttributes();
  // The copy keeps the room to grow a built mesh has (startMesh), made
  // before anything is added: reserving later would move the vertices.
  reserveInHugePages(vert, withRoomToGrow(source.vert.size()));
  reserveInHugePages(face, withRoomToGrow(source.face.size()));
  // Append copies the attributes present in both meshes: create ours first.
  if (Allocator::IsValidHandle(
          source, Allocator::FindPerVertexAttribute<VertexOrigin>(source, kVertexOriginAttribute)))
    vertexOrigins(*this)._handle->data.reserve(vert.capacity());
  if (Allocator::IsValidHandle(
          source, Allocator::FindPerFaceAttribute<FaceOrigin>(source, kFaceOriginAttribute)))
    faceOrigins(*this)._handle->data.reserve(face.capacity());
  vcg::tri::Append<Mesh, Mesh>::MeshCopy(*this, source);
}

VertexOriginHandle vertexOrigins(Mesh& mesh) {
  return vcg::tri::Allocator<Mesh>::GetPerVertexAttribute<VertexOrigin>(mesh,
                                                                        kVertexOriginAttribute);
}

FaceOriginHandle faceOrigins(Mesh& mesh) {
  return vcg::tri::Allocator<Mesh>::GetPerFaceAttribute<FaceOrigin>(mesh, kFaceOriginAttribute);
}

double smallestAngle(const Point3& a, const Point3& b, const Point3& c) {
  const double ab = (b - a).SquaredNorm(), bc = (c - b).SquaredNorm(), ca = (a - c).SquaredNorm();
  // The apex opposite the shortest side, and its two sides.
  const Point3& apex = ab <= bc && ab <= ca ? c : bc <= ca ? a : b;
  const Point3& p = ab <= bc && ab <= ca ? a : bc <= ca ? b : c;
  const Point3& q = ab <= bc && ab <= ca ? b : bc <= ca ? c : a;
  const Point3 u = p - apex, v = q - apex;
  return std::atan2((u ^ v).Norm(), u * v);
}

double scalarStep(const Point3& p, Scalar s) {
  const double m = std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])});
  if (s == Scalar::kFloat) {
    const float f = float(m);
    if (!std::isfinite(f)) return double(std::numeric_limits<float>::max()) * 0x1p-23;
    return std::max(double(std::nextafter(f, INFINITY)) - double(f),
                    double(std::numeric_limits<float>::min()) * 0x1p-23);
  }
  if (!std::isfinite(m) || m >= std::numeric_limits<double>::max())
    return std::numeric_limits<double>::max() * 0x1p-52;
  return std::max(std::nextafter(m, INFINITY) - m, std::numeric_limits<double>::min() * 0x1p-52);
}

Mesh makeMesh(const std::vector<Point3>& positions, const std::vector<Triangle>& triangles,
              int layer) {
  Mesh mesh;
  buildMesh(mesh, positions, triangles, layer);
  return mesh;
}

namespace {

void requireIndicesInRange(const std::vector<Point3>& positions,
                           const std::vector<Triangle>& triangles) {
  const int n = int(positions.size());
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int v : triangles[f])
      if (v < 0 || v >= n)
        throw InvalidInputError("face " + std::to_string(f) + " refers to vertex " +
                                std::to_string(v) + ", but the mesh has only " + std::to_string(n) +
                                " vertices");
}

}  // namespace

void startMesh(Mesh& mesh, std::size_t vertices, std::size_t faces, VertexOriginHandle& vo,
               FaceOriginHandle& fo) {
  mesh.Clear();
  mesh.ClearAttributes();
  reserveInHugePages(mesh.vert, withRoomToGrow(vertices));
  reserveInHugePages(mesh.face, withRoomToGrow(faces));
  // The attributes once the room is made (each reserves its elements'
  // capacity), and while the mesh is empty: adding one edits state that
  // vertex and face attributes share (vcglib's attribute counter).
  vo = vertexOrigins(mesh);
  fo = faceOrigins(mesh);
  adviseHugePages(vo._handle->data.data(), vo._handle->data.capacity() * sizeof(VertexOrigin));
  adviseHugePages(fo._handle->data.data(), fo._handle->data.capacity() * sizeof(FaceOrigin));
}

void buildMesh(Mesh& mesh, const std::vector<Point3>& positions,
               const std::vector<Triangle>& triangles, int layer) {
  requireIndicesInRange(positions, triangles);
  VertexOriginHandle vo;
  FaceOriginHandle fo;
  startMesh(mesh, positions.size(), triangles.size(), vo, fo);
  auto vi = vcg::tri::Allocator<Mesh>::AddVertices(mesh, positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i, ++vi) {
    vi->P() = positions[i];
    vo[i] = VertexOrigin{layer, int(i), -1, {0, 0, 0}};
  }
  auto fi = vcg::tri::Allocator<Mesh>::AddFaces(mesh, triangles.size());
  for (std::size_t f = 0; f < triangles.size(); ++f, ++fi) {
    for (int k = 0; k < 3; ++k) fi->V(k) = &mesh.vert[triangles[f][k]];
    fo[f] = FaceOrigin{layer, int(f)};
  }
}

void buildMesh(Mesh& mesh, const std::vector<Point3>& positions,
               const std::vector<Triangle>& triangles,
               const std::vector<VertexOrigin>& vertexOrigin,
               const std::vector<FaceOrigin>& faceOrigin) {
  MeshBuilder builder(mesh, positions, triangles, vertexOrigin, faceOrigin);
  for (int part = 0; part < MeshBuilder::kParts; ++part) builder.build(MeshBuilder::Part(part));
  builder.link();
}

MeshBuilder::MeshBuilder(Mesh& mesh, const std::vector<Point3>& positions,
                         const std::vector<Triangle>& triangles,
                         const std::vector<VertexOrigin>& vertexOrigin,
                         const std::vector<FaceOrigin>& faceOrigin)
    : mesh_(mesh),
      positions_(positions),
      triangles_(triangles),
      vertexOrigin_(vertexOrigin),
      faceOrigin_(faceOrigin) {
  if (vertexOrigin.size() != positions.size() || faceOrigin.size() != triangles.size())
    throw std::invalid_argument("buildMesh: one origin per vertex and per face");
  requireIndicesInRange(positions, triangles);
  startMesh(mesh, positions.size(), triangles.size(), vo_, fo_);
}

// vcglib's Allocator::AddVertices and AddFaces each resize the elements and
// their attributes together; on an empty mesh (no pointers to update) that
// is all they do, so the parts resize each array on its own.
void MeshBuilder::build(Part part) {
  switch (part) {
    case kVertices:
      mesh_.vert.resize(positions_.size());
      for (std::size_t v = 0; v < positions_.size(); ++v) mesh_.vert[v].P() = positions_[v];
      break;
    case kVertexOrigins:
      vo_._handle->Resize(vertexOrigin_.size());
      for (std::size_t v = 0; v < vertexOrigin_.size(); ++v) vo_[v] = vertexOrigin_[v];
      break;
    case kFaces:
      mesh_.face.resize(triangles_.size());
      break;
    case kFaceOrigins:
      fo_._handle->Resize(faceOrigin_.size());
      for (std::size_t f = 0; f < faceOrigin_.size(); ++f) fo_[f] = faceOrigin_[f];
      break;
  }
}

void MeshBuilder::link() {
  Vertex* vertices = mesh_.vert.data();
  for (std::size_t f = 0; f < triangles_.size(); ++f)
    for (int k = 0; k < 3; ++k) mesh_.face[f].V(k) = vertices + triangles_[f][k];
  mesh_.vn = int(mesh_.vert.size());
  mesh_.fn = int(mesh_.face.size());
}

MeshArrays arraysOf(const Mesh& mesh) {
  return {positionsOf(mesh), trianglesOf(mesh)};
}

std::vector<EdgeUse> edgeUses(const std::vector<Triangle>& triangles) {
  // A counting sort by the smaller vertex, then a small sort within each
  // vertex's few uses: linear in the mesh size, where one sort is not.
  int vertexCount = 0;
  for (const Triangle& t : triangles)
    for (int v : t) vertexCount = std::max(vertexCount, v + 1);
  std::vector<int> start(std::size_t(vertexCount) + 1, 0);
  for (const Triangle& t : triangles)
    for (int i = 0; i < 3; ++i) ++start[std::min(t[i], t[(i + 1) % 3]) + 1];
  for (int v = 0; v < vertexCount; ++v) start[v + 1] += start[v];
  std::vector<EdgeUse> uses(3 * triangles.size());
  std::vector<int> next(start.begin(), start.end() - 1);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = triangles[f][i], b = triangles[f][(i + 1) % 3];
      uses[next[std::min(a, b)]++] = {std::min(a, b), std::max(a, b), int(f), i};
    }
  // Within a vertex's uses, faces are already in order: a stable insertion
  // sort by the other vertex completes the order of EdgeUse::operator<.
  for (int v = 0; v < vertexCount; ++v)
    for (int k = start[v] + 1; k < start[v + 1]; ++k) {
      const EdgeUse use = uses[k];
      int j = k;
      for (; j > start[v] && uses[j - 1].v > use.v; --j) uses[j] = uses[j - 1];
      uses[j] = use;
    }
  return uses;
}

WeldedArrays weldCoincident(const MeshArrays& in) {
  const std::vector<Point3>& points = in.points;
  // Each vertex goes to the first vertex with its exact coordinates, found
  // in an open-addressing table keyed by the coordinates' bits. An entry
  // keeps the upper half of its hash beside the vertex index, so that a
  // probe reads a point (anywhere in memory) only when the hashes agree.
  std::size_t capacity = 16;
  while (capacity < 2 * points.size()) capacity *= 2;
  constexpr std::uint64_t kEmpty = ~std::uint64_t(0), kIndex = 0xFFFFFFFFu;
  std::vector<std::uint64_t> table;  // (hash & ~kIndex) | vertex
  assignInHugePages(table, capacity, kEmpty);
  auto hash = [](const Point3& p) {
    std::uint64_t h = 0;
    for (int k = 0; k < 3; ++k) {
      const double x = p[k] == 0 ? 0.0 : p[k];  // -0 and +0 are the same coordinate
      std::uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      h = (h ^ bits) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 32;
    }
    return h;
  };
  std::vector<int> target;
  resizeInHugePages(target, points.size());
  WeldedArrays w;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::uint64_t h = hash(points[i]), tag = h & ~kIndex;
    for (std::size_t slot = h & (capacity - 1);; slot = (slot + 1) & (capacity - 1)) {
      const std::uint64_t entry = table[slot];
      if (entry == kEmpty) {
        table[slot] = tag | i;
        target[i] = int(i);
        break;
      }
      const std::size_t j = entry & kIndex;
      if ((entry & ~kIndex) == tag && points[j] == points[i]) {
        target[i] = int(j);
        ++w.vertices_merged;
        break;
      }
    }
  }
  reserveInHugePages(w.mesh.points, points.size() - w.vertices_merged);
  reserveInHugePages(w.vertex_origin, points.size() - w.vertices_merged);
  reserveInHugePages(w.mesh.triangles, in.triangles.size());
  reserveInHugePages(w.face_origin, in.triangles.size());
  // Keep every vertex that is not a merged duplicate; renumber.
  std::vector<int> index;
  assignInHugePages(index, points.size(), -1);
  for (std::size_t v = 0; v < points.size(); ++v)
    if (target[v] == int(v)) {
      index[v] = int(w.mesh.points.size());
      w.mesh.points.push_back(points[v]);
      w.vertex_origin.push_back(int(v));
    }
  for (std::size_t f = 0; f < in.triangles.size(); ++f) {
    Triangle t;
    for (int k = 0; k < 3; ++k) t[k] = index[target[in.triangles[f][k]]];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
    w.mesh.triangles.push_back(t);
    w.face_origin.push_back(int(f));
  }
  w.faces_removed = in.triangles.size() - w.mesh.triangles.size();
  return w;
}

std::size_t weldCoincidentVertices(Mesh& mesh, std::size_t* removedFaces) {
  const WeldedArrays w = weldCoincident(arraysOf(mesh));
  if (removedFaces) *removedFaces = w.faces_removed;
  if (w.vertices_merged == 0 && w.faces_removed == 0) return 0;
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);
  std::vector<VertexOrigin> keptOrigins;
  for (int v : w.vertex_origin) keptOrigins.push_back(vo[v]);
  std::vector<FaceOrigin> keptFaces;
  for (int f : w.face_origin) keptFaces.push_back(fo[f]);
  mesh = makeMesh(w.mesh.points, w.mesh.triangles);
  VertexOriginHandle nvo = vertexOrigins(mesh);
  FaceOriginHandle nfo = faceOrigins(mesh);
  for (std::size_t v = 0; v < keptOrigins.size(); ++v) nvo[v] = keptOrigins[v];
  for (std::size_t f = 0; f < keptFaces.size(); ++f) nfo[f] = keptFaces[f];
  return w.vertices_merged;
}

Mesh appended(const Mesh& a, const Mesh& b) {
  Mesh out = a;
  vcg::tri::Append<Mesh, Mesh>::Mesh(out, const_cast<Mesh&>(b));
  return out;
}

// Both copy in chunks on the helper threads: a large mesh's copy is the
// first stage of an operation, and would leave the other cores idle.
std::vector<Point3> positionsOf(const Mesh& mesh) {
  std::vector<Point3> out;
  resizeInHugePages(out, mesh.vert.size());  // vcglib's Point3 leaves itself uninitialized
  parallelChunks(
      out.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t v = begin; v < end; ++v) out[v] = mesh.vert[v].cP();
      },
      1024);
  return out;
}

std::vector<Triangle> trianglesOf(const Mesh& mesh) {
  std::vector<Triangle> out;
  resizeInHugePages(out, mesh.face.size());
  const Vertex* first = mesh.vert.data();
  parallelChunks(
      out.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t f = begin; f < end; ++f)
          for (int k = 0; k < 3; ++k) out[f][k] = int(mesh.face[f].cV(k) - first);
      },
      1024);
  return out;
}

void CoordinateMagnitudes::add(const CoordinateMagnitudes& other) {
  smallest = std::min(smallest, other.smallest);
  largest = std::max(largest, other.largest);
}

double CoordinateMagnitudes::binades() const {
  return largest > 0 ? std::log2(largest) - std::log2(smallest) : 0;
}

CoordinateMagnitudes magnitudesOf(const std::vector<Point3>& points,
                                  const std::vector<Triangle>& triangles) {
  std::vector<char> used(points.size(), 0);
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] >= 0 && std::size_t(t[k]) < points.size()) used[std::size_t(t[k])] = 1;
  CoordinateMagnitudes m;
  for (std::size_t v = 0; v < points.size(); ++v)
    if (used[v]) m.add(points[v]);
  return m;
}

void requireCoordinateSpan(const CoordinateMagnitudes& m, const std::string& what) {
  if (m.binades() <= kMaxCoordinateBinades) return;
  std::ostringstream s;
  s.precision(3);
  s << what << ": its coordinates span " << std::lround(m.binades()) << " binades (magnitudes from "
    << m.smallest << " to " << m.largest << "); exact decisions take at most "
    << kMaxCoordinateBinades << " (every float mesh is within them). Coordinates below "
    << std::ldexp(m.largest, -int(kMaxCoordinateBinades))
    << " are far below the mesh's precision: set them to zero (or scale the mesh so that they "
       "are not needed), then run again";
  throw InvalidInputError(s.str());
}

void requireFacesAndFiniteCoordinates(const Mesh& mesh, const std::string& what) {
  if (mesh.fn == 0) throw InvalidInputError(what + " has no faces: load or select a triangle mesh");
  for (std::size_t i = 0; i < mesh.vert.size(); ++i) {
    if (mesh.vert[i].IsD() || isFinite(mesh.vert[i].cP())) continue;
    const std::string bad =
        what + ": vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or infinity)";
    for (std::size_t f = 0; f < mesh.face.size(); ++f)
      for (int k = 0; k < 3; ++k)
        if (!mesh.face[f].IsD() && mesh.face[f].cV(k) == &mesh.vert[i])
          throw InvalidInputError(bad + " and face " + std::to_string(f) +
                                  " uses it: repair the file, or delete the faces that use it");
    throw InvalidInputError(bad + "; no face uses it: run \"Remove Unreferenced Vertices\" first");
  }
  // Over the vertices the faces use (each is a corner of about six).
  const Vertex* first = mesh.vert.data();
  std::vector<char> used(mesh.vert.size(), 0);
  for (const Face& f : mesh.face)
    if (!f.IsD())
      for (int k = 0; k < 3; ++k) used[std::size_t(f.cV(k) - first)] = 1;
  CoordinateMagnitudes m;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) m.add(first[v].cP());
  requireCoordinateSpan(m, what);
}

}  // namespace meshmend
