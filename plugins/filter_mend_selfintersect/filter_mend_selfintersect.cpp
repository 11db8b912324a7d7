#include "filter_mend_selfintersect.h"

#include "common/repair/selfintersect/selfintersect.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

using namespace meshmend;
using namespace meshmend::bridge;

SelfIntersectPlugin::SelfIntersectPlugin() {
  addFilters(this, {REMOVE_SELF_INTERSECTIONS});
}

QString SelfIntersectPlugin::filterName(FilterIDType) const {
  return "MeshMend: Remove Self-Intersections";
}

QString SelfIntersectPlugin::pythonFilterName(FilterIDType) const {
  return "meshmend_remove_self_intersections";
}

QString SelfIntersectPlugin::filterInfo(FilterIDType) const {
  return "Turns a consistently oriented mesh that folds through itself into a valid one: keeps "
         "the part of the surface that is <i>outside</i> with respect to its orientation "
         "(TransforMesh, Zaharescu, Boyer and Horaud, ACCV 2007). The mesh is cut along its "
         "exact self-intersection curves; the valid region grows from seed faces (faces with "
         "nothing in front of them, decided by an exact ray test) and, where sheets meet, "
         "continues on the sheet that keeps the surface closed; the kept faces are stitched "
         "into a manifold mesh. Parts that overlap merge, pieces turned inside out go, and "
         "hollow parts keep their inner walls.<br>"
         "Needs consistent orientation (run <i>MeshMend: Close Gaps Between Borders</i> or "
         "<i>Re-Orient all faces coherently</i> first otherwise). A closed mesh turned inside "
         "out is handled and stays so. On a mesh with borders a seed must see nothing in front "
         "of it, and borders stay borders. Where the result touches itself at a vertex or edge, "
         "each side gets its own copy of the vertex, moved apart by 1/1000 of the local edge "
         "length.<br>"
         "The result is checked exactly as it will be stored: no intersecting pair, every edge "
         "with at most two faces, every vertex one fan, consistently oriented, closed where the "
         "input was, no new zero-area face. Where that does not hold the layer stays unchanged "
         "and the log says what failed and what to try. A mesh with nothing to remove stays "
         "unchanged too.";
}

void SelfIntersectPlugin::initParameters(QAction*, MeshDocument&, RichParameterList& parameters) {
  const SelfIntersectionOptions defaults;
  parameters.addParam(RichBool(
      "pretreat", defaults.pretreat, "Remove degenerate faces first",
      "Before anything else, removes faces with (nearly) zero area by collapsing their "
      "shortest edge or flipping their longest one; each change is kept only if no face turns "
      "over and no new intersection appears (exact test)."));
  parameters.addParam(RichFloat(
      "degenerate_angle_deg", float(defaults.degenerate_angle_deg), "Degenerate angle (degrees)",
      "A face whose smallest angle is below this counts as degenerate for the pre-treatment "
      "(zero-area faces always do). 0.1 touches only faces that are really slivers."));
  parameters.addParam(RichBool(
      "weld_duplicates", defaults.weld_duplicates, "Merge coincident vertices first",
      "Merges vertices with exactly the same coordinates (scan seams, STL facets), so that a "
      "seam is not taken for a border."));
  parameters.addParam(RichFloat(
      "snap_tolerance", float(defaults.snap_tolerance), "Quality snapping",
      "Where the self-intersection curves pass within this fraction of the local edge length "
      "of a vertex or an edge, they snap to it instead of leaving sliver faces (whose rounded "
      "corners could cross again). Moves the surface by at most that much near a curve; 0 "
      "inserts the curves exactly as computed."));
  parameters.addParam(RichBool(
      "separate_touching", defaults.separate_touching, "Separate touching sheets",
      "Where the outer surface touches itself at a vertex or along an edge, the stitched "
      "copies of the vertex move apart by 1/1000 of the local edge length, so that the result "
      "has no touching faces either (they count as self-intersections in exact checks)."));
  parameters.addParam(RichBool(
      "removed_to_layer", false, "Keep removed parts in a new layer",
      "Also puts the faces that were removed (the inside pieces, cut along the curves) into a "
      "new layer named 'removed parts', to see what went."));
  parameters.addParam(
      RichBool("verify", defaults.verify, "Verify the result",
               QString("Counts the intersecting face pairs left in the result, exactly, as "
                       "stored in %1 (remaining_intersecting_pairs in the log and report).")
                   .arg(kHostPrecision)));
  parameters.addParam(RichBool(
      "keep_partial", defaults.keep_partial, "Keep a partial result",
      "Where the result does not pass the check (see the filter's description), write it anyway "
      "so that it can be looked at: the layer's name then ends in '(partial)' and the report "
      "says contract_met false and lists what failed. Off, the layer stays unchanged."));
  parameters.addParam(RichInt(
      "max_intersecting_pairs", int(defaults.max_intersecting_pairs),
      "Work bound: intersecting pairs",
      "More intersecting face pairs than this (found before anything is cut) and the filter "
      "stops with a message, the layer unchanged: cutting costs about 0.1 ms per pair. 0 = no "
      "bound."));
  parameters.addParam(RichInt(
      "max_triple_points_per_face", int(defaults.max_triple_points_per_face),
      "Work bound: crossings within a face",
      "A face where more than this many pairs of the faces crossing it cross each other too "
      "(the surface passing many times through nearly one point, as in a spindle torus) stops "
      "the filter with a message, the layer unchanged: the exact arithmetic there would take "
      "minutes. Real meshes have a few. 0 = no bound."));
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      "When not empty, the outcome is also written to this path as one JSON object (keys: "
      "faces_kept, faces_removed, components_before, components_after, genus_before, "
      "genus_after, remaining_intersecting_pairs, time_ms, ...)."));
}

