#include "common/repair/inspect/inspect.h"
#include "common/base/timing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "common/base/errors.h"
#include "common/base/parallel.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"

namespace meshmend {

namespace {

// Union-find over 0..n-1 with path halving.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), std::size_t(0));
  }
  std::size_t find(std::size_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(std::size_t a, std::size_t b) { parent_[find(a)] = find(b); }

 private:
  std::vector<std::size_t> parent_;
};

// Face corners grouped by vertex (compressed rows): the corners of vertex v
// are corners[offsets[v] .. offsets[v+1]), corner c = 3 * face + position.
struct VertexCorners {
  std::vector<std::uint32_t> offsets, corners;
  VertexCorners(std::size_t vertices, const std::vector<Triangle>& triangles)
      : offsets(vertices + 1, 0), corners(3 * triangles.size()) {
    for (const Triangle& t : triangles)
      for (int v : t) ++offsets[v + 1];
    for (std::size_t v = 0; v < vertices; ++v) offsets[v + 1] += offsets[v];
    std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
    for (std::size_t f = 0; f < triangles.size(); ++f)
      for (int i = 0; i < 3; ++i) corners[next[triangles[f][i]]++] = std::uint32_t(3 * f + i);
  }
};

// What one worker finds around its range of vertices.
struct StarFindings {
  std::size_t edges = 0, border = 0, nonManifold = 0, inconsistent = 0, nonManifoldVertices = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> facePairs;    // faces sharing an edge
  std::vector<std::pair<std::uint32_t, std::uint32_t>> borderEdges;  // (v, w)
  std::vector<std::pair<std::uint32_t, std::uint8_t>> faceMarks, vertexMarks;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> duplicateFaces;  // (face, earlier face)
};

class Inspector {
 public:
  Inspector(const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
            const InspectOptions& options)
      : P_(points), T_(triangles), options_(options) {
    if (options_.mark_defects) {
      r_.face_defects.assign(T_.size(), 0);
      r_.vertex_defects.assign(P_.size(), 0);
    }
  }

  InspectResult run() {
    r_.vertices = P_.size();
    r_.faces = T_.size();
    topology();
    if (options_.measures) duplicatePoints();
    geometry();
    return std::move(r_);
  }

 private:
  void markFace(std::size_t f, std::uint8_t bit) {
    if (options_.mark_defects) r_.face_defects[f] |= bit;
  }
  void markVertex(std::size_t v, std::uint8_t bit) {
    if (options_.mark_defects) r_.vertex_defects[v] |= bit;
  }

