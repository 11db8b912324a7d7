// What the clearance stages (common/clearance/*.cpp) share: the distances
// of elements, the layers as one soup with the pair rules, the search for
// close pairs, and the state of one enforcement. Not an interface of the core.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "common/base/timing.h"
#include "common/exact/box_tree.h"
#include "common/repair/clearance/clearance.h"

namespace meshmend::clearance_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- distances of elements (distance.cpp) ----------------------------------------

// The point of triangle (a, b, c) closest to p, with its barycentric weights.
struct PointTriangle {
  double distance;
  Point3 point;
  double w[3];
};
PointTriangle pointTriangle(const Point3& p, const Point3& a, const Point3& b, const Point3& c);

// The closest points of segments p0p1 and q0q1: p0 + s (p1 - p0), q0 + t (q1 - q0).
struct SegmentSegment {
  double distance, s, t;
  Point3 pa, pb;
};
SegmentSegment segmentSegment(const Point3& p0, const Point3& p1, const Point3& q0,
                              const Point3& q1);

// The distance of two disjoint triangles: the smallest of the six
// vertex–face and nine edge–edge distances, and where it is.
struct TriangleDistance {
  double distance = kInf;
  bool edgeEdge = false;
  Point3 pa{0, 0, 0}, pb{0, 0, 0};  // closest points on a and b
};
TriangleDistance triangleDistance(const Point3* a, const Point3* b);

// ---- the layers as one soup (pairs.cpp) -------------------------------------------

inline bool includesWithin(ClearanceScope s) {
  return s != ClearanceScope::kBetweenLayers;
}
inline bool includesBetween(ClearanceScope s) {
  return s != ClearanceScope::kWithinLayers;
}

// Every layer's vertices and faces in one index space (faces of different
// layers never share a vertex), with what the pair rules need.
struct Soup {
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  std::vector<int> faceLayer;
  std::vector<int> vertexOffset, faceOffset;  // per layer, plus the totals at the end
  std::vector<int> ringStart, ring;           // vertex -> neighbours (sorted), rings == 2 only
  std::vector<int> starStart, star;           // vertex -> faces
  ClearanceScope scope = ClearanceScope::kBoth;
  int rings = 1;
  double diagonal = 0;

  // The layers' points placed in the common frame (none: as they are).
  Soup(const std::vector<const Mesh*>& layers, ClearanceScope s, int exclusionRings,
       const std::vector<Placement>& placements = {});

  std::size_t faces() const { return triangles.size(); }
  int layers() const { return int(vertexOffset.size()) - 1; }

  bool sharesVertex(std::uint32_t f, std::uint32_t g) const {
    const Triangle &a = triangles[f], &b = triangles[g];
    for (int i = 0; i < 3; ++i)
      if (a[i] == b[0] || a[i] == b[1] || a[i] == b[2]) return true;
    return false;
  }
  bool neighbours(int u, int v) const {
    return std::binary_search(ring.begin() + ringStart[u], ring.begin() + ringStart[u + 1], v);
  }
  // Does the clearance apply to faces f and g?
  bool clearancePair(std::uint32_t f, std::uint32_t g) const {
    if (faceLayer[f] != faceLayer[g]) return includesBetween(scope);
    if (!includesWithin(scope) || sharesVertex(f, g)) return false;
    if (rings == 2)
      for (int u : triangles[f])
        for (int v : triangles[g])
          if (neighbours(u, v)) return false;
    return true;
  }
  // Must faces f and g stay free of each other (intersection checks)? Always
  // within a layer; between layers when the scope includes them.
  bool checkedPair(std::uint32_t f, std::uint32_t g) const {
    return faceLayer[f] == faceLayer[g] || includesBetween(scope);
  }

  void corners(const std::vector<Point3>& P, std::uint32_t f, Point3* out) const {
    for (int i = 0; i < 3; ++i) out[i] = P[triangles[f][i]];
  }
  double distance(const std::vector<Point3>& P, std::uint32_t f, std::uint32_t g) const {
    Point3 a[3], b[3];
    corners(P, f, a);
    corners(P, g, b);
    return triangleDistance(a, b).distance;
  }

