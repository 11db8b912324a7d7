#include "common/inspect.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <sstream>

#include "common/errors.h"
#include "common/predicates.h"

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

// One side of a face along an undirected edge.
struct EdgeSide {
  std::uint64_t key;  // (smaller index << 32) | larger index
  std::uint32_t face;
  bool forward;  // the face runs the edge from the smaller to the larger index
};

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

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
    edgesAndComponents();
    nonManifoldVertices();
    duplicates();
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

  void edgesAndComponents() {
    std::vector<EdgeSide> sides;
    sides.reserve(3 * T_.size());
    std::vector<bool> used(P_.size(), false);
    for (std::size_t f = 0; f < T_.size(); ++f)
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t a = T_[f][i], b = T_[f][(i + 1) % 3];
        used[a] = true;
        if (a != b) sides.push_back({edgeKey(a, b), std::uint32_t(f), a < b});
      }
    std::sort(sides.begin(), sides.end(), [](const EdgeSide& x, const EdgeSide& y) {
      return x.key < y.key || (x.key == y.key && x.face < y.face);
    });

    DisjointSets faceSets(T_.size());
    DisjointSets borderSets(P_.size());
    std::vector<std::uint64_t> borderKeys;
    for (std::size_t i = 0; i < sides.size();) {
      std::size_t j = i;
      std::size_t forward = 0;
      while (j < sides.size() && sides[j].key == sides[i].key) {
        forward += sides[j].forward;
        if (j > i) faceSets.unite(sides[i].face, sides[j].face);
        ++j;
      }
      const std::size_t count = j - i;
      const std::uint32_t a = std::uint32_t(sides[i].key >> 32);
      const std::uint32_t b = std::uint32_t(sides[i].key & 0xffffffffu);
      ++r_.edges;
      if (count == 1) {
        ++r_.border_edges;
        borderSets.unite(a, b);
        borderKeys.push_back(sides[i].key);
        markFace(sides[i].face, kFaceOnBorder);
        markVertex(a, kVertexOnBorder);
        markVertex(b, kVertexOnBorder);
      } else if (count > 2) {
        ++r_.non_manifold_edges;
        for (std::size_t k = i; k < j; ++k) markFace(sides[k].face, kFaceOnNonManifoldEdge);
      } else if (forward != 1) {
        ++r_.orientation_inconsistent_edges;
        markFace(sides[i].face, kFaceOrientationFlip);
        markFace(sides[i + 1].face, kFaceOrientationFlip);
      }
      i = j;
    }
    for (std::size_t f = 0; f < T_.size(); ++f) r_.connected_components += faceSets.find(f) == f;
    for (std::size_t v = 0; v < P_.size(); ++v)
      if (!used[v]) {
        ++r_.isolated_vertices;
        markVertex(v, kVertexIsolated);
      }
    usedVertices_ = std::size_t(std::count(used.begin(), used.end(), true));

    // Border loops: connected components of the graph of border edges (for a
    // valid mesh these are exactly its halfedge border cycles).
    std::vector<std::size_t> loopEdges(P_.size(), 0);
    for (std::uint64_t key : borderKeys) ++loopEdges[borderSets.find(std::size_t(key >> 32))];
    for (std::size_t n : loopEdges)
      if (n > 0) {
        ++r_.border_loops;
        r_.longest_border_loop = std::max(r_.longest_border_loop, n);
      }
    r_.consistently_oriented = r_.orientation_inconsistent_edges == 0;
    r_.is_closed = r_.border_edges == 0 && !T_.empty();
    r_.euler_characteristic = long(usedVertices_) - long(r_.edges) + long(r_.faces);
  }

  // A vertex is non-manifold when its corners (the face corners at it) fall
  // into more than one group, corners being grouped when their faces share an
  // edge at that vertex.
  void nonManifoldVertices() {
    struct Side {
      std::uint32_t vertex, other;
      std::uint32_t corner;
    };
    std::vector<Side> sides;
    sides.reserve(6 * T_.size());
    for (std::size_t f = 0; f < T_.size(); ++f)
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t v = T_[f][i], prev = T_[f][(i + 2) % 3], next = T_[f][(i + 1) % 3];
        const std::uint32_t corner = std::uint32_t(3 * f + i);
        if (prev != v) sides.push_back({v, prev, corner});
        if (next != v) sides.push_back({v, next, corner});
      }
    std::sort(sides.begin(), sides.end(), [](const Side& a, const Side& b) {
      return a.vertex < b.vertex || (a.vertex == b.vertex && a.other < b.other);
    });
    DisjointSets corners(3 * T_.size());
    for (std::size_t i = 1; i < sides.size(); ++i)
      if (sides[i].vertex == sides[i - 1].vertex && sides[i].other == sides[i - 1].other)
        corners.unite(sides[i].corner, sides[i - 1].corner);

    // Corners by vertex: count distinct groups per vertex.
    std::vector<std::pair<std::uint32_t, std::size_t>> groups;  // (vertex, group root)
    groups.reserve(3 * T_.size());
    for (std::size_t c = 0; c < 3 * T_.size(); ++c)
      groups.emplace_back(std::uint32_t(T_[c / 3][c % 3]), corners.find(c));
    std::sort(groups.begin(), groups.end());
    groups.erase(std::unique(groups.begin(), groups.end()), groups.end());
    for (std::size_t i = 1; i < groups.size(); ++i)
      if (groups[i].first == groups[i - 1].first &&
          (i < 2 || groups[i - 2].first != groups[i].first)) {
        ++r_.non_manifold_vertices;  // counted once, at the vertex's second group
        markVertex(groups[i].first, kVertexNonManifold);
      }
    vertexManifold_ = r_.non_manifold_vertices == 0;
  }

  void duplicates() {
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

    std::vector<std::pair<Triangle, std::uint32_t>> sorted;
    sorted.reserve(T_.size());
    for (std::size_t f = 0; f < T_.size(); ++f) {
      Triangle t = T_[f];
      std::sort(t.begin(), t.end());
      sorted.emplace_back(t, std::uint32_t(f));
    }
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t i = 1; i < sorted.size(); ++i)
      if (sorted[i].first == sorted[i - 1].first) {
        ++r_.duplicate_faces;
        markFace(sorted[i].second, kFaceDuplicate);
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
      volume6 += (a - center) * ((b - center) ^ (c - center));
      const bool repeated = t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || a == b || b == c ||
                            c == a;
      if (repeated || collinear(a, b, c)) {
        ++r_.degenerate_faces;
        markFace(f, kFaceDegenerate);
      }
      if (a == b || b == c || c == a) continue;  // angles undefined
      const double m = std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
      r_.min_angle_deg = std::min(r_.min_angle_deg, m);
      sumMinAngle += m;
      ++angleCount;
    }
    if (angleCount == 0) r_.min_angle_deg = 0;
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
  std::size_t usedVertices_ = 0;
  bool vertexManifold_ = true;
};

}  // namespace

