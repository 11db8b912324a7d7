#include "filter_mend_stitch.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/repair/edit_contract.h"
#include "common/repair/stitch/stitch.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

// The choices of the enum parameters, in the order of the dialog and scripts.
enum KeepSide { kKeepSelectedFace, kKeepFaceIndex, kKeepLeftOfLoop };
enum PathsFrom { kTwoPathsOneLayer, kOnePathPerLayer, kSequence };
enum StitchOutput { kNewLayer, kIntoFirstLayer };

// "12 45, 46": vertex (or path) indices as a user types them. Commas and
// white space separate; anything else is an error naming the token.
std::vector<int> parseIndices(const std::string& text, const std::string& what) {
  std::vector<int> out;
  std::string token;
  auto flush = [&] {
    if (token.empty()) return;
    std::size_t used = 0;
    long value = -1;
    try {
      value = std::stol(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size() || value < 0 || value > 2147483647L)
      throw InvalidInputError(what + ": '" + token +
                              "' is not a vertex index (give indices separated by spaces)");
    out.push_back(int(value));
    token.clear();
  };
  for (char c : text) {
    if (c == ',' || std::isspace(static_cast<unsigned char>(c)))
      flush();
    else
      token += c;
  }
  flush();
  return out;
}

// Lists separated by ';' ("0 1 2; 7 8 9").
std::vector<std::vector<int>> parseLists(const std::string& text, const std::string& what) {
  std::vector<std::vector<int>> lists;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find(';', begin), text.size());
    std::vector<int> list = parseIndices(text.substr(begin, end - begin), what);
    if (!list.empty()) lists.push_back(std::move(list));
    begin = end + 1;
  }
  return lists;
}

// MeshLab's indices (slots of cm.vert / cm.face, the numbers a user sees)
// to the core's, which skip deleted elements.
struct IndexMap {
  std::vector<int> vertex, face;
};

IndexMap indexMapOf(Mesh& core, const CMeshO& cm) {
  IndexMap map;
  map.vertex.assign(cm.vert.size(), -1);
  map.face.assign(cm.face.size(), -1);
  VertexOriginHandle vo = vertexOrigins(core);
  FaceOriginHandle fo = faceOrigins(core);
  for (std::size_t v = 0; v < core.vert.size(); ++v) map.vertex[vo[v].vertex] = int(v);
  for (std::size_t f = 0; f < core.face.size(); ++f) map.face[fo[f].face] = int(f);
  return map;
}

std::vector<int> toCoreVertices(const std::vector<int>& indices, const IndexMap& map,
                                const MeshModel& model, const std::string& what, int offset = 0) {
  std::vector<int> out;
  out.reserve(indices.size());
  for (int i : indices) {
    if (i < 0 || std::size_t(i) >= map.vertex.size() || map.vertex[i] < 0)
      throw InvalidInputError(what + " names vertex " + std::to_string(i) + ", which " +
                              layerName(model) + " does not have (it has " +
                              std::to_string(model.cm.vn) + " vertices)");
    out.push_back(map.vertex[i] + offset);
  }
  return out;
}

// The selected vertices as one flag per core vertex.
std::vector<bool> selectedVertices(Mesh& core, const CMeshO& cm) {
  VertexOriginHandle vo = vertexOrigins(core);
  std::vector<bool> selected(core.vert.size(), false);
  for (std::size_t v = 0; v < core.vert.size(); ++v) selected[v] = cm.vert[vo[v].vertex].IsS();
  return selected;
}

std::vector<int> selectedFaces(Mesh& core, const CMeshO& cm) {
  FaceOriginHandle fo = faceOrigins(core);
  std::vector<int> selected;
  for (std::size_t f = 0; f < core.face.size(); ++f)
    if (cm.face[fo[f].face].IsS()) selected.push_back(int(f));
  return selected;
}

std::string describePath(const BorderPath& p) {
  std::string s = std::to_string(p.vertices.size()) + " vertices, " +
                  (p.shape == BorderPath::Shape::Closed ? "closed" : "open") + ", from vertex " +
                  std::to_string(p.vertices.front());
  if (p.shape != BorderPath::Shape::Closed) s += " to " + std::to_string(p.vertices.back());
  return s;
}

// The border runs of a selection; `want` of them (0: any number, at least one).
std::vector<BorderPath> selectedBorderPaths(Mesh& core, const CMeshO& cm, const MeshModel& model,
                                            std::size_t want) {
  std::vector<BorderPath> paths = borderPathsFromSelection(core, selectedVertices(core, cm));
  if (paths.empty())
    throw InvalidInputError("no selected vertex of " + layerName(model) +
                            " is on a border edge next to another selected one: select the border "
                            "vertices of the paths to stitch (e.g. Filters > Selection > Select "
                            "Border, then deselect what to leave open)");
  if (want > 0 && paths.size() != want) {
    std::string list;
    for (std::size_t k = 0; k < paths.size() && k < 6; ++k)
      list += (k ? "; " : "") + describePath(paths[k]);
    throw InvalidInputError("the selected border vertices of " + layerName(model) + " form " +
                            std::to_string(paths.size()) + " paths along border edges (" + list +
                            "), but " + std::to_string(want) + (want == 1 ? " is" : " are") +
                            " needed here: select exactly that");
  }
  return paths;
}

