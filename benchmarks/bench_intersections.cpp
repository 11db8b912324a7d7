// bench_intersections [--repeat N] A [B]: intersecting-pair detection, ours
// against CGAL 5.5 and against an alternative candidate layout, on the same
// inputs in the same run. Prints one JSON object.
//
// With two meshes: cross pairs (ours; CGAL box_intersection_d + do_intersect;
// a sort-and-sweep layout), and the self-intersections of the two joined into
// one mesh (ours; CGAL PMP::self_intersections), which is the same job for
// both. With one mesh: its self-intersections (ours; CGAL; sweep).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>

#include <atomic>
#include <cstdio>
#include <cstring>

#include "benchmarks/harness.h"
#include "common/box_tree.h"
#include "common/intersections.h"
#include "common/mesh_io.h"
#include "common/parallel.h"
#include "common/predicates.h"

using namespace meshmend;
using namespace meshmend::bench;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

Mesh joined(const Mesh& a, const Mesh& b) {
  std::vector<Point3> p = positionsOf(a), pb = positionsOf(b);
  std::vector<Triangle> t = trianglesOf(a);
  const int offset = int(p.size());
  p.insert(p.end(), pb.begin(), pb.end());
  for (Triangle f : trianglesOf(b)) t.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  return makeMesh(p, t);
}

K::Triangle_3 cgalTriangle(const Mesh& m, std::size_t f) {
  auto p = [&](int k) {
    const Point3& q = m.face[f].cV(k)->cP();
    return K::Point_3(q[0], q[1], q[2]);
  };
  return {p(0), p(1), p(2)};
}

// ---- the alternative layout: sort-and-sweep along x --------------------------

struct Swept {
  std::vector<Box> boxes;
  std::vector<std::uint32_t> order;  // by lo.x
  std::vector<bool> degenerate;
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  explicit Swept(const Mesh& m) : points(positionsOf(m)), triangles(trianglesOf(m)) {
    for (const Triangle& t : triangles) {
      boxes.push_back(boxOf(points[t[0]], points[t[1]], points[t[2]]));
      degenerate.push_back(collinear(points[t[0]], points[t[1]], points[t[2]]));
    }
    order.resize(boxes.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t x, std::uint32_t y) { return boxes[x].lo[0] < boxes[y].lo[0]; });
  }
  TrianglePoints at(std::uint32_t f) const {
    return {points[triangles[f][0]], points[triangles[f][1]], points[triangles[f][2]]};
  }
};

bool selfRule(const Swept& s, std::uint32_t f, std::uint32_t g) {
  const Triangle &a = s.triangles[f], &b = s.triangles[g];
  int shared = 0, ia = -1, ib = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a[i] == b[j]) ++shared, ia = i, ib = j;
  if (shared == 2) {
    for (int i = 0; i < 3; ++i)
      if (a[i] != b[0] && a[i] != b[1] && a[i] != b[2]) ia = i;
    for (int j = 0; j < 3; ++j)
      if (b[j] != a[0] && b[j] != a[1] && b[j] != a[2]) ib = j;
  }
  return intersectBeyondShared(s.at(f), s.at(g), shared, ia, ib);
}

long sweepSelf(const Swept& s) {
  std::atomic<long> found{0};
  parallelChunks(s.order.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    long local = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t f = s.order[i];
      if (s.degenerate[f]) continue;
      for (std::size_t j = i + 1; j < s.order.size() && s.boxes[s.order[j]].lo[0] <= s.boxes[f].hi[0]; ++j) {
        const std::uint32_t g = s.order[j];
        if (!s.degenerate[g] && overlap(s.boxes[f], s.boxes[g]) && selfRule(s, std::min(f, g), std::max(f, g)))
          ++local;
      }
    }
    found += local;
  });
  return found;
}

long sweepCross(const Swept& a, const Swept& b) {
  // Every box of b against the boxes of a whose x-interval overlaps it.
  std::atomic<long> found{0};
  parallelChunks(b.boxes.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    long local = 0;
    for (std::size_t g = begin; g < end; ++g) {
      if (b.degenerate[g]) continue;
      const Box& bg = b.boxes[g];
      // a's boxes starting at or before bg's end; those ending before bg's start fail overlap().
      const auto last = std::upper_bound(a.order.begin(), a.order.end(), bg.hi[0],
                                         [&](float x, std::uint32_t f) { return x < a.boxes[f].lo[0]; });
      for (auto it = a.order.begin(); it != last; ++it)
        if (!a.degenerate[*it] && overlap(a.boxes[*it], bg) && trianglesIntersect(a.at(*it), b.at(std::uint32_t(g))))
          ++local;
    }
    found += local;
  });
  return found;
}

