// Painting surface patches between intersection curves, classifying them
// with generalized winding numbers, and keeping or removing them (booleans),
// on arrays.
#include <chrono>

#include "common/base/timing.h"
#include "common/exact/intersections.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/patches/patch_ops.h"
#include "common/repair/patches/patches.h"
#include "common/repair/split/split.h"
#include "python/src/bindings.h"
#include "python/src/options.h"

namespace meshmend::python {

namespace {

const MeshArgument kOneMesh;

// What bounds and tells the patches apart, as given from Python; turned into
// core FaceLabels once the mesh is known.
struct LabelArguments {
  py::object part = py::none(), curve_edges = py::none(), colour = py::none();
  const char* part_name = "part";  // the option's name (addLabelOptions)
};

// Per-face integers (length = faces), e.g. part numbers or patch ids, >= 0.
std::vector<int> perFace(py::handle value, const std::string& name, std::size_t faces) {
  const py::array a = py::module_::import("numpy").attr("asarray")(value);
  const char kind = a.dtype().kind();
  if (a.ndim() != 1 || std::size_t(a.size()) != faces || (kind != 'i' && kind != 'u'))
    throw InvalidInputError(name + " must hold one integer per face (" + std::to_string(faces) +
                            ")");
  using Ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const Ints ints = Ints::ensure(a);
  std::vector<int> out(faces);
  for (std::size_t f = 0; f < faces; ++f) {
    const std::int64_t v = ints.data()[f];
    if (v < 0 || v > INT_MAX)
      throw InvalidInputError(name + "[" + std::to_string(f) + "] is " + std::to_string(v) +
                              ": it must be 0 or more");
    out[f] = int(v);
  }
  return out;
}

FaceLabels labelsOf(const Mesh& mesh, const LabelArguments& given) {
  FaceLabels labels;
  const std::size_t faces = mesh.face.size();
  if (!given.part.is_none()) labels.part = perFace(given.part, given.part_name, faces);
  if (!given.curve_edges.is_none()) {
    const py::array a = py::module_::import("numpy").attr("asarray")(given.curve_edges);
    const char kind = a.dtype().kind();
    if (a.size() > 0 && (a.ndim() != 2 || a.shape(1) != 2 || (kind != 'i' && kind != 'u')))
      throw InvalidInputError(
          "curve_edges must be a (k, 2) array of vertex index pairs (as intersect_and_split "
          "returns them)");
    using Ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
    const Ints ints = Ints::ensure(a);
    std::vector<std::array<int, 2>> edges(std::size_t(a.size() / 2));
    for (std::size_t e = 0; e < edges.size(); ++e)
      for (int k = 0; k < 2; ++k) {
        const std::int64_t v = ints.data()[2 * e + k];
        if (v < 0 || std::uint64_t(v) >= mesh.vert.size())
          throw InvalidInputError("curve_edges[" + std::to_string(e) + "] names vertex " +
                                  std::to_string(v) + ", but the mesh has " +
                                  std::to_string(mesh.vert.size()) + " vertices");
        edges[e][k] = int(v);
      }
    labels.curve_edges = curveEdgeFlags(mesh, edges);
  }
  if (!given.colour.is_none()) {
    // (m,) packed RGBA integers, or (m, 3) / (m, 4) channels 0-255.
    const py::array a = py::module_::import("numpy").attr("asarray")(given.colour);
    const char kind = a.dtype().kind();
    const bool packed = a.ndim() == 1,
               channels = a.ndim() == 2 && (a.shape(1) == 3 || a.shape(1) == 4);
    if ((!packed && !channels) || std::size_t(a.shape(0)) != faces || (kind != 'i' && kind != 'u'))
      throw InvalidInputError("colour must hold one colour per face: (" + std::to_string(faces) +
                              ",) packed integers or (" + std::to_string(faces) +
                              ", 3) channels 0-255");
    using Ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
    const Ints ints = Ints::ensure(a);
    const std::size_t width = packed ? 1 : std::size_t(a.shape(1));
    labels.colour.resize(faces);
    for (std::size_t f = 0; f < faces; ++f) {
      std::uint32_t c = 0;
      for (std::size_t k = 0; k < width; ++k)
        c |= packed ? std::uint32_t(ints.data()[f])
                    : std::uint32_t(ints.data()[f * width + k] & 0xff) << (8 * k);
      labels.colour[f] = c;
    }
  }
  return labels;
}

// The options that label the faces. The per-face parts are `partName`:
// "part" where that name is free, another where the function's own `part`
// is the filter's (Select Patches: the part a patch is inside).
template <class Call>
void addLabelOptions(OptionTable<Call>& t, const char* partName = "part") {
  t.addCustom(
      partName, py::none(),
      [partName](Call& c, py::handle v, const Bounds&) {
        c.labels.part = py::reinterpret_borrow<py::object>(v);
        c.labels.part_name = partName;
      },
      "per face, the input mesh it came from (merged_part of intersect_and_split); None = one "
      "part");
  t.addCustom(
      "curve_edges", py::none(),
      [](Call& c, py::handle v, const Bounds&) {
        c.labels.curve_edges = py::reinterpret_borrow<py::object>(v);
      },
      "the intersection curves as (k, 2) vertex pairs (merged_curve_edges of "
      "intersect_and_split)");
}

// ---------------------------------------------------------------- paint

struct PaintCall {
  PaintOptions paint;
  LabelArguments labels;
  bool classify = true;
};

OptionTable<PaintCall> paintTable() {
  OptionTable<PaintCall> t;
  addLabelOptions(t);
  t.addCustom(
      "colour", py::none(),
      [](PaintCall& c, py::handle v, const Bounds&) {
        c.labels.colour = py::reinterpret_borrow<py::object>(v);
      },
      "per face colour, (m,) packed or (m, 3) channels, for at_colour_changes");
  t.add(
      "at_curves", [](PaintCall& c) -> bool& { return c.paint.at_curves; },
      "curve edges bound patches");
  t.add(
      "at_borders", [](PaintCall& c) -> bool& { return c.paint.at_borders; },
      "border edges bound patches");
  t.add(
      "at_non_manifold", [](PaintCall& c) -> bool& { return c.paint.at_non_manifold; },
      "edges of three or more faces bound patches");
  t.add(
      "at_colour_changes", [](PaintCall& c) -> bool& { return c.paint.at_colour_changes; },
      "an edge between faces of different colour bounds patches");
  t.add(
      "crease_angle_deg", [](PaintCall& c) -> double& { return c.paint.crease_angle_deg; },
      "an edge whose dihedral angle exceeds this (degrees) bounds patches; 0 = off");
  t.add(
      "classify", [](PaintCall& c) -> bool& { return c.classify; },
      "compute each patch's winding numbers (inside or outside each other part; on the outer "
      "surface or not)");
  return t;
}

py::dict paintArrays(py::handle vertices, py::handle faces, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  const PaintCall c =
      paintTable().parse("paint_patches", kwargs, {mesh.vert.size(), mesh.face.size()});
  if (!(c.paint.crease_angle_deg >= 0 && c.paint.crease_angle_deg < 180))
    throw InvalidInputError("crease_angle_deg must be between 0 (off) and 180 degrees");
  const FaceLabels labels = labelsOf(mesh, c.labels);
  const auto start = Clock::now();
  const Patches p = call([&] {
    Patches painted = paintPatches(mesh, labels, c.paint);
    if (c.classify) classifyPatches(mesh, labels, painted);
    return painted;
  });
  JsonObject report = toJson(p);
  report.set("time_ms", msSince(start));
  py::dict out;
  out["patch_of_face"] = intArray(p.patch_of_face);
  out["report"] = dictOf(report);
  return out;
}

// ---------------------------------------------------------------- remove / keep

struct RemoveCall {
  LabelArguments labels;
  py::object patch_of_face = py::none();
  py::object remove = py::none();
  py::object keep = py::none();
  bool verify = true;
  bool removed_mesh = false;
  bool round_to_float = false;
};

OptionTable<RemoveCall> removeTable() {
  OptionTable<RemoveCall> t;
  addLabelOptions(t);
  t.addCustom(
      "patch_of_face", py::none(),
      [](RemoveCall& c, py::handle v, const Bounds&) {
        c.patch_of_face = py::reinterpret_borrow<py::object>(v);
      },
      "the patches as painted (paint_patches' patch_of_face); None = painted now with the "
      "defaults");
  t.addCustom(
      "remove", py::none(),
      [](RemoveCall& c, py::handle v, const Bounds&) {
        c.remove = py::reinterpret_borrow<py::object>(v);
      },
      "ids of the patches to remove (the others are kept)");
  t.addCustom(
      "keep", py::none(),
      [](RemoveCall& c, py::handle v, const Bounds&) {
        c.keep = py::reinterpret_borrow<py::object>(v);
      },
      "a boolean result instead: 'union' (outer surface), 'intersection' (common interior) or "
      "'difference' (part 0 minus the others)");
  t.add(
      "verify", [](RemoveCall& c) -> bool& { return c.verify; },
      "check the result: intersecting pairs (exact, the rule of meshcheck), non-manifold and "
      "border edges, closedness, volume");
  t.add(
      "removed_mesh", [](RemoveCall& c) -> bool& { return c.removed_mesh; },
      "also return the removed patches (removed)");
  t.add(
      "round_to_float", [](RemoveCall& c) -> bool& { return c.round_to_float; },
      "the check counts on the coordinates rounded to float (as a float host stores them)");
  return t;
}

BooleanOperation operationNamed(py::handle keep) {
  if (py::isinstance<py::str>(keep)) {
    const std::string name = keep.cast<std::string>();
    if (name == "union") return BooleanOperation::kUnion;
    if (name == "intersection") return BooleanOperation::kIntersection;
    if (name == "difference") return BooleanOperation::kDifference;
  }
  throw InvalidInputError("keep must be 'union', 'intersection' or 'difference' (got " +
                          py::repr(keep).cast<std::string>() + ")");
}

// patch_of_face as given (empty for None), read while the GIL is held.
std::vector<int> patchIdsGiven(const Mesh& mesh, const py::object& patchOfFace) {
  if (patchOfFace.is_none()) return {};
  return perFace(patchOfFace, "patch_of_face", mesh.face.size());
}

// The patches of `mesh` with the ids given (patchIdsGiven), or painted with
// the defaults where none were given. Touches no Python object: it runs
// with the GIL released (CoreCall).
Patches patchesGiven(const Mesh& mesh, const FaceLabels& labels, const std::vector<int>& ids) {
  if (ids.empty()) return paintPatches(mesh, labels);
  return patchesFromIds(mesh, labels, ids);
}

py::dict removeArrays(py::handle vertices, py::handle faces, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  const RemoveCall c =
      removeTable().parse("remove_patches", kwargs, {mesh.vert.size(), mesh.face.size()});
  if (c.remove.is_none() == c.keep.is_none())
    throw InvalidInputError(
        "give either remove (patch ids to remove) or keep ('union', 'intersection' or "
        "'difference')");
  const FaceLabels labels = labelsOf(mesh, c.labels);
  RemovePatchesOptions options;
  options.verify = c.verify;
  options.removed_mesh = c.removed_mesh;
  options.scalar = c.round_to_float ? Scalar::kFloat : Scalar::kDouble;
  options.progress = call.progress();
  if (!c.remove.is_none()) {
    options.keep.reset();
    const py::array a = py::module_::import("numpy").attr("asarray")(c.remove);
    const char kind = a.dtype().kind();
    if (a.ndim() != 1 || (a.size() > 0 && kind != 'i' && kind != 'u'))
      throw InvalidInputError("remove must be a sequence of patch ids");
    if (a.size() == 0) throw InvalidInputError("remove is empty: name the patches to remove");
    using Ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
    const Ints given = Ints::ensure(a);
    for (py::ssize_t i = 0; i < a.size(); ++i) {
      const std::int64_t id = given.data()[i];
      options.remove.push_back(id < 0 || id > INT_MAX ? -1 : int(id));
    }
  } else {
    options.keep = operationNamed(c.keep);
  }
  const std::vector<int> ids = patchIdsGiven(mesh, c.patch_of_face);
  const RemovePatchesResult r =
      call([&] { return removePatches(mesh, labels, patchesGiven(mesh, labels, ids), options); });
  py::dict out;
  out["mesh"] = meshTuple(r.mesh);
  out["face_origin"] = faceOriginsOf(const_cast<Mesh&>(r.mesh));
  out["removed"] = c.removed_mesh ? py::object(meshTuple(r.removed)) : py::none();
  JsonObject report = toJson(r);
  py::dict d = dictOf(report);
  if (!r.notes.empty()) d["notes"] = stringList(r.notes);
  out["report"] = d;
  return out;
}

// ---------------------------------------------------------------- select

struct SelectCall {
  SelectPatchesOptions select;
  LabelArguments labels;
  py::object patch_of_face = py::none();
  py::object selected_faces = py::none();
};

OptionTable<SelectCall> selectTable() {
  OptionTable<SelectCall> t;
  addLabelOptions(t, "face_part");
  t.addCustom(
      "patch_of_face", py::none(),
      [](SelectCall& c, py::handle v, const Bounds&) {
        c.patch_of_face = py::reinterpret_borrow<py::object>(v);
      },
      "the patches as painted (paint_patches' patch_of_face); None = painted now with the "
      "defaults");
  t.addCustom(
      "selected_faces", py::none(),
      [](SelectCall& c, py::handle v, const Bounds&) {
        c.selected_faces = py::reinterpret_borrow<py::object>(v);
      },
      "per face, selected or not (a boolean mask or face indices), for by=1");
  return t;
}

py::dict selectArrays(py::handle vertices, py::handle faces, int by, const std::string& ids,
                      int part, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  Mesh mesh;
  readArrays(mesh, vertices, faces, kOneMesh);
  SelectCall c =
      selectTable().parse("select_patches", kwargs, {mesh.vert.size(), mesh.face.size()});
  if (by < 0 || by > int(PatchSelection::kUnionInterior))
    throw InvalidInputError(
        "by must be 0 (ids), 1 (touching the selected faces), 2 (outside all "
        "other parts), 3 (inside all other parts), 4 (inside one part) or 5 "
        "(inside the union)");
  c.select.by = PatchSelection(by);
  c.select.ids = ids;
  c.select.part = part;
  if (!c.selected_faces.is_none()) {
    const std::vector<bool> mask = faceMask(c.selected_faces, "selected_faces", mesh.face.size());
    c.select.selected_faces.assign(mask.begin(), mask.end());
  }
  const FaceLabels labels = labelsOf(mesh, c.labels);
  const auto start = Clock::now();
  const std::vector<int> patchIds = patchIdsGiven(mesh, c.patch_of_face);
  Patches p = call([&] { return patchesGiven(mesh, labels, patchIds); });
  const SelectPatchesResult r = call([&] { return selectPatches(mesh, labels, p, c.select); });
  std::vector<std::uint8_t> selected(mesh.face.size(), 0);
  std::vector<double> chosenIds;
  for (std::size_t f = 0; f < selected.size(); ++f) selected[f] = r.chosen[p.patch_of_face[f]];
  for (std::size_t id = 0; id < r.chosen.size(); ++id)
    if (r.chosen[id]) chosenIds.push_back(double(id));
  JsonObject report;
  report.set("patches", p.patches.size())
      .set("patches_selected", r.patches_selected)
      .set("faces_selected", r.faces_selected)
      .set("selected_ids", chosenIds)
      .set("time_ms", msSince(start));
  py::dict out;
  out["selected_faces"] =
      py::array_t<bool>(py::ssize_t(selected.size()), reinterpret_cast<bool*>(selected.data()));
  out["patch_of_face"] = intArray(p.patch_of_face);
  py::dict d = dictOf(report);
  if (!r.notes.empty()) d["notes"] = stringList(r.notes);
  out["report"] = d;
  return out;
}

}  // namespace

void bindPatches(py::module_& m) {
  m.def("paint_patches", &paintArrays, py::arg("vertices"), py::arg("faces"),
        "Flood-fills the faces into patches bounded by curves, borders and non-manifold edges, "
        "and classifies them.");
  registerOptions(m, "paint_patches", paintTable().describe());
  m.def("remove_patches", &removeArrays, py::arg("vertices"), py::arg("faces"),
        "Removes patches by id, or keeps a boolean result; welds what is left.");
  registerOptions(m, "remove_patches", removeTable().describe());
  m.def("select_patches", &selectArrays, py::arg("vertices"), py::arg("faces"), py::arg("by"),
        py::arg("ids"), py::arg("part"),
        "Chooses patches: by ids, touching selected faces, or by classification.");
  registerOptions(m, "select_patches", selectTable().describe());
}

}  // namespace meshmend::python