BorderPath pathFromList(const std::vector<int>& vertices) {
  BorderPath p;
  p.vertices = vertices;
  return p;  // Shape::Auto: closed when the first vertex is repeated at the end
}

void selectOnly(CMeshO& cm, const std::vector<int>& faces) {
  for (CFaceO& f : cm.face) f.ClearS();
  for (CVertexO& v : cm.vert) v.ClearS();
  for (int f : faces) cm.face[f].SetS();
}

}  // namespace

StitchPlugin::StitchPlugin() {
  addFilters(this, {TRIM_ALONG_LOOP, STITCH_BOUNDARIES, CLOSE_GAPS});
}

QString StitchPlugin::filterName(FilterIDType id) const {
  switch (id) {
    case TRIM_ALONG_LOOP:
      return "MeshMend: Trim Along Vertex Loop";
    case STITCH_BOUNDARIES:
      return "MeshMend: Stitch Boundaries";
    default:
      return "MeshMend: Close Gaps Between Borders";
  }
}

QString StitchPlugin::pythonFilterName(FilterIDType filter) const {
  switch (filter) {
    case TRIM_ALONG_LOOP:
      return "meshmend_trim_along_vertex_loop";
    case STITCH_BOUNDARIES:
      return "meshmend_stitch_boundaries";
    default:
      return "meshmend_close_gaps";
  }
}

QString StitchPlugin::filterInfo(FilterIDType id) const {
  const QString paper =
      "<br>Method: <i>Ekeberg, Engwall, Stavness et al.</i>, <b>\"Trimming and stitching of "
      "surface meshes for a dynamic vocal tract\"</b> (merge-like stitching, §2.2; trimming, "
      "§2.1), with consistently oriented stitches, automatic pairing and exact checks added.";
  if (id == TRIM_ALONG_LOOP)
    return "Removes the faces on one side of a closed loop of vertices, without adding or moving "
           "any vertex. The loop is, in this order of precedence: the ordered vertex indices of "
           "<i>loop_vertices</i> (consecutive ones must share an edge); a few "
           "<i>picked_vertices</i> joined by shortest edge paths; or the selected vertices, "
           "which must form one closed path along edges.<br>"
           "<b>In the GUI:</b> select the loop's vertices (Edit > Select Vertices, or "
           "Filters > Selection), then select exactly one face on the side to keep (Edit > "
           "Select Faces) and run the filter with 'Side to keep' = the selected face. If "
           "selecting that face also selected its corners, those corners are ignored for the "
           "loop when the loop needs it. Other sides: a face given by index, or the left of "
           "the loop as seen from the side the normals point to (index lists only: a "
           "selection has no direction). Faces with all three corners on the loop are "
           "classified by their orientation. Parts the loop does not touch are kept. "
           "Optionally the removed faces go to a new layer. A selection that is not a loop "
           "(the message names the vertex where it breaks) or a loop that does not separate "
           "the mesh leaves the layer unchanged." +
           paper;
  if (id == STITCH_BOUNDARIES)
    return "Joins two border paths with a strip of new faces (the merge-like triangulation: "
           "at each step the shorter of the two next diagonals). No vertex is added unless "
           "subdivision is asked for; the new faces are oriented like the faces they join; "
           "paths of different density, non-coplanar paths, open paths and closed loops "
           "(aligned automatically) are handled; every new face is checked exactly against "
           "the mesh.<br>"
           "<b>Paths:</b> two runs of selected border vertices on the current layer; one run "
           "on each of two layers (the layer matrices are applied); or, for junctions of three "
           "or more patches, several paths stitched in sequence, where two leftover paths that "
           "a stitch connects are concatenated so the junction is covered too. Index lists "
           "(<i>path_a</i>, <i>path_b</i>, <i>paths</i>) replace the selection in scripts; a "
           "path is closed when its first index is repeated at its end.<br>"
           "<b>Two layers:</b> by default the result is a new layer 'stitched' holding both "
           "layers joined by the strip (it becomes the current layer; the two inputs are kept "
           "and hidden); or, as chosen, the first layer receives the result and the second "
           "layer is deleted (it is merged into the first).<br>" +
           QString(
               "With subdivision, new vertices are computed in double precision and stored "
               "by MeshLab in %1; the exact check is made on the double ones.")
               .arg(kHostPrecision) +
           paper;
  return "Closes the gaps between borders automatically. Step 1 (what CGAL's stitch_borders "
         "does, with a tolerance): faces that face against their neighbours are flipped (a "
         "closed part is turned outward), then border edges whose end points coincide within "
         "the merge tolerance and that run opposite ways are merged; a border edge of zero "
         "length collapses its face, and where solids touch along an edge each closes on its "
         "own. Step 2: border loops, or runs of them, that face each other within the maximum "
         "gap are stitched with the merge-like triangulation, also the two sides of a crack in "
         "one loop; within one part, a slit or crack no wider than the local gap factor times "
         "its border edges is closed even beyond the maximum gap, and borders that face each "
         "other after a round of stitches are stitched in the next. Nothing is merged or "
         "stitched that would make an edge non-manifold or break the orientation; a stitch "
         "whose faces would intersect the mesh is left out "
         "with its reason in the log. Works on the current layer, or on all visible layers "
         "merged into a new layer (layer matrices applied). Merged vertices are removed, so "
         "vertex indices change; faces keep their attributes." +
         paper;
}

