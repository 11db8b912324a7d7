// Stitching two border paths (Widing & Ekeberg 2015, §2.2): the
// merge-like triangulation that takes the shorter of the two next
// diagonals, subdivided into rows where the gap is wide, planned before the
// mesh changes, checked exactly for new intersections, then applied.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <future>
#include <memory>
#include <numeric>
#include <queue>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "common/base/border_loops.h"
#include "common/base/errors.h"
#include "common/exact/box_tree.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"
#include "common/repair/stitch/detail.h"

namespace meshmend {

using namespace stitch_detail;

namespace {

// The square of the aspect ratio, longest edge over shortest altitude
// (infinite for a degenerate triangle): no root per face, one for the largest.
double squaredAspectRatio(const Point3& a, const Point3& b, const Point3& c) {
  const double l = std::max({(b - a).SquaredNorm(), (c - b).SquaredNorm(), (a - c).SquaredNorm()});
  const double area2 = ((b - a) ^ (c - a)).SquaredNorm();
  return area2 > 0 ? l * l / area2 : INFINITY;
}

// Arc-length parametrised polyline (the rows of a subdivided strip).
class Polyline {
 public:
  explicit Polyline(std::vector<Point3> points) : p_(std::move(points)), s_(p_.size(), 0) {
    for (std::size_t i = 1; i < p_.size(); ++i) s_[i] = s_[i - 1] + (p_[i] - p_[i - 1]).Norm();
  }
  double length() const { return s_.back(); }
  // The point at arc length s (clamped; NaN, as 0 x an infinite length
  // gives, is the start).
  Point3 at(double s) const {
    if (p_.size() == 1 || !(s > 0)) return p_.front();
    if (s >= s_.back()) return p_.back();
    const std::size_t i = std::upper_bound(s_.begin(), s_.end(), s) - s_.begin() - 1;
    const double span = s_[i + 1] - s_[i];
    const double t = span > 0 ? (s - s_[i]) / span : 0;
    return p_[i] * (1 - t) + p_[i + 1] * t;
  }

 private:
  std::vector<Point3> p_;
  std::vector<double> s_;
};

// A path of mesh vertices (closed: back to its first vertex) as an
// arc-length parametrised polyline, its points read from the mesh.
class PathLine {
 public:
  PathLine(const Mesh& mesh, const std::vector<int>& path, bool closed)
      : mesh_(mesh), path_(path), s_(path.size() + (closed ? 1 : 0), 0) {
    for (std::size_t i = 1; i < s_.size(); ++i)
      s_[i] = s_[i - 1] + (point(i) - point(i - 1)).Norm();
  }
  double length() const { return s_.back(); }
  // The point at arc length s (clamped; NaN, as 0 x an infinite length
  // gives, is the start: past the search it read beyond the arrays).
  Point3 at(double s) const {
    if (s_.size() == 1 || !(s > 0)) return point(0);
    if (s >= s_.back()) return point(s_.size() - 1);
    const std::size_t i = std::upper_bound(s_.begin(), s_.end(), s) - s_.begin() - 1;
    const double span = s_[i + 1] - s_[i];
    const double t = span > 0 ? (s - s_[i]) / span : 0;
    return point(i) * (1 - t) + point(i + 1) * t;
  }

