#include "filter_mend_holes.h"

#include <algorithm>

#include "common/repair/holes/holes.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

// The order of the "fairing" choices in the dialog and in scripts.
const HoleFairing kFairings[] = {HoleFairing::LaplacianRegression, HoleFairing::Biharmonic,
                                 HoleFairing::Harmonic, HoleFairing::Flat};

}  // namespace

HolesPlugin::HolesPlugin() {
  addFilters(this, {FILL_HOLES});
}

QString HolesPlugin::filterName(FilterIDType) const {
  return "MeshMend: Fill Holes (Feature Preserving)";
}

QString HolesPlugin::pythonFilterName(FilterIDType) const {
  return "meshmend_fill_holes";
}

QString HolesPlugin::filterInfo(FilterIDType) const {
  return "Fills the holes of a mesh with patches that follow the shape around them (Xu, Li and "
         "Tan, feature based hole filling). Each hole's long border edges are split first; the "
         "hole is covered by an advancing front whose triangles take the size of the border "
         "edges around them (over the hole's plane; over a disk where no plane fits, the "
         "plane's patch is less round or would intersect); the patch vertices are then placed "
         "by a least-squares Poisson solve, by default "
         "the biharmonic one (smoothest, tangent to the surface: on the project's fidelity "
         "benchmark the closest to the removed surface). The paper's shape, whose target "
         "Laplacians are learned (LS-SVM regression) from the rings of vertices around the "
         "hole, a membrane (harmonic) and the flat patch are options.<br>"
         "Every patch is checked exactly against itself and the surface around it; one that "
         "would intersect falls back to a flatter shape, or is left out with a reason in the "
         "log. Holes at a non-manifold border vertex are split there. Existing vertices and "
         "faces keep their indices; new ones are appended. Threads: every CPU, or as many as "
         "the environment variable MESHMEND_THREADS says.";
}

void HolesPlugin::initParameters(QAction*, MeshDocument&, RichParameterList& parameters) {
  const HoleFillOptions defaults;
  parameters.addParam(RichInt(
      "max_boundary_edges", int(defaults.max_boundary_edges), "Max hole size (border edges)",
      "Holes with more border edges than this are left open; 0 fills holes of any size."));
  parameters.addParam(RichFloat(
      "max_diameter", 0.5f, "Max hole diameter (fraction of the diagonal)",
      "Holes wider than this fraction of the bounding box diagonal are left open, so that the "
      "open side of a scan is not closed by mistake; 0 fills holes of any width."));
  parameters.addParam(RichBool(
      "selected_only", false, "Only holes touching the selection",
      "Fills only the holes with at least one selected border vertex (select them, e.g. with "
      "Filters > Selection > Select Border, then deselect what to keep open)."));
  const int defaultFairing =
      int(std::find(std::begin(kFairings), std::end(kFairings), defaults.fairing) -
          std::begin(kFairings));
  parameters.addParam(RichEnum(
      "fairing", defaultFairing,
      QStringList() << "Feature preserving (learned Laplacians)"
                    << "Biharmonic (smoothest)"
                    << "Harmonic (membrane)"
                    << "Flat (no fairing)",
      "Patch shape",
      "Feature preserving: the paper's Poisson solve with Laplacians predicted from the rings "
      "around the hole (continues their curvature). Biharmonic (default): minimal curvature, "
      "tangent to the surface. Harmonic: a membrane spanning the border. Flat: the "
      "triangulation as the front built it."));
  parameters.addParam(RichInt(
      "regression_rings", defaults.regression_rings, "Rings learned from",
      "How many rings of vertices around each hole train the Laplacian regression (feature "
      "preserving shape): more rings follow larger-scale shape, fewer the shape right at the "
      "border."));
  parameters.addParam(RichFloat(
      "long_edge_factor", float(defaults.long_edge_factor), "Split border edges longer than",
      "Border edges longer than this many times the hole's mean border edge length are split "
      "first (with the face they border), so the patch grades smoothly; 0 turns it off."));
  parameters.addParam(RichBool(
      "check_intersections", defaults.check_intersections, "Check intersections",
      "Tests every patch exactly against itself and the surface around it; a patch that would "
      "intersect falls back to a flatter shape or is left out. Turn off only for speed on "
      "meshes known to be simple around their holes."));
  parameters.addParam(RichBool(
      "select_new_faces", false, "Select the new faces",
      "Selects the patch faces afterwards (and nothing else). Off by default: selected faces "
      "restrict later filters such as smoothing to the selection."));
  parameters.addParam(RichBool(
      "verify", defaults.verify, "Verify the result",
      "Counts every intersecting pair of the result as stored, by the rule of CGAL's "
      "self_intersections and of the checker meshcheck (remaining_intersecting_pairs in the log "
      "and report; the mesh's own pairs included). The pairs that involve new or split faces "
      "are always counted (new_intersecting_pairs)."));
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      "When not empty, the outcome is also written to this path as one JSON object (keys: "
      "holes_found, holes_filled, holes_skipped, skipped, faces_added, new_intersecting_pairs, "
      "remaining_intersecting_pairs (with verify), time_ms, holes, ...)."));
}

