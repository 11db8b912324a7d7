#include "filter_mend_clearance.h"

#include <algorithm>
#include <cmath>

#include "common/repair/clearance/clearance.h"
#include "common/repair/edit_contract.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

// The order of the "scope" choices in the dialog and in scripts.
enum Scope { kWithinCurrent, kBetweenTwo, kBothOfTwo };

}  // namespace

ClearancePlugin::ClearancePlugin() {
  addFilters(this, {MEASURE_CLEARANCE, ENFORCE_CLEARANCE});
}

QString ClearancePlugin::filterName(FilterIDType id) const {
  return id == MEASURE_CLEARANCE ? "MeshMend: Measure Clearance"
                                 : "MeshMend: Enforce Minimum Clearance";
}

QString ClearancePlugin::pythonFilterName(FilterIDType filter) const {
  switch (filter) {
    case MEASURE_CLEARANCE:
      return "meshmend_measure_clearance";
    default:
      return "meshmend_enforce_minimum_clearance";
  }
}

QString ClearancePlugin::filterInfo(FilterIDType id) const {
  const QString pairs =
      "Two faces count when they share no vertex (faces of different layers never do); their "
      "distance is the smallest of their vertex-face and edge-edge distances. Between layers, "
      "the layer matrices are applied, so the distances are those seen in the viewer. ";
  if (id == MEASURE_CLEARANCE)
    return "Measures the clearance: the smallest distance between non-adjacent faces within the "
           "current layer, between two chosen layers, or both. " +
           pairs +
           "Each vertex gets the smallest distance of a pair involving one of its faces as its "
           "quality (capped at twice tau, or twice the minimum when tau is 0; run Filters > Color "
           "Creation and Processing > "
           "Colorize by vertex quality to see it), the faces closer than tau are selected, and "
           "the log gives the minimum, the closest pairs and a histogram of the pair distances. "
           "Nothing moves.<br>"
           "Method: the distance functions of <i>Aycheh and Kyung</i>, <b>\"Self-intersection "
           "avoidance for 3-D triangular mesh model\"</b>, with a spatial index over the faces.";
  return "Moves vertices as little as possible until every pair of non-adjacent faces in the "
         "scope (within the current layer, between two chosen layers, or both) is at least tau "
         "apart. " +
         pairs +
         "Selected vertices can be locked; a cap limits how far any vertex moves. The input "
         "must be free of intersections (the message names the MeshMend filter that resolves "
         "them); every intermediate configuration stays free of them. When tau cannot be "
         "reached (locked vertices, the cap, a part thinner than tau) the filter moves what it "
         "can, keeps the mesh intact and reports the pairs still short. Connectivity, "
         "attributes and the layer matrices stay as they were; the result is float as MeshLab "
         "stores it, and checked as such.<br>"
         "Method: <i>Aycheh and Kyung</i>, <b>\"Self-intersection avoidance for 3-D triangular "
         "mesh model\"</b>: Gauss-Newton steps on the distances of the pairs closer than tau, "
         "the minimum-norm step from a sparse least-squares solve (instead of the paper's dense "
         "SVD), and a backtracking line search that also keeps the surfaces from crossing.";
}