void SelfIntersectPlugin::apply(QAction*, MeshDocument& md, const RichParameterList& parameters,
                                vcg::CallBackPos* cb) {
  MeshModel* model = md.mm();
  if (!model) throw InvalidInputError("there is no current layer: open a mesh first");
  SelfIntersectionOptions options;
  options.pretreat = parameters.getBool("pretreat");
  options.degenerate_angle_deg = parameters.getFloat("degenerate_angle_deg");
  options.weld_duplicates = parameters.getBool("weld_duplicates");
  options.snap_tolerance = parameters.getFloat("snap_tolerance");
  options.separate_touching = parameters.getBool("separate_touching");
  options.keep_removed = parameters.getBool("removed_to_layer");
  options.verify = parameters.getBool("verify");
  options.keep_partial = parameters.getBool("keep_partial");
  const int maxPairs = parameters.getInt("max_intersecting_pairs");
  const int maxTriples = parameters.getInt("max_triple_points_per_face");
  if (maxPairs < 0 || maxTriples < 0)
    throw InvalidInputError("the work bounds must be 0 (no bound) or more");
  options.max_intersecting_pairs = std::size_t(maxPairs);
  options.max_triple_points_per_face = std::size_t(maxTriples);
  options.round_to_float = kHostStoresFloat;  // decide on what MeshLab will store
  options.progress = progressFrom(cb);

  reportProgress(options.progress, 0, "MeshMend: reading the layer");
  const Mesh core = toCore(model->cm);
  const SelfIntersectionResult r = removeSelfIntersections(core, options);

  JsonObject report = toJson(r);
  report.set("layer", toStd(model->label())).set("partial", !r.contract_met);
  publishReport(parameters, report);
  if (r.unchanged) {
    Log("MeshMend: %s has no self-intersection and nothing enclosed to remove (%.0f ms); the "
        "layer is unchanged",
        layerName(*model).c_str(), r.time_ms);
    reportProgress(options.progress, 100, "MeshMend: done");
    return;
  }

  // The only changes to the document, made last.
  const std::vector<LayerAttributes> attributes{snapshot(*model)};
  if (options.keep_removed && r.removed.fn > 0) {
    MeshModel* rest = md.addNewMesh("", "removed parts", false);
    writeMesh(r.removed, attributes, *rest);
  }
  writeMesh(r.mesh, attributes, *model);
  if (!r.contract_met) model->setLabel(model->label() + " (partial)");

  Log("MeshMend: removed self-intersections of %s in %.0f ms", layerName(*model).c_str(),
      r.time_ms);
  Log("  %zu intersecting pairs cut %zu faces; faces kept %zu, removed %zu",
      r.intersecting_pairs_before, r.faces_split, r.faces_kept, r.faces_removed);
  Log("  components %d -> %d; genus %s -> %s", r.components_before, r.components_after,
      r.genus_before >= 0 ? std::to_string(r.genus_before).c_str() : "n/a",
      r.genus_after >= 0 ? std::to_string(r.genus_after).c_str() : "n/a");
  Log("  pre-treatment: %zu degenerate faces, %zu collapses, %zu flips, %zu left",
      r.degenerate_faces_before, r.collapses, r.flips, r.degenerate_faces_left);
  Log("  stitching: %zu vertices and %zu edges duplicated, %zu copies moved apart",
      r.vertices_duplicated, r.edges_duplicated, r.vertices_separated);
  Log("  result: %s, %zu border edges, %zu non-manifold edges", r.output_closed ? "closed" : "open",
      r.border_edges_after, r.non_manifold_edges_after);
  if (!r.input_closed)
    Log("  note: the mesh has borders: seeds were faces with nothing in front of them, and "
        "borders stay borders");
  if (r.inside_out)
    Log("  note: the mesh is closed and inside out (negative volume); it stays so: run "
        "Filters > Normals > Invert Faces Orientation if that is not intended");
  if (r.snapping_dropped)
    Log("  note: snapping left crossings or non-manifold edges (sheets closer than its "
        "tolerance): the result was made again without snapping");
  if (r.verified) Log("  check: %zu intersecting pairs left", r.remaining_intersecting_pairs);
  if (!r.contract_met) {
    Log("  warning: PARTIAL result (kept as asked), the layer is now %s; what does not hold:",
        layerName(*model).c_str());
    for (const std::string& failure : r.contract_failures) Log("    %s", failure.c_str());
  }
  reportProgress(options.progress, 100, "MeshMend: done");
}

MESHLAB_PLUGIN_NAME_EXPORTER(SelfIntersectPlugin)