void HolesPlugin::apply(QAction*, MeshDocument& md, const RichParameterList& parameters,
                        vcg::CallBackPos* cb) {
  MeshModel* model = md.mm();
  if (!model) throw InvalidInputError("there is no current layer: open a mesh first");
  HoleFillOptions options;
  const int maxEdges = parameters.getInt("max_boundary_edges");
  if (maxEdges < 0) throw InvalidInputError("the max hole size must be 0 (no limit) or more");
  options.max_boundary_edges = std::size_t(maxEdges);
  options.max_diameter = parameters.getFloat("max_diameter");
  const int fairing = parameters.getEnum("fairing");
  if (fairing < 0 || fairing >= int(std::size(kFairings)))
    throw InvalidInputError("unknown patch shape " + std::to_string(fairing) +
                            ": use 0 (feature preserving) to 3 (flat)");
  options.fairing = kFairings[fairing];
  options.regression_rings = parameters.getInt("regression_rings");
  options.long_edge_factor = parameters.getFloat("long_edge_factor");
  options.check_intersections = parameters.getBool("check_intersections");
  options.verify = parameters.getBool("verify");
  options.round_to_float = kHostStoresFloat;  // check what MeshLab will store
  options.progress = progressFrom(cb);

  reportProgress(options.progress, 0, "MeshMend: reading the layer");
  Mesh core = toCore(model->cm);
  if (parameters.getBool("selected_only")) {
    VertexOriginHandle origin = vertexOrigins(core);
    options.selected_vertices.assign(core.vert.size(), false);
    bool any = false;
    for (std::size_t v = 0; v < core.vert.size(); ++v) {
      const bool selected = model->cm.vert[origin[v].vertex].IsS();
      options.selected_vertices[v] = selected;
      any |= selected;
    }
    if (!any)
      throw InvalidInputError(
          "'Only holes touching the selection' is on but no vertex is selected: select the "
          "border of the holes to fill (Filters > Selection > Select Border) or turn it off");
  }
  const HoleFillResult r = fillHoles(core, options);

  JsonObject report = toJson(r);
  report.set("layer", toStd(model->label()));
  publishReport(parameters, report);

  Log("MeshMend: %zu holes found in %s, %zu filled, %zu left open; %zu faces added, %.0f ms",
      r.holes_found, layerName(*model).c_str(), r.holes_filled, r.holes_skipped, r.faces_added,
      r.time_ms);
  for (std::size_t i = 0; i < r.holes.size(); ++i) {
    const HoleReport& h = r.holes[i];
    if (h.filled)
      Log("  hole %zu: %zu border edges, %zu faces added, %s, residual %.3g, %.1f ms%s%s", i,
          h.boundary_edges, h.faces_added, toString(h.fairing), h.fairing_residual, h.time_ms,
          h.reason.empty() ? "" : "; ", h.reason.c_str());
    else
      Log("  hole %zu: %zu border edges, left open: %s", i, h.boundary_edges, h.reason.c_str());
  }
  if (r.verified)
    Log("  check of the stored result: %zu intersecting pairs with a new or split face",
        r.new_intersecting_pairs);
  if (r.remaining_counted)
    Log("  verify: %zu intersecting pairs in the whole result", r.remaining_intersecting_pairs);
  if (r.holes_found == 0) {
    Log("MeshMend: the mesh has no holes (no border edges); nothing to do");
    return;  // the layer stays exactly as it was
  }
  if (r.holes_filled == 0) return;

  // The only change to the document, made last.
  const std::vector<LayerAttributes> attributes{snapshot(*model)};
  writeMesh(core, attributes, *model);
  if (parameters.getBool("select_new_faces")) {
    for (CFaceO& f : model->cm.face) f.ClearS();
    for (CVertexO& v : model->cm.vert) v.ClearS();
    for (int f : r.new_faces) model->cm.face[f].SetS();
  }
  reportProgress(options.progress, 100, "MeshMend: done");
}

MESHLAB_PLUGIN_NAME_EXPORTER(HolesPlugin)