void ClearancePlugin::initParameters(QAction* a, MeshDocument& md, RichParameterList& parameters) {
  MeshModel* current = md.mm();
  MeshModel* other = layerOtherThanCurrent(md);
  // Percentages of tau and the cap are of the diagonal of all layers (as
  // placed by their matrices), the frame the distances are measured in. A
  // document without a box yet (nothing loaded) gets 1: percent of a unit.
  const Box3m box = md.bbox();
  const float diagonal = box.IsNull() ? 1.0f : box.Diag();
  const bool measuring = ID(a) == MEASURE_CLEARANCE;
  parameters.addParam(RichDistance(
      "tau", diagonal * 0.01f, 0, diagonal, "Clearance tau",
      measuring ? "The clearance to check, in mesh units or as a percentage of the bounding box "
                  "diagonal: faces of pairs closer than this are selected; 0 only measures the "
                  "minimum. Vertex quality is capped at twice this (twice the minimum when 0)."
                : "The smallest distance every pair of non-adjacent faces in the scope must "
                  "reach, in mesh units or as a percentage of the bounding box diagonal; must "
                  "be more than 0."));
  parameters.addParam(RichEnum(
      "scope", kWithinCurrent,
      QStringList() << "Within the current layer"
                    << "Between two chosen layers"
                    << "Both (within and between the two chosen layers)",
      "Scope",
      "Which face pairs count. Within the current layer: its own non-adjacent faces (the inner "
      "and outer skin of a shell, a fold). Between two chosen layers: faces of the first against "
      "faces of the second (layer matrices applied). Both: the two chosen layers, within each "
      "and between them."));
  parameters.addParam(
      layerParameter("first_layer", current, md, "First layer",
                     "First of the two chosen layers (scopes 'between' and 'both'); "
                     "in a script, the layer's index in loading order."));
  parameters.addParam(
      layerParameter("second_layer", other, md, "Second layer",
                     "Second of the two chosen layers (scopes 'between' and 'both'); "
                     "in a script, the layer's index in loading order."));
  parameters.addParam(RichInt(
      "exclusion_rings", 1, "Adjacent within (rings)",
      "Faces of one layer within this many vertex rings of each other are neighbours and never "
      "compared. 1: faces sharing a vertex (the paper's rule). 2: also faces touching a "
      "neighbour of a corner, so that a tau near the edge length measures the gaps between "
      "sheets rather than the mesh's own resolution."));
  if (!measuring) {
    parameters.addParam(RichBool(
        "lock_selected", false, "Lock selected vertices",
        "Selected vertices do not move (select a part that must keep its shape, e.g. the bore "
        "a piston must fit). A pair short of tau whose faces are all locked is reported, not "
        "solved."));
    parameters.addParam(RichDistance(
        "max_displacement", 0, 0, diagonal, "Max vertex displacement",
        "No vertex moves farther than this from where it was, in mesh units or as a percentage "
        "of the bounding box diagonal; a vertex that reaches it stays there and the others go "
        "on without it. 0: no cap."));
    parameters.addParam(RichInt(
        "max_iterations", ClearanceOptions().max_iterations, "Max iterations",
        "Gauss-Newton steps at most; each step re-detects the pairs closer than tau. The filter "
        "stops earlier when tau is reached."));
    parameters.addParam(RichInt(
        "max_short_pairs", int(ClearanceOptions().max_short_pairs), "Max pairs closer than tau",
        "Work bound: with more face pairs closer than tau than this, nothing is moved and the "
        "filter says so (so many mean a tau larger than the parts or than a few edge lengths; "
        "each one costs time in every step). 0: no bound."));
    parameters.addParam(RichBool(
        "keep_partial", EditContractOptions().keep_partial, "Keep a partial result",
        "The result is checked as it will be stored: no intersecting pair, and no pair closer "
        "than the closest was before (tau not reached within the cap, the locks or the "
        "iterations is an outcome the log explains, not a failure). Where that does not hold "
        "the layers stay unchanged; on, the result is written anyway, the layers' names ending "
        "in '(partial)'."));
  }
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      measuring
          ? "When not empty, the measurement is also written to this path as one JSON object: "
            "tau, min_distance, violating_pairs, faces_below_tau, histogram, closest, shortest, "
            "time_ms (compute time, file I/O excluded), ..."
          : "When not empty, the outcome is also written to this path as one JSON object: tau, "
            "reached, stop_reason, min_distance_before, min_distance_after, "
            "violating_pairs_before, violating_pairs_after, max_displacement, "
            "mean_displacement, displacement_lower_bound, short_pairs, time_ms, ..."));
}

