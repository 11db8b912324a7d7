// bench_selfintersect [--repeat N] [--limit S] [--threads N] FILE:
// self-intersection removal, ours against CGAL 5.5 on the same input in the
// same run. Prints one JSON object.
//
// Ours: removeSelfIntersections with the options of the filter (defaults,
// rounded to float as MeshLab stores the result; its own verification
// included), on --threads threads (default 1, as the peers; 0: every CPU),
// and as meshmend_remove_self_intersections_all_cores on every CPU. CGAL:
// PMP::experimental::remove_self_intersections (local smoothing and hole filling;
// repair_self_intersections.h) and PMP::experimental::autorefine_and_remove_self_intersections
// (autorefine, drop the inner patches, stitch; corefinement.h in 5.5, autorefinement.h only exists
// from 6.0), each on its own Surface_mesh copy. A file that a Surface_mesh refuses (non-manifold
// edges or vertices) is first repaired as a CGAL user would: repair_polygon_soup, then
// orient_polygon_soup. The autorefinement needs a mesh without degenerate faces: it is skipped
// otherwise.
//
// Success is checked independently: in its child process, each method's
// first run is timed by hand and its output measured, untimed (faces,
// border and non-manifold edges and vertices by vertex index, and the
// intersecting pairs left by CGAL's PMP::self_intersections); the harness
// then times the other N - 1 runs. The first run's time and the check reach
// the parent through shared memory. A method whose first run takes more than
// 10 s is not repeated. Each method runs under a time limit (--limit,
// covering all its runs).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <new>
#include <numeric>

#include <sys/mman.h>

#include "benchmarks/cgal_mesh.h"
#include "benchmarks/harness.h"
#include "common/base/parallel.h"
#include "common/io/mesh_io.h"
#include "common/repair/selfintersect/selfintersect.h"

using namespace meshmend;
using namespace meshmend::bench;
using K = Kernel;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

constexpr double kSlowMs = 10000;  // a method slower than this runs once

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

using meshmend::bench::soupOf;  // and the core mesh's (cgal_mesh.h)

Soup soupOf(SurfaceMesh& tm) {
  tm.collect_garbage();  // vertex indices 0..n-1
  Soup s;
  for (SurfaceMesh::Vertex_index v : tm.vertices()) s.points.push_back(tm.point(v));
  for (SurfaceMesh::Face_index f : tm.faces()) {
    std::vector<std::size_t> corners;
    for (SurfaceMesh::Vertex_index v : CGAL::vertices_around_face(tm.halfedge(f), tm))
      corners.push_back(std::size_t(v));
    if (corners.size() != 3) throw std::runtime_error("output has a face that is not a triangle");
    s.triangles.push_back(corners);
  }
  return s;
}

// The untimed check of one output (or of the input), written by a child
// into memory it shares with the parent: plain data only.
struct Outcome {
  bool checked = false;
  double first_run_ms = 0;       // the method's first run, timed in its child
  bool claimed = false;          // the method's own verdict: no intersection left
  bool input_repaired = false;   // CGAL: the file needed repair_polygon_soup + orient_polygon_soup
  long input_degenerate = 0;     // CGAL: degenerate faces of its input mesh
  long input_pairs = 0;          // CGAL: intersecting pairs of its input mesh
  long vertices = 0, faces = 0;  // referenced vertices, faces
  long components = 0;           // connected through shared vertices
  long border_edges = 0, non_manifold_edges = 0, non_manifold_vertices = 0;
  long degenerate_faces = 0;           // collinear corners (exact)
  long remaining_pairs = 0;            // intersecting pairs (the rule of PMP::self_intersections)
  bool pairs_by_surface_mesh = false;  // PMP::self_intersections (else the soup rule)
};

// Stores the check of a method's first run, keeping what prepare noted before.
void record(Outcome* outcome, Outcome checked, double ms, bool claimed) {
  checked.first_run_ms = ms;
  checked.claimed = claimed;
  checked.input_repaired = outcome->input_repaired;
  checked.input_degenerate = outcome->input_degenerate;
  checked.input_pairs = outcome->input_pairs;
  *outcome = checked;
}

