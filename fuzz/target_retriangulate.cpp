// The re-triangulation of one triangle (common/retriangulate.h) with the
// contact points and segments other triangles make on it, as the split
// gives them: the result is a triangulation of the triangle (every piece
// turns as the triangle does, the count is Euler's) with every constraint
// an edge.
#include <algorithm>
#include <cmath>
#include <set>

#include "common/base/errors.h"
#include "common/exact/exact_point.h"
#include "common/exact/predicates.h"
#include "common/exact/retriangulate.h"
#include "fuzz/fuzz_input.h"

namespace meshmend::fuzz {

namespace {

bool usable(const TrianglePoints& t) {
  for (const Point3& p : t)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(p[k]) || std::abs(p[k]) > 1e300) return false;
  return !collinear(t[0], t[1], t[2]);
}

// The constraints another triangle makes on `t`: its contact points, and
// the segments between consecutive ones (a crossing or touching segment,
// or the outline of a coplanar overlap).
void addContact(const TrianglePoints& t, const TrianglePoints& other, PatchInput& input) {
  if (!trianglesIntersect(t, other)) return;
  const TriangleContact c = classifyContact(t, other);
  const int first = 3 + int(input.points.size());
  for (const ExactPoint& p : c.exact) input.points.push_back(p);
  const int n = int(c.exact.size());
  if (n == 2) input.segments.push_back({first, first + 1});
  if (n > 2)
    for (int i = 0; i < n; ++i) input.segments.push_back({first + i, first + (i + 1) % n});
}

void checkPatch(const PatchInput& input, const RetriangulatedPatch& patch, int axis) {
  const std::size_t inputs = 3 + input.points.size();
  const int nv = int(patch.vertices.size());
  check(patch.vertex_of_input.size() == inputs, "one vertex per input point");
  for (int v : patch.vertex_of_input) check(v >= 0 && v < nv, "input vertex in range");
  const int turn = orient2dDropping(input.corners[0], input.corners[1], input.corners[2], axis);
  std::vector<char> used(nv, 0);
  std::set<std::array<int, 2>> edges;
  for (const auto& t : patch.triangles) {
    for (int v : t) check(v >= 0 && v < nv, "triangle corner in range");
    check(orient2dDropping(patch.vertices[t[0]], patch.vertices[t[1]], patch.vertices[t[2]],
                           axis) == turn,
          "every triangle turns as the input triangle (none flat or flipped)");
    for (int i = 0; i < 3; ++i) {
      used[t[i]] = 1;
      edges.insert({std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])});
    }
  }
  for (int v = 0; v < nv; ++v) check(used[v], "every vertex is a corner of a triangle");
  for (const auto& e : patch.constrained_edges)
    check(edges.count({std::min(e[0], e[1]), std::max(e[0], e[1])}) == 1,
          "every constrained edge is an edge of the triangulation");
  // A triangulation of a triangle with V vertices, B of them on its sides,
  // has 2V - B - 2 triangles (no overlap, no gap, given that all turn alike).
  int onSides = 0;
  for (const ExactPoint& v : patch.vertices) {
    bool side = false;
    for (int i = 0; i < 3; ++i) side |= onSegment(v, input.corners[i], input.corners[(i + 1) % 3]);
    onSides += side;
  }
  check(int(patch.triangles.size()) == 2 * nv - onSides - 2, "Euler's count of triangles");
}

}  // namespace

void retriangulateTriangle(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  const std::uint8_t kind = in.byte(), flags = in.byte();
  const double scale = gridScale(in.byte());
  TrianglePoints t;
  for (Point3& p : t) p = decodePoint(in, kind, scale);
  if (!usable(t)) return;
  PatchInput input;
  for (int k = 0; k < 3; ++k) input.corners[k] = ExactPoint(t[k]);
  input.improve = flags & 1;
  for (int i = 0; i < 8 && in.left() > 0; ++i) {
    TrianglePoints other;
    for (Point3& p : other) p = decodePoint(in, kind, scale);
    // Sharing corners with t, as neighbours in a mesh do.
    if (flags & (2 << i % 4)) other[0] = t[i % 3];
    if (usable(other)) addContact(t, other, input);
  }
  RetriangulatedPatch patch;
  try {
    patch = retriangulate(input);
  } catch (const InvalidInputError& e) {
    check(false, std::string("contact points are valid input: ") + e.what());
  }
  checkPatch(input, patch, projectionAxis(t[0], t[1], t[2]));
}

}  // namespace meshmend::fuzz