// ---- CGAL ------------------------------------------------------------------------

long cgalSelfIntersections(const SurfaceMesh& tm) {
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> out;
  PMP::self_intersections(tm, std::back_inserter(out));
  long pairs = 0;
  for (const auto& [f, g] : out) pairs += f != g;  // (f, f) marks a degenerate face
  return pairs;
}

SurfaceMesh toSurfaceMesh(const Mesh& m) {
  std::vector<K::Point_3> points;
  for (const Point3& p : positionsOf(m)) points.emplace_back(p[0], p[1], p[2]);
  std::vector<std::vector<std::size_t>> polygons;
  for (const Triangle& t : trianglesOf(m)) polygons.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    throw std::runtime_error("not a polygon mesh for CGAL's Surface_mesh");
  SurfaceMesh tm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, tm);
  return tm;
}

long cgalCross(const Mesh& a, const Mesh& b) {
  using CgalBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;
  std::vector<CgalBox> ba, bb;
  std::vector<K::Triangle_3> ta, tb;
  for (std::size_t f = 0; f < a.face.size(); ++f) {
    ta.push_back(cgalTriangle(a, f));
    if (!ta.back().is_degenerate()) ba.emplace_back(ta.back().bbox(), f);
  }
  for (std::size_t f = 0; f < b.face.size(); ++f) {
    tb.push_back(cgalTriangle(b, f));
    if (!tb.back().is_degenerate()) bb.emplace_back(tb.back().bbox(), f);
  }
  long pairs = 0;
  CGAL::box_intersection_d(ba.begin(), ba.end(), bb.begin(), bb.end(), [&](const CgalBox& x, const CgalBox& y) {
    pairs += CGAL::do_intersect(ta[x.info()], tb[y.info()]);
  });
  return pairs;
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::atoi(argv[++i]);
    else
      files.push_back(argv[i]);
  }
  if (files.empty() || files.size() > 2) {
    std::fprintf(stderr, "usage: bench_intersections [--repeat N] A [B]\n");
    return 1;
  }
  const std::string a = files[0], b = files.size() > 1 ? files[1] : "";
  std::vector<Method> methods;
  if (!b.empty()) {
    methods.push_back({"meshmend_cross", "ours", [=] {
      auto ma = std::make_shared<Mesh>(readMesh(a)), mb = std::make_shared<Mesh>(readMesh(b));
      return std::function<long()>([=] {
        FindIntersectionsOptions o;
        o.self = false;
        return long(findIntersections({ma.get(), mb.get()}, o).cross_pairs);
      });
    }});
    methods.push_back({"cgal_box_intersection_d_cross", "peer", [=] {
      auto ma = std::make_shared<Mesh>(readMesh(a)), mb = std::make_shared<Mesh>(readMesh(b));
      return std::function<long()>([=] { return cgalCross(*ma, *mb); });
    }});
    methods.push_back({"sweep_cross", "alternative", [=] {
      auto sa = std::make_shared<Swept>(readMesh(a)), sb = std::make_shared<Swept>(readMesh(b));
      return std::function<long()>([=] { return sweepCross(*sa, *sb); });
    }});
  }
  const bool join = !b.empty();
  methods.push_back({join ? "meshmend_self_joined" : "meshmend_self", "ours", [=] {
    auto m = std::make_shared<Mesh>(join ? joined(readMesh(a), readMesh(b)) : readMesh(a));
    return std::function<long()>([=] {
      FindIntersectionsOptions o;
      o.cross = false;
      return long(findIntersections({m.get()}, o).self_pairs[0]);
    });
  }});
  methods.push_back({join ? "cgal_self_intersections_joined" : "cgal_self_intersections", "peer", [=] {
    auto tm = std::make_shared<SurfaceMesh>(toSurfaceMesh(join ? joined(readMesh(a), readMesh(b)) : readMesh(a)));
    return std::function<long()>([=] { return cgalSelfIntersections(*tm); });
  }});
  if (!join)
    methods.push_back({"sweep_self", "alternative", [=] {
      auto s = std::make_shared<Swept>(readMesh(a));
      return std::function<long()>([=] { return sweepSelf(*s); });
    }});

  std::vector<JsonObject> results;
  for (const Method& m : methods) {
    const Measurement r = measure(m, repeat);
    results.push_back(toJson(r));
    std::fprintf(stderr, "  %-34s %s\n", m.name.c_str(), toJson(r).str().c_str());
  }
  JsonObject out;
  out.set("a", a).set("b", b).set("repeat", repeat).set("workers", long(workerCount())).set("methods", results);
  std::printf("%s\n", out.str(true).c_str());
}