 private:
  Point3 point(std::size_t i) const {  // i == path_.size(): back at the first vertex
    return mesh_.vert[path_[i < path_.size() ? i : 0]].cP();
  }
  const Mesh& mesh_;
  const std::vector<int>& path_;
  std::vector<double> s_;
};

// Sum of distances between points at the same arc-length fraction (of b
// run backwards when reversedB): small when the two paths run side by side
// in the same direction. A closed path run backwards from its first vertex
// is its forward run reversed, so one parametrisation serves both ways.
double correspondenceCost(const PathLine& a, const PathLine& b, bool reversedB) {
  constexpr int kSamples = 32;
  double cost = 0;
  for (int k = 0; k <= kSamples; ++k) {
    const double t = double(k) / kSamples;
    cost += (a.at(t * a.length()) - b.at((reversedB ? 1 - t : t) * b.length())).Norm();
  }
  return cost;
}

// The merge-like triangulation (§2.2) of the strip between lists a and b
// (indices into `points`), from rung (a[0], b[0]) to (a.back(), b.back()):
// each step advances along the list whose next diagonal is shorter, any
// number of steps along one list. A step that would make a triangle with
// exactly collinear corners takes the other list when it can, and so does a
// step whose triangle would fold back over the face on its path edge
// (valid(false, i, x): x lies beyond edge a[i]-a[i+1], away from that face;
// valid(true, j, x): beyond edge b[j]-b[j+1]). Faces are
// `forward` = (a[i], a[i+1], b[j]) and (b[j], a[i], b[j+1]), else reversed.
// Returns, per step, whether it advanced along a; raises maxSquaredAspect to
// the faces' squared aspect ratios (their corners are at hand).
template <class PointOf, class Valid>
std::vector<char> zipper(const std::vector<int>& a, const std::vector<int>& b, PointOf&& point,
                         Valid&& valid, bool forward, std::vector<Triangle>& faces,
                         double& maxSquaredAspect) {
  std::vector<char> steps;
  steps.reserve(a.size() + b.size());
  faces.reserve(faces.size() + a.size() + b.size());
  std::size_t i = 0, j = 0;
  while (i + 1 < a.size() || j + 1 < b.size()) {
    bool alongA;
    if (i + 1 == a.size()) {
      alongA = false;
    } else if (j + 1 == b.size()) {
      alongA = true;
    } else {
      const Point3 &ai = point(a[i]), &ai1 = point(a[i + 1]), &bj = point(b[j]),
                   &bj1 = point(b[j + 1]);
      alongA = (ai1 - bj).SquaredNorm() <= (ai - bj1).SquaredNorm();
      const bool validA = valid(false, i, b[j]), validB = valid(true, j, a[i]);
      if (validA != validB) alongA = validA;
      const bool flat = alongA ? collinear(ai, ai1, bj) : collinear(bj, ai, bj1);
      if (flat && !(alongA ? collinear(bj, ai, bj1) : collinear(ai, ai1, bj))) alongA = !alongA;
    }
    if (alongA) {
      faces.push_back(forward ? Triangle{a[i], a[i + 1], b[j]} : Triangle{a[i + 1], a[i], b[j]});
      maxSquaredAspect =
          std::max(maxSquaredAspect, squaredAspectRatio(point(a[i]), point(a[i + 1]), point(b[j])));
      ++i;
    } else {
      faces.push_back(forward ? Triangle{b[j], a[i], b[j + 1]} : Triangle{a[i], b[j], b[j + 1]});
      maxSquaredAspect =
          std::max(maxSquaredAspect, squaredAspectRatio(point(b[j]), point(a[i]), point(b[j + 1])));
      ++j;
    }
    steps.push_back(alongA);
  }
  return steps;
}

struct PreparedPath {
  std::vector<int> v;
  bool closed = false;
  int sign = 0;  // +1: the path runs along its border edges' direction, -1 against, 0 unknown
  std::size_t against = 0;  // border edges against the majority
};

PreparedPath preparePath(const Mesh& mesh, const BorderPath& path, const char* name) {
  PreparedPath p;
  p.v = path.vertices;
  const std::string what = std::string("path ") + name;
  for (int v : p.v)
    if (v < 0 || std::size_t(v) >= mesh.vert.size()) requireVertex(mesh, v, what);
  bool repeated = false;
  if (p.v.size() > 2 && p.v.front() == p.v.back()) {
    p.v.pop_back();
    repeated = true;
  }
  if (p.v.size() < 2 && !(p.v.size() == 1 && path.shape != BorderPath::Shape::Closed))
    throw InvalidInputError(what + " has fewer than two vertices");
  p.closed = path.shape == BorderPath::Shape::Closed ||
             (path.shape == BorderPath::Shape::Auto && repeated);
  if (path.shape == BorderPath::Shape::Closed && p.v.size() < 3)
    throw InvalidInputError(what + " is a closed loop of fewer than three vertices");
  return p;
}

// Marks the path's vertices with `bit` in `on`, and refuses a repeated one.
void checkDistinct(const Mesh& mesh, const PreparedPath& p, std::vector<char>& on, char bit,
                   const char* name) {
  for (int v : p.v) {
    if (on[v] & bit)
      throw InvalidInputError(describeVertex(mesh, v) + " appears twice in path " + name);
    on[v] |= bit;
  }
}

// Direction of a path relative to its border edges, by majority.
void orientPath(PreparedPath& p, const LocalEdges& edges) {
  long along = 0, against = 0;
  const std::size_t count = p.closed ? p.v.size() : p.v.size() - 1;
  for (std::size_t k = 0; k < count; ++k) {
    const LocalEdges::Neighbour e = edges.find(p.v[k], p.v[k + 1 < p.v.size() ? k + 1 : 0]);
    if (e.out + e.in != 1) continue;
    (e.out ? along : against)++;
  }
  p.sign = along > against ? 1 : against > along ? -1 : 0;
  p.against = std::size_t(std::min(along, against));
}

template <class T>
void rotate(std::vector<T>& v, std::size_t first) {
  std::rotate(v.begin(), v.begin() + first, v.end());
}

// Every path vertex must be on a border edge. Most are on a border edge of
// their path; the others are checked against all their edges.
void requireOnBorders(const Mesh& mesh, const PreparedPath& A, const PreparedPath& B,
                      const LocalEdges& edges) {
  std::vector<int> unsure;
  for (const PreparedPath* p : {&A, &B})
    for (int v : p->v)
      if (!edges.onBorder(v)) unsure.push_back(v);
  if (unsure.empty()) return;
  const LocalEdges full(mesh, unsure);
  for (const PreparedPath* p : {&A, &B})
    for (int v : p->v)
      if (!edges.onBorder(v) && !full.onBorder(v))
        throw InvalidInputError(describeVertex(mesh, v) + " of path " + (p == &A ? "a" : "b") +
                                " is not on a border edge: stitch paths must follow borders");
}

// Both paths open or both closed (an Auto path whose ends share a border
// edge goes all around); shared vertices only at the ends of open paths
// (a crack closing at a point); each path oriented along its border.
void settleShapes(const Mesh& mesh, const StitchOptions& o, PreparedPath& A, PreparedPath& B,
                  const LocalEdges& edges, const std::vector<char>& on, char onA) {
  for (auto [p, path] : {std::make_pair(&A, &o.a), std::make_pair(&B, &o.b)})
    if (path->shape == BorderPath::Shape::Auto && !p->closed && p->v.size() >= 3 &&
        edges.uses(p->v.front(), p->v.back()) == 1)
      p->closed = true;
  if (A.closed != B.closed)
    throw InvalidInputError(
        "one path is a closed loop and the other is open: stitch a loop to a loop, or give two "
        "open paths");
  for (std::size_t k = 0; k < B.v.size(); ++k)
    if (on[B.v[k]] & onA) {
      const bool endOfB = k == 0 || k + 1 == B.v.size();
      const bool endOfA = B.v[k] == A.v.front() || B.v[k] == A.v.back();
      if (A.closed || !endOfA || !endOfB)
        throw InvalidInputError(describeVertex(mesh, B.v[k]) +
                                " is on both paths (only open paths may share an end)");
    }
  orientPath(A, edges);
  orientPath(B, edges);
}

// Closed loops start at their nearest pair of vertices (nearest to a
// sample of a's vertices: linear, and good enough to start the zipper).
void startAtNearestPair(const Mesh& mesh, PreparedPath& A, PreparedPath& B) {
  const std::size_t samples = std::min<std::size_t>(A.v.size(), 32);
  double best = INFINITY;
  std::size_t bi = 0, bj = 0;
  for (std::size_t s = 0; s < samples; ++s) {
    const std::size_t i = s * A.v.size() / samples;
    const Point3& p = mesh.vert[A.v[i]].cP();
    for (std::size_t j = 0; j < B.v.size(); ++j) {
      const double d = (mesh.vert[B.v[j]].cP() - p).SquaredNorm();
      if (d < best) best = d, bi = i, bj = j;
    }
  }
  rotate(A.v, bi);
  rotate(B.v, bj);
}

// Which way b runs beside a: by geometry, and by orientation (a side that
// runs along its border must meet one that runs against it). Reverses b
// when it runs the other way; returns whether the new faces run forward
// (against a[i] -> a[i+1] and along b[j+1] -> b[j]: right when a runs
// against its border and b along its own).
bool chooseDirection(const Mesh& mesh, const StitchOptions& o, PreparedPath& A, PreparedPath& B,
                     StitchPlan& plan) {
  const PathLine lineA(mesh, A.v, A.closed), lineB(mesh, B.v, B.closed);
  const double costSame = correspondenceCost(lineA, lineB, false);
  const double costReversed = correspondenceCost(lineA, lineB, true);
  const bool geometrySame = costSame <= costReversed;
  bool same = geometrySame;
  if (A.sign != 0 && B.sign != 0) {
    const bool orientationSame = A.sign == -B.sign;
    const double chosen = orientationSame ? costSame : costReversed;
    const double other = orientationSame ? costReversed : costSame;
    if (orientationSame != geometrySame && chosen > 2 * other) {
      if (!o.allow_orientation_conflict)
        throw TopologyError(
            "the two sides are oppositely oriented: following the borders' directions would "
            "twist the stitch across the gap (path a runs " +
            std::string(A.sign > 0 ? "along" : "against") + " its border, path b " +
            (B.sign > 0 ? "along" : "against") +
            " its own, side by side); invert the faces of one side first");
      plan.conflicts += B.v.size();
    } else {
      same = orientationSame;
    }
  }
  plan.reversedB = !same;
  if (!same) {
    std::reverse(B.v.begin() + (B.closed ? 1 : 0), B.v.end());
    B.sign = -B.sign;
  }
  plan.conflicts += A.against + B.against;
  return A.sign != 0 ? A.sign < 0 : B.sign != 0 ? B.sign > 0 : true;
}

// Every edge of a path gets one new face: it must be a border edge run the
// other way, or no edge yet. Returns per edge the third corner of the face
// on it (-1: no face), for the zipper's fold test.
std::vector<int> checkPathEdges(const Mesh& mesh, const LocalEdges& edges, const StitchOptions& o,
                                const std::vector<int>& p, bool newFaceRunsForward,
                                const char* name, StitchPlan& plan) {
  std::vector<int> opposite(p.size() > 1 ? p.size() - 1 : 0, -1);
  for (std::size_t k = 0; k + 1 < p.size(); ++k) {
    const LocalEdges::Neighbour e = edges.find(p[k], p[k + 1]);
    const int used = e.out + e.in;
    if (used == 0) {
      ++plan.borderDelta;
    } else if (used == 1) {
      opposite[k] = e.opposite;
      const bool existingForward = e.out == 1;
      if (existingForward == newFaceRunsForward && !o.allow_orientation_conflict)
        throw TopologyError("the border along path " + std::string(name) +
                            " changes direction between " + describeVertex(mesh, p[k]) + " and " +
                            describeVertex(mesh, p[k + 1]) +
                            ": the faces there are inconsistently oriented");
      --plan.borderDelta;
    } else {
      throw TopologyError("the edge from " + describeVertex(mesh, p[k]) + " to " +
                          describeVertex(mesh, p[k + 1]) + " on path " + name +
                          " already has two faces: the path leaves the border there");
    }
  }
  return opposite;
}

// The zipper between the rows a and b of existing vertices: a new face may
// not fold over the face already on a path edge, so a vertex must lie
// beyond edge k of path a (onB: of path b), on the other side of it than
// the face there, measured in that face's plane (any point is beyond an
// edge with no face). The zipper asks about one edge of each path until it
// moves past it: the edge's frame is kept for the next question.
std::vector<char> zipExisting(const Mesh& mesh, const std::vector<int>& a,
                              const std::vector<int>& b, const std::vector<int>& oppositeA,
                              const std::vector<int>& oppositeB, bool forward, StitchPlan& plan,
                              double& maxSquaredAspect) {
  auto existingPoint = [&](int v) -> Point3 { return mesh.vert[v].cP(); };
  struct EdgeFrame {
    std::size_t k = SIZE_MAX;
    Point3 P, d, normal;
  } frames[2];
  auto beyond = [&](bool onB, std::size_t k, int x) {
    const int opposite = (onB ? oppositeB : oppositeA)[k];
    if (opposite < 0) return true;
    EdgeFrame& f = frames[onB];
    if (f.k != k) {
      const std::vector<int>& p = onB ? b : a;
      f.k = k;
      f.P = existingPoint(p[k]);
      f.d = existingPoint(p[k + 1]) - f.P;
      f.normal = f.d ^ (existingPoint(opposite) - f.P);
    }
    return ((f.d ^ (existingPoint(x) - f.P)) * f.normal) < 0;
  };
  return zipper(a, b, existingPoint, beyond, forward, plan.faces, maxSquaredAspect);
}

// Rungs: an end rung may close an existing border edge; an inner rung gets
// two new faces, so it must not exist yet.
void checkRungs(const Mesh& mesh, const LocalEdges& edges, bool closed, const std::vector<int>& a,
                const std::vector<int>& b, const std::vector<char>& steps, bool forward,
                StitchPlan& plan) {
  std::size_t i = 0, j = 0;
  for (std::size_t s = 0; s <= steps.size(); ++s) {
    const bool end = !closed && (s == 0 || s == steps.size());
    const LocalEdges::Neighbour e =
        a[i] != b[j] ? edges.find(a[i], b[j]) : LocalEdges::Neighbour{b[j], -1, 0, 0};
    const int used = e.out + e.in;
    if (end) {
      // The first face runs b[0] -> a[0] (forward), the last a -> b.
      const bool newRunsAToB = (s == 0) != forward;
      if (used == 0) {
        ++plan.borderDelta;
      } else if (used == 1 && (e.out == 1) != newRunsAToB) {
        --plan.borderDelta;
      } else {
        throw TopologyError("the stitch would add a face to the edge from " +
                            describeVertex(mesh, a[i]) + " to " + describeVertex(mesh, b[j]) +
                            ", which " +
                            (used == 1 ? "runs the same way" : "already has two faces"));
      }
    } else if (used > 0) {
      throw TopologyError("the stitch would add two faces to the existing edge from " +
                          describeVertex(mesh, a[i]) + " to " + describeVertex(mesh, b[j]) +
                          ": the paths touch there; stitch shorter paths");
    }
    if (s < steps.size()) (steps[s] ? i : j)++;
  }
}

// Subdivision: rows of new vertices across a wide strip, one row count for
// the whole strip: enough for the widest rung, but never so many that rows
// crowd closer than h / max_aspect_ratio where the gap is narrowest (that
// would trade long slivers for flat ones).
void subdivide(const Mesh& mesh, const LocalEdges& edges, const StitchOptions& o, bool closed,
               const std::vector<int>& a, const std::vector<int>& b, const std::vector<char>& steps,
               bool forward, StitchPlan& plan, double& maxSquaredAspect) {
  const int n = int(mesh.vert.size());
  auto existingPoint = [&](int v) -> Point3 { return mesh.vert[v].cP(); };
  auto meanEdge = [&](const std::vector<int>& p) {
    double sum = 0;
    for (std::size_t k = 0; k + 1 < p.size(); ++k)
      sum += (existingPoint(p[k + 1]) - existingPoint(p[k])).Norm();
    return p.size() > 1 ? sum / double(p.size() - 1) : 0.0;
  };
  const double ha = meanEdge(a), hb = meanEdge(b.size() > 1 ? b : a);
  const double h = 0.5 * (ha + hb);
  std::vector<std::array<int, 2>> rungs{{a[0], b[0]}};
  std::size_t i = 0, j = 0;
  for (char s : steps) {
    (s ? i : j)++;
    rungs.push_back({a[i], b[j]});
  }
  double longest = 0, shortest = INFINITY;
  for (const auto& r : rungs) {
    const double l = (existingPoint(r[0]) - existingPoint(r[1])).Norm();
    longest = std::max(longest, l);
    shortest = std::min(shortest, l);
  }
  int strips = 1;
  if (h > 0) {
    strips = int(std::ceil(longest / (o.max_aspect_ratio * h)));
    strips = std::min(strips, int(std::floor(shortest * o.max_aspect_ratio / h)));
    strips = std::max(1, std::min(strips, o.max_rows + 1));
  }
  if (strips <= 1) return;
  plan.faces.clear();
  maxSquaredAspect = 0;
  std::vector<std::vector<int>> rows{a};
  for (int k = 1; k < strips; ++k) {
    const double t = double(k) / strips;
    std::vector<Point3> curve;
    for (const auto& r : rungs)
      curve.push_back(existingPoint(r[0]) * (1 - t) + existingPoint(r[1]) * t);
    const Polyline line(curve);
    const double spacing = (1 - t) * ha + t * hb;
    const int segments = std::max(1, int(std::lround(line.length() / std::max(spacing, 1e-300))));
    std::vector<int> row;
    for (int s = 0; s <= segments; ++s) {
      if (closed && s == segments) {
        row.push_back(row.front());
        break;
      }
      row.push_back(n + int(plan.newPoints.size()));
      plan.newPoints.push_back(line.at(line.length() * s / segments));
    }
    rows.push_back(row);
  }
  rows.push_back(b);
  auto anyPoint = [&](int v) -> Point3 {
    return v < n ? mesh.vert[v].cP() : plan.newPoints[v - n];
  };
  // One of the two rows of every strip is new vertices: the fold test,
  // made between an existing edge and an existing vertex, never applies.
  auto anyIsValid = [](bool, std::size_t, int) { return true; };
  for (std::size_t k = 0; k + 1 < rows.size(); ++k)
    zipper(rows[k], rows[k + 1], anyPoint, anyIsValid, forward, plan.faces, maxSquaredAspect);
  // End rungs are now chains of strips edges (new border edges).
  if (closed) return;
  if (edges.uses(a.front(), b.front()) == 1 || edges.uses(a.back(), b.back()) == 1)
    throw TopologyError(
        "a wide stitch cannot be subdivided where its end rung is an existing edge");
  plan.borderDelta += 2 * (strips - 1);
}

}  // namespace

namespace stitch_detail {

// topologyRead is called once the mesh's faces are no longer read (from
// then on the plan reads the path vertices' coordinates and what it
// gathered).
StitchPlan planStitch(const Mesh& mesh, const StitchOptions& o,
                      const std::function<void()>& topologyRead) {
  StitchPlan plan;
  PreparedPath A = preparePath(mesh, o.a, "a"), B = preparePath(mesh, o.b, "b");
  constexpr char kOnA = 1, kOnB = 2;
  std::vector<char> on(mesh.vert.size(), 0);
  checkDistinct(mesh, A, on, kOnA, "a");
  checkDistinct(mesh, B, on, kOnB, "b");
  std::vector<int> all = A.v;
  all.insert(all.end(), B.v.begin(), B.v.end());
  const LocalEdges edges(mesh, all, true);
  requireOnBorders(mesh, A, B, edges);
  if (topologyRead) topologyRead();
  settleShapes(mesh, o, A, B, edges, on, kOnA);
  plan.closed = A.closed;
  if (A.closed) startAtNearestPair(mesh, A, B);
  const bool forward = chooseDirection(mesh, o, A, B, plan);

  std::vector<int> a = A.v, b = B.v;
  if (A.closed) {
    a.push_back(a.front());
    b.push_back(b.front());
  } else {
    if (b.front() == a.front()) b.erase(b.begin());
    if (!b.empty() && b.back() == a.back()) b.pop_back();
    if (b.empty()) throw InvalidInputError("path b has no vertex that path a does not share");
  }
  const std::vector<int> oppositeA = checkPathEdges(mesh, edges, o, a, forward, "a", plan);
  const std::vector<int> oppositeB = checkPathEdges(mesh, edges, o, b, !forward, "b", plan);
  double maxSquaredAspect = 0;
  const std::vector<char> steps =
      zipExisting(mesh, a, b, oppositeA, oppositeB, forward, plan, maxSquaredAspect);
  checkRungs(mesh, edges, A.closed, a, b, steps, forward, plan);
  if (!A.closed) {
    plan.firstRung = {a.front(), b.front()};
    plan.lastRung = {a.back(), b.back()};
  }
  if (o.max_aspect_ratio > 0)
    subdivide(mesh, edges, o, A.closed, a, b, steps, forward, plan, maxSquaredAspect);
  plan.maxAspect = std::sqrt(maxSquaredAspect);
  return plan;
}

}  // namespace stitch_detail

namespace stitch_detail {

// Exact count of the intersecting pairs that involve a planned face. Only
// the faces near the gap are looked at: the planned faces' boxes go into a
// tree, every face of the mesh whose box meets the tree's bounds is looked
// up in it, and the pairs found are decided on a small copy of the faces
// concerned.
std::size_t newIntersections(const Mesh& mesh, const StitchPlan& plan) {
  if (plan.faces.empty()) return 0;
  const int n = int(mesh.vert.size());
  const Vertex* base = mesh.vert.data();
  auto point = [&](int v) -> Point3 { return v < n ? mesh.vert[v].cP() : plan.newPoints[v - n]; };
  std::vector<Box> boxes;
  boxes.reserve(plan.faces.size());
  for (const Triangle& t : plan.faces)
    boxes.push_back(boxOf(point(t[0]), point(t[1]), point(t[2])));
  const BoxTree tree(boxes);
  const Box bounds = tree.bounds();
  // Mesh faces whose boxes overlap a planned face's: (planned, mesh face).
  std::vector<std::vector<std::array<std::uint32_t, 2>>> found(workerCount());
  parallelChunks(mesh.face.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
    for (std::size_t g = begin; g < end; ++g) {
      const Face& f = mesh.face[g];
      const Box b = boxOf(f.cV(0)->cP(), f.cV(1)->cP(), f.cV(2)->cP());
      if (!overlap(b, bounds)) continue;
      tree.query(b, worker, [&](std::uint32_t i, unsigned) {
        found[worker].push_back({i, std::uint32_t(g)});
      });
    }
  });
  // The faces concerned, renumbered: the planned ones first.
  std::vector<Point3> P;
  std::vector<Triangle> T;
  std::vector<int> localVertex(n + plan.newPoints.size(), -1);
  auto local = [&](int v) {
    if (localVertex[v] < 0) {
      localVertex[v] = int(P.size());
      P.push_back(point(v));
    }
    return localVertex[v];
  };
  T.reserve(plan.faces.size());
  for (const Triangle& t : plan.faces) T.push_back({local(t[0]), local(t[1]), local(t[2])});
  std::vector<std::uint32_t> localFace(mesh.face.size(), 0);  // 0: not copied yet
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (const auto& list : found)
    for (const auto& [i, g] : list) {
      if (localFace[g] == 0) {
        const Face& f = mesh.face[g];
        localFace[g] = std::uint32_t(T.size());
        T.push_back(
            {local(int(f.cV(0) - base)), local(int(f.cV(1) - base)), local(int(f.cV(2) - base))});
      }
      pairs.push_back({i, localFace[g]});
    }
  // Planned faces among themselves (their local indices are their own).
  for (auto& list : found) list.clear();
  tree.selfPairs([&](std::uint32_t i, std::uint32_t j, unsigned worker) {
    found[worker].push_back({i, j});
  });
  for (const auto& list : found) pairs.insert(pairs.end(), list.begin(), list.end());
  return intersectingOf(P, T, pairs).size();
}

}  // namespace stitch_detail