namespace {

// The layers the scope and layer parameters choose, and the core scope.
struct Chosen {
  std::vector<MeshModel*> layers;
  ClearanceScope scope = ClearanceScope::kWithinLayers;
};

Chosen chosenLayers(MeshDocument& md, const RichParameterList& parameters) {
  const int scope = parameters.getEnum("scope");
  if (scope == kWithinCurrent) {
    if (!md.mm()) throw InvalidInputError("there is no current layer: open a mesh first");
    return {{md.mm()}, ClearanceScope::kWithinLayers};
  }
  if (scope != kBetweenTwo && scope != kBothOfTwo)
    throw InvalidInputError("unknown scope " + std::to_string(scope) +
                            ": use 0 (within), 1 (between) or 2 (both)");
  MeshModel* a = layerFrom(parameters, md, "first_layer");
  MeshModel* b = layerFrom(parameters, md, "second_layer");
  if (!a || !b) throw InvalidInputError("choose the two layers");
  if (a == b)
    throw InvalidInputError("the same layer (" + layerName(*a) +
                            ") was chosen twice: choose two different layers, or use the scope "
                            "'Within the current layer'");
  return {{a, b}, scope == kBetweenTwo ? ClearanceScope::kBetweenLayers : ClearanceScope::kBoth};
}

// The chosen layers as core meshes in their own frames, with the layers'
// matrices as the core's placements: the core measures where the viewer
// shows them (a percentage of the document's diagonal means the same for
// every scope) and stores moved vertices in each layer's frame.
struct Inputs {
  Chosen chosen;
  std::vector<Mesh> cores;
  std::vector<Placement> placements;
  bool anyMatrix = false;
};

void readInputs(MeshDocument& md, const RichParameterList& parameters, Inputs& in) {
  in.chosen = chosenLayers(md, parameters);
  in.cores = std::vector<Mesh>(in.chosen.layers.size());
  for (std::size_t i = 0; i < in.chosen.layers.size(); ++i) {
    const CMeshO& cm = in.chosen.layers[i]->cm;
    toCore(cm, in.cores[i], {int(i), false});
    requireFacesAndFiniteCoordinates(in.cores[i], layerName(*in.chosen.layers[i]));
    in.placements.push_back(Placement::Construct(cm.Tr));
    in.anyMatrix |= !(cm.Tr == Matrix44m::Identity());
  }
}

// The core names layers by their index among the chosen ones; users know
// them by name.
std::string layerList(const std::vector<MeshModel*>& layers) {
  std::string s;
  for (std::size_t i = 0; i < layers.size(); ++i)
    s += (i ? ", " : "") + std::string("layer ") + std::to_string(i) + " is '" +
         toStd(layers[i]->label()) + "'";
  return s;
}

std::vector<std::string> labels(const std::vector<MeshModel*>& layers) {
  std::vector<std::string> names;
  for (MeshModel* m : layers) names.push_back(toStd(m->label()));
  return names;
}

// A core face index as MeshLab's face index in its layer (the index users see
// in MeshLab's info tools, deleted slots included).
int meshlabFace(const std::vector<Mesh>& cores, int layer, int face) {
  FaceOriginHandle fo = faceOrigins(const_cast<Mesh&>(cores[layer]));
  return fo[face].face;
}

std::string describe(const ClearancePair& p, const std::vector<Mesh>& cores,
                     const std::vector<MeshModel*>& layers) {
  char text[512];
  std::snprintf(text, sizeof text,
                "%.6g between face %d of '%s' and face %d of '%s' (%s), at (%.6g, %.6g, %.6g) "
                "and (%.6g, %.6g, %.6g)",
                p.distance, meshlabFace(cores, p.layer_a, p.face_a),
                toStd(layers[p.layer_a]->label()).c_str(), meshlabFace(cores, p.layer_b, p.face_b),
                toStd(layers[p.layer_b]->label()).c_str(),
                p.kind == "edge_edge" ? "edge to edge" : "vertex to face", p.point_a[0],
                p.point_a[1], p.point_a[2], p.point_b[0], p.point_b[1], p.point_b[2]);
  return text;
}

// The same pairs in the report, with MeshLab's face indices.
std::vector<JsonObject> pairsJson(const std::vector<ClearancePair>& pairs,
                                  const std::vector<Mesh>& cores) {
  std::vector<JsonObject> out;
  for (const ClearancePair& p : pairs)
    out.push_back(
        JsonObject()
            .set("layer_a", p.layer_a)
            .set("face_a", meshlabFace(cores, p.layer_a, p.face_a))
            .set("layer_b", p.layer_b)
            .set("face_b", meshlabFace(cores, p.layer_b, p.face_b))
            .set("kind", p.kind)
            .set("distance", p.distance)
            .set("point_a", std::vector<double>{p.point_a[0], p.point_a[1], p.point_a[2]})
            .set("point_b", std::vector<double>{p.point_b[0], p.point_b[1], p.point_b[2]}));
  return out;
}

// A distance parameter: finite and not negative.
double distanceParameter(const RichParameterList& parameters, const char* name, const char* what) {
  const double value = parameters.getAbsPerc(name);
  if (!std::isfinite(value) || value < 0)
    throw InvalidInputError(std::string(what) + " must be a distance of 0 or more (got " +
                            std::to_string(value) + ")");
  return value;
}

}  // namespace

