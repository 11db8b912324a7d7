#include "common/clearance.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>

#include "common/box_tree.h"
#include "common/errors.h"
#include "common/intersections.h"
#include "common/parallel.h"
#include "common/predicates.h"

namespace meshmend {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// ---- distances of elements (§4.1) ------------------------------------------------

// The point of triangle (a, b, c) closest to p, with its barycentric weights.
// Region by region (vertex, edge, interior), so that no weight leaves [0, 1].
struct PointTriangle {
  double distance;
  Point3 point;
  double w[3];
};

// Point–segment: the fallback for a triangle with (numerically) no area.
PointTriangle pointSegment(const Point3& p, const Point3& a, const Point3& b, int ia, int ib) {
  const Point3 ab = b - a;
  const double len2 = ab.SquaredNorm();
  double s = len2 > 0 ? std::clamp(((p - a) * ab) / len2, 0.0, 1.0) : 0.0;
  PointTriangle r;
  r.point = a + ab * s;
  r.distance = (p - r.point).Norm();
  r.w[0] = r.w[1] = r.w[2] = 0;
  r.w[ia] = 1 - s;
  r.w[ib] = s;
  return r;
}

PointTriangle pointTriangle(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  PointTriangle r;
  auto at = [&](double wa, double wb, double wc) {
    r.w[0] = wa;
    r.w[1] = wb;
    r.w[2] = wc;
    r.point = a * wa + b * wb + c * wc;
    r.distance = (p - r.point).Norm();
    return r;
  };
  const Point3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab * ap, d2 = ac * ap;
  if (d1 <= 0 && d2 <= 0) return at(1, 0, 0);
  const Point3 bp = p - b;
  const double d3 = ab * bp, d4 = ac * bp;
  if (d3 >= 0 && d4 <= d3) return at(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return at(1 - v, v, 0);
  }
  const Point3 cp = p - c;
  const double d5 = ab * cp, d6 = ac * cp;
  if (d6 >= 0 && d5 <= d6) return at(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return at(1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return at(0, 1 - w, w);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // No area: the closest of the three edges.
    PointTriangle best = pointSegment(p, a, b, 0, 1);
    for (const PointTriangle& e : {pointSegment(p, b, c, 1, 2), pointSegment(p, c, a, 2, 0)})
      if (e.distance < best.distance) best = e;
    return best;
  }
  const double v = vb / sum, w = vc / sum;
  return at(1 - v - w, v, w);
}

// The closest points of segments p0p1 and q0q1: p0 + s (p1 - p0), q0 + t (q1 - q0).
struct SegmentSegment {
  double distance, s, t;
  Point3 pa, pb;
};

SegmentSegment segmentSegment(const Point3& p0, const Point3& p1, const Point3& q0,
                              const Point3& q1) {
  const Point3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.SquaredNorm(), e = d2.SquaredNorm(), f = d2 * r;
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) {
  } else if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1 * r;
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1 * d2, denom = a * e - b * b;
      // Parallel segments (denom 0): any s works for the lines; start at 0.
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  SegmentSegment out;
  out.s = s;
  out.t = t;
  out.pa = p0 + d1 * s;
  out.pb = q0 + d2 * t;
  out.distance = (out.pa - out.pb).Norm();
  return out;
}

// The distance of two disjoint triangles: the smallest of the six
// vertex–face and nine edge–edge distances, and where it is.
struct TriangleDistance {
  double distance = kInf;
  bool edgeEdge = false;
  Point3 pa{0, 0, 0}, pb{0, 0, 0};  // closest points on a and b
};

TriangleDistance triangleDistance(const Point3* a, const Point3* b) {
  TriangleDistance best;
  for (int i = 0; i < 3; ++i) {
    const PointTriangle x = pointTriangle(a[i], b[0], b[1], b[2]);
    if (x.distance < best.distance) best = {x.distance, false, a[i], x.point};
    const PointTriangle y = pointTriangle(b[i], a[0], a[1], a[2]);
    if (y.distance < best.distance) best = {y.distance, false, y.point, b[i]};
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const SegmentSegment e = segmentSegment(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
      if (e.distance < best.distance) best = {e.distance, true, e.pa, e.pb};
    }
  return best;
}

// ---- the layers as one soup -------------------------------------------------------

bool includesWithin(ClearanceScope s) {
  return s != ClearanceScope::kBetweenLayers;
}
bool includesBetween(ClearanceScope s) {
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

  Soup(const std::vector<const Mesh*>& layers, ClearanceScope s, int exclusionRings)
      : scope(s), rings(exclusionRings) {
    for (std::size_t l = 0; l < layers.size(); ++l) {
      vertexOffset.push_back(int(points.size()));
      faceOffset.push_back(int(triangles.size()));
      const int offset = int(points.size());
      for (const Point3& p : positionsOf(*layers[l])) points.push_back(p);
      for (Triangle t : trianglesOf(*layers[l])) {
        for (int& v : t) v += offset;
        triangles.push_back(t);
        faceLayer.push_back(int(l));
      }
    }
    vertexOffset.push_back(int(points.size()));
    faceOffset.push_back(int(triangles.size()));
    Point3 lo = points.empty() ? Point3(0, 0, 0) : points[0], hi = lo;
    for (const Point3& p : points)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], p[k]);
        hi[k] = std::max(hi[k], p[k]);
      }
    diagonal = (hi - lo).Norm();
    // Faces around each vertex (a counting sort).
    starStart.assign(points.size() + 1, 0);
    for (const Triangle& t : triangles)
      for (int v : t) ++starStart[v + 1];
    std::partial_sum(starStart.begin(), starStart.end(), starStart.begin());
    star.resize(starStart.back());
    std::vector<int> fill(starStart.begin(), starStart.end() - 1);
    for (std::size_t f = 0; f < triangles.size(); ++f)
      for (int v : triangles[f]) star[fill[v]++] = int(f);
    if (rings == 2) {
      ringStart.assign(points.size() + 1, 0);
      for (std::size_t v = 0; v < points.size(); ++v) {
        std::vector<int> n;
        for (int i = starStart[v]; i < starStart[v + 1]; ++i)
          for (int u : triangles[star[i]])
            if (u != int(v)) n.push_back(u);
        std::sort(n.begin(), n.end());
        n.erase(std::unique(n.begin(), n.end()), n.end());
        ring.insert(ring.end(), n.begin(), n.end());
        ringStart[v + 1] = int(ring.size());
      }
    }
  }

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