namespace stitch_detail {

void applyPlan(Mesh& mesh, const StitchPlan& plan, StitchResult& r) {
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);
  const int layer = mesh.vert.empty() ? 0 : std::max(0, vo[0].layer);
  const std::size_t n = mesh.vert.size(), m = mesh.face.size();
  if (!plan.newPoints.empty()) {
    auto vi = vcg::tri::Allocator<Mesh>::AddVertices(mesh, plan.newPoints.size());
    for (std::size_t k = 0; k < plan.newPoints.size(); ++k, ++vi) {
      vi->P() = plan.newPoints[k];
      vo[n + k] = VertexOrigin{layer, -1, -1, {0, 0, 0}};
      r.new_vertices.push_back(int(n + k));
    }
  }
  r.new_faces.reserve(plan.faces.size());
  if (!plan.faces.empty()) {
    auto fi = vcg::tri::Allocator<Mesh>::AddFaces(mesh, plan.faces.size());
    for (std::size_t k = 0; k < plan.faces.size(); ++k, ++fi) {
      for (int c = 0; c < 3; ++c) fi->V(c) = &mesh.vert[plan.faces[k][c]];
      fo[m + k] = FaceOrigin{layer, -1};
      r.new_faces.push_back(int(m + k));
    }
  }
  r.faces_added = plan.faces.size();
  r.vertices_added = plan.newPoints.size();
  r.closed = plan.closed;
  r.reversed_b = plan.reversedB;
  r.orientation_conflicts = plan.conflicts;
  r.first_rung = plan.firstRung;
  r.last_rung = plan.lastRung;
  r.max_aspect_ratio = plan.maxAspect;
}

}  // namespace stitch_detail