void ClearancePlugin::apply(QAction* a, MeshDocument& md, const RichParameterList& parameters,
                            vcg::CallBackPos* cb) {
  if (ID(a) == MEASURE_CLEARANCE)
    measure(md, parameters, cb);
  else
    enforce(md, parameters, cb);
}

void ClearancePlugin::measure(MeshDocument& md, const RichParameterList& parameters,
                              vcg::CallBackPos* cb) {
  ClearanceMeasureOptions options;
  options.tau = distanceParameter(parameters, "tau", "tau");
  options.exclusion_rings = parameters.getInt("exclusion_rings");
  options.progress = progressFrom(cb);
  Inputs in;
  reportProgress(options.progress, 0, "MeshMend: reading the layers");
  readInputs(md, parameters, in);
  const std::vector<MeshModel*>& layers = in.chosen.layers;
  options.scope = in.chosen.scope;
  options.placements = in.placements;
  std::vector<const Mesh*> meshes;
  for (const Mesh& m : in.cores) meshes.push_back(&m);
  const ClearanceMeasure r = measureClearance(meshes, options);

  JsonObject report = toJson(r);
  report.set("scope", toString(options.scope)).set("layers", labels(layers));
  if (r.found) report.set("closest", pairsJson({r.closest}, in.cores).front());
  report.set("shortest", pairsJson(r.shortest, in.cores));
  publishReport(parameters, report);

  // The document changes only from here on: quality and selection, no geometry.
  for (std::size_t l = 0; l < layers.size(); ++l) {
    MeshModel& model = *layers[l];
    model.updateDataMask(MeshModel::MM_VERTQUALITY);
    CMeshO& cm = model.cm;
    VertexOriginHandle vo = vertexOrigins(in.cores[l]);
    FaceOriginHandle fo = faceOrigins(in.cores[l]);
    for (std::size_t v = 0; v < r.vertex_clearance[l].size(); ++v)
      cm.vert[vo[v].vertex].Q() = float(r.vertex_clearance[l][v]);
    if (!(options.tau > 0)) continue;  // no tau: nothing to select, the user's selection stays
    for (CFaceO& f : cm.face) f.ClearS();
    for (std::size_t f = 0; f < r.faces_below_tau[l].size(); ++f)
      if (r.faces_below_tau[l][f]) cm.face[fo[f].face].SetS();
  }

  const char* scopeText = options.scope == ClearanceScope::kWithinLayers    ? "within"
                          : options.scope == ClearanceScope::kBetweenLayers ? "between"
                                                                            : "within and between";
  std::string where = layerName(*layers[0]);
  if (layers.size() > 1)
    where = "layers '" + toStd(layers[0]->label()) + "' and '" + toStd(layers[1]->label()) + "'";
  if (!r.found) {
    Log("MeshMend: no pair of non-adjacent faces %s %s: nothing to measure", scopeText,
        where.c_str());
    return;
  }
  Log("MeshMend: clearance %s %s: minimum %s", scopeText, where.c_str(),
      describe(r.closest, in.cores, layers).c_str());
  if (options.tau > 0)
    Log("  %zu face pairs closer than tau = %.6g; %zu faces selected", r.violating_pairs,
        options.tau, r.faces_below_tau_count);
  for (std::size_t i = 1; i < r.shortest.size(); ++i)
    Log("  pair %zu: %s", i + 1, describe(r.shortest[i], in.cores, layers).c_str());
  Log("  face pairs by distance (vertex quality = local clearance, capped at %.6g):", r.local_max);
  const std::size_t bins = r.histogram.size();
  for (std::size_t b = 0; b < bins; ++b)
    Log("    [%.4g, %.4g): %zu", r.local_max * double(b) / double(bins),
        r.local_max * double(b + 1) / double(bins), r.histogram[b]);
  Log("  %zu candidate pairs measured in %.0f ms", r.candidate_pairs, r.time_ms);
}