InspectResult inspect(const Mesh& mesh, const InspectOptions& options) {
  if (std::size_t(mesh.vn) != mesh.vert.size() || std::size_t(mesh.fn) != mesh.face.size())
    throw InvalidInputError("inspect() needs a compact mesh (no deleted vertices or faces)");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Point3> points = positionsOf(mesh);
  const std::vector<Triangle> triangles = trianglesOf(mesh);
  InspectResult result = Inspector(points, triangles, options).run();
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
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
      .set("volume", r.volume)
      .set("euler_characteristic", r.euler_characteristic);
  if (r.genus)
    j.set("genus", *r.genus);
  else
    j.setNull("genus");
  j.set("bbox", std::vector<double>(r.bbox.begin(), r.bbox.end()))
      .set("bbox_diagonal", r.bbox_diagonal)
      .set("min_angle_deg", r.min_angle_deg)
      .set("mean_min_angle_deg", r.mean_min_angle_deg)
      .set("time_ms", r.time_ms);
  return j;
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
  if (defects.empty()) {
    s << "no defects";
  } else {
    for (std::size_t i = 0; i < defects.size(); ++i) s << (i ? ", " : "") << defects[i];
  }
  s << (r.is_closed ? "; closed" : "; open");
  if (r.volume) s << ", volume " << *r.volume;
  if (r.genus) s << ", genus " << *r.genus;
  return s.str();
}

}  // namespace meshmend
