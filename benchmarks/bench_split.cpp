// bench_split [--repeat N] [--limit S] [--sample] [--autorefine]
//             [--warm-allocator] A B:
// intersect-and-split, ours against CGAL 5.5 on the same inputs in the same
// run. Prints one JSON object. With --warm-allocator every method runs with
// glibc's malloc as a host that has handled large meshes has it
// (warmAllocator() in harness.h), so that no method's time includes memory
// handed back to the system after one run and faulted in by the next.
//
// Ours: splitAlongIntersections with the merged output off
// (meshmend_split_refine: the curves inserted into both meshes, the two
// refined meshes built: what corefine does), and as a second line the default
// (meshmend_split: the welded merged mesh built too). With --sample, ours
// runs the configuration of samples/intersect_split.mlx instead (seams
// welded, duplicate faces removed, self-intersections split too, merged
// output, rounded to float): the filter's own work. CGAL: PMP::corefine on
// two Surface_mesh copies (the same job: both meshes refined along their
// intersection, in place, so the copies are timed as ours times reading its
// input into arrays), with its default parameters (cgal_corefine) and with
// throw_on_self_intersection (cgal_corefine_checked, which first searches
// each mesh for self-intersections near the curves and throws on one;
// corefine's result is unspecified on such inputs without it). With --sample
// only the checked one runs (the dragon self-intersects). With --autorefine
// also PMP::experimental::autorefine of the two joined into one mesh (CGAL
// 5.5's only way to refine a mesh along its own self-intersections). Each
// method runs under a time limit (--limit).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "benchmarks/cgal_mesh.h"
#include "benchmarks/harness.h"
#include "common/io/mesh_io.h"
#include "common/repair/output_stage.h"
#include "common/repair/split/split.h"

using namespace meshmend;
using namespace meshmend::bench;
using K = Kernel;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {}  // namespace

int main(int argc, char** argv) {
  CommandLine args(argc, argv, {"--sample", "--output-stage", "--autorefine", "--warm-allocator"});
  const int repeat = args.integer("--repeat", 3), limit = args.integer("--limit", 600);
  const bool sample = args.flag("--sample"), autorefine = args.flag("--autorefine"),
             warm = args.flag("--warm-allocator"), outputStage = args.flag("--output-stage");
  if (!args.complete(2, 2,
                     "bench_split [--repeat N] [--limit SECONDS] [--sample] [--autorefine] "
                     "[--warm-allocator] [--output-stage] A B"))
    return 1;
  const std::vector<std::string>& files = args.files();
  if (warm) warmAllocator();  // before the children fork: all methods alike
  const std::string a = files[0], b = files[1];
  std::vector<Method> methods;
  auto ours = [&](const char* name, const char* role, bool merged) {
    methods.push_back({name, role, [=] {
                         auto ma = std::make_shared<Mesh>(readMesh(a));
                         auto mb = std::make_shared<Mesh>(readMesh(b));
                         return std::function<long()>([=] {
                           SplitOptions o;
                           o.merged_output = merged;
                           if (sample) {
                             o.self = o.weld_duplicates = o.remove_duplicate_faces = true;
                             o.separate_meshes = false;
                           }
                           SplitResult r = splitAlongIntersections({ma.get(), mb.get()}, o);
                           OutputStageOptions stage;
                           stage.scalar = Scalar::kFloat;
                           if (sample && roundForHost(r, stage) != 0) return -1L;
                           return long(r.faces_split);
                         });
                       }});
  };
  // The output stage (output_stage.h) after the sample's split, for each
  // host scalar, and with the check of the stored result the filter makes
  // (storedIntersectingPairs). The result of the stage's methods is the
  // median of its own times over the runs so far, in microseconds (-1
  // where it left defects), of the checked one the intersecting pairs the
  // check counts.
  auto stored = [&](const char* name, std::optional<Scalar> scalar, bool check) {
    methods.push_back({name, "ours", [=] {
                         auto ma = std::make_shared<Mesh>(readMesh(a));
                         auto mb = std::make_shared<Mesh>(readMesh(b));
                         auto times = std::make_shared<std::vector<long>>();
                         return std::function<long()>([=] {
                           SplitOptions o;
                           o.self = o.weld_duplicates = o.remove_duplicate_faces = true;
                           o.separate_meshes = false;
                           SplitResult r = splitAlongIntersections({ma.get(), mb.get()}, o);
                           if (scalar) {
                             OutputStageOptions stage;
                             stage.scalar = *scalar;
                             const StoredOutput s = storeForHost(r, {ma.get(), mb.get()}, o, stage);
                             if (check) return long(storedIntersectingPairs(r.merged, *scalar));
                             // The stage's own time, in microseconds (-1: defects left).
                             if (s.crossing + s.degenerate_new_faces > 0) return -1L;
                             times->push_back(long(s.time_ms * 1000));
                             std::vector<long> sorted = *times;
                             std::sort(sorted.begin(), sorted.end());
                             return sorted[sorted.size() / 2];
                           }
                           return long(r.faces_split);
                         });
                       }});
  };
  if (outputStage) {
    stored("meshmend_split_sample_unstored", std::nullopt, false);
    stored("meshmend_store_float", Scalar::kFloat, false);
    stored("meshmend_store_double", Scalar::kDouble, false);
    stored("meshmend_store_float_checked", Scalar::kFloat, true);
  } else if (sample) {
    ours("meshmend_split_sample", "ours", true);
  } else {
    ours("meshmend_split_refine", "ours", false);
    ours("meshmend_split", "alternative", true);
  }
  auto corefine = [&](const char* name, bool checked) {
    methods.push_back({name, "peer", [=] {
                         auto ta = std::make_shared<SurfaceMesh>(toSurfaceMesh(readMesh(a)));
                         auto tb = std::make_shared<SurfaceMesh>(toSurfaceMesh(readMesh(b)));
                         return std::function<long()>([=] {
                           SurfaceMesh x = *ta, y = *tb;  // corefine works in place
                           PMP::corefine(x, y,
                                         CGAL::parameters::throw_on_self_intersection(checked));
                           return long(x.number_of_faces() + y.number_of_faces());
                         });
                       }});
  };
  if (!sample && !outputStage) corefine("cgal_corefine", false);
  if (!outputStage) corefine("cgal_corefine_checked", true);
  if (autorefine)
    methods.push_back({"cgal_autorefine", "peer", [=] {
                         auto joined = std::make_shared<SurfaceMesh>(
                             toSurfaceMesh(appended(readMesh(a), readMesh(b))));
                         return std::function<long()>([=] {
                           SurfaceMesh x = *joined;
                           PMP::experimental::autorefine(x);
                           return long(x.number_of_faces());
                         });
                       }});
  std::vector<JsonObject> results;
  for (const Method& m : methods) {
    const Measurement r = measure(m, repeat, limit);
    results.push_back(toJson(r));
    std::fprintf(stderr, "  %-20s %s\n", m.name.c_str(), toJson(r).str().c_str());
  }
  JsonObject out;
  out.set("a", a)
      .set("b", b)
      .set("repeat", repeat)
      .set("warm_allocator", warm)
      .set("methods", results);
  std::printf("%s\n", out.str(true).c_str());
}