namespace {

// Border edges (edges used by exactly one face) counted in two passes over
// the faces: tally() for every face, which lets a caller count while it
// reads the faces for its own purpose, then count(). Each edge's other end
// is listed at its smaller end (a counting sort: the tallies size the
// lists). While placing, the few ends already listed at that vertex are
// searched: an end listed once is turned into its complement (a second
// use), and a third use changes nothing. The count follows as the edges are
// placed: no sort, no pass over the lists.
class BorderEdgeCounter {
 public:
  explicit BorderEdgeCounter(const Mesh& mesh)
      : mesh_(mesh), base_(mesh.vert.data()), fill_(mesh.vert.size() + 1, 0) {}

  void tally(const Face& f) {
    const std::array<int, 3> c = cornersOf(f);
    ++fill_[std::min(c[0], c[1]) + 1];
    ++fill_[std::min(c[1], c[2]) + 1];
    ++fill_[std::min(c[2], c[0]) + 1];
  }

  std::size_t count() {
    // fill_[v]: where v's list starts, then where its next end goes.
    const std::size_t n = mesh_.vert.size();
    for (std::size_t v = 0; v < n; ++v) fill_[v + 1] += fill_[v];
    const std::vector<int> start(fill_.begin(), fill_.end() - 1);
    const std::unique_ptr<int[]> other(new int[std::size_t(fill_[n])]);  // written before read
    std::size_t border = 0;
    auto place = [&](int a, int b) {
      const int low = std::min(a, b), high = std::max(a, b);  // ~high < 0 <= high
      int* const first = other.get() + start[low];
      int* const last = other.get() + fill_[low];
      for (int* e = first; e != last; ++e) {
        if (*e == high) {  // the second use: no longer a border edge
          *e = ~high;
          --border;
          return;
        }
        if (*e == ~high) return;  // a third or later use
      }
      *last = high;
      ++fill_[low];
      ++border;
    };
    for (const Face& f : mesh_.face) {
      const std::array<int, 3> c = cornersOf(f);
      place(c[0], c[1]);
      place(c[1], c[2]);
      place(c[2], c[0]);
    }
    return border;
  }

