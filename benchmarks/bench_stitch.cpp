// bench_stitch [--repeat N] [--limit S] --paths N: stitching two border
// paths of N vertices each (two generated sheets side by side), ours alone:
// no peer library stitches two border paths across a gap (CGAL's
// stitch_borders only merges borders that already coincide).
//
// bench_stitch [--repeat N] [--limit S] FILE: closing the gaps of a soup
// (an STL as stored: three vertices per facet), ours (closeGaps with the
// filter's defaults, and without its verification of the result) against CGAL 5.5's
// PMP::stitch_borders on a Surface_mesh of the same soup (its points not merged first; a soup that
// is not a polygon mesh is oriented by PMP::orient_polygon_soup, as
// ../shared/tools/peer_stitch does). Both work on a copy made in the timed
// run (small next to the work); the result count is the border edges left.
//
// Prints one JSON object: the timed methods, and one untimed run of each
// (for the paths: with CPU times and stages).
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>

#include "benchmarks/cgal_mesh.h"
#include "benchmarks/harness.h"
#include "common/io/mesh_io.h"
#include "common/repair/stitch/stitch.h"

using namespace meshmend;
using namespace meshmend::bench;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

// Two sheets of `count` x 3 vertices facing each other across a gap of
// about 3 edge lengths, the second one half a step along and gently waved
// (not coplanar): path a is the first sheet's last row, path b the second
// sheet's first row, each `count` vertices.
struct TwoSheets {
  Mesh mesh;
  std::vector<int> a, b;
};

TwoSheets twoSheets(int count) {
  const int rows = 3;
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  TwoSheets s;
  for (int sheet = 0; sheet < 2; ++sheet) {
    const int first = int(points.size());
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < count; ++i) {
        const double x = i + 0.5 * sheet;
        const double y = sheet == 0 ? j : rows - 1 + 3 + j;
        const double z = sheet == 0 ? 0 : 0.5 * std::sin(x * 0.01) * (1 + j);
        points.emplace_back(x, y, z);
      }
    auto at = [&](int i, int j) { return first + j * count + i; };
    for (int j = 0; j + 1 < rows; ++j)
      for (int i = 0; i + 1 < count; ++i) {
        triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    for (int i = 0; i < count; ++i)
      (sheet == 0 ? s.a : s.b).push_back(at(i, sheet == 0 ? rows - 1 : 0));
  }
  buildMesh(s.mesh, points, triangles);
  return s;
}

double cpuMs(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) / 1e6;
}

SurfaceMesh cgalSoupMesh(const Mesh& soup) {
  std::vector<Kernel::Point_3> points;
  for (const Point3& p : positionsOf(soup)) points.emplace_back(p[0], p[1], p[2]);
  std::vector<std::vector<std::size_t>> polygons;
  for (const Triangle& t : trianglesOf(soup))
    polygons.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) PMP::orient_polygon_soup(points, polygons);
  SurfaceMesh tm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, tm);
  return tm;
}

std::size_t borderEdgesOf(const SurfaceMesh& tm) {
  std::size_t border = 0;
  for (auto e : tm.edges())
    if (tm.is_border(e)) ++border;
  return border;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine args(argc, argv);
  const int repeat = args.integer("--repeat", 5), limit = args.integer("--limit", 600),
            paths = args.integer("--paths", 0);
  const char* usage = "bench_stitch [--repeat N] [--limit SECONDS] (--paths N | FILE)";
  if (!args.complete(paths > 0 ? 0 : 1, paths > 0 ? 0 : 1, usage)) return 1;
  const std::string file = paths > 0 ? "" : args.files()[0];
  std::vector<Method> methods;
  JsonObject out;
  if (paths > 0) {
    // Each timed run stitches its own copy, made beforehand.
    for (const bool check : {false, true})
      methods.push_back({check ? "meshmend_stitch_checked" : "meshmend_stitch", "ours", [=] {
                           auto input = std::make_shared<TwoSheets>(twoSheets(paths));
                           auto copies = std::make_shared<std::vector<Mesh>>(repeat, input->mesh);
                           auto used = std::make_shared<std::size_t>(0);
                           return std::function<long()>([=] {
                             StitchOptions o;
                             o.a.vertices = input->a;
                             o.b.vertices = input->b;
                             o.check_intersections = check;
                             return long(stitchPaths((*copies)[(*used)++], o).faces_added);
                           });
                         }});
    // Untimed runs, without and with the check: CPU time of the calling
    // thread and of the whole process (both threads; on a busy machine the
    // wall time also waits for other programs), the stages and the outcome.
    const TwoSheets s = twoSheets(paths);
    out.set("paths", paths)
        .set("faces", std::size_t(s.mesh.fn))
        .set("vertices", std::size_t(s.mesh.vn));
    for (const bool check : {false, true}) {
      Mesh mesh(s.mesh);
      StitchOptions o;
      o.a.vertices = s.a;
      o.b.vertices = s.b;
      o.check_intersections = check;
      const double threadBefore = cpuMs(CLOCK_THREAD_CPUTIME_ID);
      const double processBefore = cpuMs(CLOCK_PROCESS_CPUTIME_ID);
      const StitchResult r = stitchPaths(mesh, o);
      JsonObject run;
      run.set("cpu_ms_calling_thread", cpuMs(CLOCK_THREAD_CPUTIME_ID) - threadBefore)
          .set("cpu_ms_process", cpuMs(CLOCK_PROCESS_CPUTIME_ID) - processBefore)
          .set("stage_ms", JsonObject()
                               .set("plan", r.stage_ms.plan)
                               .set("check", r.stage_ms.check)
                               .set("count", r.stage_ms.count)
                               .set("write", r.stage_ms.write))
          .set("outcome", toJson(r));
      out.set(check ? "checked" : "unchecked", run);
    }
  } else {
    for (const bool verify : {true, false})
      methods.push_back({verify ? "meshmend_close_gaps" : "meshmend_close_gaps_unverified",
                         verify ? "ours" : "alternative", [=] {
                           auto input = std::make_shared<Mesh>(readMesh(file));
                           return std::function<long()>([=] {
                             Mesh copy(*input);  // closing works in place
                             CloseGapsOptions o;
                             o.verify = verify;
                             return long(closeGaps(copy, o).border_edges_after);
                           });
                         }});
    methods.push_back({"cgal_stitch_borders", "peer", [=] {
                         auto input = std::make_shared<SurfaceMesh>(cgalSoupMesh(readMesh(file)));
                         return std::function<long()>([=] {
                           SurfaceMesh copy(*input);
                           PMP::stitch_borders(copy);
                           return long(borderEdgesOf(copy));
                         });
                       }});
    Mesh mesh = readMesh(file);
    out.set("file", file).set("faces", std::size_t(mesh.fn));
    out.set("outcome", toJson(closeGaps(mesh)));
  }
  std::vector<JsonObject> results;
  for (const Method& m : methods) {
    const Measurement r = measure(m, repeat, limit);
    results.push_back(toJson(r));
    std::fprintf(stderr, "  %-28s %s\n", m.name.c_str(), toJson(r).str().c_str());
  }
  out.set("repeat", repeat).set("methods", results);
  std::printf("%s\n", out.str(true).c_str());
}