// A float box grown by `by` on every side, rounded outward.
Box inflated(Box b, double by) {
  for (int k = 0; k < 3; ++k) {
    float lo = float(double(b.lo[k]) - by), hi = float(double(b.hi[k]) + by);
    b.lo[k] = std::nextafter(lo, -std::numeric_limits<float>::infinity());
    b.hi[k] = std::nextafter(hi, std::numeric_limits<float>::infinity());
  }
  return b;
}

// Squared Euclidean gap between two boxes (0 when they overlap).
double gap2(const Box& x, const Box& y) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double g = std::max({0.0, double(y.lo[k]) - x.hi[k], double(x.lo[k]) - y.hi[k]});
    s += g * g;
  }
  return s;
}

struct NearPair {
  std::uint32_t f, g;  // f < g
  double d;
};

// Every pair in scope closer than `radius` (boxes grown by radius / 2, so
// that a pair at distance < radius always has overlapping boxes): one tree
// per layer for pairs within layers, the smaller layer's tree queried by the
// larger one's faces for pairs between layers, one tree of all faces for both.
std::vector<NearPair> pairsWithin(const Soup& soup, const std::vector<Point3>& P, double radius,
                                  std::size_t* candidates = nullptr) {
  const std::size_t nf = soup.faces();
  std::vector<Box> boxes(nf), grown(nf);
  // Unit normal and offset of each face's plane: a face whose corners all
  // lie `radius` or more to one side of the other's plane is that far away.
  std::vector<Point3> normal(nf);
  std::vector<double> offset(nf);
  // And the outward normals of its edges in its plane: neighbours on a
  // smooth sheet are not beside each other's planes but beside an edge.
  std::vector<std::array<Point3, 3>> side(nf);
  parallelChunks(nf, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t f = b; f < e; ++f) {
      const Triangle& t = soup.triangles[f];
      boxes[f] = boxOf(P[t[0]], P[t[1]], P[t[2]]);
      grown[f] = inflated(boxes[f], radius / 2);
      Point3 n = (P[t[1]] - P[t[0]]) ^ (P[t[2]] - P[t[0]]);
      const double len = n.Norm();
      n = len > 0 ? n / len : Point3(0, 0, 0);
      normal[f] = n;
      offset[f] = n * P[t[0]];
      for (int i = 0; i < 3; ++i) {
        Point3 a = (P[t[(i + 1) % 3]] - P[t[i]]) ^ n;  // outward for a counter-clockwise face
        const double l = a.Norm();
        side[f][i] = l > 0 ? a / l : Point3(0, 0, 0);
      }
    }
  });
  // Rounding in the plane test is far below `radius`; a margin of a
  // millionth keeps it conservative.
  const double planeRadius = radius * (1 + 1e-6);
  auto beside = [&](std::uint32_t f, std::uint32_t g) {
    if (normal[f] == Point3(0, 0, 0)) return false;
    double lo = kInf, hi = -kInf;
    for (int v : soup.triangles[g]) {
      const double s = normal[f] * P[v] - offset[f];
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    if (lo >= planeRadius || hi <= -planeRadius) return true;
    for (int i = 0; i < 3; ++i) {
      const Point3& a = side[f][i];
      const double from = a * P[soup.triangles[f][i]];
      double nearest = kInf;
      for (int v : soup.triangles[g]) nearest = std::min(nearest, a * P[v] - from);
      if (nearest >= planeRadius) return true;
    }
    return false;
  };
  struct alignas(64) Found {
    std::vector<NearPair> pairs;
    std::size_t candidates = 0;
  };
  std::vector<Found> found(workerCount());
  const double r2 = radius * radius;
  auto visit = [&](std::uint32_t f, std::uint32_t g, unsigned w) {
    if (g < f) std::swap(f, g);
    if (!soup.clearancePair(f, g) || gap2(boxes[f], boxes[g]) >= r2) return;
    if (beside(f, g) || beside(g, f)) return;
    ++found[w].candidates;
    const double d = soup.distance(P, f, g);
    if (d < radius) found[w].pairs.push_back({f, g, d});
  };
  // Trees answer one self-join or one pass of queries: Morton order builds
  // three times faster than median splits.
  auto treeOf = [&](int first, int last) {
    return BoxTree(std::vector<Box>(grown.begin() + first, grown.begin() + last),
                   BoxTree::Layout::kMorton);
  };
  const int nl = soup.layers();
  if (soup.scope == ClearanceScope::kBoth || nl == 1) {
    if (soup.scope != ClearanceScope::kBetweenLayers) treeOf(0, int(nf)).selfPairs(visit);
  } else if (soup.scope == ClearanceScope::kWithinLayers) {
    for (int l = 0; l < nl; ++l) {
      const std::uint32_t first = std::uint32_t(soup.faceOffset[l]);
      treeOf(soup.faceOffset[l], soup.faceOffset[l + 1])
          .selfPairs([&](std::uint32_t f, std::uint32_t g, unsigned w) {
            visit(first + f, first + g, w);
          });
    }
  } else {
    for (int a = 0; a < nl; ++a)
      for (int b = a + 1; b < nl; ++b) {
        const int sizeA = soup.faceOffset[a + 1] - soup.faceOffset[a];
        const int sizeB = soup.faceOffset[b + 1] - soup.faceOffset[b];
        const int small = sizeA <= sizeB ? a : b, large = sizeA <= sizeB ? b : a;
        const BoxTree tree = treeOf(soup.faceOffset[small], soup.faceOffset[small + 1]);
        const std::uint32_t firstSmall = std::uint32_t(soup.faceOffset[small]);
        const int firstLarge = soup.faceOffset[large];
        parallelChunks(
            std::size_t(soup.faceOffset[large + 1] - firstLarge),
            [&](std::size_t begin, std::size_t end, unsigned worker) {
              for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t g = std::uint32_t(firstLarge + i);
                if (!overlap(grown[g], tree.bounds())) continue;
                tree.query(grown[g], worker,
                           [&](std::uint32_t f, unsigned w) { visit(firstSmall + f, g, w); });
              }
            },
            1024);
      }
  }
  std::vector<NearPair> all;
  std::size_t count = 0;
  for (const Found& x : found) {
    all.insert(all.end(), x.pairs.begin(), x.pairs.end());
    count += x.candidates;
  }
  if (candidates) *candidates += count;
  // Deterministic order whatever the threads did.
  std::sort(all.begin(), all.end(), [](const NearPair& x, const NearPair& y) {
    return x.f != y.f ? x.f < y.f : x.g < y.g;
  });
  return all;
}

// Does any pair of faces fall under the scope at all?
bool anyPairInScope(const Soup& soup) {
  if (includesBetween(soup.scope) && soup.layers() > 1) return true;
  return includesWithin(soup.scope) && soup.faces() > 1;
}