  // Edges, components, border loops, non-manifold vertices and duplicate
  // faces, all from the star of each vertex (its corners): every undirected
  // edge is examined at its smaller endpoint, every face at its smallest vertex.
  void topology() {
    const VertexCorners star(P_.size(), T_);
    std::vector<StarFindings> found(workerCount());
    parallelChunks(P_.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
      StarFindings& out = found[worker];
      struct Side {
        std::uint32_t other, face;
        bool forward;
      };
      struct Link {
        std::uint32_t other, corner;
      };
      std::vector<Side> sides;
      std::vector<Link> links;
      std::vector<std::uint32_t> group;
      std::vector<std::pair<Triangle, std::uint32_t>> owned;
      for (std::size_t v = begin; v < end; ++v) {
        const std::uint32_t first = star.offsets[v], last = star.offsets[v + 1];
        sides.clear();
        links.clear();
        owned.clear();
        for (std::uint32_t k = first; k < last; ++k) {
          const std::uint32_t c = star.corners[k], f = c / 3, i = c % 3;
          const std::uint32_t next = T_[f][(i + 1) % 3], prev = T_[f][(i + 2) % 3];
          if (next != v) {
            links.push_back({next, k - first});
            if (next > v) sides.push_back({next, f, true});
          }
          if (prev != v) {
            links.push_back({prev, k - first});
            if (prev > v) sides.push_back({prev, f, false});
          }
          Triangle sorted = T_[f];
          std::sort(sorted.begin(), sorted.end());
          if (std::uint32_t(sorted[0]) == v) owned.emplace_back(sorted, f);
        }
        // Edges at their smaller endpoint.
        std::sort(sides.begin(), sides.end(), [](const Side& a, const Side& b) {
          return a.other < b.other || (a.other == b.other && a.face < b.face);
        });
        for (std::size_t a = 0; a < sides.size();) {
          std::size_t b = a, forward = 0;
          while (b < sides.size() && sides[b].other == sides[a].other) {
            forward += sides[b].forward;
            if (b > a) out.facePairs.emplace_back(sides[a].face, sides[b].face);
            ++b;
          }
          const std::size_t count = b - a;
          ++out.edges;
          if (count == 1) {
            ++out.border;
            out.borderEdges.emplace_back(std::uint32_t(v), sides[a].other);
            out.faceMarks.emplace_back(sides[a].face, kFaceOnBorder);
            out.vertexMarks.emplace_back(std::uint32_t(v), kVertexOnBorder);
            out.vertexMarks.emplace_back(sides[a].other, kVertexOnBorder);
          } else if (count > 2) {
            ++out.nonManifold;
            for (std::size_t k = a; k < b; ++k)
              out.faceMarks.emplace_back(sides[k].face, kFaceOnNonManifoldEdge);
          } else if (forward != 1) {
            ++out.inconsistent;
            out.faceMarks.emplace_back(sides[a].face, kFaceOrientationFlip);
            out.faceMarks.emplace_back(sides[a + 1].face, kFaceOrientationFlip);
          }
          a = b;
        }
        // Fans: corners are grouped when their faces share an edge at v.
        const std::uint32_t n = last - first;
        if (n > 1) {
          group.resize(n);
          for (std::uint32_t k = 0; k < n; ++k) group[k] = k;
          auto root = [&](std::uint32_t x) {
            while (group[x] != x) x = group[x] = group[group[x]];
            return x;
          };
          std::sort(links.begin(), links.end(),
                    [](const Link& a, const Link& b) { return a.other < b.other; });
          for (std::size_t k = 1; k < links.size(); ++k)
            if (links[k].other == links[k - 1].other)
              group[root(links[k].corner)] = root(links[k - 1].corner);
          std::uint32_t fans = 0;
          for (std::uint32_t k = 0; k < n; ++k) fans += root(k) == k;
          if (fans > 1) {
            ++out.nonManifoldVertices;
            out.vertexMarks.emplace_back(std::uint32_t(v), kVertexNonManifold);
          }
        }
        // Duplicate faces share their smallest vertex: compare them there.
        std::sort(owned.begin(), owned.end());
        owned.erase(std::unique(owned.begin(), owned.end()), owned.end());  // a face seen twice
        for (std::size_t k = 1; k < owned.size(); ++k)
          if (owned[k].first == owned[k - 1].first)
            out.duplicateFaces.emplace_back(owned[k].second, owned[k - 1].second);
      }
    });

    DisjointSets faceSets(T_.size()), borderSets(P_.size());
    std::vector<bool> used(P_.size(), false);
    for (std::size_t v = 0; v < P_.size(); ++v) used[v] = star.offsets[v + 1] > star.offsets[v];
    for (const StarFindings& out : found) {
      r_.edges += out.edges;
      r_.border_edges += out.border;
      r_.non_manifold_edges += out.nonManifold;
      r_.orientation_inconsistent_edges += out.inconsistent;
      r_.non_manifold_vertices += out.nonManifoldVertices;
      r_.duplicate_faces += out.duplicateFaces.size();
      for (const auto& [a, b] : out.facePairs) faceSets.unite(a, b);
      for (const auto& [a, b] : out.borderEdges) borderSets.unite(a, b);
      for (const auto& [f, bit] : out.faceMarks) markFace(f, bit);
      for (const auto& [v, bit] : out.vertexMarks) markVertex(v, bit);
      for (const auto& [f, earlier] : out.duplicateFaces)
        markFace(std::max(f, earlier), kFaceDuplicate);  // the later one is the duplicate
    }
    for (std::size_t f = 0; f < T_.size(); ++f) r_.connected_components += faceSets.find(f) == f;
    for (std::size_t v = 0; v < P_.size(); ++v)
      if (!used[v]) {
        ++r_.isolated_vertices;
        markVertex(v, kVertexIsolated);
      }
    const std::size_t usedVertices = std::size_t(std::count(used.begin(), used.end(), true));