namespace {

ClearanceOptions enforceOptions(const RichParameterList& parameters, vcg::CallBackPos* cb) {
  ClearanceOptions options;
  options.tau = parameters.getAbsPerc("tau");
  if (!(options.tau > 0) || !std::isfinite(options.tau))
    throw InvalidInputError("tau must be more than 0 (got " + std::to_string(options.tau) +
                            "): it is the distance every pair of faces must reach");
  options.max_displacement =
      distanceParameter(parameters, "max_displacement", "the max vertex displacement");
  options.max_iterations = parameters.getInt("max_iterations");
  if (options.max_iterations < 1) throw InvalidInputError("max iterations must be at least 1");
  const int maxShortPairs = parameters.getInt("max_short_pairs");
  if (maxShortPairs < 0) throw InvalidInputError("max pairs closer than tau must be >= 0");
  options.max_short_pairs = std::size_t(maxShortPairs);
  options.exclusion_rings = parameters.getInt("exclusion_rings");
  options.round_to_float = kHostStoresFloat;  // reach tau in what MeshLab will store
  options.progress = progressFrom(cb);
  return options;
}

// The selected vertices of each layer as the core's locked lists; returns
// how many.
std::size_t lockSelected(Inputs& in, ClearanceOptions& options) {
  std::size_t count = 0;
  for (std::size_t l = 0; l < in.chosen.layers.size(); ++l) {
    VertexOriginHandle vo = vertexOrigins(in.cores[l]);
    std::vector<char> locked(in.cores[l].vert.size(), 0);
    for (std::size_t v = 0; v < locked.size(); ++v) {
      locked[v] = in.chosen.layers[l]->cm.vert[vo[v].vertex].IsS();
      count += locked[v];
    }
    options.locked.push_back(std::move(locked));
  }
  return count;
}

// Per layer, the vertices the core moved (MeshLab's indices) and their new
// positions in the layer's frame; the others keep theirs bit for bit.
using Moves = std::vector<std::vector<std::pair<int, HostPoint>>>;

Moves movesOf(const Inputs& in) {
  Moves moves(in.cores.size());
  for (std::size_t l = 0; l < in.cores.size(); ++l) {
    const CMeshO& cm = in.chosen.layers[l]->cm;
    VertexOriginHandle vo = vertexOrigins(const_cast<Mesh&>(in.cores[l]));
    for (std::size_t v = 0; v < in.cores[l].vert.size(); ++v) {
      const Point3& p = in.cores[l].vert[v].cP();
      if (p != Point3::Construct(cm.vert[vo[v].vertex].cP()))
        moves[l].emplace_back(vo[v].vertex, HostPoint::Construct(p));
    }
  }
  return moves;
}

JsonObject enforceReport(const ClearanceResult& r, const std::vector<std::string>& failures,
                         const Inputs& in, std::size_t lockedCount) {
  JsonObject report = toJson(r);
  reportContract(report, failures);
  return report.set("unchanged", r.violating_pairs_before == 0)
      .set("scope", toString(in.chosen.scope))
      .set("layers", labels(in.chosen.layers))
      .set("layer_matrices", in.anyMatrix)
      .set("locked_vertices", lockedCount)
      .set("short_pairs", pairsJson(r.short_pairs, in.cores));
}

// Why tau was not reached, and what to try.
std::string whyNotReached(const ClearanceResult& r, bool anyMatrix) {
  if (r.stop_reason == "rounding" && anyMatrix)
    return "storing the moved vertices in the layers' own frames (their matrices) took some "
           "pairs back below tau: apply the matrices first (Filters > Normals, Curvatures and "
           "Orientation > Matrix: Freeze Current Matrix) and run again";
  if (r.stop_reason == "rounding")
    return "rounding to float took some pairs back below tau: a double-precision MeshLab keeps "
           "them, or choose a slightly larger tau";
  if (r.stop_reason == "locked")
    return "every pair still short has only locked (selected) or capped vertices: deselect "
           "some, raise the max displacement, or lower tau";
  if (r.stop_reason == "iterations") return "the max iterations were used up: raise them";
  if (r.stop_reason == "stalled")
    return "no step that keeps the surfaces apart gets closer to tau (locked vertices, the "
           "cap, or a part thinner than tau allows)";
  return r.stop_reason;
}

}  // namespace

