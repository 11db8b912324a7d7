// Measuring and enforcing a minimum clearance between the faces of meshes,
// on arrays.
#include "common/repair/clearance/clearance.h"
#include "common/repair/edit_contract.h"
#include "python/src/bindings.h"
#include "python/src/options.h"

namespace meshmend::python {

namespace {

const std::vector<std::pair<const char*, ClearanceScope>> kScopes{
    {"within_layers", ClearanceScope::kWithinLayers},
    {"between_layers", ClearanceScope::kBetweenLayers},
    {"both", ClearanceScope::kBoth}};

const char* kScopeDoc =
    "which face pairs count: 'within_layers' (non-adjacent faces of one mesh), "
    "'between_layers' (faces of different meshes) or 'both'";
const char* kRingsDoc =
    "faces within this many vertex rings of each other are never compared: 1 = faces sharing a "
    "vertex, 2 = also faces touching a neighbour of a corner";

Bounds boundsOf(const std::vector<Mesh>& meshes) {
  Bounds b{meshes.front().vert.size(), meshes.front().face.size(), {}};
  for (const Mesh& m : meshes) b.layer_vertices.push_back(m.vert.size());
  return b;
}

OptionTable<ClearanceMeasureOptions> measureTable() {
  using O = ClearanceMeasureOptions;
  OptionTable<O> t;
  t.add(
      "tau", [](O& o) -> double& { return o.tau; },
      "the clearance to check (mesh units); 0 = only the minimum and the local clearances");
  t.addChoice(
      "scope", [](O& o) -> ClearanceScope& { return o.scope; }, kScopes, kScopeDoc);
  t.add(
      "exclusion_rings", [](O& o) -> int& { return o.exclusion_rings; }, kRingsDoc);
  t.add(
      "local_max", [](O& o) -> double& { return o.local_max; },
      "local clearances and the histogram stop at this distance; 0 = 2 tau, or twice the minimum "
      "when tau is 0");
  t.add(
      "histogram_bins", [](O& o) -> int& { return o.histogram_bins; },
      "equal bins over [0, local_max)");
  t.add(
      "max_listed_pairs", [](O& o) -> std::size_t& { return o.max_listed_pairs; },
      "closest face pairs listed in the report (shortest)");
  return t;
}

py::dict measureArrays(py::handle meshes, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  const std::vector<Mesh> layers = meshesFrom(meshes);
  ClearanceMeasureOptions options =
      measureTable().parse("measure_clearance", kwargs, boundsOf(layers));
  options.progress = call.progress();
  std::vector<const Mesh*> pointers;
  for (const Mesh& m : layers) pointers.push_back(&m);
  const ClearanceMeasure r = call([&] { return measureClearance(pointers, options); });
  JsonObject report = toJson(r);
  report.set("scope", toString(options.scope));
  py::list local, below;
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const std::vector<double>& v = r.vertex_clearance[l];
    local.append(py::array_t<double>(py::ssize_t(v.size()), v.data()));
    const std::vector<char>& f = r.faces_below_tau[l];
    py::array_t<bool> flags(py::ssize_t(f.size()));
    std::copy(f.begin(), f.end(), flags.mutable_data());
    below.append(flags);
  }
  py::dict out;
  out["vertex_clearance"] = local;
  out["faces_below_tau"] = below;
  out["report"] = dictOf(report);
  return out;
}

// Enforcing's options and what to do with a result that misses the contract.
struct EnforceCall : ClearanceOptions {
  bool keep_partial = EditContractOptions().keep_partial;
};

OptionTable<EnforceCall> enforceTable() {
  using O = ClearanceOptions;
  OptionTable<EnforceCall> t;
  t.add(
      "tau", [](O& o) -> double& { return o.tau; },
      "the clearance to reach (mesh units); must be more than 0");
  t.addChoice(
      "scope", [](O& o) -> ClearanceScope& { return o.scope; }, kScopes, kScopeDoc);
  t.add(
      "exclusion_rings", [](O& o) -> int& { return o.exclusion_rings; }, kRingsDoc);
  t.addCustom(
      "locked", py::none(),
      [](O& o, py::handle v, const Bounds& b) {
        // One mesh: a mask or indices; several: a list with one (or None) per mesh.
        const bool perMesh = b.layer_vertices.size() > 1;
        if (perMesh && (!py::isinstance<py::sequence>(v) || py::len(v) != b.layer_vertices.size()))
          throw InvalidInputError(
              "locked must hold one entry (a mask, vertex indices or None) "
              "per mesh: " +
              std::to_string(b.layer_vertices.size()) + " here");
        o.locked.clear();
        for (std::size_t l = 0; l < b.layer_vertices.size(); ++l) {
          const py::object entry = perMesh ? py::object(py::reinterpret_borrow<py::sequence>(v)[l])
                                           : py::reinterpret_borrow<py::object>(v);
          std::vector<char> flags(b.layer_vertices[l], 0);
          if (!entry.is_none()) {
            const std::string name = perMesh ? "locked[" + std::to_string(l) + "]" : "locked";
            const std::vector<bool> mask = vertexMask(entry, name, b.layer_vertices[l]);
            std::copy(mask.begin(), mask.end(), flags.begin());
          }
          o.locked.push_back(std::move(flags));
        }
      },
      "vertices that must not move: a boolean mask or vertex indices (with several meshes, a "
      "list with one such entry or None per mesh)");
  t.add(
      "max_displacement", [](O& o) -> double& { return o.max_displacement; },
      "no vertex moves farther than this; 0 = no cap");
  t.add(
      "max_iterations", [](O& o) -> int& { return o.max_iterations; },
      "Gauss-Newton steps at most");
  t.add(
      "max_short_pairs", [](O& o) -> std::size_t& { return o.max_short_pairs; },
      "work bound: more face pairs closer than tau than this, and nothing moves; 0 = none");
  t.add(
      "active_margin", [](O& o) -> double& { return o.active_margin; },
      "pairs closer than tau * (1 + active_margin) take part in each step");
  t.add(
      "round_to_float", [](O& o) -> bool& { return o.round_to_float; },
      "make the result float-representable (as MeshLab stores it) and check it again");
  t.add(
      "max_listed_pairs", [](O& o) -> std::size_t& { return o.max_listed_pairs; },
      "pairs still short listed in the report (short_pairs)");
  t.add(
      "keep_partial", [](EnforceCall& c) -> bool& { return c.keep_partial; },
      "a result that misses the contract (no intersecting pair, no pair closer than the closest "
      "was before; tau not reached is not a failure) is returned with report['partial'] True; "
      "False raises meshmend.Error, nothing returned");
  return t;
}

py::dict enforceArrays(py::handle meshes, py::kwargs kwargs) {
  CoreCall call(takeProgress(kwargs));
  std::vector<Mesh> layers = meshesFrom(meshes);
  EnforceCall options = enforceTable().parse("enforce_clearance", kwargs, boundsOf(layers));
  if (options.max_iterations < 1) throw InvalidInputError("max_iterations must be at least 1");
  options.progress = call.progress();
  std::vector<Mesh*> pointers;
  for (Mesh& m : layers) pointers.push_back(&m);
  const ClearanceResult r = call([&] { return enforceClearance(pointers, options); });
  const std::vector<std::string> failures = clearanceContractFailures(r);
  requireContract(failures, "enforce_clearance", options.keep_partial,
                  "Try a smaller tau or a max_displacement, or keep_partial=True to see what was "
                  "made");
  std::size_t locked = 0;
  for (const auto& flags : options.locked)
    for (char f : flags) locked += f != 0;
  JsonObject report = toJson(r);
  reportContract(report, failures);
  report.set("unchanged", r.violating_pairs_before == 0)
      .set("scope", toString(options.scope))
      .set("locked_vertices", locked);
  py::list out;
  for (const Mesh& m : layers) out.append(meshTuple(m));
  py::dict result;
  result["meshes"] = out;
  result["report"] = dictOf(report);
  return result;
}

}  // namespace

void bindClearance(py::module_& m) {
  m.def("measure_clearance", &measureArrays, py::arg("meshes"),
        "The smallest distance between non-adjacent faces of a list of (vertices, faces) meshes.");
  registerOptions(m, "measure_clearance", measureTable().describe());
  m.def("enforce_clearance", &enforceArrays, py::arg("meshes"),
        "Moves vertices as little as possible until every pair in scope is tau apart.");
  registerOptions(m, "enforce_clearance", enforceTable().describe());
}

}  // namespace meshmend::python
