#include "common/split.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <unordered_map>

#include "common/box_tree.h"
#include "common/errors.h"
#include "common/parallel.h"
#include "common/predicates.h"
#include "common/retriangulate.h"

namespace meshmend {

namespace {

using Clock = std::chrono::steady_clock;

bool sameExact(const RationalPoint& p, const RationalPoint& q) {
  return p.x[0] == q.x[0] && p.x[1] == q.x[1] && p.x[2] == q.x[2];
}

RationalPoint exactOf(const Point3& p) {
  return {{mpq_class(p[0]), mpq_class(p[1]), mpq_class(p[2])}};
}

Point3 roundedOf(const RationalPoint& p) {
  return {p.x[0].get_d(), p.x[1].get_d(), p.x[2].get_d()};
}

// Lexicographic order on exact coordinates, to key points.
struct ExactLess {
  bool operator()(const RationalPoint& p, const RationalPoint& q) const {
    for (int k = 0; k < 3; ++k) {
      if (p.x[k] < q.x[k]) return true;
      if (q.x[k] < p.x[k]) return false;
    }
    return false;
  }
};

// The points and curve segments one face receives.
struct FaceWork {
  std::vector<RationalPoint> points;
  std::vector<std::array<int, 2>> segments;  // indices into points

  int add(const RationalPoint& p) {
    for (std::size_t i = 0; i < points.size(); ++i)
      if (sameExact(points[i], p)) return int(i);
    points.push_back(p);
    return int(points.size()) - 1;
  }
};

// Is the exact point p on the closed segment a-b (a, b input doubles)?
bool onSegment(const RationalPoint& p, const Point3& a, const Point3& b) {
  const RationalPoint A = exactOf(a), B = exactOf(b);
  for (int k = 0; k < 3; ++k) {
    const int u = (k + 1) % 3;
    // (p - a) x (b - a) == 0, component by component
    if ((p.x[k] - A.x[k]) * (B.x[u] - A.x[u]) != (p.x[u] - A.x[u]) * (B.x[k] - A.x[k]))
      return false;
  }
  for (int k = 0; k < 3; ++k)
    if (sgn(p.x[k] - A.x[k]) * sgn(B.x[k] - p.x[k]) < 0) return false;
  return true;
}

// Barycentric coordinates of p in triangle (a, b, c), from the rounded values.
Point3 barycentric(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  const Point3 n = (b - a) ^ (c - a);
  const double n2 = n.SquaredNorm();
  if (!(n2 > 0)) return {1, 0, 0};
  const double wa = (((c - b) ^ (p - b)) * n) / n2, wb = (((a - c) ^ (p - c)) * n) / n2;
  return {wa, wb, 1 - wa - wb};
}

class MeshSplitter {
 public:
  MeshSplitter(const Mesh& mesh, std::uint32_t index) : index_(index) {
    points_ = positionsOf(mesh);
    triangles_ = trianglesOf(mesh);
    // Faces around each vertex (compressed rows), to find the faces on an edge.
    offsets_.assign(points_.size() + 1, 0);
    for (const Triangle& t : triangles_)
      for (int v : t) ++offsets_[v + 1];
    for (std::size_t v = 0; v < points_.size(); ++v) offsets_[v + 1] += offsets_[v];
    faces_.resize(offsets_.back());
    std::vector<std::uint32_t> next(offsets_.begin(), offsets_.end() - 1);
    for (std::size_t f = 0; f < triangles_.size(); ++f)
      for (int v : triangles_[f]) faces_[next[v]++] = std::uint32_t(f);
  }

  TrianglePoints at(std::uint32_t f) const {
    return {points_[triangles_[f][0]], points_[triangles_[f][1]], points_[triangles_[f][2]]};
  }

  // The contact of a pair, seen from this mesh's face f.
  void addContact(std::uint32_t f, const std::vector<RationalPoint>& contact) {
    FaceWork& w = work_[f];
    std::vector<int> ids;
    for (const RationalPoint& p : contact) ids.push_back(w.add(p));
    if (ids.size() == 2) w.segments.push_back({ids[0], ids[1]});
    if (ids.size() > 2)
      for (std::size_t i = 0; i < ids.size(); ++i)
        w.segments.push_back({ids[i], ids[(i + 1) % ids.size()]});
  }

