// Inspection, intersection finding, intersect-and-split and self-intersection
// removal on arrays; reading and writing mesh files.
#include <chrono>

#include "common/base/timing.h"
#include "common/exact/intersections.h"
#include "common/io/mesh_io.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/output_stage.h"
#include "common/repair/selfintersect/selfintersect.h"
#include "common/repair/split/split.h"
#include "python/src/bindings.h"
#include "python/src/options.h"

namespace meshmend::python {

namespace {

const MeshArgument kOneMesh;

// ---------------------------------------------------------------- inspect

OptionTable<InspectOptions> inspectTable() {
  OptionTable<InspectOptions> t;
  t.add(
      "self_intersections", [](InspectOptions& o) -> bool& { return o.self_intersections; },
      "also count self-intersecting pairs (exact, slower)");
  t.add(
      "mark_defects", [](InspectOptions& o) -> bool& { return o.mark_defects; },
      "add face_defects and vertex_defects (per-element bit masks, see FACE_DEFECTS and "
      "VERTEX_DEFECTS) to the report");
  return t;
}

py::dict inspectArrays(py::handle vertices, py::handle faces, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh, 0, Coordinates::kAny);
  const InspectOptions options =
      inspectTable().parse("inspect", kwargs, {mesh.vert.size(), mesh.face.size()});
  const InspectResult r = call([&] { return inspect(mesh, options); });
  py::dict report = dictOf(toJson(r));
  if (options.mark_defects) {
    report["face_defects"] =
        py::array_t<std::uint8_t>(py::ssize_t(r.face_defects.size()), r.face_defects.data());
    report["vertex_defects"] =
        py::array_t<std::uint8_t>(py::ssize_t(r.vertex_defects.size()), r.vertex_defects.data());
  }
  return report;
}

// ---------------------------------------------------------------- find intersections

OptionTable<FindIntersectionsOptions> findTable() {
  OptionTable<FindIntersectionsOptions> t;
  t.add(
      "self", [](FindIntersectionsOptions& o) -> bool& { return o.self; },
      "pairs of faces of the same mesh (the rule of CGAL's self_intersections)");
  t.add(
      "cross", [](FindIntersectionsOptions& o) -> bool& { return o.cross; },
      "pairs of faces of different meshes (any contact)");
  t.add(
      "contacts", [](FindIntersectionsOptions& o) -> bool& { return o.contacts; },
      "also return the exact intersection segments (rounded to double) as (points, edges)");
  t.add(
      "layout", [](FindIntersectionsOptions& o) -> int& { return o.layout; },
      "candidate search: 0 (default) a Morton-order hierarchy within each mesh and a hashed grid "
      "between meshes, 1 median-split hierarchies for both");
  return t;
}

py::tuple findArrays(py::handle meshes, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  const std::vector<Mesh> inputs = meshesFrom(meshes);
  FindIntersectionsOptions options = findTable().parse("find_intersections", kwargs, {});
  if (options.layout != 0 && options.layout != 1)
    throw InvalidInputError("layout must be 0 (the default) or 1 (median-split hierarchies)");
  options.progress = call.progress();
  std::vector<const Mesh*> pointers;
  for (const Mesh& m : inputs) pointers.push_back(&m);
  const FindIntersectionsResult r = call([&] { return findIntersections(pointers, options); });
  py::array_t<std::int32_t> pairs({py::ssize_t(r.pairs.size()), py::ssize_t(4)});
  std::int32_t* p = pairs.mutable_data();
  for (const IntersectingPair& pair : r.pairs) {
    *p++ = std::int32_t(pair.a.mesh), *p++ = std::int32_t(pair.a.face);
    *p++ = std::int32_t(pair.b.mesh), *p++ = std::int32_t(pair.b.face);
  }
  py::object segments = py::none();
  if (options.contacts) {
    const SegmentSoup soup = contactSegments(r);
    Mesh points;  // the soup's points as vertices, to reuse verticesOf
    vcg::tri::Allocator<Mesh>::AddVertices(points, soup.points.size());
    for (std::size_t i = 0; i < soup.points.size(); ++i) points.vert[i].P() = soup.points[i];
    segments = py::make_tuple(verticesOf(points), pairArray(soup.edges));
  }
  return py::make_tuple(pairs, segments, dictOf(toJson(r)));
}

std::size_t countSelfIntersections(py::handle vertices, py::handle faces) {
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  CoreCall call;
  return call([&] { return selfIntersectingPairs(mesh); });
}

// ---------------------------------------------------------------- intersect and split

struct SplitCall {
  SplitOptions core;
  bool round_to_float = false;  // prepare the output for float storage (roundToFloat)
  bool verify = true;           // count the intersecting pairs left in the merged output
  bool all_or_nothing = true;   // fail instead of returning a result with defects once stored
};

OptionTable<SplitCall> splitTable() {
  OptionTable<SplitCall> t;
  t.add(
      "between_meshes", [](SplitCall& c) -> bool& { return c.core.between_meshes; },
      "insert the curves where different meshes meet");
  t.add(
      "self", [](SplitCall& c) -> bool& { return c.core.self; },
      "also split each mesh along its own self-intersections");
  t.add(
      "weld_duplicates", [](SplitCall& c) -> bool& { return c.core.weld_duplicates; },
      "first merge exact-duplicate vertices (scan seams) in each mesh");
  t.add(
      "remove_duplicate_faces", [](SplitCall& c) -> bool& { return c.core.remove_duplicate_faces; },
      "first remove faces with the same three vertices as another face of their mesh");
  t.add(
      "overlaps_once", [](SplitCall& c) -> bool& { return c.core.overlaps_once; },
      "where meshes (or a mesh and itself) overlap in a plane, keep each coinciding face once "
      "in the merged output, so that it is free of duplicate faces (a repaired result); off, it "
      "keeps both, so that each input stays a whole surface there, as boolean() needs");
  t.add(
      "separate_meshes", [](SplitCall& c) -> bool& { return c.core.separate_meshes; },
      "also return each mesh with the curves inserted (else the merged mesh only)");
  t.add(
      "snap_tolerance", [](SplitCall& c) -> double& { return c.core.snap_tolerance; },
      "quality snapping, a fraction of the local edge length in [0, 0.5); 0 = off, 0.05 removes "
      "most slivers");
  t.add(
      "round_to_float", [](SplitCall& c) -> bool& { return c.round_to_float; },
      "round the output to float (as MeshLab and STL, float PLY or OBJ files store it), "
      "re-rounding curve points where rounding to nearest would make faces cross, merging curve "
      "points a few float steps apart and splitting the merged output again where it still "
      "crosses (the separate meshes follow it), trying quality snapping where that still leaves "
      "crossings, as the MeshLab filter does; the check then counts the float output");
  t.add(
      "verify", [](SplitCall& c) -> bool& { return c.verify; },
      "count the intersecting pairs left in the output (remaining_intersecting_pairs), by the "
      "rule of meshcheck and CGAL's self_intersections: in each returned mesh "
      "(separate_meshes), else in the merged one");
  t.add(
      "all_or_nothing", [](SplitCall& c) -> bool& { return c.all_or_nothing; },
      "raise InvalidInputError instead of returning a result in which faces still cross or new "
      "faces are flat once stored (in float with round_to_float, else in double); False returns "
      "it, the report saying what is left");
  return t;
}

py::dict splitArrays(py::handle meshes, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  std::vector<Mesh> inputs = meshesFrom(meshes);
  SplitCall c = splitTable().parse("intersect_and_split", kwargs, {});
  if (!(c.core.snap_tolerance >= 0 && c.core.snap_tolerance < 0.5))
    throw InvalidInputError("snap_tolerance must be at least 0 (off) and below 0.5");
  if (!c.core.self && !c.core.between_meshes)
    throw InvalidInputError("between_meshes and self are both off: nothing to split");
  c.core.progress = progressWithin(call.progress(), 0, 94);
  std::vector<const Mesh*> pointers;
  for (const Mesh& m : inputs) pointers.push_back(&m);
  const auto start = Clock::now();
  SplitResult r = call([&] { return splitAlongIntersections(pointers, c.core); });
  // The output stage (output_stage.h), as the MeshLab filter runs it for its host.
  OutputStageOptions stage;
  stage.scalar = c.round_to_float ? Scalar::kFloat : Scalar::kDouble;
  stage.progress = call.progress();
  const StoredOutput stored = call([&] { return storeForHost(r, pointers, c.core, stage); });
  if (c.all_or_nothing && !stored.explanation().empty())
    throw InvalidInputError("the result is not exact once stored (all_or_nothing): " +
                            stored.explanation());
  std::size_t remaining = 0;
  if (c.verify)  // by the checker's rule, on what is returned as the output
    remaining = call([&] { return storedIntersectingPairs(r, stored, c.core.separate_meshes); });
  // The whole computation once (the core's time_ms adds up the splits it ran).
  r.time_ms = msSince(start);
  JsonObject report = toJson(r);
  addToReport(stored, report);
  if (c.verify) report.set("remaining_intersecting_pairs", remaining);
  report.set("output", c.core.separate_meshes ? "separate" : "merged");

  py::dict out;
  py::list separate, curves;
  for (std::size_t i = 0; i < r.meshes.size(); ++i) {
    separate.append(meshTuple(r.meshes[i]));
    curves.append(pairArray(r.curve_edges[i]));
  }
  out["meshes"] = separate;
  out["curve_edges"] = curves;
  out["merged"] = meshTuple(r.merged);
  out["merged_curve_edges"] = pairArray(r.merged_curve_edges);
  out["merged_part"] = faceLayers(r.merged);
  out["report"] = dictOf(report);
  return out;
}

// ---------------------------------------------------------------- self-intersection removal

OptionTable<SelfIntersectionOptions> selfTable() {
  using O = SelfIntersectionOptions;
  OptionTable<O> t;
  t.add(
      "pretreat", [](O& o) -> bool& { return o.pretreat; },
      "first remove degenerate faces (edge collapses and flips, each checked exactly)");
  t.add(
      "degenerate_angle_deg", [](O& o) -> double& { return o.degenerate_angle_deg; },
      "smallest angle (degrees) under which the pre-treatment counts a face as degenerate");
  t.add(
      "weld_duplicates", [](O& o) -> bool& { return o.weld_duplicates; },
      "merge exactly coincident vertices first (scan seams)");
  t.add(
      "snap_tolerance", [](O& o) -> double& { return o.snap_tolerance; },
      "quality snapping of the split, a fraction of the local edge length; 0 = off");
  t.add(
      "round_to_float", [](O& o) -> bool& { return o.round_to_float; },
      "work on float coordinates (as MeshLab stores them)");
  t.add(
      "separate_touching", [](O& o) -> bool& { return o.separate_touching; },
      "move the copies of a vertex where the result touches itself apart (1/1000 of the local "
      "edge length)");
  t.add(
      "keep_removed", [](O& o) -> bool& { return o.keep_removed; },
      "also return the removed faces (removed)");
  t.add(
      "verify", [](O& o) -> bool& { return o.verify; },
      "count the intersecting pairs left in the result (remaining_intersecting_pairs)");
  t.add(
      "keep_partial", [](O& o) -> bool& { return o.keep_partial; },
      "return a result that misses the contract (report contract_met False, contract_failures) "
      "instead of raising meshmend.Error");
  t.add(
      "max_intersecting_pairs", [](O& o) -> std::size_t& { return o.max_intersecting_pairs; },
      "work bound: more intersecting pairs than this and the removal stops (meshmend.Error), "
      "nothing changed; 0 = no bound");
  t.add(
      "max_triple_points_per_face",
      [](O& o) -> std::size_t& { return o.max_triple_points_per_face; },
      "work bound: a face where more pairs of its crossing faces cross each other stops the "
      "removal (meshmend.Error), nothing changed; 0 = no bound");
  return t;
}

py::dict removeSelfIntersectionsArrays(py::handle vertices, py::handle faces, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  SelfIntersectionOptions options =
      selfTable().parse("remove_self_intersections", kwargs, {mesh.vert.size(), mesh.face.size()});
  options.progress = call.progress();
  SelfIntersectionResult r = call([&] { return removeSelfIntersections(mesh, options); });
  py::dict out;
  out["mesh"] = meshTuple(r.mesh);
  out["face_origin"] = faceOriginsOf(r.mesh);
  out["removed"] = options.keep_removed ? py::object(meshTuple(r.removed)) : py::none();
  out["report"] = dictOf(toJson(r));
  return out;
}

// ---------------------------------------------------------------- files

py::tuple readMeshFile(const std::string& path) {
  Mesh mesh;
  {
    py::gil_scoped_release release;
    mesh = readMesh(path);
  }
  return meshTuple(mesh);
}

void writeMeshFile(const std::string& path, py::handle vertices, py::handle faces) {
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh, 0, Coordinates::kAny);
  py::gil_scoped_release release;
  writeMesh(path, mesh);
}

}  // namespace