void ClearancePlugin::enforce(MeshDocument& md, const RichParameterList& parameters,
                              vcg::CallBackPos* cb) {
  ClearanceOptions options = enforceOptions(parameters, cb);
  Inputs in;
  reportProgress(options.progress, 0, "MeshMend: reading the layers");
  readInputs(md, parameters, in);
  const std::vector<MeshModel*>& layers = in.chosen.layers;
  options.scope = in.chosen.scope;
  const bool lock = parameters.getBool("lock_selected");
  const std::size_t lockedCount = lock ? lockSelected(in, options) : 0;
  options.placements = in.placements;

  std::vector<Mesh*> meshes;
  for (Mesh& m : in.cores) meshes.push_back(&m);
  ClearanceResult r;
  try {
    r = enforceClearance(meshes, options);
  } catch (const TopologyError& e) {
    throw TopologyError(std::string(e.what()) + " (" + layerList(layers) + ")");
  }
  const Moves moves = movesOf(in);

  // The contract (clearance.h), on what the layers will hold.
  const std::vector<std::string> failures = clearanceContractFailures(r);
  requireContract(failures, "Enforce Minimum Clearance", parameters.getBool("keep_partial"),
                  "Try a smaller tau or a max displacement, or turn on 'Keep a partial result' "
                  "to see what was made");
  publishReport(parameters, enforceReport(r, failures, in, lockedCount));
  if (r.violating_pairs_before == 0) {
    Log("MeshMend: no pair of faces is closer than tau = %.6g (the closest: %.6g): nothing to "
        "move; the layers are unchanged",
        r.tau, r.min_distance_before);
    reportProgress(options.progress, 100, "MeshMend: done");
    return;
  }
  // The only change to the document, made last: positions of moved vertices.
  for (std::size_t l = 0; l < layers.size(); ++l) {
    if (!failures.empty()) layers[l]->setLabel(layers[l]->label() + " (partial)");
    if (moves[l].empty()) continue;
    CMeshO& cm = layers[l]->cm;
    for (const auto& [vertex, p] : moves[l]) cm.vert[vertex].P() = p;
    // Face normals follow the new geometry; vertex normals stay as they were
    // (the moves are at most about tau, and imported normals survive).
    vcg::tri::UpdateBounding<CMeshO>::Box(cm);
    vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(cm);
  }

  const char* scopeText = options.scope == ClearanceScope::kWithinLayers    ? "within"
                          : options.scope == ClearanceScope::kBetweenLayers ? "between"
                                                                            : "within and between";
  std::string where = layerName(*layers[0]);
  if (layers.size() > 1)
    where = "layers '" + toStd(layers[0]->label()) + "' and '" + toStd(layers[1]->label()) + "'";
  Log("MeshMend: clearance %s %s, tau = %.6g: %s", scopeText, where.c_str(), r.tau,
      r.reached ? "reached" : "NOT reached");
  Log("  minimum distance %.6g -> %.6g; pairs closer than tau %zu -> %zu", r.min_distance_before,
      r.min_distance_after, r.violating_pairs_before, r.violating_pairs_after);
  Log("  %zu vertices moved (%zu locked): max displacement %.6g (no solution moves less than "
      "%.6g), mean %.6g; %d iterations, %.0f ms",
      r.vertices_moved, lockedCount, r.max_displacement, r.displacement_lower_bound,
      r.mean_displacement_moved, r.iterations, r.time_ms);
  if (in.anyMatrix)
    Log("  layer matrices applied; moved vertices written back in each layer's frame");
  if (lock && lockedCount == 0) Log("  note: no vertex is selected, so none was locked");
  if (r.vertices_capped) Log("  %zu vertices stopped at the max displacement", r.vertices_capped);
  if (!r.reached) {
    Log("  tau not reached: %s", whyNotReached(r, in.anyMatrix).c_str());
    for (std::size_t i = 0; i < r.short_pairs.size(); ++i)
      Log("  short pair %zu: %s", i + 1, describe(r.short_pairs[i], in.cores, layers).c_str());
  }
  for (const std::string& w : r.warnings) Log("  warning: %s", w.c_str());
  if (r.new_intersecting_pairs)
    Log("  check: %zu intersecting pairs in the stored result", r.new_intersecting_pairs);
  for (const std::string& f : failures)
    Log("  warning: PARTIAL result (kept as asked): %s", f.c_str());
  reportProgress(options.progress, 100, "MeshMend: done");
}

MESHLAB_PLUGIN_NAME_EXPORTER(ClearancePlugin)