  // Points on an edge of a face also split that edge in the faces across it.
  void shareEdgePoints() {
    std::vector<std::pair<std::uint32_t, RationalPoint>> shared;
    for (const auto& [f, w] : work_) {
      const Triangle& t = triangles_[f];
      for (const RationalPoint& p : w.points)
        for (int i = 0; i < 3; ++i) {
          const int a = t[i], b = t[(i + 1) % 3];
          if (!onSegment(p, points_[a], points_[b])) continue;
          for (std::uint32_t k = offsets_[a]; k < offsets_[a + 1]; ++k) {
            const std::uint32_t g = faces_[k];
            if (g == f) continue;
            const Triangle& u = triangles_[g];
            if (u[0] == b || u[1] == b || u[2] == b) shared.emplace_back(g, p);
          }
        }
    }
    for (const auto& [g, p] : shared) work_[g].add(p);
  }

  // Re-triangulates every face that received points, in parallel.
  void retriangulateFaces() {
    order_.clear();
    for (const auto& [f, w] : work_) order_.push_back(f);
    std::sort(order_.begin(), order_.end());
    patches_.resize(order_.size());
    parallelChunks(
        order_.size(),
        [&](std::size_t begin, std::size_t end, unsigned) {
          for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t f = order_[i];
            const FaceWork& w = work_.at(f);
            const TrianglePoints t = at(f);
            if (collinear(t[0], t[1], t[2])) continue;  // degenerate: kept as it is (empty patch)
            PatchInput in;
            for (int k = 0; k < 3; ++k) in.corners[k] = exactOf(points_[triangles_[f][k]]);
            in.points = w.points;
            for (const auto& s : w.segments) in.segments.push_back({3 + s[0], 3 + s[1]});
            patches_[i] = retriangulate(in);
          }
        },
        16);
  }

  // Builds the output mesh and its curve edges.
  void build(Mesh& out, std::vector<std::array<int, 2>>& curves,
             std::vector<RationalPoint>& exactNew, std::size_t& facesAdded) {
    std::vector<Point3> positions = points_;
    std::vector<Triangle> triangles;
    std::vector<FaceOrigin> birthFaces;
    std::vector<VertexOrigin> newOrigins;
    std::map<RationalPoint, int, ExactLess> registry;
    std::vector<char> split(triangles_.size(), 0);
    for (std::size_t i = 0; i < order_.size(); ++i)
      split[order_[i]] = !patches_[i].triangles.empty();
    for (std::size_t f = 0; f < triangles_.size(); ++f)
      if (!split[f]) {
        triangles.push_back(triangles_[f]);
        birthFaces.push_back({int(index_), int(f)});
      }
    std::set<std::array<int, 2>> curveSet;
    for (std::size_t i = 0; i < order_.size(); ++i) {
      const std::uint32_t f = order_[i];
      const Patch& patch = patches_[i];
      if (patch.triangles.empty()) {
        ++degenerateKept_;
        continue;
      }
      std::vector<int> global(patch.vertices.size());
      for (std::size_t v = 0; v < patch.vertices.size(); ++v) {
        if (v < 3) {
          global[v] = triangles_[f][v];
          continue;
        }
        const auto [it, added] = registry.emplace(patch.vertices[v], int(positions.size()));
        if (added) {
          const Point3 p = roundedOf(patch.vertices[v]);
          positions.push_back(p);
          exactNew.push_back(patch.vertices[v]);
          const TrianglePoints t = at(f);
          newOrigins.push_back({int(index_), -1, int(f), barycentric(p, t[0], t[1], t[2])});
        }
        global[v] = it->second;
      }
      // Every contact point is a place where meshes meet, curve or not (a
      // touching corner): the merged output welds them.
      for (std::size_t i = 3; i < patch.vertex_of_input.size(); ++i)
        contactVertices_.push_back(global[patch.vertex_of_input[i]]);
      for (const auto& t : patch.triangles) {
        triangles.push_back({global[t[0]], global[t[1]], global[t[2]]});
        birthFaces.push_back({int(index_), int(f)});
      }
      for (const auto& e : patch.constrained_edges) {
        std::array<int, 2> g{global[e[0]], global[e[1]]};
        if (g[0] > g[1]) std::swap(g[0], g[1]);
        curveSet.insert(g);
      }
    }
    out = makeMesh(positions, triangles, int(index_));
    VertexOriginHandle vo = vertexOrigins(out);
    for (std::size_t i = 0; i < newOrigins.size(); ++i) vo[points_.size() + i] = newOrigins[i];
    FaceOriginHandle fo = faceOrigins(out);
    for (std::size_t f = 0; f < birthFaces.size(); ++f) fo[f] = birthFaces[f];
    curves.assign(curveSet.begin(), curveSet.end());
    facesAdded += triangles.size() - triangles_.size();
  }

