// The core mesh type: a vcglib triangle mesh in double precision, and the
// provenance every output element carries back to the input it came from.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <vcg/complex/complex.h>

namespace meshmend {

class Vertex;
class Face;
struct UsedTypes
    : public vcg::UsedTypes<vcg::Use<Vertex>::AsVertexType, vcg::Use<Face>::AsFaceType> {};

// Only what the core uses: positions, corners and flags. Every output is a
// new mesh of up to millions of faces, so each component left out is time
// and memory saved (adjacency and normals would triple a face's size).
class Vertex : public vcg::Vertex<UsedTypes, vcg::vertex::Coord3d, vcg::vertex::BitFlags> {};

class Face : public vcg::Face<UsedTypes, vcg::face::VertexRef, vcg::face::BitFlags> {};

// vcglib meshes are not copyable; this one copies its elements and every
// per-element attribute (provenance included) through vcg::tri::Append.
class Mesh : public vcg::tri::TriMesh<std::vector<Vertex>, std::vector<Face>> {
 public:
  Mesh() = default;
  Mesh(const Mesh& other) : TriMesh() { copyFrom(other); }
  Mesh& operator=(const Mesh& other) {
    if (this != &other) copyFrom(other);
    return *this;
  }
  // vcglib 2020.09's TriMesh does not free its attributes.
  ~Mesh() { ClearAttributes(); }

 private:
  void copyFrom(const Mesh& other);
};

using Point3 = vcg::Point3d;
using Triangle = std::array<int, 3>;

// Where an output vertex comes from. Either an input vertex (`vertex` >= 0), or
// a new point on input face `face` of layer `layer` at barycentric coordinates
// `barycentric` (weights of that face's three corners), so that the MeshLab
// bridge can interpolate colours, quality, normals and texture coordinates.
struct VertexOrigin {
  int layer = -1;   // input layer (index into the inputs of the operation)
  int vertex = -1;  // input vertex index, or -1 for a new vertex
  int face = -1;    // for a new vertex: the input face it lies on
  Point3 barycentric{0, 0, 0};
};

// Where an output face comes from: the input face it was cut from (or that it
// copies), or -1 for a face that fills space no input face covered (hole
// patches, stitches).
struct FaceOrigin {
  int layer = -1;
  int face = -1;
};

// Names of the persistent vcglib attributes that hold provenance.
inline constexpr const char* kVertexOriginAttribute = "meshmend_vertex_origin";
inline constexpr const char* kFaceOriginAttribute = "meshmend_face_origin";

using VertexOriginHandle = Mesh::PerVertexAttributeHandle<VertexOrigin>;
using FaceOriginHandle = Mesh::PerFaceAttributeHandle<FaceOrigin>;

// Provenance attributes of a mesh, created (with default values) if missing.
VertexOriginHandle vertexOrigins(Mesh& mesh);
FaceOriginHandle faceOrigins(Mesh& mesh);

// Builds a mesh from arrays; every vertex and face records itself as its own
// origin in `layer`. Throws InvalidInputError when a face refers to a vertex
// index out of range (the message names the first such face). Coordinates are
// not checked here: operations that need finite ones call
// requireFacesAndFiniteCoordinates, and inspect() counts the others.
Mesh makeMesh(const std::vector<Point3>& positions, const std::vector<Triangle>& triangles,
              int layer = 0);
// The same into an existing mesh (cleared first): Mesh has no move, and
// copying a million faces costs as much as building them.
void buildMesh(Mesh& mesh, const std::vector<Point3>& positions,
               const std::vector<Triangle>& triangles, int layer = 0);
// The same with the origins given, one per vertex and one per face (each
// written once: a split's output is built in the time it takes to copy it).
void buildMesh(Mesh& mesh, const std::vector<Point3>& positions,
               const std::vector<Triangle>& triangles,
               const std::vector<VertexOrigin>& vertexOrigin,
               const std::vector<FaceOrigin>& faceOrigin);

// The room a mesh keeps for `count` elements: a sixteenth more and 1,024,
// so that an operation that appends a little to a mesh (a hole's patch, a
// stitch) moves none of its elements, and no face's corner pointers need
// re-pointing. Reserved memory no element uses is never touched: it costs
// address space, not memory.
inline std::size_t withRoomToGrow(std::size_t count) {
  return count + count / 16 + 1024;
}

// Clears `mesh`, makes room for `vertices` and `faces` and a little more
// (withRoomToGrow; vcglib's arrays, reserved: adding up to that many moves
// nothing) and gives it empty origin attributes with the same room, all in
// huge pages (huge_pages.h): the start of every mesh the core builds.
void startMesh(Mesh& mesh, std::size_t vertices, std::size_t faces, VertexOriginHandle& vo,
               FaceOriginHandle& fo);

// That buildMesh in parts that may run on different threads at once. A
// large mesh's arrays are new memory, whose first touch (a page fault per
// 4 KiB) costs more than the copy into them: parts on two threads share
// it. Each part writes only its own array of the mesh; link() (the faces'
// corners, which point into the vertices, and the element counts) runs
// after all of them. The arrays given must outlive the builder.
class MeshBuilder {
 public:
  enum Part { kVertices, kVertexOrigins, kFaces, kFaceOrigins };
  static constexpr int kParts = 4;