    // Border loops: connected components of the graph of border edges (for a
    // valid mesh these are exactly its halfedge border cycles).
    std::vector<std::size_t> loopEdges(P_.size(), 0);
    for (const StarFindings& out : found)
      for (const auto& [a, b] : out.borderEdges) ++loopEdges[borderSets.find(a)];
    for (std::size_t n : loopEdges)
      if (n > 0) {
        ++r_.border_loops;
        r_.longest_border_loop = std::max(r_.longest_border_loop, n);
      }
    r_.consistently_oriented = r_.orientation_inconsistent_edges == 0;
    r_.is_closed = r_.border_edges == 0 && !T_.empty();
    r_.euler_characteristic = long(usedVertices) - long(r_.edges) + long(r_.faces);
    vertexManifold_ = r_.non_manifold_vertices == 0;
  }

  void duplicatePoints() {
    std::vector<std::uint32_t> order(P_.size());
    std::iota(order.begin(), order.end(), 0u);
    auto lexLess = [this](std::uint32_t a, std::uint32_t b) {
      const Point3 &p = P_[a], &q = P_[b];
      if (p[0] != q[0]) return p[0] < q[0];
      if (p[1] != q[1]) return p[1] < q[1];
      if (p[2] != q[2]) return p[2] < q[2];
      return a < b;
    };
    std::sort(order.begin(), order.end(), lexLess);
    for (std::size_t i = 1; i < order.size(); ++i)
      if (P_[order[i]] == P_[order[i - 1]]) {
        ++r_.duplicate_points;
        markVertex(order[i], kVertexDuplicate);
      }
  }

  void geometry() {
    std::vector<bool> finite(P_.size());
    bool anyFinite = false;
    for (std::size_t i = 0; i < P_.size(); ++i) {
      const Point3& p = P_[i];
      finite[i] = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
      if (!finite[i]) {
        ++r_.non_finite_vertices;
        markVertex(i, kVertexNonFinite);
        continue;
      }
      if (!anyFinite) r_.bbox = {p[0], p[1], p[2], p[0], p[1], p[2]};
      anyFinite = true;
      for (int k = 0; k < 3; ++k) {
        r_.bbox[k] = std::min(r_.bbox[k], p[k]);
        r_.bbox[k + 3] = std::max(r_.bbox[k + 3], p[k]);
      }
    }
    if (anyFinite) {
      const double dx = r_.bbox[3] - r_.bbox[0], dy = r_.bbox[4] - r_.bbox[1],
                   dz = r_.bbox[5] - r_.bbox[2];
      r_.bbox_diagonal = std::sqrt(dx * dx + dy * dy + dz * dz);
      for (double c : r_.bbox) r_.max_abs_coordinate = std::max(r_.max_abs_coordinate, std::abs(c));
    }
    const Point3 center((r_.bbox[0] + r_.bbox[3]) / 2, (r_.bbox[1] + r_.bbox[4]) / 2,
                        (r_.bbox[2] + r_.bbox[5]) / 2);
    double volume6 = 0, sumMinAngle = 0;
    std::size_t angleCount = 0;
    auto angle = [](const Point3& p, const Point3& q, const Point3& s) {
      const Point3 u = q - p, v = s - p;
      return std::atan2((u ^ v).Norm(), u * v) * 180.0 / M_PI;
    };
    for (std::size_t f = 0; f < T_.size(); ++f) {
      const Triangle& t = T_[f];
      if (!finite[t[0]] || !finite[t[1]] || !finite[t[2]]) continue;  // no geometry to judge
      const Point3 &a = P_[t[0]], &b = P_[t[1]], &c = P_[t[2]];
      const bool repeated =
          t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || a == b || b == c || c == a;
      if (repeated || collinear(a, b, c)) {
        ++r_.degenerate_faces;
        markFace(f, kFaceDegenerate);
      }
      if (!options_.measures) continue;
      volume6 += (a - center) * ((b - center) ^ (c - center));
      if (a == b || b == c || c == a) continue;  // angles undefined
      const double shortest = std::sqrt(
          std::min({(b - a).SquaredNorm(), (c - b).SquaredNorm(), (a - c).SquaredNorm()}));
      if (shortest > 0 && (r_.shortest_edge == 0 || shortest < r_.shortest_edge))
        r_.shortest_edge = shortest;
      const double m = std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
      r_.min_angle_deg = std::min(r_.min_angle_deg, m);
      sumMinAngle += m;
      ++angleCount;
    }
    if (angleCount == 0) r_.min_angle_deg = 0;
    if (r_.shortest_edge > 0) {
      // The spacing of each scalar's values at the largest coordinate (past
      // FLT_MAX float holds none of them: 0 steps).
      const double m = r_.max_abs_coordinate;
      if (m <= double(std::numeric_limits<float>::max())) {
        const float f = std::max(float(m), std::numeric_limits<float>::denorm_min());
        const double step =
            double(std::nextafter(f, std::numeric_limits<float>::infinity())) - double(f);
        r_.float_steps_in_shortest_edge = std::isfinite(step) ? r_.shortest_edge / step : 0;
      }
      const double d = std::max(m, std::numeric_limits<double>::denorm_min());
      const double step = std::nextafter(d, std::numeric_limits<double>::infinity()) - d;
      r_.double_steps_in_shortest_edge = std::isfinite(step) ? r_.shortest_edge / step : 0;
    }
    r_.mean_min_angle_deg = angleCount ? sumMinAngle / double(angleCount) : 0;
    const bool edgeManifoldOriented =
        r_.is_closed && r_.consistently_oriented && r_.non_manifold_edges == 0;
    if (edgeManifoldOriented && r_.non_finite_vertices == 0) r_.volume = volume6 / 6.0;
    if (edgeManifoldOriented && vertexManifold_ && r_.euler_characteristic % 2 == 0)
      r_.genus = (2 * long(r_.connected_components) - r_.euler_characteristic) / 2;
  }