// ------------------------------------------------------------------ contract

namespace {

RichBool keepPartialParameter() {
  return RichBool(
      "keep_partial", EditContractOptions().keep_partial, "Keep a partial result",
      "The result is checked exactly as it will be stored: no new edge with more than two "
      "faces, no new edge run the same way by both its faces, no new face without area, no "
      "intersecting pair with a new or changed face. Where that does not hold the layers stay "
      "unchanged; on, the result is written anyway, its layer's name ending in '(partial)' and "
      "the report saying contract_met false.");
}

void logContract(FilterAdapter& plugin, const EditContract& c, MeshModel& layer) {
  if (c.met) return;
  layer.setLabel(layer.label() + " (partial)");
  plugin.Log(
      "  warning: PARTIAL result (kept as asked), the layer is now %s; what does not hold: %s",
      layerName(layer).c_str(), describeFailures(c).c_str());
}

}  // namespace

namespace {

void addTrimParameters(RichParameterList& parameters) {
  const TrimOptions trim;  // the core's defaults
  parameters.addParam(RichString(
      "loop_vertices", "", "Loop (vertex indices)",
      "The loop as vertex indices in order, separated by spaces, e.g. '12 45 46 ...' "
      "(consecutive vertices share an edge; the last joins the first). Empty: the picked "
      "vertices below, else the selected vertices."));
  parameters.addParam(RichString(
      "picked_vertices", "", "Picked vertices (indices)",
      "A few vertex indices in order around the loop, joined by shortest edge paths "
      "(used when the loop above is empty). Empty: the selected vertices form the loop."));
  parameters.addParam(RichEnum(
      "keep_side", kKeepSelectedFace,
      QStringList() << "The side of the selected face"
                    << "The side of face 'keep_face'"
                    << "Left of the loop (its direction)",
      "Side to keep",
      "Selected face: exactly one face must be selected, on the side to keep. keep_face: "
      "the face with that index. Left of the loop: the side on the left when walking the "
      "loop in its given order, seen from where the normals point (an index list or picked "
      "vertices only: a selection has no direction)."));
  parameters.addParam(RichInt("keep_face", trim.keep_face, "Face to keep (index)",
                              "Index of a face on the side to keep, for 'Side to keep' = "
                              "face 'keep_face'; ignored otherwise."));
  parameters.addParam(RichBool(
      "remove_unreferenced_vertices", trim.remove_unreferenced_vertices,
      "Remove unreferenced vertices",
      "Also removes the vertices that only removed faces used (vertex indices change). Off: "
      "every vertex stays, some unreferenced."));
  parameters.addParam(
      RichBool("removed_to_layer", false, "Keep removed faces in a new layer",
               "Also puts the removed faces into a new layer named 'trimmed away', so nothing is "
               "lost."));
}

void addStitchParameters(MeshDocument& md, RichParameterList& parameters) {
  const StitchOptions stitch;  // the core's defaults
  MeshModel* current = md.mm();
  MeshModel* other = layerOtherThanCurrent(md);
  parameters.addParam(RichEnum(
      "paths_from", kTwoPathsOneLayer,
      QStringList() << "Two paths on the current layer"
                    << "One path on each of two layers"
                    << "Several paths in sequence (junctions)",
      "Paths",
      "Two paths on the current layer: path_a and path_b, or the two runs of selected border "
      "vertices. One path on each of two layers: path_a on the first layer, path_b on the "
      "second (or one run of selected border vertices on each). Several paths in sequence: "
      "'paths' (or every run of selected border vertices) stitched pairwise as "
      "'stitch_pairs' says, leftover paths concatenated at junctions."));
  parameters.addParam(layerParameter("first_layer", current, md, "First layer",
                                     "First layer of the 'one path on each of two layers' mode."));
  parameters.addParam(layerParameter("second_layer", other, md, "Second layer",
                                     "Second layer of the 'one path on each of two layers' mode."));
  parameters.addParam(
      RichString("path_a", "", "Path A (vertex indices)",
                 "Border vertex indices in order along the border, separated by spaces; repeat the "
                 "first at the end for a closed loop. Empty: from the selected border vertices."));
  parameters.addParam(RichString(
      "path_b", "", "Path B (vertex indices)",
      "The other path, like path A (on the second layer in the two-layer mode, with that "
      "layer's indices). Empty: from the selected border vertices."));
  parameters.addParam(RichString(
      "paths", "", "Paths for the sequence (vertex indices)",
      "For the sequence mode: paths separated by ';', e.g. '0 1 2; 9 8 7; 20 21'. Empty: "
      "every run of selected border vertices, numbered as the log lists them."));
  parameters.addParam(RichString(
      "stitch_pairs", "", "Pairs to stitch, in order",
      "For the sequence mode: pairs of path numbers (from 0) separated by ';', e.g. "
      "'0 1; 2 4'. Empty: 0 1; 2 3; 4 5; ... A path concatenated into another is referred "
      "to by either number."));
  parameters.addParam(RichFloat(
      "max_aspect_ratio", float(stitch.max_aspect_ratio),
      "Subdivide above aspect ratio (0 = never)",
      QString("When a rung across the gap is longer than this many times the mean edge "
              "length of the two paths, rows of new vertices are inserted across the strip; "
              "0 adds no vertex. New vertices are stored in %1.")
          .arg(kHostPrecision)));
  parameters.addParam(RichInt("max_rows", stitch.max_rows, "Max rows of new vertices",
                              "At most this many rows of new vertices across a wide strip."));
  parameters.addParam(RichBool(
      "allow_orientation_conflict", stitch.allow_orientation_conflict,
      "Allow opposite orientations",
      "Two sides whose faces are oppositely oriented cannot be joined consistently: they are "
      "refused unless this is on; then the new faces follow path A's side and the "
      "conflicting edges are counted."));
  parameters.addParam(
      RichBool("check_intersections", stitch.check_intersections, "Check intersections",
               "Counts, exactly, the pairs of faces that a new face makes intersect "
               "(new_intersecting_pairs in the log and report)."));
  parameters.addParam(
      RichEnum("output", kNewLayer,
               QStringList() << "New layer 'stitched' (inputs kept, hidden)"
                             << "Into the first layer (the second is deleted)",
               "Two-layer output",
               "For the two-layer mode. New layer: both layers joined by the strip go to a new, "
               "current layer; the inputs are hidden, unchanged. Into the first layer: the first "
               "layer receives the result and the second layer is removed from the document."));
  parameters.addParam(RichBool("select_new_faces", false, "Select the new faces",
                               "Selects the stitched faces afterwards (and nothing else)."));
  parameters.addParam(keepPartialParameter());
}

void addCloseGapsParameters(RichParameterList& parameters) {
  const CloseGapsOptions gaps;  // the core's defaults
  parameters.addParam(RichFloat(
      "merge_tolerance", float(gaps.merge_tolerance), "Merge tolerance (fraction of the diagonal)",
      "Border vertices closer than this fraction of the bounding box diagonal are merged "
      "where their border edges pair up; 0 merges only exactly equal coordinates (what "
      "CGAL's stitch_borders does)."));
  parameters.addParam(RichBool(
      "orient_faces", gaps.orient_faces, "Orient faces consistently",
      "Before merging, flips faces so that faces meeting at an edge run it opposite ways "
      "(soups whose facets face against their neighbours then merge); a part that needs it is "
      "turned outward when closed, else keeps the orientation of most of its area."));
  parameters.addParam(RichFloat(
      "max_gap", float(gaps.max_gap), "Max gap (fraction of the diagonal)",
      "Borders facing each other within this fraction of the bounding box diagonal are "
      "stitched with new faces (within one part, narrow slits also beyond it: see the local "
      "gap factor); 0 only merges."));
  parameters.addParam(RichFloat(
      "local_gap_factor", float(gaps.local_gap_factor), "Local gap factor (x border edge length)",
      "Within one part, a slit or crack no wider than this many times the mean length of the "
      "border edges on either side is closed too, even beyond the max gap; separate parts are "
      "stitched within the max gap only. 0: the max gap alone."));
  parameters.addParam(
      RichInt("min_path_vertices", gaps.min_path_vertices, "Min facing run (vertices)",
              "Runs of fewer border vertices facing another border are left open."));
  parameters.addParam(RichFloat(
      "max_aspect_ratio", float(gaps.max_aspect_ratio), "Subdivide above aspect ratio (0 = never)",
      QString("Stitched strips whose rungs are longer than this many times the mean "
              "path edge length get rows of new vertices (stored in %1); 0 adds no "
              "vertex.")
          .arg(kHostPrecision)));
  parameters.addParam(
      RichBool("check_intersections", gaps.check_intersections, "Check intersections",
               "Tests every stitch exactly against the mesh; one whose faces would intersect is "
               "left out, with its reason in the log."));
  parameters.addParam(
      RichBool("all_visible_layers", false, "All visible layers",
               "Merges every visible layer into a new layer 'gaps closed' (layer matrices applied) "
               "and closes the gaps there, also between layers; the inputs are hidden, unchanged. "
               "Off: the current layer, in place."));
  parameters.addParam(RichBool("select_new_faces", false, "Select the new faces",
                               "Selects the stitched faces afterwards (and nothing else)."));
  parameters.addParam(keepPartialParameter());
}

}  // namespace