 private:
  std::array<int, 3> cornersOf(const Face& f) const {
    return {int(f.cV(0) - base_), int(f.cV(1) - base_), int(f.cV(2) - base_)};
  }
  const Mesh& mesh_;
  const Vertex* base_;
  std::vector<int> fill_;
};

}  // namespace

std::size_t countBorderEdges(const Mesh& mesh) {
  BorderEdgeCounter counter(mesh);
  for (const Face& f : mesh.face) counter.tally(f);
  return counter.count();
}

namespace stitch_detail {

// The output stage (output_stage.h) on `mesh` once an operation added the
// vertices from `firstNew` on and changed the faces marked `changed` (new
// faces beyond its size): the positions as the host stores them, the new
// vertices re-rounded where rounding made a changed face cross. Nothing to
// store for a double host without new vertices.
StoredOutput storeStitched(Mesh& mesh, std::size_t firstNew, std::vector<char> changed,
                           bool roundToFloat) {
  StoredOutput stored;
  stored.scalar = roundToFloat ? Scalar::kFloat : Scalar::kDouble;
  if (!roundToFloat && firstNew >= mesh.vert.size()) return stored;
  std::vector<Point3> P = positionsOf(mesh);
  const std::vector<Triangle> T = trianglesOf(mesh);
  std::vector<char> movable(P.size(), 0);
  for (std::size_t v = firstNew; v < P.size(); ++v) movable[v] = 1;
  changed.resize(T.size(), 1);
  OutputStageOptions stage;
  stage.scalar = stored.scalar;
  stored = storeNewPoints(P, T, movable, changed, stage);
  for (std::size_t v = 0; v < P.size(); ++v) mesh.vert[v].P() = P[v];
  return stored;
}

}  // namespace stitch_detail