void bindIntersect(py::module_& m) {
  m.def("inspect", &inspectArrays, py::arg("vertices"), py::arg("faces"),
        "Defect counts of a mesh, with the keys and definitions of meshcheck.");
  registerOptions(m, "inspect", inspectTable().describe());
  py::dict faceBits, vertexBits;
  faceBits["on_non_manifold_edge"] = int(kFaceOnNonManifoldEdge);
  faceBits["on_border"] = int(kFaceOnBorder);
  faceBits["degenerate"] = int(kFaceDegenerate);
  faceBits["duplicate"] = int(kFaceDuplicate);
  faceBits["orientation_flip"] = int(kFaceOrientationFlip);
  faceBits["self_intersecting"] = int(kFaceSelfIntersecting);
  vertexBits["non_manifold"] = int(kVertexNonManifold);
  vertexBits["on_border"] = int(kVertexOnBorder);
  vertexBits["isolated"] = int(kVertexIsolated);
  vertexBits["duplicate"] = int(kVertexDuplicate);
  vertexBits["non_finite"] = int(kVertexNonFinite);
  m.attr("FACE_DEFECTS") = faceBits;
  m.attr("VERTEX_DEFECTS") = vertexBits;

  m.def("find_intersections", &findArrays, py::arg("meshes"),
        "Intersecting face pairs among a list of (vertices, faces) meshes: (pairs, segments, "
        "report).");
  registerOptions(m, "find_intersections", findTable().describe());
  m.def("count_self_intersections", &countSelfIntersections, py::arg("vertices"), py::arg("faces"),
        "Number of self-intersecting face pairs (exact).");

  m.def("intersect_and_split", &splitArrays, py::arg("meshes"),
        "Inserts the intersection curves of a list of (vertices, faces) meshes into them.");
  registerOptions(m, "intersect_and_split", splitTable().describe());

  m.def("remove_self_intersections", &removeSelfIntersectionsArrays, py::arg("vertices"),
        py::arg("faces"), "Keeps the outer surface of a self-intersecting mesh.");
  registerOptions(m, "remove_self_intersections", selfTable().describe());

  m.def("read_mesh", &readMeshFile, py::arg("path"),
        "Reads an OFF, PLY, STL or OBJ file as (vertices, faces), vertices as stored.");
  m.def("write_mesh", &writeMeshFile, py::arg("path"), py::arg("vertices"), py::arg("faces"),
        "Writes OFF or binary PLY (by the extension), coordinates in double precision.");
}

}  // namespace meshmend::python