void StitchPlugin::initParameters(QAction* a, MeshDocument& md, RichParameterList& parameters) {
  // The defaults are the core's (the Python module reads the same).
  if (ID(a) == TRIM_ALONG_LOOP)
    addTrimParameters(parameters);
  else if (ID(a) == STITCH_BOUNDARIES)
    addStitchParameters(md, parameters);
  else
    addCloseGapsParameters(parameters);
  const QString report =
      "When not empty, the outcome is also written to this path as one JSON object (keys: "
      "border_edges_before, border_edges_after, faces_added, vertices_merged, time_ms, ...).";
  parameters.addParam(RichString("report_file", "", "Report file (JSON)", report));
}

void StitchPlugin::apply(QAction* a, MeshDocument& md, const RichParameterList& parameters,
                         vcg::CallBackPos* cb) {
  switch (ID(a)) {
    case TRIM_ALONG_LOOP:
      trim(md, parameters, cb);
      break;
    case STITCH_BOUNDARIES:
      stitch(md, parameters, cb);
      break;
    default:
      closeGaps(md, parameters, cb);
  }
}

// ------------------------------------------------------------------ trim

void StitchPlugin::trim(MeshDocument& md, const RichParameterList& parameters,
                        vcg::CallBackPos* cb) {
  MeshModel* model = md.mm();
  if (!model) throw InvalidInputError("there is no current layer: open a mesh first");
  TrimOptions options;
  options.progress = progressFrom(cb);
  options.remove_unreferenced_vertices = parameters.getBool("remove_unreferenced_vertices");
  reportProgress(options.progress, 0, "MeshMend: reading the layer");
  Mesh core = toCore(model->cm);
  requireFacesAndFiniteCoordinates(core, layerName(*model));
  const IndexMap map = indexMapOf(core, model->cm);

  const std::vector<int> loop =
      parseIndices(toStd(parameters.getString("loop_vertices")), "loop_vertices");
  const std::vector<int> picked =
      parseIndices(toStd(parameters.getString("picked_vertices")), "picked_vertices");
  std::string source;
  if (!loop.empty()) {
    options.loop = toCoreVertices(loop, map, *model, "loop_vertices");
    source = "the index list";
  } else if (!picked.empty()) {
    options.picked_vertices = toCoreVertices(picked, map, *model, "picked_vertices");
    source = "the picked vertices";
  } else {
    options.selected_vertices = selectedVertices(core, model->cm);
    source = "the selected vertices";
  }

  const int keepSide = parameters.getEnum("keep_side");
  std::vector<int> faceCorners;  // of the selected face: maybe selected along with it
  if (keepSide == kKeepSelectedFace) {
    const std::vector<int> faces = selectedFaces(core, model->cm);
    if (faces.size() != 1)
      throw InvalidInputError(
          std::to_string(faces.size()) +
          " faces are selected: 'Side to keep' = the selected face needs exactly one, on the "
          "side to keep (Edit > Select Faces, one click), besides the loop's vertices");
    options.keep_face = faces.front();
    for (int k = 0; k < 3; ++k)
      faceCorners.push_back(int(vcg::tri::Index(core, core.face[faces.front()].cV(k))));
  } else if (keepSide == kKeepFaceIndex) {
    const int f = parameters.getInt("keep_face");
    if (f < 0 || std::size_t(f) >= map.face.size() || map.face[f] < 0)
      throw InvalidInputError("keep_face " + std::to_string(f) + " is not a face of " +
                              layerName(*model) + " (it has " + std::to_string(model->cm.fn) +
                              " faces)");
    options.keep_face = map.face[f];
  } else if (keepSide == kKeepLeftOfLoop) {
    options.keep_face = -1;
  } else {
    throw InvalidInputError("unknown side to keep " + std::to_string(keepSide) + ": use 0 to 2");
  }

  // Selecting a face in MeshLab may select its corners too: when the
  // selection is not a loop as it is, the corners of the kept face that are
  // not needed by the loop are left out (the first subset that gives a loop).
  TrimResult r;
  bool done = false;
  if (!options.selected_vertices.empty() && !faceCorners.empty()) {
    const std::vector<bool> asSelected = options.selected_vertices;
    try {
      r = trimAlongLoop(core, options);
      done = true;
    } catch (const InvalidInputError& first) {
      for (int subset = 1; subset < 8 && !done; ++subset) {
        options.selected_vertices = asSelected;
        bool changes = false;
        for (int k = 0; k < 3; ++k)
          if ((subset >> k) & 1 && options.selected_vertices[faceCorners[k]]) {
            options.selected_vertices[faceCorners[k]] = false;
            changes = true;
          }
        if (!changes) continue;
        try {
          r = trimAlongLoop(core, options);
          done = true;
          Log("  note: corners of the selected face were left out of the loop");
        } catch (const InvalidInputError&) {
        }
      }
      if (!done) throw;
    }
  }
  const Mesh before = toCore(model->cm);
  if (!done) r = trimAlongLoop(core, options);
  EditContractOptions co = editContractOptions(options, false);
  co.as_float = kHostStoresFloat;
  const EditContract contract =
      requireEditContract(before, core, "Trim Along Vertex Loop", co,
                          "Trimming only removes faces, so this is a defect: please report it "
                          "with the mesh and the loop");

  JsonObject report = toJson(r);
  report.set("layer", toStd(model->label())).set("loop_from", source);
  reportContract(report, contract);
  publishReport(parameters, report);

  // The only changes to the document, made last.
  const std::vector<LayerAttributes> attributes{snapshot(*model)};
  if (parameters.getBool("removed_to_layer") && r.removed.fn > 0) {
    MeshModel* rest = md.addNewMesh("", "trimmed away", false);
    writeMesh(r.removed, attributes, *rest);
    rest->cm.Tr = model->cm.Tr;
  }
  writeMesh(core, attributes, *model);

  Log("MeshMend: trimmed %s along a loop of %zu vertices (from %s) in %.0f ms",
      layerName(*model).c_str(), r.loop.size(), source.c_str(), r.time_ms);
  Log("  faces kept %zu, removed %zu (%zu with all corners on the loop); border edges %zu -> %zu",
      r.faces_kept, r.faces_removed, r.faces_on_loop, r.border_edges_before, r.border_edges_after);
  reportProgress(options.progress, 100, "MeshMend: done");
}