StitchResult stitchPaths(Mesh& mesh, const StitchOptions& options) {
  const auto start = Clock::now();
  requireFacesAndFiniteCoordinates(mesh, "the mesh");
  requireCompact(mesh);
  if (options.max_aspect_ratio < 0 || options.max_rows < 0)
    throw InvalidInputError("max_aspect_ratio and max_rows must not be negative");
  reportProgress(options.progress, 0, "Planning the stitch");
  StitchResult r;
  // Room for the new faces (at most one per path vertex) and their
  // provenance, its memory touched by a resize up and back, so that writing
  // them does not stop at every fresh page: the provenance here, the faces
  // on the second core while the plan reads the faces around the paths. A
  // larger copy of the faces is made there (the mesh's border edges counted
  // in the same reading, for the report) and swapped in once the plan no
  // longer reads the faces: copying into a larger array is most of the cost
  // of adding faces.
  const std::size_t faces = mesh.face.size();
  const std::size_t room = faces + options.a.vertices.size() + options.b.vertices.size();
  {
    auto& origins = faceOrigins(mesh)._handle->data;
    origins.reserve(room);
    origins.resize(room);
    origins.resize(faces);
  }
  std::promise<void> facesFree;
  bool freed = false;
  auto release = [&] {
    if (!freed) facesFree.set_value();
    freed = true;
  };
  auto secondCore = [&mesh, free = facesFree.get_future(), faces, room] {
    const auto t = Clock::now();
    BorderEdgeCounter counter(mesh);
    std::vector<Face> larger;
    larger.reserve(room);
    for (const Face& f : mesh.face) {
      larger.push_back(f);
      counter.tally(f);
    }
    const std::size_t count = counter.count();
    const double ms = msSince(t);
    larger.resize(room);
    larger.resize(faces);
    free.wait();
    mesh.face.swap(larger);
    return std::make_pair(count, ms);
  };
  auto background = std::async(std::launch::async, std::move(secondCore));
  StitchPlan plan;
  try {
    auto clock = Clock::now();
    plan = planStitch(mesh, options, [&] {
      if (!options.check_intersections) release();
    });
    r.stage_ms.plan = msSince(clock);
    if (options.check_intersections) {
      reportProgress(options.progress, 50, "Checking intersections");
      clock = Clock::now();
      r.new_intersecting_pairs = newIntersections(mesh, plan);
      r.checked = true;
      r.stage_ms.check = msSince(clock);
    }
  } catch (...) {
    release();  // the second thread finishes before the error leaves
    throw;
  }
  release();
  reportProgress(options.progress, 90, "Writing");
  std::tie(r.border_edges_before, r.stage_ms.count) = background.get();
  const auto clock = Clock::now();
  const std::size_t verticesBefore = mesh.vert.size(), facesBefore = mesh.face.size();
  applyPlan(mesh, plan, r);
  r.stored = storeStitched(mesh, verticesBefore, std::vector<char>(facesBefore, 0),
                           options.round_to_float);
  if (r.checked && (r.stored.vertices_rerounded > 0 || options.round_to_float))
    r.new_intersecting_pairs = r.stored.crossing;  // as stored
  r.stage_ms.write = msSince(clock);
  r.border_edges_after = std::size_t(long(r.border_edges_before) + plan.borderDelta);
  reportProgress(options.progress, 100, "Done");
  r.time_ms = msSince(start);
  return r;
}

}  // namespace meshmend
