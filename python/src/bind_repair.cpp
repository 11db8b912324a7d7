// Hole filling, trimming along a vertex loop, stitching border paths and
// closing gaps between borders, on arrays.
#include "common/repair/edit_contract.h"
#include "common/repair/holes/holes.h"
#include "common/repair/stitch/stitch.h"
#include "python/src/bindings.h"
#include "python/src/options.h"

namespace meshmend::python {

namespace {

const MeshArgument kOneMesh;

// The filters' "Keep a partial result", with their default.
const char* kKeepPartialDoc =
    "a result that misses the end-of-edit contract (no new edge with more than two faces or run "
    "the same way by both its faces, no new face without area, no intersecting pair with a new "
    "face) is returned with report['partial'] True; False raises meshmend.Error, nothing returned";

// ---------------------------------------------------------------- holes

OptionTable<HoleFillOptions> holesTable() {
  using O = HoleFillOptions;
  OptionTable<O> t;
  t.add(
      "max_boundary_edges", [](O& o) -> std::size_t& { return o.max_boundary_edges; },
      "holes with more border edges are left open; 0 = no limit");
  t.add(
      "max_diameter", [](O& o) -> double& { return o.max_diameter; },
      "holes wider than this fraction of the bounding box diagonal are left open; 0 = no limit");
  t.addCustom(
      "selected_vertices", py::none(),
      [](O& o, py::handle v, const Bounds& b) {
        o.selected_vertices = vertexMask(v, "selected_vertices", b.vertices);
      },
      "only holes with one of these border vertices (a boolean mask or vertex indices) are "
      "filled");
  t.addCustom(
      "selected_vertex_indices", py::none(),
      [](O& o, py::handle v, const Bounds& b) {
        o.selected_vertex_indices = vertexIndices(v, "selected_vertex_indices", b.vertices);
      },
      "the same selection as vertex indices");
  t.add(
      "long_edge_factor", [](O& o) -> double& { return o.long_edge_factor; },
      "border edges longer than this many times the hole's mean are split first; 0 = off");
  t.add(
      "uniform_face_limit", [](O& o) -> std::size_t& { return o.uniform_face_limit; },
      "a hole whose uniform patch would exceed this many triangles gets graded triangles");
  t.add(
      "size_growth", [](O& o) -> double& { return o.size_growth; },
      "growth of the graded triangles per front layer");
  t.add(
      "max_size_factor", [](O& o) -> double& { return o.max_size_factor; },
      "largest graded triangle, in mean border edge lengths");
  t.add(
      "merge_distance", [](O& o) -> double& { return o.merge_distance; },
      "front vertices closer than this fraction of their target size merge");
  t.addChoice(
      "fairing", [](O& o) -> HoleFairing& { return o.fairing; },
      std::vector<std::pair<const char*, HoleFairing>>{
          {"laplacian_regression", HoleFairing::LaplacianRegression},
          {"biharmonic", HoleFairing::Biharmonic},
          {"harmonic", HoleFairing::Harmonic},
          {"flat", HoleFairing::Flat}},
      "patch shape: 'laplacian_regression' (the paper's, feature preserving), 'biharmonic', "
      "'harmonic' or 'flat'");
  t.add(
      "regression_rings", [](O& o) -> int& { return o.regression_rings; },
      "rings of vertices around the hole that train the regression");
  t.add(
      "regression_gamma", [](O& o) -> double& { return o.regression_gamma; },
      "LS-SVM regularisation: larger follows the samples more closely");
  t.add(
      "regression_max_samples", [](O& o) -> int& { return o.regression_max_samples; },
      "at most this many training samples");
  t.add(
      "check_intersections", [](O& o) -> bool& { return o.check_intersections; },
      "check every patch exactly; one that intersects falls back to a flatter shape or is left "
      "out");
  t.add(
      "verify", [](O& o) -> bool& { return o.verify; },
      "recount the intersecting pairs involving new or split faces independently");
  t.add(
      "round_to_float", [](O& o) -> bool& { return o.round_to_float; },
      "new vertices take float coordinates before the checks (as MeshLab stores them)");
  return t;
}

py::dict fillHolesArrays(py::handle vertices, py::handle faces, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  HoleFillOptions options =
      holesTable().parse("fill_holes", kwargs, {mesh.vert.size(), mesh.face.size()});
  options.progress = call.progress();
  const HoleFillResult r = call([&] { return fillHoles(mesh, options); });
  py::dict out;
  out["mesh"] = meshTuple(mesh);
  out["new_faces"] = intArray(r.new_faces);
  out["new_vertices"] = intArray(r.new_vertices);
  out["report"] = dictOf(toJson(r));
  return out;
}

// ---------------------------------------------------------------- trimming

OptionTable<TrimOptions> trimTable() {
  using O = TrimOptions;
  OptionTable<O> t;
  t.addCustom(
      "loop", py::none(),
      [](O& o, py::handle v, const Bounds& b) { o.loop = vertexIndices(v, "loop", b.vertices); },
      "the loop's vertex indices in order (consecutive ones share an edge)");
  t.addCustom(
      "selected_vertices", py::none(),
      [](O& o, py::handle v, const Bounds& b) {
        o.selected_vertices = vertexMask(v, "selected_vertices", b.vertices);
      },
      "vertices forming one closed path along edges (a boolean mask or vertex indices, any "
      "order); needs keep_face");
  t.addCustom(
      "picked_vertices", py::none(),
      [](O& o, py::handle v, const Bounds& b) {
        o.picked_vertices = vertexIndices(v, "picked_vertices", b.vertices);
      },
      "a few vertices in order, joined by shortest edge paths into the loop");
  t.add(
      "keep_face", [](O& o) -> int& { return o.keep_face; },
      "a face on the side to keep; -1: the left of the loop's direction (seen from where the "
      "normals point)");
  t.add(
      "remove_unreferenced_vertices", [](O& o) -> bool& { return o.remove_unreferenced_vertices; },
      "drop the vertices only removed faces used (see vertex_index)");
  return t;
}

py::dict trimArrays(py::handle vertices, py::handle faces, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  TrimOptions options =
      trimTable().parse("trim_along_loop", kwargs, {mesh.vert.size(), mesh.face.size()});
  if (options.keep_face < -1 || options.keep_face >= mesh.fn)
    throw InvalidInputError("keep_face " + std::to_string(options.keep_face) +
                            " is not a face: use -1 or 0 to " + std::to_string(mesh.fn - 1));
  const char* loopFrom = !options.loop.empty()                ? "loop"
                         : !options.selected_vertices.empty() ? "selected_vertices"
                         : !options.picked_vertices.empty()   ? "picked_vertices"
                                                              : "";
  options.progress = call.progress();
  const Mesh before = mesh;
  const TrimResult r = call([&] { return trimAlongLoop(mesh, options); });
  const EditContract contract = call([&] {
    return requireEditContract(before, mesh, "trim_along_loop", editContractOptions(options, false),
                               "Trimming only removes faces, so this is a defect: please report "
                               "it with the mesh and the loop");
  });
  JsonObject report = toJson(r);
  report.set("loop_from", loopFrom);
  reportContract(report, contract);
  py::dict out;
  out["mesh"] = meshTuple(mesh);
  out["vertex_index"] = intArray(r.vertex_index);
  out["loop"] = intArray(r.loop);
  out["removed"] = meshTuple(r.removed);
  out["report"] = dictOf(report);
  return out;
}

// ---------------------------------------------------------------- stitching

const std::vector<std::pair<const char*, BorderPath::Shape>> kShapes{
    {"auto", BorderPath::Shape::Auto},
    {"open", BorderPath::Shape::Open},
    {"closed", BorderPath::Shape::Closed}};

const char* kStitchToTry =
    "Try paths that face each other, without subdivision (max_aspect_ratio=0), or "
    "keep_partial=True to see what was made";

// The options every stitch shares (StitchOptions but the paths).
template <class Call, class Access>
void addStitchOptions(OptionTable<Call>& t, Access stitch) {
  t.add(
      "max_aspect_ratio", [stitch](Call& c) -> double& { return stitch(c).max_aspect_ratio; },
      "rungs longer than this many times the paths' mean edge length get rows of new vertices; "
      "0 = never");
  t.add(
      "max_rows", [stitch](Call& c) -> int& { return stitch(c).max_rows; },
      "at most this many rows of new vertices");
  t.add(
      "allow_orientation_conflict",
      [stitch](Call& c) -> bool& { return stitch(c).allow_orientation_conflict; },
      "stitch oppositely oriented sides too (the new faces follow path a's side)");
  t.add(
      "check_intersections", [stitch](Call& c) -> bool& { return stitch(c).check_intersections; },
      "count, exactly, the pairs a new face makes intersect");
}

// A stitch's options and what to do with a result that misses the contract.
struct StitchCall : StitchOptions {
  bool keep_partial = EditContractOptions().keep_partial;
};

OptionTable<StitchCall> stitchTable() {
  OptionTable<StitchCall> t;
  t.addChoice(
      "a_shape", [](StitchOptions& o) -> BorderPath::Shape& { return o.a.shape; }, kShapes,
      "path a: 'open', 'closed' or 'auto' (closed when its first vertex is repeated at the end or "
      "its ends share a border edge)");
  t.addChoice(
      "b_shape", [](StitchOptions& o) -> BorderPath::Shape& { return o.b.shape; }, kShapes,
      "path b, like a_shape");
  addStitchOptions(t, [](StitchOptions& o) -> StitchOptions& { return o; });
  t.add(
      "keep_partial", [](StitchCall& c) -> bool& { return c.keep_partial; }, kKeepPartialDoc);
  return t;
}

py::dict stitchArrays(py::handle vertices, py::handle faces, py::handle a, py::handle b,
                      py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  StitchCall options =
      stitchTable().parse("stitch_boundaries", kwargs, {mesh.vert.size(), mesh.face.size()});
  options.a.vertices = vertexIndices(a, "a", mesh.vert.size());
  options.b.vertices = vertexIndices(b, "b", mesh.vert.size());
  options.progress = call.progress();
  const Mesh before = mesh;
  const StitchResult r = call([&] { return stitchPaths(mesh, options); });
  const EditContract contract = call([&] {
    return requireEditContract(before, mesh, "stitch_boundaries",
                               editContractOptions(options, options.keep_partial), kStitchToTry);
  });
  JsonObject report = toJson(r);
  reportContract(report, contract);
  py::dict out;
  out["mesh"] = meshTuple(mesh);
  out["new_faces"] = intArray(r.new_faces);
  out["new_vertices"] = intArray(r.new_vertices);
  out["report"] = dictOf(report);
  return out;
}

struct SequenceCall {
  StitchSequenceOptions core;
  bool keep_partial = EditContractOptions().keep_partial;
};

OptionTable<SequenceCall> sequenceTable() {
  OptionTable<SequenceCall> t;
  t.add(
      "concatenate", [](SequenceCall& c) -> bool& { return c.core.concatenate; },
      "concatenate remaining paths joined by a stitch, so that a later stitch covers the "
      "junction");
  addStitchOptions(t, [](SequenceCall& c) -> StitchOptions& { return c.core.stitch; });
  t.add(
      "keep_partial", [](SequenceCall& c) -> bool& { return c.keep_partial; }, kKeepPartialDoc);
  return t;
}

py::dict stitchSequenceArrays(py::handle vertices, py::handle faces, py::handle paths,
                              py::handle pairs, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  SequenceCall c =
      sequenceTable().parse("stitch_sequence", kwargs, {mesh.vert.size(), mesh.face.size()});
  if (!py::isinstance<py::sequence>(paths) || py::isinstance<py::str>(paths))
    throw InvalidInputError("paths must be a list of vertex index sequences");
  const py::sequence pathList = py::reinterpret_borrow<py::sequence>(paths);
  for (std::size_t k = 0; k < pathList.size(); ++k) {
    BorderPath path;
    path.vertices =
        vertexIndices(pathList[k], "paths[" + std::to_string(k) + "]", mesh.vert.size());
    c.core.paths.push_back(path);
  }
  if (pairs.is_none()) {
    for (std::size_t k = 0; k + 1 < c.core.paths.size(); k += 2)
      c.core.pairs.push_back({int(k), int(k + 1)});
  } else {
    const py::array table = py::module_::import("numpy").attr("asarray")(pairs);
    const char kind = table.dtype().kind();
    if (table.ndim() != 2 || table.shape(1) != 2 || (kind != 'i' && kind != 'u'))
      throw InvalidInputError("pairs must be a list of (path, path) index pairs, like [(0, 1)]");
    using Indices = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
    const Indices p = Indices::ensure(table);
    for (py::ssize_t i = 0; i < table.shape(0); ++i) {
      std::array<int, 2> pair{};
      for (int k = 0; k < 2; ++k) {
        const std::int64_t v = p.data()[2 * i + k];
        if (v < 0 || std::uint64_t(v) >= c.core.paths.size())
          throw InvalidInputError("pairs[" + std::to_string(i) + "] names path " +
                                  std::to_string(v) + ", but " +
                                  std::to_string(c.core.paths.size()) + " paths are given");
        pair[k] = int(v);
      }
      c.core.pairs.push_back(pair);
    }
  }
  if (c.core.pairs.empty())
    throw InvalidInputError("the sequence needs at least two paths (" +
                            std::to_string(c.core.paths.size()) + " given)");
  c.core.stitch.progress = call.progress();
  const Mesh before = mesh;
  const StitchSequenceResult r = call([&] { return stitchPathsSequence(mesh, c.core); });
  const EditContract contract = call([&] {
    return requireEditContract(before, mesh, "stitch_sequence",
                               editContractOptions(c.core.stitch, c.keep_partial), kStitchToTry);
  });
  JsonObject report = toJson(r);
  reportContract(report, contract);
  std::vector<int> newFaces, newVertices;
  for (const StitchResult& s : r.steps) {
    newFaces.insert(newFaces.end(), s.new_faces.begin(), s.new_faces.end());
    newVertices.insert(newVertices.end(), s.new_vertices.begin(), s.new_vertices.end());
  }
  py::dict out;
  out["mesh"] = meshTuple(mesh);
  out["new_faces"] = intArray(newFaces);
  out["new_vertices"] = intArray(newVertices);
  out["report"] = dictOf(report);
  return out;
}

py::list borderPathsArrays(py::handle vertices, py::handle faces, py::handle selected) {
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  const std::vector<bool> mask = vertexMask(selected, "selected_vertices", mesh.vert.size());
  py::list out;
  for (const BorderPath& p : borderPathsFromSelection(mesh, mask))
    out.append(py::make_tuple(intArray(p.vertices), p.shape == BorderPath::Shape::Closed));
  return out;
}

// ---------------------------------------------------------------- gap closing

// Closing gaps' options and what to do with a result that misses the contract.
struct GapsCall : CloseGapsOptions {
  bool keep_partial = EditContractOptions().keep_partial;
};

OptionTable<GapsCall> gapsTable() {
  using O = CloseGapsOptions;
  OptionTable<GapsCall> t;
  t.add(
      "absolute_distances", [](O& o) -> bool& { return o.absolute_distances; },
      "merge_tolerance and max_gap are in mesh units (else fractions of the bounding box "
      "diagonal)");
  t.add(
      "merge_tolerance", [](O& o) -> double& { return o.merge_tolerance; },
      "border edges whose ends coincide within this distance are merged; 0 = exactly equal "
      "coordinates (CGAL's stitch_borders)");
  t.add(
      "orient_faces", [](O& o) -> bool& { return o.orient_faces; },
      "first flip faces so that faces meeting at an edge run it opposite ways (soups)");
  t.add(
      "max_gap", [](O& o) -> double& { return o.max_gap; },
      "border runs facing each other within this distance are stitched; 0 = no stitching");
  t.add(
      "local_gap_factor", [](O& o) -> double& { return o.local_gap_factor; },
      "within one part, slits no wider than this many times their border edges are closed too "
      "(even beyond max_gap); 0 = max_gap alone");
  t.add(
      "min_path_vertices", [](O& o) -> int& { return o.min_path_vertices; },
      "runs of fewer border vertices facing another border are left open");
  t.add(
      "max_aspect_ratio", [](O& o) -> double& { return o.max_aspect_ratio; },
      "subdivision of the stitched strips; 0 = never");
  t.add(
      "check_intersections", [](O& o) -> bool& { return o.check_intersections; },
      "check every stitch exactly; one that would intersect the mesh is left out");
  t.add(
      "verify", [](O& o) -> bool& { return o.verify; },
      "count the output's intersecting pairs that involve a merged or stitched face");
  t.add(
      "keep_partial", [](GapsCall& c) -> bool& { return c.keep_partial; }, kKeepPartialDoc);
  return t;
}

py::dict closeGapsArrays(py::handle vertices, py::handle faces, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  GapsCall options = gapsTable().parse("close_gaps", kwargs, {mesh.vert.size(), mesh.face.size()});
  options.progress = call.progress();
  const Mesh before = mesh;
  const CloseGapsResult r = call([&] { return closeGaps(mesh, options); });
  const EditContract contract = !changedAnything(r) ? EditContract{} : call([&] {
    return requireEditContract(
        before, mesh, "close_gaps", editContractOptions(options, options.keep_partial),
        "Try a smaller merge_tolerance and max_gap, with check_intersections=True, or "
        "keep_partial=True to see what was made");
  });
  JsonObject report = toJson(r);
  reportContract(report, contract);
  py::dict out;
  out["mesh"] = meshTuple(mesh);
  out["vertex_index"] = intArray(r.vertex_index);
  out["report"] = dictOf(report);
  return out;
}

}  // namespace

void bindRepair(py::module_& m) {
  m.def("fill_holes", &fillHolesArrays, py::arg("vertices"), py::arg("faces"),
        "Fills the holes of a mesh with feature-preserving patches.");
  registerOptions(m, "fill_holes", holesTable().describe());
  m.def("trim_along_loop", &trimArrays, py::arg("vertices"), py::arg("faces"),
        "Removes the faces on one side of a closed loop of vertices.");
  registerOptions(m, "trim_along_loop", trimTable().describe());
  m.def("stitch_boundaries", &stitchArrays, py::arg("vertices"), py::arg("faces"), py::arg("a"),
        py::arg("b"), "Joins two border paths with a strip of faces.");
  registerOptions(m, "stitch_boundaries", stitchTable().describe());
  m.def("stitch_sequence", &stitchSequenceArrays, py::arg("vertices"), py::arg("faces"),
        py::arg("paths"), py::arg("pairs") = py::none(),
        "Stitches border paths pairwise in order, concatenating leftovers at junctions.");
  registerOptions(m, "stitch_sequence", sequenceTable().describe());
  m.def("border_paths", &borderPathsArrays, py::arg("vertices"), py::arg("faces"),
        py::arg("selected_vertices"),
        "The runs of selected border vertices, as [(vertex indices, closed)].");
  m.def("close_gaps", &closeGapsArrays, py::arg("vertices"), py::arg("faces"),
        "Merges coincident borders and stitches borders facing each other.");
  registerOptions(m, "close_gaps", gapsTable().describe());
}

}  // namespace meshmend::python