  std::size_t facesSplit() const { return order_.size() - degenerateKept_; }
  const std::vector<int>& contactVertices() const { return contactVertices_; }
  std::size_t degenerateKept() const { return degenerateKept_; }
  const std::vector<Point3>& points() const { return points_; }

 private:
  std::uint32_t index_;
  std::vector<Point3> points_;
  std::vector<Triangle> triangles_;
  std::vector<std::uint32_t> offsets_, faces_;
  std::unordered_map<std::uint32_t, FaceWork> work_;
  std::vector<std::uint32_t> order_;
  std::vector<Patch> patches_;
  std::size_t degenerateKept_ = 0;
  std::vector<int> contactVertices_;  // output vertices at contact points
};

// Closed and open components of a curve graph.
void countCurves(std::size_t vertices, const std::vector<std::array<int, 2>>& edges,
                 std::size_t& loops, std::size_t& open) {
  std::vector<int> parent(vertices), degree(vertices, 0);
  for (std::size_t v = 0; v < vertices; ++v) parent[v] = int(v);
  std::function<int(int)> find = [&](int x) {
    return parent[x] == x ? x : parent[x] = find(parent[x]);
  };
  for (const auto& e : edges) {
    ++degree[e[0]], ++degree[e[1]];
    parent[find(e[0])] = find(e[1]);
  }
  std::map<int, bool> closed;  // component root -> every vertex of even degree
  for (const auto& e : edges)
    for (int v : e) {
      auto [it, added] = closed.emplace(find(v), true);
      if (degree[v] % 2) it->second = false;
    }
  loops = open = 0;
  for (const auto& [root, c] : closed) (c ? loops : open) += 1;
}

}  // namespace