// The pairs closer than `start`, or, when there are none, those closer than
// a radius grown fourfold until some pair is found (the global minimum).
std::vector<NearPair> pairsFromRadius(const Soup& soup, const std::vector<Point3>& P, double start,
                                      double* used, std::size_t* candidates) {
  double radius = start;
  while (true) {
    std::vector<NearPair> pairs = pairsWithin(soup, P, radius, candidates);
    // (A diagonal beyond double's range is infinite: the radius stops once
    // it is too.)
    if (!pairs.empty() || radius > 2 * soup.diagonal || std::isinf(radius) ||
        !anyPairInScope(soup)) {
      *used = radius;
      return pairs;
    }
    radius *= 4;
  }
}

std::vector<ClearancePair> listShortest(const Soup& soup, const std::vector<Point3>& P,
                                        std::vector<NearPair> pairs, double below,
                                        std::size_t count) {
  pairs.erase(
      std::remove_if(pairs.begin(), pairs.end(), [&](const NearPair& p) { return !(p.d < below); }),
      pairs.end());
  auto closer = [](const NearPair& x, const NearPair& y) {
    return x.d != y.d ? x.d < y.d : (x.f != y.f ? x.f < y.f : x.g < y.g);
  };
  const std::size_t n = std::min(count, pairs.size());
  std::partial_sort(pairs.begin(), pairs.begin() + n, pairs.end(), closer);
  std::vector<ClearancePair> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(soup.describe(P, pairs[i].f, pairs[i].g));
  return out;
}

void checkCommon(const std::vector<const Mesh*>& layers, int rings) {
  if (layers.empty()) throw InvalidInputError("no layer given");
  for (std::size_t l = 0; l < layers.size(); ++l)
    requireFacesAndFiniteCoordinates(*layers[l], "layer " + std::to_string(l));
  if (rings != 1 && rings != 2)
    throw InvalidInputError("exclusion_rings must be 1 or 2, not " + std::to_string(rings));
}

// ---- the Gauss-Newton rows ----------------------------------------------------------

// One vertex–face or edge–edge distance, by its four vertices: kind 0 =
// vertex v[0] against face (v[1], v[2], v[3]); kind 1 = edge (v[0], v[1])
// against edge (v[2], v[3]), each edge's smaller index first, the smaller edge first.
struct Element {
  std::array<int, 4> v;
  int kind;
  bool operator<(const Element& o) const { return kind != o.kind ? kind < o.kind : v < o.v; }
  bool operator==(const Element& o) const { return kind == o.kind && v == o.v; }
};

// A linearised distance: d + Σ_i w[i] (n · Δx_{v[i]}). The gradient comes from
// the closest points (envelope theorem): moving a corner moves the closest
// point by its weight, along the direction between the closest points.
struct Row {
  Element e;
  double d;
  Point3 n;
  double w[4];
};

bool evaluate(const std::vector<Point3>& P, const Element& e, Row& row) {
  row.e = e;
  Point3 a, b;
  if (e.kind == 0) {
    const PointTriangle x = pointTriangle(P[e.v[0]], P[e.v[1]], P[e.v[2]], P[e.v[3]]);
    a = P[e.v[0]];
    b = x.point;
    row.w[0] = 1;
    for (int i = 0; i < 3; ++i) row.w[i + 1] = -x.w[i];
    row.d = x.distance;
  } else {
    const SegmentSegment x = segmentSegment(P[e.v[0]], P[e.v[1]], P[e.v[2]], P[e.v[3]]);
    a = x.pa;
    b = x.pb;
    row.w[0] = 1 - x.s;
    row.w[1] = x.s;
    row.w[2] = -(1 - x.t);
    row.w[3] = -x.t;
    row.d = x.distance;
  }
  if (!(row.d > 0)) return false;
  row.n = (a - b) / row.d;
  return true;
}

// The elements of face pair (f, g) closer than `below`.
void elementsOf(const Soup& soup, const std::vector<Point3>& P, std::uint32_t f, std::uint32_t g,
                double below, std::vector<Element>& out) {
  const Triangle &a = soup.triangles[f], &b = soup.triangles[g];
  for (int i = 0; i < 3; ++i) {
    if (pointTriangle(P[a[i]], P[b[0]], P[b[1]], P[b[2]]).distance < below)
      out.push_back({{a[i], b[0], b[1], b[2]}, 0});
    if (pointTriangle(P[b[i]], P[a[0]], P[a[1]], P[a[2]]).distance < below)
      out.push_back({{b[i], a[0], a[1], a[2]}, 0});
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      int a0 = a[i], a1 = a[(i + 1) % 3], b0 = b[j], b1 = b[(j + 1) % 3];
      if (segmentSegment(P[a0], P[a1], P[b0], P[b1]).distance >= below) continue;
      if (a0 > a1) std::swap(a0, a1);
      if (b0 > b1) std::swap(b0, b1);
      if (std::make_pair(b0, b1) < std::make_pair(a0, a1)) {
        std::swap(a0, b0);
        std::swap(a1, b1);
      }
      out.push_back({{a0, a1, b0, b1}, 1});
    }
}

