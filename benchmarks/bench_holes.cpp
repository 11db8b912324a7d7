// bench_holes [--repeat N] [--limit S] [--threads N] [--methods a,b,...] [--out-dir DIR] FILE:
// hole filling, ours against CGAL 5.5 and MeshLab's own "Close Holes" on the
// same holes in the same run. Fills every hole of FILE. Prints one JSON object.
//
// Methods:
//   meshmend_biharmonic   ours, fillHoles with the default options (the
//                         biharmonic shape), on --threads threads (default 1)
//   meshmend_biharmonic_all_cores
//                         the same on every CPU the process may use
//   meshmend_regression, meshmend_harmonic, meshmend_flat
//                         ours with the other patch shapes (regression: the
//                         paper's LS-SVM Laplacian regression)
//   cgal_refine_fair      PMP::triangulate_refine_and_fair_hole on each border
//                         cycle (defaults: Delaunay search space, fairing
//                         continuity 1), on a Surface_mesh copy; only the calls
//                         are timed (the cycles are found beforehand); one
//                         thread (CGAL's hole filling has no parallel code)
//   meshlab_close_holes   the work of MeshLab 2020.09's filter "Close Holes"
//                         (meshfilter.cpp, FP_CLOSE_HOLES with its default
//                         "prevent self-intersections"): face-face adjacency,
//                         the non-manifold edge check, then vcglib's
//                         Hole::EarCuttingIntersectionFill with
//                         SelfIntersectionEar, on a float mesh like CMeshO,
//                         compiled here from the same vcglib headers
//
// Each method runs in child processes (benchmarks/harness.h). A first child
// loads the input, then copies and fills it once, timing the fill by hand:
// its peak memory (the input, its copy and the fill; the harness resets the
// peak once the input is loaded) is the method's. The harness then times N
// runs on copies made beforehand, so that copying the input is never timed.
// A method whose first run takes over 10 s is not repeated. With --out-dir,
// a last child writes the filled mesh (DIR/<method>.ply for ours, .off for
// the peers) and a report (DIR/<method>.json: faces added, ours' full
// HoleFillResult, and for ours the medians of its own per-hole and
// per-stage times over N more fills).
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include <vcg/complex/algorithms/clean.h>
#include <vcg/complex/algorithms/hole.h>
#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/append.h>
#include <vcg/complex/complex.h>

#include "benchmarks/cgal_mesh.h"
#include "benchmarks/harness.h"
#include "common/base/parallel.h"
#include "common/io/mesh_io.h"
#include "common/repair/holes/holes.h"

using namespace meshmend;
using namespace meshmend::bench;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

constexpr double kSlowMs = 10000;  // a method slower than this runs once

// The components of MeshLab's CMeshO that vcglib's hole filling touches:
// float coordinates, normals, flags, marks and face-face adjacency.
class MlVertex;
class MlFace;
struct MlTypes
    : public vcg::UsedTypes<vcg::Use<MlVertex>::AsVertexType, vcg::Use<MlFace>::AsFaceType> {};
class MlVertex : public vcg::Vertex<MlTypes, vcg::vertex::Coord3f, vcg::vertex::Normal3f,
                                    vcg::vertex::BitFlags, vcg::vertex::Mark> {};
class MlFace : public vcg::Face<MlTypes, vcg::face::VertexRef, vcg::face::FFAdj,
                                vcg::face::Normal3f, vcg::face::BitFlags, vcg::face::Mark> {};
class MlMesh : public vcg::tri::TriMesh<std::vector<MlVertex>, std::vector<MlFace>> {};

void toMlMesh(const Mesh& in, MlMesh& out) {
  const std::vector<Point3> points = positionsOf(in);
  const std::vector<Triangle> triangles = trianglesOf(in);
  auto v = vcg::tri::Allocator<MlMesh>::AddVertices(out, points.size());
  for (const Point3& p : points) (v++)->P() = vcg::Point3f(float(p[0]), float(p[1]), float(p[2]));
  auto f = vcg::tri::Allocator<MlMesh>::AddFaces(out, triangles.size());
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) f->V(k) = &out.vert[std::size_t(t[k])];
    ++f;
  }
  // What meshlabserver does after loading (MeshModel::UpdateBoxAndNormals):
  // the ears' quality reads the face normals around the hole.
  vcg::tri::UpdateBounding<MlMesh>::Box(out);
  vcg::tri::UpdateNormal<MlMesh>::PerFaceNormalized(out);
  vcg::tri::UpdateNormal<MlMesh>::PerVertexAngleWeighted(out);
}