  ClearancePair describe(const std::vector<Point3>& P, std::uint32_t f, std::uint32_t g) const {
    if (g < f) std::swap(f, g);
    Point3 a[3], b[3];
    corners(P, f, a);
    corners(P, g, b);
    const TriangleDistance d = triangleDistance(a, b);
    ClearancePair pair;
    pair.layer_a = faceLayer[f];
    pair.face_a = int(f) - faceOffset[pair.layer_a];
    pair.layer_b = faceLayer[g];
    pair.face_b = int(g) - faceOffset[pair.layer_b];
    pair.kind = d.edgeEdge ? "edge_edge" : "vertex_face";
    pair.distance = d.distance;
    pair.point_a = d.pa;
    pair.point_b = d.pb;
    return pair;
  }
};
// ---- close pairs (pairs.cpp) --------------------------------------------------------

// A float box grown by `by` on every side, rounded outward.
Box inflated(Box b, double by);

struct NearPair {
  std::uint32_t f, g;  // f < g
  double d;
};

// Every pair in scope closer than `radius`, in (f, g) order; `candidates`
// (when given) grows by the pairs whose distance was computed.
std::vector<NearPair> pairsWithin(const Soup& soup, const std::vector<Point3>& P, double radius,
                                  std::size_t* candidates = nullptr);

// Does any pair of faces fall under the scope at all?
bool anyPairInScope(const Soup& soup);

// The pairs closer than `start`, or, when there are none, those closer than
// a radius grown fourfold until some pair is found (the global minimum).
std::vector<NearPair> pairsFromRadius(const Soup& soup, const std::vector<Point3>& P, double start,
                                      double* used, std::size_t* candidates);

// The `count` closest of `pairs` below `below`, described.
std::vector<ClearancePair> listShortest(const Soup& soup, const std::vector<Point3>& P,
                                        std::vector<NearPair> pairs, double below,
                                        std::size_t count);

// What measuring and enforcing both require of the layers, the rings and
// the placements (none, or one affine invertible matrix per layer).
void checkCommon(const std::vector<const Mesh*>& layers, int rings,
                 const std::vector<Placement>& placements);

// Is the placement the identity (the layer's frame is the common one)?
bool isIdentity(const Placement& m);

// ---- one enforcement (enforce.cpp, step.cpp, line_search.cpp) ---------------------

// The distances the solve works with: tau as reached (with the rounding
// margin), the goal of each linearised step a little beyond, and the
// distance below which pairs take part in a step.
struct Targets {
  double reached = 0, goal = 0, near = 0;
};

// The state of one enforcement, stage to stage.
struct Separation {
  const ClearanceOptions& options;
  Soup soup;
  Targets targets;
  std::vector<Point3>& P;  // current positions (soup.points)
  std::vector<Point3> P0;  // the input's positions (rounded, with round_to_float)
  // With placements: per vertex, its position in its layer's own frame as
  // it will be written back (the input's, until a move is stored).
  std::vector<Point3> own;
  std::vector<char> locked;    // per vertex: may not move
  std::vector<char> capped;    // per vertex: reached max_displacement
  std::vector<NearPair> near;  // the active pairs: in scope, closer than targets.near
  ClearanceResult result;
  std::size_t candidates = 0;  // pair distances computed

  Separation(const std::vector<const Mesh*>& layers, const ClearanceOptions& o)
      : options(o), soup(layers, o.scope, o.exclusion_rings, o.placements), P(soup.points) {}
};

// One linearised step: the moved vertices and each one's displacement.
struct Step {
  std::vector<int> vertices;
  std::vector<Point3> by;  // per soup vertex; zero for the others
};

// The minimum-norm step that brings the active pairs' elements to the goal
// (within the trust radius tau and the cap). Empty when no row can move:
// sets result.stop_reason to "locked" when every short row is held.
Step linearisedStep(Separation& s);

// Backtracking along `step` until it keeps every face pair apart all along
// the way and lowers Σ (goal - d)² over the pairs short of it; then takes it
// and updates the active pairs. False (nothing moved) when no fraction does.
bool takeStep(Separation& s, const Step& step);

}  // namespace meshmend::clearance_detail