using SparseRows = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// The minimum-norm step Δ with d_k + J_k Δ ≥ goal for every row (the
// linearised problem, a quadratic programme with inequalities: rows already
// beyond the goal only stop the step from pushing them below it).
//
// First Hildreth's method (coordinate ascent on the dual, Δ = Jᵀ y, y ≥ 0)
// finds which rows bind; it handles repeated rows (a vertex–face and an
// edge–edge distance meeting at the same points) and more rows than moved
// coordinates. Then the step is solved exactly for the binding rows W with
// a sparse solve, Δ = (J_Wᵀ J_W + λI)⁻¹ J_Wᵀ (goal - d_W): for a small λ the
// minimum-norm solution J_Wᵀ (J_W J_Wᵀ)⁻¹ (goal - d_W), in the form whose
// size is the moved coordinates (J_W J_Wᵀ is singular when rows repeat). The
// solved step is kept if it satisfies every row, else Hildreth's.
Eigen::VectorXd minimumNormStep(const SparseRows& J, const Eigen::VectorXd& d, double goal,
                                double tolerance) {
  const int m = int(J.rows());
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(J.cols());
  Eigen::VectorXd y = Eigen::VectorXd::Zero(m);
  std::vector<double> norm2(m, 0);
  for (int k = 0; k < m; ++k)
    for (SparseRows::InnerIterator it(J, k); it; ++it) norm2[k] += it.value() * it.value();
  std::vector<int> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return d[a] < d[b]; });
  for (int sweep = 0; sweep < 400; ++sweep) {
    double worst = 0;
    for (int k : order) {
      if (!(norm2[k] > 0)) continue;
      double predicted = d[k];
      for (SparseRows::InnerIterator it(J, k); it; ++it) predicted += it.value() * delta[it.col()];
      const double shortfall = goal - predicted;
      if (y[k] == 0 && shortfall <= 0) continue;
      const double next = std::max(0.0, y[k] + shortfall / norm2[k]);
      const double change = next - y[k];
      if (change == 0) continue;
      y[k] = next;
      for (SparseRows::InnerIterator it(J, k); it; ++it) delta[it.col()] += change * it.value();
      worst = std::max(worst, std::abs(shortfall));
    }
    if (worst < 100 * tolerance) break;  // enough to tell the binding rows
  }

  std::vector<char> binding(m, 0);
  for (int k = 0; k < m; ++k) binding[k] = y[k] > 0;
  for (int round = 0; round < 4; ++round) {
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<double> r;
    for (int k = 0; k < m; ++k) {
      if (!binding[k]) continue;
      for (SparseRows::InnerIterator it(J, k); it; ++it)
        entries.emplace_back(int(r.size()), int(it.col()), it.value());
      r.push_back(goal - d[k]);
    }
    if (r.empty()) return delta;
    Eigen::SparseMatrix<double> JW(int(r.size()), J.cols());
    JW.setFromTriplets(entries.begin(), entries.end());
    Eigen::SparseMatrix<double> H = Eigen::SparseMatrix<double>(JW.transpose()) * JW;
    double largest = 0;
    for (int i = 0; i < H.rows(); ++i) largest = std::max(largest, H.coeff(i, i));
    // The ridge keeps the solve defined for coordinates no binding row moves
    // and in directions no row sees; small enough not to shorten the step.
    Eigen::SparseMatrix<double> ridge(H.rows(), H.cols());
    ridge.setIdentity();
    H += ridge * (1e-10 * std::max(largest, 1e-300));
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(H);
    if (solver.info() != Eigen::Success) return delta;
    const Eigen::VectorXd solved = solver.solve(
        Eigen::VectorXd(JW.transpose() * Eigen::Map<const Eigen::VectorXd>(r.data(), r.size())));
    const Eigen::VectorXd predicted = d + J * solved;
    bool short_ = false;
    for (int k = 0; k < m; ++k)
      if (norm2[k] > 0 && predicted[k] < goal - tolerance) {
        short_ = true;
        binding[k] = 1;  // a row Hildreth had not yet seen binding
      }
    if (!short_) return solved;
  }
  return delta;
}

// The work bound on the input's short pairs (ClearanceOptions::max_short_pairs).
void boundShortPairs(std::size_t shortPairs, std::size_t bound, double tau, double closest) {
  if (bound == 0 || shortPairs <= bound) return;
  std::ostringstream message;
  message << shortPairs << " face pairs are closer than tau = " << tau
          << ", more than the work bound of " << bound
          << " (max_short_pairs): separating them all would take minutes, and so many mean a "
             "tau larger than the parts or than a few edge lengths, not gaps to open. Nothing "
             "was changed. Try a smaller tau (the closest pair is "
          << closest
          << " apart), more exclusion rings, or raise the bound if the parts really are that "
             "close everywhere";
  throw WorkLimitError(message.str());
}

}  // namespace

const char* toString(ClearanceScope scope) {
  switch (scope) {
    case ClearanceScope::kWithinLayers:
      return "within_layers";
    case ClearanceScope::kBetweenLayers:
      return "between_layers";
    default:
      return "both";
  }
}

// ---- measuring ----------------------------------------------------------------------

ClearanceMeasure measureClearance(const std::vector<const Mesh*>& layers,
                                  const ClearanceMeasureOptions& options) {
  const auto start = Clock::now();
  if (!(options.tau >= 0) || !std::isfinite(options.tau))
    throw InvalidInputError("tau must be a finite distance >= 0");
  if (!(options.local_max >= 0) || !std::isfinite(options.local_max))
    throw InvalidInputError("local_max must be a finite distance >= 0");
  if (options.histogram_bins < 1) throw InvalidInputError("histogram_bins must be at least 1");
  checkCommon(layers, options.exclusion_rings);
  reportProgress(options.progress, 0, "Preparing");
  const Soup soup(layers, options.scope, options.exclusion_rings);
  const std::vector<Point3>& P = soup.points;

  ClearanceMeasure m;
  m.tau = options.tau;
  // Without tau or cap, the search starts at a quarter of the mean edge
  // length and grows until the closest pair is found.
  // Pairs up to tau must all be found (counted, selected), whatever the
  // local clearance cap.
  double startRadius = std::max(options.local_max, 2 * options.tau);
  if (!(startRadius > 0)) {
    double sum = 0;
    for (const Triangle& t : soup.triangles) sum += (P[t[0]] - P[t[1]]).Norm();
    startRadius = std::max(0.25 * sum / double(soup.faces()), 1e-12 * soup.diagonal);
    if (!(startRadius > 0)) startRadius = 1e-300;
  }
  reportProgress(options.progress, 10, "Closest pairs");
  double used = 0;
  std::vector<NearPair> pairs = pairsFromRadius(soup, P, startRadius, &used, &m.candidate_pairs);
  for (const NearPair& p : pairs)
    if (!m.found || p.d < m.min_distance) {
      m.found = true;
      m.min_distance = p.d;
    }
  m.local_max = options.local_max > 0 ? options.local_max
                : options.tau > 0     ? 2 * options.tau
                : m.found             ? 2 * m.min_distance
                                      : 0;
  if (m.local_max > used) {
    reportProgress(options.progress, 50, "Local clearances");
    pairs = pairsWithin(soup, P, m.local_max, &m.candidate_pairs);
  }

  const int n = soup.layers();
  m.faces_below_tau.resize(n);
  m.vertex_clearance.resize(n);
  for (int l = 0; l < n; ++l) {
    m.faces_below_tau[l].assign(soup.faceOffset[l + 1] - soup.faceOffset[l], 0);
    m.vertex_clearance[l].assign(soup.vertexOffset[l + 1] - soup.vertexOffset[l], m.local_max);
  }
  m.histogram.assign(options.histogram_bins, 0);
  for (const NearPair& p : pairs) {
    if (p.d < options.tau) {
      ++m.violating_pairs;
      for (std::uint32_t f : {p.f, p.g})
        m.faces_below_tau[soup.faceLayer[f]][f - soup.faceOffset[soup.faceLayer[f]]] = 1;
    }
    if (p.d < m.local_max) {
      const int bin =
          std::min(options.histogram_bins - 1, int(p.d / m.local_max * options.histogram_bins));
      ++m.histogram[bin];
      for (std::uint32_t f : {p.f, p.g}) {
        const int l = soup.faceLayer[f];
        for (int v : soup.triangles[f]) {
          double& c = m.vertex_clearance[l][v - soup.vertexOffset[l]];
          c = std::min(c, p.d);
        }
      }
    }
  }
  for (const auto& faces : m.faces_below_tau)
    m.faces_below_tau_count += std::size_t(std::count(faces.begin(), faces.end(), 1));
  if (m.found) {
    m.shortest = listShortest(soup, P, pairs, kInf, options.max_listed_pairs);
    m.closest = m.shortest.front();
  }
  reportProgress(options.progress, 100, "Done");
  m.time_ms = msSince(start);
  return m;
}

