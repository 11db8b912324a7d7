// bench_intersections [--repeat N] A [B]: intersecting-pair detection, ours
// against CGAL 5.5 and against an alternative candidate layout, on the same
// inputs in the same run. Prints one JSON object.
//
// With two meshes: cross pairs (ours; CGAL box_intersection_d + do_intersect;
// ours with median-split hierarchies, no hashed grid), and the self-
// intersections of the two joined into one mesh (ours; CGAL
// PMP::self_intersections; the alternative layout), which is the same job for
// all. With one mesh: its self-intersections (ours; CGAL; alternative).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>

#include <cstdio>

#include "benchmarks/cgal_mesh.h"
#include "benchmarks/harness.h"
#include "common/base/parallel.h"
#include "common/exact/intersections.h"
#include "common/exact/triangle_intersection.h"
#include "common/io/mesh_io.h"

using namespace meshmend;
using namespace meshmend::bench;
using K = Kernel;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

K::Triangle_3 cgalTriangle(const Mesh& m, std::size_t f) {
  auto p = [&](int k) {
    const Point3& q = m.face[f].cV(k)->cP();
    return K::Point_3(q[0], q[1], q[2]);
  };
  return {p(0), p(1), p(2)};
}

// ---- CGAL ------------------------------------------------------------------------

long cgalSelfIntersections(const SurfaceMesh& tm) {
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> out;
  PMP::self_intersections(tm, std::back_inserter(out));
  long pairs = 0;
  for (const auto& [f, g] : out) pairs += f != g;  // (f, f) marks a degenerate face
  return pairs;
}

// For inputs that are not a valid Surface_mesh (non-manifold edges): the
// same rule as PMP::self_intersections on the soup (cgal_mesh.h).
long cgalSoupSelfIntersections(const Mesh& m) {
  long degenerate = 0;
  return soupPairs(soupOf(m), degenerate);
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
  CGAL::box_intersection_d(ba.begin(), ba.end(), bb.begin(), bb.end(),
                           [&](const CgalBox& x, const CgalBox& y) {
                             pairs += CGAL::do_intersect(ta[x.info()], tb[y.info()]);
                           });
  return pairs;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine args(argc, argv);
  const int repeat = args.integer("--repeat", 5);
  if (!args.complete(1, 2, "bench_intersections [--repeat N] A [B]")) return 1;
  const std::vector<std::string>& files = args.files();
  const std::string a = files[0], b = files.size() > 1 ? files[1] : "";
  std::vector<Method> methods;
  if (!b.empty()) {
    methods.push_back({"meshmend_cross", "ours", [=] {
                         auto ma = std::make_shared<Mesh>(readMesh(a)),
                              mb = std::make_shared<Mesh>(readMesh(b));
                         return std::function<long()>([=] {
                           FindIntersectionsOptions o;
                           o.self = false;
                           return long(findIntersections({ma.get(), mb.get()}, o).cross_pairs);
                         });
                       }});
    methods.push_back({"cgal_box_intersection_d_cross", "peer", [=] {
                         auto ma = std::make_shared<Mesh>(readMesh(a)),
                              mb = std::make_shared<Mesh>(readMesh(b));
                         return std::function<long()>([=] { return cgalCross(*ma, *mb); });
                       }});
    methods.push_back({"meshmend_cross_median_layout", "alternative", [=] {
                         auto ma = std::make_shared<Mesh>(readMesh(a)),
                              mb = std::make_shared<Mesh>(readMesh(b));
                         return std::function<long()>([=] {
                           FindIntersectionsOptions o;
                           o.self = false;
                           o.layout = 1;
                           return long(findIntersections({ma.get(), mb.get()}, o).cross_pairs);
                         });
                       }});
  }
  const bool join = !b.empty();
  methods.push_back({join ? "meshmend_self_joined" : "meshmend_self", "ours", [=] {
                       auto m = std::make_shared<Mesh>(join ? appended(readMesh(a), readMesh(b))
                                                            : readMesh(a));
                       return std::function<long()>([=] {
                         FindIntersectionsOptions o;
                         o.cross = false;
                         return long(findIntersections({m.get()}, o).self_pairs[0]);
                       });
                     }});
  methods.push_back(
      {join ? "cgal_self_intersections_joined" : "cgal_self_intersections", "peer", [=] {
         // PMP::self_intersections needs a valid Surface_mesh; other inputs get
         // CGAL's box_self_intersection_d with the same rule (as meshcheck does).
         auto m = std::make_shared<Mesh>(join ? appended(readMesh(a), readMesh(b)) : readMesh(a));
         std::shared_ptr<SurfaceMesh> tm;
         try {
           tm = std::make_shared<SurfaceMesh>(toSurfaceMesh(*m));
         } catch (const std::exception&) {
         }
         return std::function<long()>(
             [=] { return tm ? cgalSelfIntersections(*tm) : cgalSoupSelfIntersections(*m); });
       }});
  methods.push_back({join ? "meshmend_self_joined_median_layout" : "meshmend_self_median_layout",
                     "alternative", [=] {
                       auto m = std::make_shared<Mesh>(join ? appended(readMesh(a), readMesh(b))
                                                            : readMesh(a));
                       return std::function<long()>([=] {
                         FindIntersectionsOptions o;
                         o.cross = false;
                         o.layout = 1;
                         return long(findIntersections({m.get()}, o).self_pairs[0]);
                       });
                     }});

  std::vector<JsonObject> results;
  for (const Method& m : methods) {
    const Measurement r = measure(m, repeat);
    results.push_back(toJson(r));
    std::fprintf(stderr, "  %-34s %s\n", m.name.c_str(), toJson(r).str().c_str());
  }
  JsonObject out;
  out.set("a", a)
      .set("b", b)
      .set("repeat", repeat)
      .set("workers", long(workerCount()))
      .set("methods", results);
  std::printf("%s\n", out.str(true).c_str());
}