SplitResult splitAlongIntersections(const std::vector<const Mesh*>& meshes,
                                    const SplitOptions& options) {
  const auto start = Clock::now();
  SplitResult r;
  std::vector<Mesh> welded;  // the inputs with their seams closed, when asked
  std::vector<const Mesh*> inputs = meshes;
  if (options.weld_duplicates) {
    welded.reserve(meshes.size());
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      welded.push_back(*meshes[m]);
      r.vertices_welded += weldCoincidentVertices(welded.back());
      inputs[m] = &welded.back();
    }
  }
  FindIntersectionsOptions find;
  find.self = options.self;
  find.cross = options.between_meshes;
  find.contacts = true;
  find.progress = [&](int percent, const char* stage) {
    return !options.progress || options.progress(percent * 4 / 10, stage);
  };
  const FindIntersectionsResult found = findIntersections(inputs, find);
  r.intersecting_pairs = found.pairs.size();

  reportProgress(options.progress, 40, "Collecting curve points");
  std::vector<MeshSplitter> splitters;
  for (std::size_t m = 0; m < meshes.size(); ++m)
    splitters.emplace_back(*inputs[m], std::uint32_t(m));
  for (std::size_t i = 0; i < found.pairs.size(); ++i) {
    const IntersectingPair& p = found.pairs[i];
    const std::vector<RationalPoint>& contact = found.contacts[i].exact;
    splitters[p.a.mesh].addContact(p.a.face, contact);
    splitters[p.b.mesh].addContact(p.b.face, contact);
  }
  reportProgress(options.progress, 55, "Re-triangulating crossed faces");
  std::vector<std::vector<RationalPoint>> exactNew(meshes.size());
  r.meshes.resize(meshes.size());
  r.curve_edges.resize(meshes.size());
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    splitters[m].shareEdgePoints();
    splitters[m].retriangulateFaces();
    splitters[m].build(r.meshes[m], r.curve_edges[m], exactNew[m], r.faces_added);
    r.faces_split += splitters[m].facesSplit();
    r.degenerate_faces_kept += splitters[m].degenerateKept();
    r.new_vertices += exactNew[m].size();
  }

  reportProgress(options.progress, 90, "Welding along the curves");
  {
    // All meshes in one; curve vertices with the same exact position merge.
    std::vector<Point3> positions;
    std::vector<Triangle> triangles;
    std::vector<VertexOrigin> vertexOrigin;
    std::vector<FaceOrigin> faceOrigin;
    std::map<RationalPoint, int, ExactLess> weld;
    std::set<std::array<int, 2>> curves;
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      Mesh& mesh = r.meshes[m];
      VertexOriginHandle vo = vertexOrigins(mesh);
      FaceOriginHandle fo = faceOrigins(mesh);
      std::vector<char> onCurve(mesh.vert.size(), 0);  // on a curve or at a contact point
      for (const auto& e : r.curve_edges[m]) onCurve[e[0]] = onCurve[e[1]] = 1;
      for (int v : splitters[m].contactVertices()) onCurve[v] = 1;
      const std::size_t inputVertices = splitters[m].points().size();
      std::vector<int>& global = r.merged_vertex.emplace_back(mesh.vert.size());
      for (std::size_t v = 0; v < mesh.vert.size(); ++v) {
        if (onCurve[v]) {
          const RationalPoint exact =
              v < inputVertices ? exactOf(mesh.vert[v].cP()) : exactNew[m][v - inputVertices];
          const auto [it, added] = weld.emplace(exact, int(positions.size()));
          global[v] = it->second;
          if (!added) continue;
        } else {
          global[v] = int(positions.size());
        }
        positions.push_back(mesh.vert[v].cP());
        vertexOrigin.push_back(vo[v]);
      }
      for (std::size_t f = 0; f < mesh.face.size(); ++f) {
        const Face& face = mesh.face[f];
        triangles.push_back({global[vcg::tri::Index(mesh, face.cV(0))],
                             global[vcg::tri::Index(mesh, face.cV(1))],
                             global[vcg::tri::Index(mesh, face.cV(2))]});
        faceOrigin.push_back(fo[f]);
      }
      for (const auto& e : r.curve_edges[m]) {
        std::array<int, 2> g{global[e[0]], global[e[1]]};
        if (g[0] > g[1]) std::swap(g[0], g[1]);
        curves.insert(g);
      }
    }
    r.merged = makeMesh(positions, triangles);
    VertexOriginHandle vo = vertexOrigins(r.merged);
    FaceOriginHandle fo = faceOrigins(r.merged);
    for (std::size_t v = 0; v < vertexOrigin.size(); ++v) vo[v] = vertexOrigin[v];
    for (std::size_t f = 0; f < faceOrigin.size(); ++f) fo[f] = faceOrigin[f];
    r.merged_curve_edges.assign(curves.begin(), curves.end());
    countCurves(positions.size(), r.merged_curve_edges, r.curve_loops, r.open_curves);
  }
  reportProgress(options.progress, 100, "Done");
  r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  return r;
}

std::size_t remainingIntersections(const SplitResult& result, bool asFloat) {
  if (result.merged.fn == 0) return 0;
  Mesh check = result.merged;
  if (asFloat)
    for (Vertex& v : check.vert)
      for (int k = 0; k < 3; ++k) v.P()[k] = double(float(v.P()[k]));
  FindIntersectionsOptions o;
  o.cross = false;
  return findIntersections({&check}, o).self_pairs[0];
}

namespace {

float below(double x) {
  float f = float(x);
  return double(f) > x ? std::nextafter(f, -INFINITY) : f;
}
float above(double x) {
  float f = float(x);
  return double(f) < x ? std::nextafter(f, INFINITY) : f;
}

}  // namespace