// ---- enforcing ----------------------------------------------------------------------

ClearanceResult enforceClearance(std::vector<Mesh*>& layers, const ClearanceOptions& options) {
  const auto start = Clock::now();
  ClearanceResult result;
  const double tau = options.tau;
  result.tau = tau;
  if (!(tau > 0) || !std::isfinite(tau))
    throw InvalidInputError("tau must be a finite distance > 0 (got " + std::to_string(tau) + ")");
  if (!(options.max_displacement >= 0) || !std::isfinite(options.max_displacement))
    throw InvalidInputError("max_displacement must be a finite distance >= 0 (0 = no cap)");
  if (!(options.active_margin >= 0)) throw InvalidInputError("active_margin must be >= 0");
  const std::vector<const Mesh*> constLayers(layers.begin(), layers.end());
  checkCommon(constLayers, options.exclusion_rings);
  if (!options.locked.empty()) {
    if (options.locked.size() != layers.size())
      throw InvalidInputError("locked must hold one list per layer (" +
                              std::to_string(layers.size()) + "), not " +
                              std::to_string(options.locked.size()));
    for (std::size_t l = 0; l < layers.size(); ++l)
      if (!options.locked[l].empty() && options.locked[l].size() != std::size_t(layers[l]->vn))
        throw InvalidInputError("locked list of layer " + std::to_string(l) + " has " +
                                std::to_string(options.locked[l].size()) + " entries for " +
                                std::to_string(layers[l]->vn) + " vertices");
  }
  reportProgress(options.progress, 0, "Checking intersections");
  Soup soup(constLayers, options.scope, options.exclusion_rings);
  const std::size_t nv = soup.points.size(), nf = soup.faces();
  const int nl = soup.layers();
  // With round_to_float everything works on the input as MeshLab stores it
  // (a no-op for a mesh that comes from MeshLab), so that only the moved
  // vertices are rounded at the end, within the margin the solve keeps.
  if (options.round_to_float)
    for (Point3& p : soup.points) p = roundedToFloat(p);

  // The clearance is a distance between surfaces that do not meet: crossing
  // faces would have to pass through each other, which no small move does.
  {
    const auto t0 = Clock::now();
    std::vector<MeshArrays> arrays(nl);
    for (int l = 0; l < nl; ++l) {
      const int first = soup.vertexOffset[l];
      arrays[l].points.assign(soup.points.begin() + first,
                              soup.points.begin() + soup.vertexOffset[l + 1]);
      for (int f = soup.faceOffset[l]; f < soup.faceOffset[l + 1]; ++f)
        arrays[l].triangles.push_back({soup.triangles[f][0] - first, soup.triangles[f][1] - first,
                                       soup.triangles[f][2] - first});
    }
    std::vector<const MeshArrays*> pointers;
    for (const MeshArrays& a : arrays) pointers.push_back(&a);
    FindIntersectionsOptions fo;
    fo.self = true;
    fo.cross = includesBetween(options.scope) && nl > 1;
    fo.layout = 1;  // Morton order: one pass of queries
    const FindIntersectionsResult found = findIntersectionsInArrays(pointers, fo);
    for (int l = 0; l < nl; ++l)
      if (found.self_pairs[l] > 0)
        throw TopologyError("layer " + std::to_string(l) + " intersects itself (" +
                            std::to_string(found.self_pairs[l]) +
                            " pairs of faces); a clearance can only be enforced between "
                            "surfaces that do not meet: run \"MeshMend: Remove "
                            "Self-Intersections\" on it first");
    for (const IntersectingPair& p : found.pairs)
      if (p.a.mesh != p.b.mesh)
        throw TopologyError("layers " + std::to_string(p.a.mesh) + " and " +
                            std::to_string(p.b.mesh) + " intersect (" +
                            std::to_string(found.cross_pairs) +
                            " pairs of faces between layers); a clearance can only be enforced "
                            "between surfaces that do not meet: run \"MeshMend: Intersect and "
                            "Split Layers\" and the patch filters (\"MeshMend: Remove Patches\") "
                            "first, or enforce the clearance within layers only");
    result.stage_ms.check = msSince(t0);
  }

  std::vector<char> locked(nv, 0);
  if (!options.locked.empty())
    for (int l = 0; l < nl; ++l)
      for (std::size_t i = 0; i < options.locked[l].size(); ++i)
        locked[soup.vertexOffset[l] + i] = options.locked[l][i] != 0;

  // Targets. Rounding to float moves each point by at most 2^-24 of its
  // largest coordinate in each axis, so two faces by twice √3 times that: the
  // solve aims beyond tau by four times this, and the result is checked again.
  double maxCoordinate = 0;
  for (const Point3& p : soup.points)
    for (int k = 0; k < 3; ++k) maxCoordinate = std::max(maxCoordinate, std::abs(p[k]));
  const double roundingMargin =
      options.round_to_float ? 8 * std::sqrt(3.0) * std::ldexp(maxCoordinate, -24) : 0;
  const double tauReached = tau * (1 + 1e-9) + roundingMargin;  // "done" for the solve
  const double tauGoal = tauReached + 1e-4 * tau;               // aimed at by each linearised step
  const double nearDist = tauGoal + options.active_margin * tau;  // active rows
  const double cap = options.max_displacement;

  std::vector<Point3>& P = soup.points;
  const std::vector<Point3> P0 = P;

  // The active face pairs: every pair in scope closer than nearDist.
  auto t0 = Clock::now();
  std::size_t candidates = 0;
  std::vector<NearPair> near = pairsWithin(soup, P, nearDist, &candidates);
  result.stage_ms.detect += msSince(t0);
  auto minimumOf = [&](const std::vector<NearPair>& pairs, double* minimum, std::size_t* below) {
    *minimum = kInf;
    *below = 0;
    for (const NearPair& p : pairs) {
      *minimum = std::min(*minimum, p.d);
      if (p.d < tau) ++*below;
    }
  };
  minimumOf(near, &result.min_distance_before, &result.violating_pairs_before);
  boundShortPairs(result.violating_pairs_before, options.max_short_pairs, tau,
                  result.min_distance_before);
  if (near.empty() && anyPairInScope(soup)) {
    // Nothing close: the minimum comes from a growing search.
    double used = 0;
    const std::vector<NearPair> far = pairsFromRadius(soup, P, 4 * nearDist, &used, &candidates);
    std::size_t none = 0;
    minimumOf(far, &result.min_distance_before, &none);
  }
  for (const NearPair& p : near) {
    if (!(p.d < tau)) continue;
    auto allLocked = [&](std::uint32_t f) {
      const Triangle& t = soup.triangles[f];
      return locked[t[0]] && locked[t[1]] && locked[t[2]];
    };
    const double need = allLocked(p.f) || allLocked(p.g) ? tau - p.d : (tau - p.d) / 2;
    result.displacement_lower_bound = std::max(result.displacement_lower_bound, need);
  }

  std::vector<char> capped(nv, 0);
  std::vector<Point3> step(nv, Point3(0, 0, 0));
  std::vector<Point3> trial = P;
  result.stop_reason = "reached";
  const int maxIterations = std::max(0, options.max_iterations);
  for (int iteration = 0;; ++iteration) {
    double smallest = kInf;
    for (const NearPair& p : near) smallest = std::min(smallest, p.d);
    if (smallest >= tauReached) break;
    if (iteration >= maxIterations) {
      result.stop_reason = "iterations";
      break;
    }
    reportProgress(options.progress, 5 + 90 * iteration / std::max(1, maxIterations), "Separating");
    t0 = Clock::now();

    // Rows: the elements of the active pairs closer than nearDist, once each.
    std::vector<Element> elements;
    for (const NearPair& p : near) elementsOf(soup, P, p.f, p.g, nearDist, elements);
    std::sort(elements.begin(), elements.end());
    elements.erase(std::unique(elements.begin(), elements.end()), elements.end());
    std::vector<Row> rows;
    rows.reserve(elements.size());
    std::vector<int> column(nv, -1);
    std::vector<int> columnVertex;
    bool anyShortMovable = false;
    for (const Element& e : elements) {
      Row row;
      if (!evaluate(P, e, row)) continue;
      bool movable = false;
      for (int v : e.v) movable |= !locked[v] && !capped[v];
      if (!movable) continue;  // only locked or capped vertices: nothing to solve for
      if (row.d < tauGoal) anyShortMovable = true;
      for (int v : e.v)
        if (!locked[v] && !capped[v] && column[v] < 0) {
          column[v] = int(columnVertex.size());
          columnVertex.push_back(v);
        }
      rows.push_back(row);
    }
    result.constraints_last = rows.size();
    if (!anyShortMovable) {
      result.stop_reason = "locked";
      break;
    }
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::VectorXd d(rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const Row& r = rows[k];
      d[k] = r.d;
      for (int i = 0; i < 4; ++i) {
        const int c = column[r.e.v[i]];
        if (c < 0) continue;
        for (int a = 0; a < 3; ++a)
          if (r.w[i] * r.n[a] != 0) entries.emplace_back(int(k), 3 * c + a, r.w[i] * r.n[a]);
      }
    }
    SparseRows J(int(rows.size()), int(3 * columnVertex.size()));
    J.setFromTriplets(entries.begin(), entries.end());
    const Eigen::VectorXd delta = minimumNormStep(J, d, tauGoal, 1e-6 * tau);

    // The step per vertex: within a trust radius of tau (conflicting rows can
    // ask for far more than any single pair needs), then within the cap.
    double largest = 0;
    for (std::size_t c = 0; c < columnVertex.size(); ++c)
      largest = std::max(largest, Point3(delta[3 * c], delta[3 * c + 1], delta[3 * c + 2]).Norm());
    const double scale = largest > tau ? tau / largest : 1.0;
    std::vector<int> movedVertices;
    for (std::size_t c = 0; c < columnVertex.size(); ++c) {
      const int v = columnVertex[c];
      Point3 s(delta[3 * c] * scale, delta[3 * c + 1] * scale, delta[3 * c + 2] * scale);
      if (cap > 0) {
        const Point3 total = P[v] - P0[v] + s;
        const double len = total.Norm();
        if (len > cap) s = total * (cap / len) - (P[v] - P0[v]);
      }
      if (s.Norm() == 0) continue;
      step[v] = s;
      movedVertices.push_back(v);
    }
    result.stage_ms.solve += msSince(t0);
    if (movedVertices.empty()) {
      result.stop_reason = "stalled";
      break;
    }

    // Pairs that the step can change: a moved face against any face its
    // swept box (grown by nearDist) reaches.
    t0 = Clock::now();
    std::vector<char> changed(nf, 0);
    std::vector<double> faceMotion(nf, 0);  // largest corner move of each face
    for (int v : movedVertices)
      for (int i = soup.starStart[v]; i < soup.starStart[v + 1]; ++i) {
        const int f = soup.star[i];
        changed[f] = 1;
        faceMotion[f] = std::max(faceMotion[f], step[v].Norm());
      }
    std::vector<Box> swept;
    for (std::size_t f = 0; f < nf; ++f) {
      if (!changed[f]) continue;
      const Triangle& t = soup.triangles[f];
      Box a = boxOf(P[t[0]], P[t[1]], P[t[2]]);
      const Box b = boxOf(P[t[0]] + step[t[0]], P[t[1]] + step[t[1]], P[t[2]] + step[t[2]]);
      for (int k = 0; k < 3; ++k) {
        a.lo[k] = std::min(a.lo[k], b.lo[k]);
        a.hi[k] = std::max(a.hi[k], b.hi[k]);
      }
      swept.push_back(inflated(a, nearDist));
    }
    std::vector<std::array<std::uint32_t, 2>> touched =
        pairsWithChangedBoxes(P, soup.triangles, changed, swept);
    touched.erase(std::remove_if(touched.begin(), touched.end(),
                                 [&](const std::array<std::uint32_t, 2>& p) {
                                   return !soup.checkedPair(p[0], p[1]);
                                 }),
                  touched.end());
    for (auto& p : touched)
      if (p[1] < p[0]) std::swap(p[0], p[1]);
    const std::size_t nt = touched.size();
    std::vector<char> shares(nt), counts(nt);
    std::vector<double> before(nt, kInf), after(nt, kInf);
    parallelChunks(
        nt,
        [&](std::size_t b, std::size_t e, unsigned) {
          for (std::size_t i = b; i < e; ++i) {
            const auto [f, g] = touched[i];
            shares[i] = soup.sharesVertex(f, g);
            counts[i] = soup.clearancePair(f, g);
            if (!shares[i]) before[i] = soup.distance(P, f, g);
          }
        },
        256);
    double meritBefore = 0;
    for (std::size_t i = 0; i < nt; ++i)
      if (counts[i] && before[i] < tauGoal)
        meritBefore += (tauGoal - before[i]) * (tauGoal - before[i]);

    // Backtracking: halve the step until it keeps every face pair apart all
    // along the way and lowers Σ (tauGoal - d)² over the pairs short of it.
    bool accepted = false;
    for (double alpha = 1; alpha >= 1.0 / 1024; alpha /= 2) {
      for (int v : movedVertices) trial[v] = P[v] + step[v] * alpha;
      std::atomic<bool> collides{false};
      parallelChunks(
          nt,
          [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t i = b; i < e && !collides.load(std::memory_order_relaxed); ++i) {
              const auto [f, g] = touched[i];
              if (shares[i]) {
                // Neighbours: exact test at the end of the step (a face
                // turned into a segment counts as a collision).
                for (std::uint32_t h : {f, g}) {
                  const Triangle& t = soup.triangles[h];
                  if (changed[h] && collinear(trial[t[0]], trial[t[1]], trial[t[2]]) &&
                      !collinear(P[t[0]], P[t[1]], P[t[2]]))
                    collides = true;
                }
                if (!collides && facesIntersect(trial, soup.triangles, f, g)) collides = true;
                continue;
              }
              // Conservative advancement: every point of a face moves at most
              // its largest corner move, so the pair cannot meet before
              // their distance has been used up by both faces' motion.
              const double motion = alpha * (faceMotion[f] + faceMotion[g]);
              double dist = before[i], t = 0;
              Point3 a[3], c[3];
              auto at = [&](double s) {
                for (int k = 0; k < 3; ++k) {
                  const int u = soup.triangles[f][k], w = soup.triangles[g][k];
                  a[k] = P[u] + step[u] * (alpha * s);
                  c[k] = P[w] + step[w] * (alpha * s);
                }
                return triangleDistance(a, c).distance;
              };
              bool safe = false;
              for (int round = 0; round < 200; ++round) {
                if (dist > motion * (1 - t)) {
                  safe = true;
                  break;
                }
                if (!(dist > 1e-14 * soup.diagonal)) break;
                t = std::min(1.0, t + 0.9 * dist / motion);
                dist = at(t);
                if (t == 1.0) {
                  safe = dist > 0;
                  break;
                }
              }
              if (!safe) {
                collides = true;
                continue;
              }
              // The distance is a float computation: below a thousandth of
              // tau, the exact test decides.
              after[i] = motion > 0 && t < 1.0 ? at(1.0) : dist;
              if (after[i] < 1e-3 * tau && facesIntersect(trial, soup.triangles, f, g))
                collides = true;
            }
          },
          256);
      double meritAfter = 0;
      if (!collides)
        for (std::size_t i = 0; i < nt; ++i)
          if (counts[i] && after[i] < tauGoal)
            meritAfter += (tauGoal - after[i]) * (tauGoal - after[i]);
      if (!collides && meritAfter < meritBefore) {
        accepted = true;
        break;
      }
      ++result.step_halvings;
    }
    if (!accepted) {
      for (int v : movedVertices) trial[v] = P[v];
      for (int v : movedVertices) step[v] = Point3(0, 0, 0);
      result.stop_reason = "stalled";
      result.stage_ms.line_search += msSince(t0);
      break;
    }
    for (int v : movedVertices) {
      P[v] = trial[v];
      step[v] = Point3(0, 0, 0);
      if (cap > 0 && (P[v] - P0[v]).Norm() >= cap * (1 - 1e-9)) capped[v] = 1;
    }
    // The active set again: pairs of unchanged faces keep their distance,
    // the others come from the touched pairs.
    near.erase(std::remove_if(near.begin(), near.end(),
                              [&](const NearPair& p) { return changed[p.f] || changed[p.g]; }),
               near.end());
    for (std::size_t i = 0; i < nt; ++i)
      if (counts[i] && after[i] < nearDist)
        near.push_back({touched[i][0], touched[i][1], after[i]});
    ++result.iterations;
    result.stage_ms.line_search += msSince(t0);
  }

  // Verification of the output as it will be stored: every pair with a face
  // that moved is measured again and tested exactly for intersection.
  t0 = Clock::now();
  std::vector<char> movedVertex(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) movedVertex[v] = !(P[v] == P0[v]);
  {
    // The output stage (output_stage.h): the moved vertices as the host
    // stores them, re-rounded where rounding would make a face around them
    // cross another (the input is as stored already).
    std::vector<char> aroundMoved(nf, 0);
    for (std::size_t f = 0; f < nf; ++f) {
      const Triangle& t = soup.triangles[f];
      aroundMoved[f] = movedVertex[t[0]] || movedVertex[t[1]] || movedVertex[t[2]];
    }
    OutputStageOptions stage;
    stage.scalar = options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
    result.stored = storeNewPoints(P, soup.triangles, movedVertex, aroundMoved, stage);
    result.rounded_to_float = options.round_to_float;
  }
  {
    std::vector<char> changed(nf, 0);
    std::vector<Box> boxes;
    for (std::size_t f = 0; f < nf; ++f) {
      const Triangle& t = soup.triangles[f];
      if (!(movedVertex[t[0]] || movedVertex[t[1]] || movedVertex[t[2]])) continue;
      changed[f] = 1;
      boxes.push_back(inflated(boxOf(P[t[0]], P[t[1]], P[t[2]]), nearDist));
    }
    std::vector<std::array<std::uint32_t, 2>> touched =
        pairsWithChangedBoxes(P, soup.triangles, changed, boxes);
    touched.erase(std::remove_if(touched.begin(), touched.end(),
                                 [&](const std::array<std::uint32_t, 2>& p) {
                                   return !soup.checkedPair(p[0], p[1]);
                                 }),
                  touched.end());
    result.new_intersecting_pairs = intersectingOf(P, soup.triangles, touched).size();
    near.erase(std::remove_if(near.begin(), near.end(),
                              [&](const NearPair& p) { return changed[p.f] || changed[p.g]; }),
               near.end());
    std::vector<double> dist(touched.size(), kInf);
    parallelChunks(
        touched.size(),
        [&](std::size_t b, std::size_t e, unsigned) {
          for (std::size_t i = b; i < e; ++i)
            if (soup.clearancePair(touched[i][0], touched[i][1]))
              dist[i] = soup.distance(P, touched[i][0], touched[i][1]);
        },
        256);
    for (std::size_t i = 0; i < touched.size(); ++i)
      if (dist[i] < nearDist)
        near.push_back({std::min(touched[i][0], touched[i][1]),
                        std::max(touched[i][0], touched[i][1]), dist[i]});
  }
  minimumOf(near, &result.min_distance_after, &result.violating_pairs_after);
  if (near.empty()) {
    if (anyPairInScope(soup)) {
      double used = 0;
      const std::vector<NearPair> far = pairsFromRadius(soup, P, 4 * nearDist, &used, &candidates);
      std::size_t none = 0;
      minimumOf(far, &result.min_distance_after, &none);
    }
  }
  result.reached = result.violating_pairs_after == 0 && result.new_intersecting_pairs == 0;
  if (result.reached) {
    result.stop_reason = "reached";
  } else if (result.stop_reason == "reached") {
    // Only rounding to float can get here.
    result.stop_reason = "rounding";
    result.warnings.push_back(
        "rounding to float left " + std::to_string(result.violating_pairs_after) +
        " pairs short of tau and " + std::to_string(result.new_intersecting_pairs) +
        " intersecting pairs");
  }
  result.short_pairs = listShortest(soup, P, near, tau, options.max_listed_pairs);
  if (!result.reached && result.stop_reason == "stalled")
    result.warnings.push_back("no step keeping the surfaces apart improved the " +
                              std::to_string(result.violating_pairs_after) +
                              " pairs still short: tau may be more than the shape allows "
                              "there (a part thinner than tau, faces a few rings apart), or "
                              "locked vertices and the cap hold them");
  if (!result.reached && result.stop_reason == "locked")
    result.warnings.push_back("the pairs still short have only locked or capped vertices");
  result.stage_ms.verify = msSince(t0);

  // Displacements, then the positions into the layers.
  double sum = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    const double len = (P[v] - P0[v]).Norm();
    if (len > 0) ++result.vertices_moved;
    sum += len;
    result.max_displacement = std::max(result.max_displacement, len);
    if (capped[v]) ++result.vertices_capped;
  }
  result.mean_displacement_all = nv ? sum / double(nv) : 0;
  result.mean_displacement_moved = result.vertices_moved ? sum / double(result.vertices_moved) : 0;
  // The last chance to cancel comes before the layers change.
  reportProgress(options.progress, 100, "Done");
  for (int l = 0; l < nl; ++l) {
    Mesh& mesh = *layers[l];
    for (int i = 0; i < soup.vertexOffset[l + 1] - soup.vertexOffset[l]; ++i)
      mesh.vert[i].P() = P[soup.vertexOffset[l] + i];
  }
  result.time_ms = msSince(start);
  return result;
}