Outcome* sharedOutcome() {
  void* p =
      mmap(nullptr, sizeof(Outcome), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::runtime_error("mmap failed");
  return new (p) Outcome();
}

std::size_t findRoot(std::vector<std::size_t>& parent, std::size_t x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

Outcome check(const Soup& s) {
  Outcome o;
  o.checked = true;
  o.faces = long(s.triangles.size());
  // Edges by vertex index: used once = border, more than twice = non-manifold.
  struct Use {
    std::size_t u, v, face;
    bool operator<(const Use& x) const {
      return u != x.u ? u < x.u : v != x.v ? v < x.v : face < x.face;
    }
  };
  std::vector<Use> uses;
  for (std::size_t f = 0; f < s.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::size_t a = s.triangles[f][k], b = s.triangles[f][(k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), f});
    }
  std::sort(uses.begin(), uses.end());
  // Corners (3 f + k) around a vertex are joined across the edges they share:
  // a vertex whose corners form more than one fan is non-manifold.
  std::vector<std::size_t> parent(3 * s.triangles.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto corner = [&](std::size_t f, std::size_t v) {
    const auto& t = s.triangles[f];
    return 3 * f + (t[0] == v ? 0 : t[1] == v ? 1 : 2);
  };
  for (std::size_t i = 0, j; i < uses.size(); i = j) {
    for (j = i + 1; j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v;) ++j;
    o.border_edges += j - i == 1;
    o.non_manifold_edges += j - i > 2;
    for (std::size_t k = i + 1; k < j; ++k)
      for (std::size_t v : {uses[i].u, uses[i].v}) {
        const std::size_t a = findRoot(parent, corner(uses[k].face, v));
        parent[a] = findRoot(parent, corner(uses[i].face, v));
      }
  }
  // Components: vertices joined through their faces.
  std::vector<std::size_t> part(s.points.size());
  std::iota(part.begin(), part.end(), 0);
  for (const auto& t : s.triangles)
    for (int k = 1; k < 3; ++k) {
      const std::size_t a = findRoot(part, t[k]);
      part[a] = findRoot(part, t[0]);
    }
  std::vector<std::size_t> fan(s.points.size(), SIZE_MAX);  // the first fan's root, per vertex
  std::vector<char> counted(s.points.size(), 0);
  for (std::size_t f = 0; f < s.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = s.triangles[f][k], root = findRoot(parent, 3 * f + k);
      if (fan[v] == SIZE_MAX) {
        fan[v] = root;
        ++o.vertices;
        o.components += findRoot(part, v) == v;
      } else if (fan[v] != root && !counted[v]) {
        counted[v] = 1;
        ++o.non_manifold_vertices;
      }
    }
  // Intersecting pairs: PMP::self_intersections on a Surface_mesh when the
  // soup is one (it reports a degenerate face f as the pair (f, f)).
  if (PMP::is_polygon_soup_a_polygon_mesh(s.triangles)) {
    SurfaceMesh tm;
    PMP::polygon_soup_to_polygon_mesh(s.points, s.triangles, tm);
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> out;
    PMP::self_intersections(tm, std::back_inserter(out));
    for (const auto& [f, g] : out) (f == g ? o.degenerate_faces : o.remaining_pairs) += 1;
    o.pairs_by_surface_mesh = true;
  } else {
    o.remaining_pairs = soupPairs(s, o.degenerate_faces);
  }
  return o;
}

JsonObject toJson(const Outcome& o) {
  JsonObject j;
  j.set("faces", o.faces)
      .set("vertices", o.vertices)
      .set("components", o.components)
      .set("remaining_pairs", o.remaining_pairs)
      .set("border_edges", o.border_edges)
      .set("non_manifold_edges", o.non_manifold_edges)
      .set("non_manifold_vertices", o.non_manifold_vertices)
      .set("degenerate_faces", o.degenerate_faces)
      .set("closed", o.faces > 0 && o.border_edges == 0 && o.non_manifold_edges == 0)
      .set("manifold", o.non_manifold_edges == 0 && o.non_manifold_vertices == 0)
      .set("pairs_by", o.pairs_by_surface_mesh ? "PMP::self_intersections" : "soup rule");
  return j;
}

// The input as a CGAL user would give it to the peers.
SurfaceMesh cgalInput(const Mesh& m, bool& repaired) {
  repaired = false;
  try {
    return toSurfaceMesh(m);
  } catch (const std::runtime_error&) {
    repaired = true;
  }
  Soup s = soupOf(m);
  PMP::repair_polygon_soup(s.points, s.triangles);
  PMP::orient_polygon_soup(s.points, s.triangles);
  if (!PMP::is_polygon_soup_a_polygon_mesh(s.triangles))
    throw std::runtime_error(
        "not a polygon mesh even after repair_polygon_soup + orient_polygon_soup");
  SurfaceMesh tm;
  PMP::polygon_soup_to_polygon_mesh(s.points, s.triangles, tm);
  return tm;
}

// A CGAL function that works in place and returns its own verdict; the runs
// after the first work on copies made beforehand.
Method cgalMethod(const std::string& name, const std::string& file, int repeat, Outcome* outcome,
                  bool needsNonDegenerate, std::function<bool(SurfaceMesh&)> function) {
  return {name, "peer", [=] {
            bool repaired = false;
            const SurfaceMesh input = cgalInput(readMesh(file), repaired);
            long degenerate = 0;
            for (SurfaceMesh::Face_index f : input.faces())
              degenerate += PMP::is_degenerate_triangle_face(f, input);
            outcome->input_repaired = repaired;
            outcome->input_degenerate = degenerate;
            if (needsNonDegenerate && degenerate > 0)
              throw std::runtime_error("skipped: " + std::to_string(degenerate) +
                                       " degenerate faces (precondition)");
            SurfaceMesh first = input;
            outcome->input_pairs = check(soupOf(first)).remaining_pairs;
            const auto start = std::chrono::steady_clock::now();
            const bool claimed = function(first);
            const double ms = msSince(start);
            record(outcome, check(soupOf(first)), ms, claimed);
            const std::size_t runs = ms > kSlowMs ? 0 : std::size_t(repeat - 1);
            auto copies = std::make_shared<std::vector<SurfaceMesh>>(runs, input);
            auto next = std::make_shared<std::size_t>(0);
            return std::function<long()>([=] {
              if (*next == copies->size()) return 0L;  // slow: not repeated
              SurfaceMesh& x = (*copies)[(*next)++];
              function(x);
              return long(x.number_of_faces());
            });
          }};
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine args(argc, argv);
  const int repeat = std::max(1, args.integer("--repeat", 3)), limit = args.integer("--limit", 600),
            threads = std::max(0, args.integer("--threads", 1));
  if (!args.complete(1, 1,
                     "bench_selfintersect [--repeat N] [--limit SECONDS] [--threads N (0: all)] "
                     "FILE"))
    return 1;
  const std::string file = args.files()[0];
  std::vector<Method> methods;
  std::vector<Outcome*> outcomes;
  for (const char* name :
       {"meshmend_remove_self_intersections", "meshmend_remove_self_intersections_all_cores"}) {
    outcomes.push_back(sharedOutcome());
    const bool first = methods.empty();
    methods.push_back({name, first ? "ours" : "alternative", [=, outcome = outcomes.back()] {
                         auto input = std::make_shared<Mesh>(readMesh(file));
                         SelfIntersectionOptions options;  // as the filter sets them
                         options.round_to_float = true;
                         const auto start = std::chrono::steady_clock::now();
                         const SelfIntersectionResult r = removeSelfIntersections(*input, options);
                         const double ms = msSince(start);
                         record(outcome, check(soupOf(r.mesh)), ms,
                                r.verified && r.remaining_intersecting_pairs == 0);
                         const bool slow = ms > kSlowMs;
                         return std::function<long()>([=] {
                           return slow ? 0L
                                       : long(removeSelfIntersections(*input, options).mesh.fn);
                         });
                       }});
  }
  outcomes.push_back(sharedOutcome());
  methods.push_back(
      cgalMethod("cgal_remove_self_intersections", file, repeat, outcomes.back(), false,
                 [](SurfaceMesh& m) { return PMP::experimental::remove_self_intersections(m); }));
  outcomes.push_back(sharedOutcome());
  methods.push_back(cgalMethod("cgal_autorefine_and_remove_self_intersections", file, repeat,
                               outcomes.back(), true, [](SurfaceMesh& m) {
                                 return PMP::experimental::autorefine_and_remove_self_intersections(
                                     m);
                               }));
  std::vector<JsonObject> results;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    // Ours on the threads asked for (every CPU for *_all_cores); the peers
    // use one whatever this says.
    const bool ours = methods[i].name.rfind("meshmend", 0) == 0;
    setThreadCount(methods[i].name.find("_all_cores") != std::string::npos ? 0 : unsigned(threads));
    const unsigned used = ours ? workerCount() : 1;
    Measurement r = measure(methods[i], repeat - 1, limit);
    const Outcome& o = *outcomes[i];
    if (r.ok) {  // the first run is the first sample; a slow method ran only that one
      if (o.first_run_ms > kSlowMs) r.times_ms.clear();
      r.times_ms.insert(r.times_ms.begin(), o.first_run_ms);
      std::vector<double> sorted = r.times_ms;
      std::sort(sorted.begin(), sorted.end());
      r.median_ms = sorted[sorted.size() / 2];
      r.min_ms = sorted.front();
      r.result = o.faces;
    } else {
      r.error.erase(0, r.error.find_first_not_of(' '));  // an exception's message, as passed on
    }
    JsonObject j = toJson(r);
    j.set("threads", long(used));
    if (o.checked) j.set("claimed_success", o.claimed).set("check", toJson(o));
    if (methods[i].role == "peer")
      j.set("input_repaired", o.input_repaired)
          .set("input_degenerate_faces", o.input_degenerate)
          .set("input_pairs", o.input_pairs);
    results.push_back(j);
    std::fprintf(stderr, "  %-46s %s\n", methods[i].name.c_str(), j.str().c_str());
  }
  // The input, measured the same way (in the parent, after the children).
  const Outcome input = check(soupOf(readMesh(file)));
  JsonObject out;
  out.set("file", file).set("repeat", repeat).set("input", toJson(input)).set("methods", results);
  std::printf("%s\n", out.str(true).c_str());
}