// ------------------------------------------------------------------ stitch

namespace {

StitchOptions stitchOptionsFrom(const RichParameterList& parameters, vcg::CallBackPos* cb) {
  StitchOptions options;
  options.max_aspect_ratio = parameters.getFloat("max_aspect_ratio");
  options.round_to_float = kHostStoresFloat;  // store what this MeshLab stores
  options.max_rows = parameters.getInt("max_rows");
  if (!(options.max_aspect_ratio >= 0) || options.max_rows < 0)
    throw InvalidInputError("the aspect ratio bound and the number of rows must not be negative");
  options.allow_orientation_conflict = parameters.getBool("allow_orientation_conflict");
  options.check_intersections = parameters.getBool("check_intersections");
  options.progress = progressFrom(cb);
  return options;
}

// The layers a stitch reads and the core mesh it edits (a Mesh cannot
// move: built in place).
struct StitchInput {
  std::vector<MeshModel*> layers;
  std::unique_ptr<Mesh> core;
};

// One path on each of two layers: both layers in one mesh, in one frame
// (the layer matrices applied), path b after a's vertices.
StitchInput readTwoLayers(MeshDocument& md, const RichParameterList& parameters,
                          StitchOptions& options) {
  MeshModel* first = layerFrom(parameters, md, "first_layer");
  MeshModel* second = layerFrom(parameters, md, "second_layer");
  if (!first || !second) throw InvalidInputError("choose the two layers to stitch");
  if (first == second)
    throw InvalidInputError("the same layer (" + layerName(*first) +
                            ") was chosen twice: choose two layers, or the mode 'Two paths "
                            "on the current layer'");
  reportProgress(options.progress, 0, "MeshMend: reading the layers");
  Mesh a, b;
  toCore(first->cm, a, {0, true});
  toCore(second->cm, b, {1, true});
  requireFacesAndFiniteCoordinates(a, layerName(*first));
  requireFacesAndFiniteCoordinates(b, layerName(*second));
  const std::string listA = toStd(parameters.getString("path_a"));
  const std::string listB = toStd(parameters.getString("path_b"));
  const IndexMap mapA = indexMapOf(a, first->cm), mapB = indexMapOf(b, second->cm);
  options.a =
      listA.empty()
          ? selectedBorderPaths(a, first->cm, *first, 1).front()
          : pathFromList(toCoreVertices(parseIndices(listA, "path_a"), mapA, *first, "path_a"));
  options.b =
      listB.empty()
          ? selectedBorderPaths(b, second->cm, *second, 1).front()
          : pathFromList(toCoreVertices(parseIndices(listB, "path_b"), mapB, *second, "path_b"));
  for (int& v : options.b.vertices) v += int(a.vert.size());
  StitchInput in;
  in.layers = {first, second};
  in.core.reset(new Mesh(appended(a, b)));
  return in;
}

StitchInput readCurrentLayer(MeshDocument& md, const StitchOptions& options) {
  MeshModel* model = md.mm();
  if (!model) throw InvalidInputError("there is no current layer: open a mesh first");
  reportProgress(options.progress, 0, "MeshMend: reading the layer");
  StitchInput in;
  in.layers = {model};
  in.core = std::make_unique<Mesh>();
  toCore(model->cm, *in.core);
  requireFacesAndFiniteCoordinates(*in.core, layerName(*model));
  return in;
}

// Two paths on the current layer: path_a and path_b, or the two runs of
// selected border vertices.
void pathsOnOneLayer(const RichParameterList& parameters, Mesh& core, MeshModel& current,
                     StitchOptions& options) {
  const std::string listA = toStd(parameters.getString("path_a"));
  const std::string listB = toStd(parameters.getString("path_b"));
  if (listA.empty() != listB.empty())
    throw InvalidInputError(
        "give both path_a and path_b, or neither (then the selected border vertices form the "
        "two paths)");
  if (listA.empty()) {
    const std::vector<BorderPath> paths = selectedBorderPaths(core, current.cm, current, 2);
    options.a = paths[0];
    options.b = paths[1];
    return;
  }
  const IndexMap map = indexMapOf(core, current.cm);
  options.a = pathFromList(toCoreVertices(parseIndices(listA, "path_a"), map, current, "path_a"));
  options.b = pathFromList(toCoreVertices(parseIndices(listB, "path_b"), map, current, "path_b"));
}

// Several paths in sequence: 'paths' (or every run of selected border
// vertices) stitched pairwise as 'stitch_pairs' says.
StitchSequenceOptions sequenceOptionsFrom(const RichParameterList& parameters, Mesh& core,
                                          MeshModel& current, const StitchOptions& options) {
  StitchSequenceOptions so;
  so.stitch = options;
  const std::string listed = toStd(parameters.getString("paths"));
  if (listed.empty()) {
    so.paths = selectedBorderPaths(core, current.cm, current, 0);
  } else {
    const IndexMap map = indexMapOf(core, current.cm);
    for (const std::vector<int>& list : parseLists(listed, "paths"))
      so.paths.push_back(pathFromList(toCoreVertices(list, map, current, "paths")));
  }
  const std::string pairsText = toStd(parameters.getString("stitch_pairs"));
  if (pairsText.empty()) {
    for (std::size_t k = 0; k + 1 < so.paths.size(); k += 2)
      so.pairs.push_back({int(k), int(k + 1)});
  } else {
    for (const std::vector<int>& pair : parseLists(pairsText, "stitch_pairs")) {
      if (pair.size() != 2)
        throw InvalidInputError("stitch_pairs: each pair is two path numbers ('0 1; 2 4')");
      for (int p : pair)
        if (std::size_t(p) >= so.paths.size())
          throw InvalidInputError("stitch_pairs names path " + std::to_string(p) + ", but " +
                                  std::to_string(so.paths.size()) + " paths are given");
      so.pairs.push_back({pair[0], pair[1]});
    }
  }
  if (so.pairs.empty())
    throw InvalidInputError("the sequence needs at least two paths (" +
                            std::to_string(so.paths.size()) + " given)");
  return so;
}

}  // namespace