  const std::vector<Point3>& P_;
  const std::vector<Triangle>& T_;
  InspectOptions options_;
  InspectResult r_;
  bool vertexManifold_ = true;
};

}  // namespace

InspectResult inspect(const Mesh& mesh, const InspectOptions& options) {
  if (std::size_t(mesh.vn) != mesh.vert.size() || std::size_t(mesh.fn) != mesh.face.size())
    throw InvalidInputError("inspect() needs a compact mesh (no deleted vertices or faces)");
  const auto start = Clock::now();
  const std::vector<Point3> points = positionsOf(mesh);
  const std::vector<Triangle> triangles = trianglesOf(mesh);
  InspectResult result = Inspector(points, triangles, options).run();
  result.coordinate_binades = magnitudesOf(points, triangles).binades();
  if (options.self_intersections && result.non_finite_vertices == 0 && mesh.fn > 0 &&
      result.coordinate_binades <= kMaxCoordinateBinades) {
    FindIntersectionsOptions find;
    find.cross = false;
    const FindIntersectionsResult found = findIntersections({&mesh}, find);
    result.self_intersecting_pairs = found.self_pairs[0];
    result.self_intersecting_faces = found.self_faces[0];
    if (options.mark_defects)
      for (std::size_t f = 0; f < found.face_involved[0].size(); ++f)
        if (found.face_involved[0][f]) result.face_defects[f] |= kFaceSelfIntersecting;
  }
  result.time_ms = msSince(start);
  return result;
}