// ---- reports ------------------------------------------------------------------------

namespace {

JsonObject toJson(const ClearancePair& p) {
  return JsonObject()
      .set("layer_a", p.layer_a)
      .set("face_a", p.face_a)
      .set("layer_b", p.layer_b)
      .set("face_b", p.face_b)
      .set("kind", p.kind)
      .set("distance", p.distance)
      .set("point_a", std::vector<double>{p.point_a[0], p.point_a[1], p.point_a[2]})
      .set("point_b", std::vector<double>{p.point_b[0], p.point_b[1], p.point_b[2]});
}

std::vector<JsonObject> toJson(const std::vector<ClearancePair>& pairs) {
  std::vector<JsonObject> out;
  for (const ClearancePair& p : pairs) out.push_back(toJson(p));
  return out;
}

}  // namespace

JsonObject toJson(const ClearanceMeasure& m) {
  JsonObject j;
  const std::optional<double> minimum =
      m.found ? std::optional<double>(m.min_distance) : std::nullopt;
  std::vector<double> histogram(m.histogram.begin(), m.histogram.end());
  j.set("tau", m.tau)
      .set("min_distance", minimum)
      .set("min_distance_before", minimum)
      .set("min_distance_after", minimum)
      .set("violating_pairs", m.violating_pairs)
      .set("violating_pairs_before", m.violating_pairs)
      .set("violating_pairs_after", m.violating_pairs)
      .set("faces_below_tau", m.faces_below_tau_count)
      .set("max_displacement", 0.0)
      .set("mean_displacement", 0.0)
      .set("local_max", m.local_max)
      .set("histogram", histogram)
      .set("candidate_pairs", m.candidate_pairs);
  if (m.found) j.set("closest", toJson(m.closest));
  j.set("shortest", toJson(m.shortest)).set("time_ms", m.time_ms);
  return j;
}