std::size_t roundToFloat(SplitResult& r, int passes) {
  Mesh& merged = r.merged;
  if (merged.fn == 0) return 0;
  const std::vector<Point3> exact = positionsOf(merged);
  std::vector<Point3> P = exact;
  for (Point3& p : P) p = Point3(double(float(p[0])), double(float(p[1])), double(float(p[2])));
  const std::vector<Triangle> T = trianglesOf(merged);
  VertexOriginHandle vo = vertexOrigins(merged);
  // Faces around each vertex.
  std::vector<std::vector<std::uint32_t>> around(P.size());
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int v : T[f]) around[v].push_back(std::uint32_t(f));
  auto at = [&](std::uint32_t f) -> TrianglePoints { return {P[T[f][0]], P[T[f][1]], P[T[f][2]]}; };
  auto crosses = [&](std::uint32_t f, std::uint32_t g) {
    const TrianglePoints a = at(f), b = at(g);
    if (collinear(a[0], a[1], a[2]) || collinear(b[0], b[1], b[2])) return false;
    const SharedCorners c = sharedCorners(T[f], T[g]);
    return intersectBeyondShared(a, b, c.count, c.ia, c.ib);
  };
  std::size_t remaining = 0;
  for (int pass = 0; pass <= passes; ++pass) {
    const Mesh current = makeMesh(P, T);
    FindIntersectionsOptions o;
    o.cross = false;
    const FindIntersectionsResult found = findIntersections({&current}, o);
    remaining = found.pairs.size();
    if (remaining == 0 || pass == passes) break;
    std::vector<Box> boxes;
    for (std::size_t f = 0; f < T.size(); ++f)
      boxes.push_back(boxOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]));
    const BoxTree tree(boxes);
    std::set<int> candidates;
    for (const IntersectingPair& p : found.pairs)
      for (std::uint32_t f : {p.a.face, p.b.face})
        for (int v : T[f])
          if (vo[v].vertex < 0) candidates.insert(v);  // new vertices only: inputs stay as they are
    // How many faces the faces around v cross, with v where it is now.
    auto localCrossings = [&](int v) {
      std::size_t n = 0;
      for (std::uint32_t f : around[v]) {
        Box b = boxOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]);
        for (int k = 0; k < 3; ++k) {  // neighbours may have moved by an ulp this pass
          for (int i = 0; i < 4; ++i) {
            b.lo[k] = std::nextafter(b.lo[k], -INFINITY);
            b.hi[k] = std::nextafter(b.hi[k], INFINITY);
          }
        }
        tree.query(b, 0, [&](std::uint32_t g, unsigned) {
          if (g != f && crosses(f, g)) ++n;
        });
      }
      return n;
    };
    for (int v : candidates) {
      const Point3 e = exact[v];
      Point3 best = P[v];
      std::size_t bestCount = localCrossings(v);
      for (int choice = 0; choice < 8 && bestCount > 0; ++choice) {
        P[v] =
            Point3(choice & 1 ? above(e[0]) : below(e[0]), choice & 2 ? above(e[1]) : below(e[1]),
                   choice & 4 ? above(e[2]) : below(e[2]));
        const std::size_t n = localCrossings(v);
        if (n < bestCount) best = P[v], bestCount = n;
      }
      P[v] = best;
    }
  }
  // Write the float positions back, to the merged output and to each mesh.
  for (std::size_t v = 0; v < P.size(); ++v) merged.vert[v].P() = P[v];
  for (std::size_t m = 0; m < r.meshes.size(); ++m)
    for (std::size_t v = 0; v < r.merged_vertex[m].size(); ++v)
      r.meshes[m].vert[v].P() = P[r.merged_vertex[m][v]];
  return remaining;
}

JsonObject toJson(const SplitResult& r) {
  std::size_t curveEdges = r.merged_curve_edges.size();
  if (curveEdges == 0)
    for (const auto& c : r.curve_edges) curveEdges += c.size();
  JsonObject j;
  j.set("intersecting_pairs", r.intersecting_pairs)
      .set("curve_edges", curveEdges)
      .set("curve_loops", r.curve_loops)
      .set("open_curves", r.open_curves)
      .set("faces_split", r.faces_split)
      .set("faces_added", r.faces_added)
      .set("new_vertices", r.new_vertices)
      .set("degenerate_faces_kept", r.degenerate_faces_kept)
      .set("vertices_welded", r.vertices_welded)
      .set("time_ms", r.time_ms);
  return j;
}

}  // namespace meshmend