// MeshLab's filter: adjacency, refusal of non-manifold edges, ear cutting
// of every hole below MaxHoleSize (the benchmark's holes are all below the
// limit given). Returns the faces added.
long closeHolesLikeMeshLab(MlMesh& m) {
  const std::size_t before = std::size_t(m.fn);
  vcg::tri::UpdateTopology<MlMesh>::FaceFace(m);
  if (vcg::tri::Clean<MlMesh>::CountNonManifoldEdgeFF(m) > 0)
    throw std::runtime_error("non-manifold edges: MeshLab's filter refuses the mesh");
  vcg::tri::Hole<MlMesh>::EarCuttingIntersectionFill<vcg::tri::SelfIntersectionEar<MlMesh>>(
      m, 1 << 30, false);
  return long(std::size_t(m.fn) - before);
}

void writeOff(const std::string& path, MlMesh& m) {
  vcg::tri::Allocator<MlMesh>::CompactEveryVector(m);
  std::ofstream out(path);
  out.precision(17);  // a float widened to double, written exactly
  out << "OFF\n" << m.vn << ' ' << m.fn << " 0\n";
  for (const MlVertex& v : m.vert)
    out << double(v.cP()[0]) << ' ' << double(v.cP()[1]) << ' ' << double(v.cP()[2]) << '\n';
  for (const MlFace& f : m.face)
    out << "3 " << vcg::tri::Index(m, f.cV(0)) << ' ' << vcg::tri::Index(m, f.cV(1)) << ' '
        << vcg::tri::Index(m, f.cV(2)) << '\n';
  if (!out) throw std::runtime_error("cannot write " + path);
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

// How one method fills a copy of the input: `load` builds the input once
// (untimed), `fill` fills one copy, `write` saves a filled copy and its report.
template <class M>
struct Filler {
  std::function<M()> load;
  std::function<long(M&)> fill;
  std::function<void(M&, long faces, double ms, const std::string& stem)> write;
};

// The harness passes of one method (see the file comment): the first run
// (its result the fill's time in microseconds, which is how the parent
// learns it), the timed runs, and the writing of the outputs (`stem` is
// DIR/<method>; no pass when it is empty).
struct Passes {
  Method first, timed, write;
  bool writes = false;
};

template <class M>
Passes passes(const std::string& name, const std::string& role, const Filler<M>& f,
              const std::string& stem, int repeat) {
  Passes p;
  p.first = {name, role, [=] {
               auto input = std::make_shared<M>(f.load());
               return std::function<long()>([=] {
                 M copy = *input;
                 const auto t0 = std::chrono::steady_clock::now();
                 f.fill(copy);
                 return long(msSince(t0) * 1000);
               });
             }};
  p.timed = {name, role, [=] {
               auto input = std::make_shared<M>(f.load());
               auto copies = std::make_shared<std::vector<M>>(std::size_t(repeat), *input);
               auto next = std::make_shared<std::size_t>(0);
               return std::function<long()>([=] { return f.fill((*copies)[(*next)++]); });
             }};
  p.writes = !stem.empty();
  p.write = {name, role, [=] {
               auto input = std::make_shared<M>(f.load());
               return std::function<long()>([=] {
                 M copy = *input;
                 const auto t0 = std::chrono::steady_clock::now();
                 const long faces = f.fill(copy);
                 const double ms = msSince(t0);
                 f.write(copy, faces, ms, stem);
                 return faces;
               });
             }};
  return p;
}

// Ours keeps the result of its fill for the report.
struct OursInput {
  Mesh mesh;
  HoleFillResult result;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// Ours' report also has the medians, over `repeat` more fills, of the
// parts of our own time that the harness cannot see: the holes' own time and
// each stage's (finding the border and writing the patch scan the whole mesh).
Filler<OursInput> ours(const std::string& file, HoleFairing fairing, int repeat) {
  Filler<OursInput> f;
  f.load = [file] { return OursInput{readMesh(file), {}}; };
  f.fill = [fairing](OursInput& in) {
    HoleFillOptions o;
    o.fairing = fairing;
    in.result = fillHoles(in.mesh, o);
    return long(in.result.faces_added);
  };
  f.write = [file, fairing, repeat](OursInput& in, long, double ms, const std::string& stem) {
    writeMesh(stem + ".ply", in.mesh);  // binary doubles: every coordinate exact
    JsonObject j = toJson(in.result);
    j.set("first_run_ms", ms);
    const Mesh input = readMesh(file);
    std::vector<double> total, holes, find, split, triangulate, fair, check, write;
    for (int i = 0; i < repeat; ++i) {
      Mesh m = input;
      HoleFillOptions o;
      o.fairing = fairing;
      const HoleFillResult r = fillHoles(m, o);
      double holeMs = 0;
      for (const HoleReport& h : r.holes) holeMs += h.time_ms;
      total.push_back(r.time_ms);
      holes.push_back(holeMs);
      find.push_back(r.stage_ms.find);
      split.push_back(r.stage_ms.split);
      triangulate.push_back(r.stage_ms.triangulate);
      fair.push_back(r.stage_ms.fair);
      check.push_back(r.stage_ms.check);
      write.push_back(r.stage_ms.write);
    }
    JsonObject stages;
    stages.set("find", median(find))
        .set("split", median(split))
        .set("triangulate", median(triangulate))
        .set("fair", median(fair))
        .set("check", median(check))
        .set("write", median(write));
    j.set("median_time_ms", median(total))
        .set("median_holes_ms", median(holes))
        .set("median_stage_ms", stages);
    writeJsonFile(stem + ".json", j);
  };
  return f;
}

struct CgalInput {
  SurfaceMesh mesh;
  std::vector<SurfaceMesh::Halfedge_index> cycles;  // one border halfedge per hole
};

Filler<CgalInput> cgal(const std::string& file) {
  Filler<CgalInput> f;
  f.load = [file] {
    CgalInput in;
    in.mesh = toSurfaceMesh(readMesh(file));
    PMP::extract_boundary_cycles(in.mesh, std::back_inserter(in.cycles));
    return in;
  };
  f.fill = [](CgalInput& in) {
    long faces = 0;
    for (SurfaceMesh::Halfedge_index h : in.cycles) {
      std::vector<SurfaceMesh::Face_index> added;
      std::vector<SurfaceMesh::Vertex_index> vertices;
      PMP::triangulate_refine_and_fair_hole(in.mesh, h, std::back_inserter(added),
                                            std::back_inserter(vertices));
      faces += long(added.size());
    }
    return faces;
  };
  f.write = [](CgalInput& in, long faces, double ms, const std::string& stem) {
    in.mesh.collect_garbage();
    if (!CGAL::IO::write_polygon_mesh(stem + ".off", in.mesh,
                                      CGAL::parameters::stream_precision(17)))
      throw std::runtime_error("cannot write " + stem + ".off");
    JsonObject j;
    j.set("faces_added", faces).set("holes", long(in.cycles.size())).set("first_run_ms", ms);
    writeJsonFile(stem + ".json", j);
  };
  return f;
}

// MlMesh is not copyable (vcglib); the pool holds copies made with Append.
struct MlInput {
  std::shared_ptr<MlMesh> mesh = std::make_shared<MlMesh>();
  MlInput() = default;
  MlInput(const MlInput& other) { vcg::tri::Append<MlMesh, MlMesh>::MeshCopy(*mesh, *other.mesh); }
  MlInput& operator=(const MlInput& other) {
    if (this != &other) {
      mesh = std::make_shared<MlMesh>();
      vcg::tri::Append<MlMesh, MlMesh>::MeshCopy(*mesh, *other.mesh);
    }
    return *this;
  }
};

Filler<MlInput> meshlab(const std::string& file) {
  Filler<MlInput> f;
  f.load = [file] {
    MlInput in;
    toMlMesh(readMesh(file), *in.mesh);
    return in;
  };
  f.fill = [](MlInput& in) { return closeHolesLikeMeshLab(*in.mesh); };
  f.write = [](MlInput& in, long faces, double ms, const std::string& stem) {
    writeOff(stem + ".off", *in.mesh);
    JsonObject j;
    j.set("faces_added", faces).set("first_run_ms", ms);
    writeJsonFile(stem + ".json", j);
  };
  return f;
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine args(argc, argv);
  const int repeat = std::max(1, args.integer("--repeat", 5)), limit = args.integer("--limit", 600),
            threads = std::max(0, args.integer("--threads", 1));
  const std::string outDir = args.text("--out-dir", "");
  const std::vector<std::string> names =
      splitList(args.text("--methods",
                          "meshmend_biharmonic,meshmend_regression,meshmend_harmonic,"
                          "meshmend_flat,cgal_refine_fair,meshlab_close_holes"));
  if (!args.complete(1, 1,
                     "bench_holes [--repeat N] [--limit SECONDS] [--threads N (0: all)] "
                     "[--methods a,b,...] [--out-dir DIR] FILE"))
    return 1;
  const std::string file = args.files()[0];
  std::vector<JsonObject> results;
  for (const std::string& name : names) {
    const std::string stem = outDir.empty() ? "" : outDir + "/" + name;
    // Ours on the threads asked for (all of them for *_all_cores); the
    // peers use one whatever this says.
    setThreadCount(name == "meshmend_biharmonic_all_cores" ? 0 : unsigned(threads));
    const unsigned used = name.rfind("meshmend", 0) == 0 ? workerCount() : 1;
    auto run = [&](auto p) {
      const Measurement first = measure(p.first, 1, limit);
      Measurement m = first;
      if (first.ok) {
        const double firstMs = double(first.result) / 1000;
        if (firstMs <= kSlowMs && repeat > 1) {
          m = measure(p.timed, repeat, limit);
        } else {          // too slow to repeat: the first run's own clock
          m.result = -1;  // faces added: in the report
          m.times_ms = {firstMs};
          m.median_ms = m.min_ms = firstMs;
        }
      }
      JsonObject j = toJson(m);
      if (first.ok)
        j.set("first_run_ms", double(first.result) / 1000)
            .set("first_peak_rss_mb", first.peak_rss_mb);
      else if (m.ok)
        j.set("ok", false).set("error", first.error);
      j.set("threads", long(used));
      if (p.writes && first.ok) {
        const Measurement w = measure(p.write, 1, limit);
        if (w.ok)
          j.set("output", stem + (name.rfind("meshmend", 0) == 0 ? ".ply" : ".off"))
              .set("report", stem + ".json");
      }
      return j;
    };
    JsonObject j;
    if (name == "meshmend_regression")
      j = run(passes(name, "alternative", ours(file, HoleFairing::LaplacianRegression, repeat),
                     stem, repeat));
    else if (name == "meshmend_biharmonic" || name == "meshmend_biharmonic_all_cores")
      j = run(passes(name, name == "meshmend_biharmonic" ? "ours" : "alternative",
                     ours(file, HoleFairing::Biharmonic, repeat), stem, repeat));
    else if (name == "meshmend_harmonic")
      j = run(passes(name, "alternative", ours(file, HoleFairing::Harmonic, repeat), stem, repeat));
    else if (name == "meshmend_flat")
      j = run(passes(name, "alternative", ours(file, HoleFairing::Flat, repeat), stem, repeat));
    else if (name == "cgal_refine_fair")
      j = run(passes(name, "peer", cgal(file), stem, repeat));
    else if (name == "meshlab_close_holes")
      j = run(passes(name, "peer", meshlab(file), stem, repeat));
    else {
      std::fprintf(stderr, "unknown method %s\n", name.c_str());
      return 1;
    }
    results.push_back(j);
    std::fprintf(stderr, "  %-22s %s\n", name.c_str(), j.str().c_str());
  }
  JsonObject out;
  out.set("file", file).set("repeat", repeat).set("methods", results);
  std::printf("%s\n", out.str(true).c_str());
}