JsonObject toJson(const InspectResult& r) {
  JsonObject j;
  j.set("vertices", r.vertices)
      .set("faces", r.faces)
      .set("triangles", r.faces)
      .set("edges", r.edges)
      .set("connected_components", r.connected_components)
      .set("border_edges", r.border_edges)
      .set("border_loops", r.border_loops)
      .set("longest_border_loop", r.longest_border_loop)
      .set("non_manifold_edges", r.non_manifold_edges)
      .set("non_manifold_vertices", r.non_manifold_vertices)
      .set("isolated_vertices", r.isolated_vertices)
      .set("duplicate_points", r.duplicate_points)
      .set("non_finite_vertices", r.non_finite_vertices)
      .set("degenerate_faces", r.degenerate_faces)
      .set("duplicate_faces", r.duplicate_faces)
      .set("is_closed", r.is_closed)
      .set("consistently_oriented", r.consistently_oriented)
      .set("orientation_inconsistent_edges", r.orientation_inconsistent_edges)
      .set("volume", r.volume);
  if (r.self_intersecting_pairs)
    j.set("self_intersecting_pairs", *r.self_intersecting_pairs)
        .set("self_intersecting_faces", *r.self_intersecting_faces);
  j.set("euler_characteristic", r.euler_characteristic);
  if (r.genus)
    j.set("genus", *r.genus);
  else
    j.setNull("genus");
  j.set("bbox", std::vector<double>(r.bbox.begin(), r.bbox.end()))
      .set("bbox_diagonal", r.bbox_diagonal)
      .set("min_angle_deg", r.min_angle_deg)
      .set("mean_min_angle_deg", r.mean_min_angle_deg)
      .set("max_abs_coordinate", r.max_abs_coordinate)
      .set("coordinate_binades", r.coordinate_binades)
      .set("shortest_edge", r.shortest_edge)
      .set("float_steps_in_shortest_edge", r.float_steps_in_shortest_edge)
      .set("double_steps_in_shortest_edge", r.double_steps_in_shortest_edge);
  const std::string precision = precisionNote(r);
  if (!precision.empty()) j.set("precision_note", precision);
  j.set("time_ms", r.time_ms);
  return j;
}

std::string precisionNote(const InspectResult& r) {
  if (r.shortest_edge <= 0 || r.float_steps_in_shortest_edge >= kFewFloatSteps) return {};
  std::ostringstream s;
  s.precision(3);
  s << "the shortest edge (" << r.shortest_edge << ") spans only " << r.float_steps_in_shortest_edge
    << " float steps at coordinates up to " << r.max_abs_coordinate
    << ": stored in float (MeshLab's float builds, float PLY/STL/OBJ files) the faces can "
       "cross or collapse where they do not in the file; use a double host (MeshLab 2025.07d, "
       "pymeshlab, the meshmend Python module), where it spans "
    << r.double_steps_in_shortest_edge << " steps";
  return s.str();
}

std::string summarize(const InspectResult& r) {
  std::ostringstream s;
  s << r.vertices << " vertices, " << r.faces << " faces, " << r.connected_components
    << (r.connected_components == 1 ? " component; " : " components; ");
  std::vector<std::string> defects;
  auto add = [&](std::size_t n, const char* what) {
    if (n) defects.push_back(std::to_string(n) + " " + what);
  };
  add(r.border_edges, "border edges");
  if (r.border_edges) defects.back() += " in " + std::to_string(r.border_loops) + " loops";
  add(r.non_manifold_edges, "non-manifold edges");
  add(r.non_manifold_vertices, "non-manifold vertices");
  add(r.orientation_inconsistent_edges, "inconsistently oriented edges");
  add(r.degenerate_faces, "degenerate faces");
  add(r.duplicate_faces, "duplicate faces");
  add(r.duplicate_points, "duplicate points");
  add(r.isolated_vertices, "unreferenced vertices");
  add(r.non_finite_vertices, "vertices with NaN or infinite coordinates");
  if (r.self_intersecting_pairs) add(*r.self_intersecting_pairs, "self-intersecting face pairs");
  if (defects.empty()) {
    s << "no defects";
  } else {
    for (std::size_t i = 0; i < defects.size(); ++i) s << (i ? ", " : "") << defects[i];
  }
  s << (r.is_closed ? "; closed" : "; open");
  if (r.volume) s << ", volume " << *r.volume;
  if (r.genus) s << ", genus " << *r.genus;
  const std::string precision = precisionNote(r);
  if (!precision.empty()) s << ". Precision: " << precision;
  if (r.coordinate_binades > kMaxCoordinateBinades)
    s << ". Coordinates span " << std::lround(r.coordinate_binades) << " binades: beyond the "
      << kMaxCoordinateBinades
      << " MeshMend decides on exactly, so self-intersections are not counted and its "
         "filters refuse the mesh (set the tiniest coordinates to zero)";
  return s.str();
}

}  // namespace meshmend