void StitchPlugin::stitch(MeshDocument& md, const RichParameterList& parameters,
                          vcg::CallBackPos* cb) {
  const int mode = parameters.getEnum("paths_from");
  if (mode < 0 || mode > kSequence)
    throw InvalidInputError("unknown path source " + std::to_string(mode) + ": use 0 to 2");
  StitchOptions options = stitchOptionsFrom(parameters, cb);
  StitchInput in = mode == kOnePathPerLayer ? readTwoLayers(md, parameters, options)
                                            : readCurrentLayer(md, options);
  const std::vector<MeshModel*>& layers = in.layers;
  Mesh& core = *in.core;
  MeshModel& current = *layers.front();
  const Mesh before = core;

  JsonObject report;
  std::vector<int> newFaces;
  if (mode == kSequence) {
    const StitchSequenceOptions so = sequenceOptionsFrom(parameters, core, current, options);
    for (std::size_t k = 0; k < so.paths.size(); ++k)
      Log("  path %zu: %s", k, describePath(so.paths[k]).c_str());
    const StitchSequenceResult r = stitchPathsSequence(core, so);
    report = toJson(r);
    for (const StitchResult& s : r.steps)
      newFaces.insert(newFaces.end(), s.new_faces.begin(), s.new_faces.end());
    Log("MeshMend: %zu stitches in sequence on %s: %zu faces and %zu vertices added, border "
        "edges %zu -> %zu, %zu intersecting pairs with new faces (%.0f ms)",
        r.steps.size(), layerName(current).c_str(), r.faces_added, r.vertices_added,
        r.border_edges_before, r.border_edges_after, r.new_intersecting_pairs, r.time_ms);
    for (std::size_t k = 0; k < r.concatenated.size(); ++k)
      for (const auto& c : r.concatenated[k])
        Log("  after stitch %zu: paths %d and %d concatenated at the junction", k, c[0], c[1]);
  } else {
    if (mode == kTwoPathsOneLayer) pathsOnOneLayer(parameters, core, current, options);
    const StitchResult r = stitchPaths(core, options);
    report = toJson(r);
    newFaces = r.new_faces;
    Log("MeshMend: stitched %s (%zu and %zu path vertices%s): %zu faces and %zu vertices added, "
        "border edges %zu -> %zu, largest aspect ratio %.3g (%.0f ms)",
        layers.size() == 2 ? "two layers" : layerName(current).c_str(), options.a.vertices.size(),
        options.b.vertices.size(), r.closed ? ", two loops" : "", r.faces_added, r.vertices_added,
        r.border_edges_before, r.border_edges_after, r.max_aspect_ratio, r.time_ms);
    if (r.checked) Log("  check: %zu intersecting pairs with a new face", r.new_intersecting_pairs);
    if (r.orientation_conflicts)
      Log("  warning: %zu border edges run against the orientation of the new faces",
          r.orientation_conflicts);
    if (r.vertices_added)
      Log("  note: the %zu new vertices are stored in %s (computed in double)", r.vertices_added,
          kHostPrecision);
  }
  const EditContract contract = requireEditContract(
      before, core, "Stitch Boundaries",
      editContractOptions(options, parameters.getBool("keep_partial")),
      "Try paths that face each other, without subdivision (aspect ratio 0), or turn on 'Keep "
      "a partial result' to see what was made");
  reportContract(report, contract);
  const int output = parameters.getEnum("output");
  std::vector<std::string> names;
  for (MeshModel* m : layers) names.push_back(toStd(m->label()));
  report.set("layers", names);
  if (layers.size() == 2)
    report.set("output", output == kIntoFirstLayer ? "first layer" : "new layer");
  publishReport(parameters, report);

  // The only changes to the document, made last.
  std::vector<LayerAttributes> attributes;
  for (MeshModel* m : layers) attributes.push_back(snapshot(*m));
  MeshModel* target = &current;
  if (layers.size() == 2 && output == kIntoFirstLayer) {
    writeMesh(core, attributes, current);
    current.cm.Tr.SetIdentity();  // the geometry is in the common frame now
    deleteLayer(md, layers[1]);
    md.setCurrent(&current);
    Log("  the result is in %s; the second layer was merged into it and removed",
        layerName(current).c_str());
  } else if (layers.size() == 2) {
    target = md.addNewMesh("", "stitched", true);
    writeMesh(core, attributes, *target);
    target->cm.Tr.SetIdentity();
    for (MeshModel* m : layers) setLayerVisible(*m, false);
    Log("  the result is the new layer 'stitched'; the inputs are hidden, unchanged");
  } else {
    writeMesh(core, attributes, current);
  }
  if (parameters.getBool("select_new_faces")) selectOnly(target->cm, newFaces);
  logContract(*this, contract, *target);
  reportProgress(options.progress, 100, "MeshMend: done");
}