JsonObject toJson(const ClearanceResult& r) {
  auto finite = [](double x) { return std::isfinite(x) ? std::optional<double>(x) : std::nullopt; };
  JsonObject j;
  j.set("tau", r.tau)
      .set("reached", r.reached)
      .set("stop_reason", r.stop_reason)
      .set("min_distance_before", finite(r.min_distance_before))
      .set("min_distance_after", finite(r.min_distance_after))
      .set("violating_pairs_before", r.violating_pairs_before)
      .set("violating_pairs_after", r.violating_pairs_after)
      .set("max_displacement", r.max_displacement)
      .set("mean_displacement", r.mean_displacement_moved)
      .set("mean_displacement_moved", r.mean_displacement_moved)
      .set("mean_displacement_all", r.mean_displacement_all)
      .set("vertices_moved", r.vertices_moved)
      .set("displacement_lower_bound", r.displacement_lower_bound)
      .set("vertices_capped", r.vertices_capped)
      .set("iterations", r.iterations)
      .set("step_halvings", r.step_halvings)
      .set("constraints_last", r.constraints_last)
      .set("new_intersecting_pairs", r.new_intersecting_pairs)
      .set("rounded_to_float", r.rounded_to_float)
      .set("short_pairs", toJson(r.short_pairs))
      .set("warnings", r.warnings)
      .set("time_ms", r.time_ms);
  const auto& t = r.stage_ms;
  j.set("stage_ms", JsonObject()
                        .set("check", t.check)
                        .set("detect", t.detect)
                        .set("solve", t.solve)
                        .set("line_search", t.line_search)
                        .set("verify", t.verify));
  return j;
}

}  // namespace meshmend