  // Checks the sizes and indices (throws as buildMesh), clears `mesh` and
  // gives it empty origin attributes.
  MeshBuilder(Mesh& mesh, const std::vector<Point3>& positions,
              const std::vector<Triangle>& triangles, const std::vector<VertexOrigin>& vertexOrigin,
              const std::vector<FaceOrigin>& faceOrigin);
  void build(Part part);
  void link();

 private:
  Mesh& mesh_;
  const std::vector<Point3>& positions_;
  const std::vector<Triangle>& triangles_;
  const std::vector<VertexOrigin>& vertexOrigin_;
  const std::vector<FaceOrigin>& faceOrigin_;
  VertexOriginHandle vo_;
  FaceOriginHandle fo_;
};

// A mesh as plain arrays, for the inner loops of the core.
struct MeshArrays {
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
};
MeshArrays arraysOf(const Mesh& mesh);

// weldCoincident on arrays: the welded mesh, and for each of its vertices and
// faces the input index it keeps.
struct WeldedArrays {
  MeshArrays mesh;
  std::vector<int> vertex_origin, face_origin;
  std::size_t vertices_merged = 0, faces_removed = 0;
};
WeldedArrays weldCoincident(const MeshArrays& mesh);

// Merges vertices with exactly equal coordinates (scan seams, STL facets):
// faces are re-pointed to the first such vertex, faces left with a repeated
// corner (or that had one) are removed, unused duplicates are dropped: the
// mesh becomes weldCoincident's. Provenance is kept.
// Returns the number of vertices merged away; `removedFaces` (optional)
// receives the number of faces removed.
std::size_t weldCoincidentVertices(Mesh& mesh, std::size_t* removedFaces = nullptr);

// The two meshes in one (b's vertices and faces after a's), provenance kept.
Mesh appended(const Mesh& a, const Mesh& b);

// One use of an edge by a face: the edge (smaller vertex first), the face,
// and the corner the use starts at (it runs to the next corner).
struct EdgeUse {
  int u, v, face, corner;
  bool operator<(const EdgeUse& o) const {
    return u != o.u         ? u < o.u
           : v != o.v       ? v < o.v
           : face != o.face ? face < o.face
                            : corner < o.corner;
  }
};
// Every edge use of the faces, sorted: the uses of one edge are adjacent.
std::vector<EdgeUse> edgeUses(const std::vector<Triangle>& triangles);

// Vertex positions and face corner indices of a compact mesh (no deleted elements).
std::vector<Point3> positionsOf(const Mesh& mesh);
std::vector<Triangle> trianglesOf(const Mesh& mesh);

// The smallest interior angle of triangle (a, b, c), in radians: the one
// opposite the shortest side (one atan2 instead of three).
double smallestAngle(const Point3& a, const Point3& b, const Point3& c);

namespace detail {
// `condition ? x : y` by a mask of the bits (compilers branch on a ternary).
inline double select(bool condition, double x, double y) {
  std::uint64_t bx, by;
  std::memcpy(&bx, &x, sizeof bx);
  std::memcpy(&by, &y, sizeof by);
  const std::uint64_t take = -std::uint64_t(condition);
  bx = (bx & take) | (by & ~take);
  std::memcpy(&x, &bx, sizeof x);
  return x;
}
}  // namespace detail

// A measure that grows with the smallest angle of triangle (a, b, c), cheaper
// than the angle: the squared sine of the angle opposite the shortest side
// (at most 60°, where the sine still grows), 0 when degenerate. Inline: the
// re-triangulation's flips ask it of every candidate triangle.
inline double smallestAngleMeasure(const Point3& a, const Point3& b, const Point3& c) {
  const double ab = (b - a).SquaredNorm(), bc = (c - b).SquaredNorm(), ca = (a - c).SquaredNorm();
  const double cross = ((b - a) ^ (c - a)).SquaredNorm();  // 4 area²
  // sin² at the apex opposite the shortest side = 4 area² / (product of the
  // two others). The products chosen by selects, not branches: which side
  // is shortest is as good as random.
  const double others =
      detail::select((ab <= bc) & (ab <= ca), bc * ca, detail::select(bc <= ca, ab * ca, ab * bc));
  return others > 0 ? cross / others : 0;
}

inline bool isFinite(const Point3& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// `p` as MeshLab stores it: each coordinate rounded to float.
inline Point3 roundedToFloat(const Point3& p) {
  return Point3(double(float(p[0])), double(float(p[1])), double(float(p[2])));
}

// The scalar a host stores coordinates in: float (MeshLab 2020.09 and
// MeshLab's float builds; STL and float PLY files) or double (pymeshlab,
// MeshLab's "d" builds, the NumPy module). The core computes exactly and in
// double; what a host stores is `p` rounded to its scalar (storedAs).
enum class Scalar : std::uint8_t { kFloat, kDouble };
inline const char* toString(Scalar s) {
  return s == Scalar::kFloat ? "float" : "double";
}
inline Point3 storedAs(const Point3& p, Scalar s) {
  return s == Scalar::kFloat ? roundedToFloat(p) : p;
}
// The step between values of scalar `s` at the magnitude of `p`'s largest
// coordinate (at least the smallest normal step, so that it is never 0).
double scalarStep(const Point3& p, Scalar s);

// The span of the coordinates MeshMend decides on exactly: their nonzero
// magnitudes lie within 2^kMaxCoordinateBinades of each other. The rationals
// of intersection points and of the exact fallbacks grow with that span (a
// mesh from 1e-315 to 1e304 needs integers of thousands of bits, and a split
// of it minutes of GMP arithmetic). Floats span 277 binades (2^-149 to
// 2^128), so no mesh a float host stores is refused.
inline constexpr double kMaxCoordinateBinades = 280;

// The smallest nonzero and the largest magnitude among finite coordinates.
struct CoordinateMagnitudes {
  double smallest = std::numeric_limits<double>::infinity();
  double largest = 0;
  // Inline: it runs once per vertex of every input.
  void add(const Point3& p) {
    for (int k = 0; k < 3; ++k) {
      const double a = p[k] < 0 ? -p[k] : p[k];
      if (a > 0 && a <= std::numeric_limits<double>::max()) {  // nonzero and finite
        smallest = a < smallest ? a : smallest;
        largest = a > largest ? a : largest;
      }
    }
  }
  void add(const CoordinateMagnitudes& other);
  // log2(largest / smallest); 0 without a nonzero coordinate.
  double binades() const;
};
// Over the corners of the faces (unused vertices cost the arithmetic nothing).
CoordinateMagnitudes magnitudesOf(const std::vector<Point3>& points,
                                  const std::vector<Triangle>& triangles);

// Throws InvalidInputError naming `what` when `m` spans more than
// kMaxCoordinateBinades, saying which coordinates to set to zero.
void requireCoordinateSpan(const CoordinateMagnitudes& m, const std::string& what);

// Throws InvalidInputError naming `what` (e.g. "layer 'bunny'") when the mesh
// has no faces or a non-finite coordinate, or its faces' coordinates span
// more than requireCoordinateSpan takes.
void requireFacesAndFiniteCoordinates(const Mesh& mesh, const std::string& what);

}  // namespace meshmend