// ------------------------------------------------------------------ close gaps

void StitchPlugin::closeGaps(MeshDocument& md, const RichParameterList& parameters,
                             vcg::CallBackPos* cb) {
  CloseGapsOptions options;
  options.progress = progressFrom(cb);
  options.merge_tolerance = parameters.getFloat("merge_tolerance");  // fractions of the diagonal
  options.max_gap = parameters.getFloat("max_gap");
  options.local_gap_factor = parameters.getFloat("local_gap_factor");
  options.orient_faces = parameters.getBool("orient_faces");
  options.min_path_vertices = parameters.getInt("min_path_vertices");
  options.max_aspect_ratio = parameters.getFloat("max_aspect_ratio");
  options.round_to_float = kHostStoresFloat;  // store what this MeshLab stores
  options.check_intersections = parameters.getBool("check_intersections");
  if (!(options.merge_tolerance >= 0) || !(options.max_gap >= 0) ||
      !(options.local_gap_factor >= 0) || !(options.max_aspect_ratio >= 0))
    throw InvalidInputError(
        "the merge tolerance, the max gap, the local gap factor and the aspect ratio bound must "
        "not be negative");
  const bool allVisible = parameters.getBool("all_visible_layers");

  std::vector<MeshModel*> layers;
  std::unique_ptr<Mesh> core = std::make_unique<Mesh>();
  reportProgress(options.progress, 0, "MeshMend: reading the layers");
  if (allVisible) {
    for (MeshModel* m : layersOf(md))
      if (m->isVisible() && m->cm.fn > 0) layers.push_back(m);
    if (layers.empty()) throw InvalidInputError("no visible layer has faces");
    toCore(layers[0]->cm, *core, {0, true});
    for (std::size_t i = 1; i < layers.size(); ++i) {
      Mesh next;
      toCore(layers[i]->cm, next, {int(i), true});
      std::unique_ptr<Mesh> joined(new Mesh(appended(*core, next)));
      core = std::move(joined);
    }
  } else {
    MeshModel* model = md.mm();
    if (!model) throw InvalidInputError("there is no current layer: open a mesh first");
    layers = {model};
    toCore(model->cm, *core);
  }
  const std::string what = allVisible ? "the visible layers" : layerName(*layers[0]);
  requireFacesAndFiniteCoordinates(*core, what);
  const std::size_t facesBefore = core->face.size();
  const Mesh before = *core;

  const CloseGapsResult r = meshmend::closeGaps(*core, options);
  const bool nothingDone = !changedAnything(r);
  const EditContract contract =
      nothingDone
          ? EditContract{}
          : requireEditContract(before, *core, "Close Gaps Between Borders",
                                editContractOptions(options, parameters.getBool("keep_partial")),
                                "Try a smaller merge tolerance and max gap, with 'Check "
                                "intersections' on, or turn on 'Keep a partial result' "
                                "to see what was made");
  JsonObject report = toJson(r);
  reportContract(report, contract);
  std::vector<std::string> names;
  for (MeshModel* m : layers) names.push_back(toStd(m->label()));
  report.set("layers", names);
  publishReport(parameters, report);

  Log("MeshMend: closed gaps in %s: border edges %zu -> %zu after merging (%zu vertices, %zu "
      "edge pairs merged, %zu refused) -> %zu after stitching %zu of %zu facing pairs (%zu "
      "faces added) in %.0f ms",
      what.c_str(), r.border_edges_before, r.border_edges_after_merge, r.vertices_merged,
      r.edges_merged, r.merges_skipped, r.border_edges_after, r.gaps_stitched, r.gaps_found,
      r.faces_added, r.time_ms);
  for (std::size_t k = 0; k < r.gaps.size(); ++k) {
    const GapReport& g = r.gaps[k];
    if (!g.stitched)
      Log("  gap %zu (%zu and %zu vertices, width %.3g): left open: %s", k, g.path_a.size(),
          g.path_b.size(), g.gap, g.reason.c_str());
  }
  if (r.faces_flipped || r.degenerate_faces_removed)
    Log("  %zu faces flipped to agree with their neighbours, %zu collapsed faces removed",
        r.faces_flipped, r.degenerate_faces_removed);
  if (r.vertices_added)
    Log("  note: the %zu new vertices are stored in %s (computed in double)", r.vertices_added,
        kHostPrecision);
  if (nothingDone && !allVisible) {
    Log("MeshMend: nothing to merge or stitch; the layer is unchanged");
    return;
  }

  // The only changes to the document, made last.
  std::vector<LayerAttributes> attributes;
  for (MeshModel* m : layers) attributes.push_back(snapshot(*m));
  MeshModel* target = layers[0];
  if (allVisible) {
    target = md.addNewMesh("", "gaps closed", true);
    writeMesh(*core, attributes, *target);
    target->cm.Tr.SetIdentity();
    for (MeshModel* m : layers) setLayerVisible(*m, false);
  } else {
    writeMesh(*core, attributes, *target);
  }
  if (parameters.getBool("select_new_faces")) {
    std::vector<int> added;
    for (std::size_t f = facesBefore; f < core->face.size(); ++f) added.push_back(int(f));
    selectOnly(target->cm, added);
  }
  logContract(*this, contract, *target);
  reportProgress(options.progress, 100, "MeshMend: done");
}

MESHLAB_PLUGIN_NAME_EXPORTER(StitchPlugin)
