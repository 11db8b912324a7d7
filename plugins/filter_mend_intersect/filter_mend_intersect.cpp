#include "filter_mend_intersect.h"

#include <chrono>

#include "common/base/timing.h"
#include "common/exact/intersections.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/output_stage.h"
#include "common/repair/patches/patches.h"
#include "common/repair/split/split.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

#include <vcg/complex/algorithms/clean.h>

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

enum Mode { kWithinCurrent, kBetweenTwo, kAllVisible };

}  // namespace

IntersectPlugin::IntersectPlugin() {
  addFilters(this, {SELECT_INTERSECTING, INTERSECT_AND_SPLIT});
}

QString IntersectPlugin::filterName(FilterIDType id) const {
  return id == SELECT_INTERSECTING ? "MeshMend: Select Intersecting Faces"
                                   : "MeshMend: Intersect and Split Layers";
}

QString IntersectPlugin::pythonFilterName(FilterIDType filter) const {
  switch (filter) {
    case SELECT_INTERSECTING:
      return "meshmend_select_intersecting_faces";
    default:
      return "meshmend_intersect_and_split";
  }
}

QString IntersectPlugin::filterInfo(FilterIDType id) const {
  if (id == INTERSECT_AND_SPLIT)
    return "Inserts the exact intersection curves into the layers that cross, in place: each "
           "crossed face is re-triangulated on its own with its curve segments as constrained "
           "edges (a point on an edge splits the edge in both faces that share it), every "
           "decision exact (the curve points are kept as rationals and rounded only on output), "
           "and every face not crossed stays exactly as it was. Between two chosen layers, among "
           "all visible layers, or within the current layer along its own self-intersections "
           "(optionally also in the same pass). The result keeps the layers separate (the curves "
           "inserted in each, with identical vertices along them) or merges them into one new "
           "layer welded along the curves (the curves become non-manifold edges). Colours, "
           "quality, normals and texture coordinates carry over. The written (float) result is "
           "checked again and the remaining intersecting pairs are logged.<br>"
           "Method: <i>McLaurin, Marcum, Remotigue, Blades</i>, <b>\"Repairing unstructured "
           "triangular mesh intersections\"</b>, IJNME 2013 (local re-triangulation, edge split, "
           "edge recovery, min-max angle reconnection), with exact instead of tolerance-based "
           "decisions.";
  return "Selects the faces that intersect, exactly: within the current layer, between two "
         "chosen layers, or among all visible layers (within each and between every two). "
         "Within a layer, faces that share vertices count only when they meet beyond what they "
         "share (the rule of CGAL's self_intersections); vertices are shared by index, so faces "
         "touching across an unwelded seam count. Degenerate (collinear) faces are skipped. "
         "Every decision uses exact predicates (floating-point filters with a rational "
         "fallback), so there are no missed or spurious pairs. Optionally creates a layer with "
         "the intersection segments, to see the curves.<br>"
         "Candidates come from a bounding-volume hierarchy built and searched on all cores; the "
         "method follows the detection stage of <i>McLaurin, Marcum, Remotigue, Blades</i>, "
         "<b>\"Repairing unstructured triangular mesh intersections\"</b>, IJNME 2013, with "
         "exact instead of tolerance-based decisions.";
}

void IntersectPlugin::initParameters(QAction* a, MeshDocument& md, RichParameterList& parameters) {
  MeshModel* current = md.mm();
  MeshModel* other = layerOtherThanCurrent(md);
  parameters.addParam(RichEnum(
      "mode", kWithinCurrent,
      QStringList() << "Within the current layer"
                    << "Between two chosen layers"
                    << "Among all visible layers",
      "Mode",
      "Within the current layer: its self-intersections. Between two chosen layers: faces of "
      "the first that meet faces of the second (layer matrices applied). Among all visible "
      "layers: both, for every visible layer and every two of them."));
  parameters.addParam(layerParameter("first_layer", current, md, "First layer",
                                     "First layer of the 'between two chosen layers' mode."));
  parameters.addParam(layerParameter("second_layer", other, md, "Second layer",
                                     "Second layer of the 'between two chosen layers' mode."));
  if (ID(a) == INTERSECT_AND_SPLIT) {
    parameters.addParam(RichBool(
        "split_self_intersections", false, "Also split self-intersections",
        "Also inserts each layer's own self-intersection curves in the same pass, so that the "
        "result is free of every intersection (real scans often fold through themselves)."));
    parameters.addParam(RichBool(
        "weld_duplicate_vertices", false, "Weld duplicate vertices first",
        "First merges vertices with exactly equal coordinates in each layer (scan seams: the "
        "Stanford dragon has 2,100); otherwise faces touching across such a seam are, "
        "geometrically, intersecting faces and get split along it."));
    parameters.addParam(RichBool(
        "remove_duplicate_faces", true, "Remove duplicate faces first",
        "First removes faces that have the same three vertices as another face of their layer "
        "(after welding): the same surface twice, which intersects itself everywhere and "
        "cannot be split apart (decimated scans have hundreds). The first of each group "
        "stays."));
    parameters.addParam(RichBool(
        "overlaps_once", false, "Planar overlaps once",
        "Where layers (or a layer and itself) overlap in a plane, their faces there coincide "
        "after the split. On, the merged layer keeps each such face once, so that it is free "
        "of duplicate faces (a repaired result). Off, it keeps both, so that each input layer "
        "stays a whole surface there, as the boolean filters (Keep Outer Surface, Difference, "
        "...) need."));
    parameters.addParam(RichFloat(
        "snap_tolerance", 0, "Quality snapping (0 = off)",
        "Scale-free tolerance, as a fraction of the local edge length (0.05 is a good value). "
        "A curve point closer than this to an existing vertex (or to the next curve point) is "
        "merged into it, and one this close to an edge splits that edge, instead of leaving a "
        "sliver triangle. Each snap is kept only if the result stays manifold and free of new "
        "intersections; the surfaces move by at most the tolerance near the curves. The log "
        "gives the smallest new angle with and without snapping."));
    parameters.addParam(RichEnum(
        "output", 0,
        QStringList() << "Keep the layers separate"
                      << "Merge into one welded layer",
        "Output",
        "Keep the layers separate: the curves are inserted into each layer in place, with "
        "identical vertices along them. Merge: a new layer holds all faces, welded along the "
        "curves (which become non-manifold edges); the input layers are left unchanged."));
    parameters.addParam(RichBool("curves_layer", false, "Create a layer with the curves",
                                 "Adds a layer named 'intersection curves' with the inserted "
                                 "curve edges, to see them and save them."));
    parameters.addParam(RichBool(
        "verify", true, "Check the written result",
        QString("Counts the intersecting pairs left in the result as written (in %1, as "
                "this MeshLab stores meshes) by the rule of CGAL's self_intersections and of the "
                "checker meshcheck, so that any such tool gives the same count: faces that share "
                "an edge or a vertex count only where they meet beyond it, and faces with the "
                "same three vertices (planar overlaps kept in each layer) count. In each layer "
                "as written, or in the merged layer.")
            .arg(kHostPrecision)));
    parameters.addParam(RichBool(
        "all_or_nothing", true, "All or nothing",
        QString("On: when faces would still cross, or new faces be flat, once the result is "
                "stored in %1 (what rounding breaks and the repair cannot mend), the layers are "
                "left unchanged and the filter fails with the reason. Off: that result is "
                "written all the same, and the log and the report say what is left.")
            .arg(kHostPrecision)));
  } else {
    parameters.addParam(RichBool(
        "segments_layer", false, "Create a layer with the segments",
        "Adds a layer named 'intersection segments' holding the exact intersection segments "
        "(rounded to float) as edges, so that the curves can be seen and saved."));
  }
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      ID(a) == INTERSECT_AND_SPLIT
          ? "When not empty, the result is also written to this path as one JSON object: "
            "curve_edges, curve_loops, open_curves, faces_split, faces_added, new_vertices, "
            "coincident_faces_removed, remaining_intersecting_pairs and time_ms (compute time, "
            "file I/O excluded)."
          : "When not empty, the result is also written to this path as one JSON object: "
            "self_intersecting_pairs, self_intersecting_faces, cross_intersecting_pairs, per-layer "
            "counts, candidate_pairs and time_ms (detection time, file I/O excluded)."));
}

namespace {

// The layers the mode and layer parameters choose (both filters share them).
std::vector<MeshModel*> chosenLayers(MeshDocument& md, const RichParameterList& parameters) {
  const int mode = parameters.getEnum("mode");
  if (mode == kWithinCurrent) {
    if (!md.mm()) throw InvalidInputError("there is no current layer: open a mesh first");
    return {md.mm()};
  }
  if (mode == kBetweenTwo) {
    MeshModel* a = layerFrom(parameters, md, "first_layer");
    MeshModel* b = layerFrom(parameters, md, "second_layer");
    if (!a || !b) throw InvalidInputError("choose the two layers to intersect");
    if (a == b)
      throw InvalidInputError("the same layer (" + layerName(*a) +
                              ") was chosen twice: choose two different layers, or use the "
                              "mode 'Within the current layer'");
    return {a, b};
  }
  std::vector<MeshModel*> layers;
  for (MeshModel* m : layersOf(md))
    if (m->isVisible() && m->cm.fn > 0) layers.push_back(m);
  if (layers.empty()) throw InvalidInputError("no visible layer has faces");
  return layers;
}

// The chosen layers as core meshes in one frame (layer matrices applied).
struct Inputs {
  std::vector<MeshModel*> layers;
  std::vector<Mesh> cores;
  std::vector<const Mesh*> meshes;  // pointers to cores, as the core functions take them
};

Inputs inputsOf(MeshDocument& md, const RichParameterList& parameters) {
  Inputs in;
  in.layers = chosenLayers(md, parameters);
  in.cores.resize(in.layers.size());
  for (std::size_t i = 0; i < in.layers.size(); ++i) {
    toCore(in.layers[i]->cm, in.cores[i], {int(i), true});
    requireFacesAndFiniteCoordinates(in.cores[i], layerName(*in.layers[i]));
  }
  for (const Mesh& m : in.cores) in.meshes.push_back(&m);
  return in;
}

// A float host rounded each layer's coordinates when it loaded the file.
// Where a layer's detail spans few float steps, that alone can make faces
// cross that do not in the file: the split works on what the layer holds
// and cannot undo it, but it says so (inspect.h's precision note), per layer.
std::vector<std::string> floatStorageNotes(const Inputs& in) {
  std::vector<std::string> notes;
  if (!kHostStoresFloat) return notes;
  for (std::size_t i = 0; i < in.meshes.size(); ++i) {
    const std::string note = precisionNote(inspect(*in.meshes[i], InspectOptions{}));
    if (!note.empty()) notes.push_back(layerName(*in.layers[i]) + ": " + note);
  }
  return notes;
}

}  // namespace

void IntersectPlugin::apply(QAction* a, MeshDocument& md, const RichParameterList& parameters,
                            vcg::CallBackPos* cb) {
  if (ID(a) == SELECT_INTERSECTING)
    selectIntersecting(md, parameters, cb);
  else
    intersectAndSplit(md, parameters, cb);
}

void IntersectPlugin::selectIntersecting(MeshDocument& md, const RichParameterList& parameters,
                                         vcg::CallBackPos* cb) {
  const int mode = parameters.getEnum("mode");
  const Inputs in = inputsOf(md, parameters);
  const std::vector<MeshModel*>& layers = in.layers;
  FindIntersectionsOptions options;
  options.self = mode != kBetweenTwo;
  options.cross = mode != kWithinCurrent;
  options.contacts = parameters.getBool("segments_layer");
  options.progress = progressFrom(cb);
  const FindIntersectionsResult r = findIntersections(in.meshes, options);

  JsonObject report = toJson(r);
  std::vector<std::string> names;
  for (MeshModel* m : layers) names.push_back(toStd(m->label()));
  report.set("layers", names);
  publishReport(parameters, report);

  // The document changes only from here on.
  std::size_t selected = 0;
  for (std::size_t i = 0; i < layers.size(); ++i) {
    CMeshO& cm = layers[i]->cm;
    for (CFaceO& f : cm.face) f.ClearS();
    FaceOriginHandle fo = faceOrigins(const_cast<Mesh&>(in.cores[i]));
    for (std::size_t f = 0; f < r.face_involved[i].size(); ++f)
      if (r.face_involved[i][f]) {
        cm.face[fo[f].face].SetS();
        ++selected;
      }
  }
  if (options.contacts) {
    const SegmentSoup soup = contactSegments(r);
    MeshModel* seg = md.addNewMesh("", "intersection segments", false);
    auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(seg->cm, soup.points.size());
    for (std::size_t i = 0; i < soup.points.size(); ++i, ++vi)
      vi->P() = HostPoint::Construct(soup.points[i]);
    for (const auto& e : soup.edges) vcg::tri::Allocator<CMeshO>::AddEdge(seg->cm, e[0], e[1]);
    vcg::tri::UpdateBounding<CMeshO>::Box(seg->cm);
    Log("  created layer 'intersection segments': %zu segments", soup.edges.size());
  }

  for (std::size_t i = 0; i < layers.size(); ++i)
    if (options.self)
      Log("MeshMend: %s has %zu self-intersecting pairs (%zu faces)", layerName(*layers[i]).c_str(),
          r.self_pairs[i], r.self_faces[i]);
  if (options.cross)
    Log("MeshMend: %zu intersecting pairs between layers (faces per layer: %s)", r.cross_pairs,
        [&] {
          std::string s;
          for (std::size_t i = 0; i < layers.size(); ++i)
            s += (i ? ", " : "") + toStd(layers[i]->label()) + " " +
                 std::to_string(r.cross_faces[i]);
          return s;
        }()
            .c_str());
  Log("  selected %zu faces; %zu candidate pairs tested exactly in %.1f ms", selected,
      r.candidate_pairs, r.time_ms);
}

namespace {

// Marks the curve edges of a written layer in its per-face attribute.
void markCurveEdges(const Mesh& core, const std::vector<std::array<int, 2>>& curves, CMeshO& cm) {
  const std::vector<std::uint8_t> flags = curveEdgeFlags(core, curves);
  auto attribute =
      vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<unsigned char>(cm, kCurveEdgesAttribute);
  for (std::size_t f = 0; f < flags.size() && f < cm.face.size(); ++f) attribute[f] = flags[f];
}

// Records in a written layer which input layer (part) each face came from,
// so that the patch filters can classify the patches of a merged layer.
void markParts(const Mesh& core, CMeshO& cm) {
  FaceOriginHandle fo = faceOrigins(const_cast<Mesh&>(core));
  auto attribute = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(cm, kPartAttribute);
  for (std::size_t f = 0; f < core.face.size() && f < cm.face.size(); ++f)
    attribute[f] = fo[f].layer;
}

}  // namespace

namespace {

// The scalar this MeshLab stores coordinates in.
constexpr Scalar kHostScalar = kHostStoresFloat ? Scalar::kFloat : Scalar::kDouble;

}  // namespace

// What the output stage did and what it left, in the log.
void IntersectPlugin::logStored(const StoredOutput& stored, const SplitResult& r) {
  if (r.pairs_split_after_rounding > 0)
    Log("  %zu pairs of faces that crossed once stored in %s were split again (%d rounds)",
        r.pairs_split_after_rounding, kHostPrecision, stored.rounds_split_again);
  if (stored.collinear_faces_mended)
    Log("  %zu new faces that rounding to %s left flat (collinear corners) were mended: the "
        "edge beyond flipped, or the face removed where it filled no gap",
        stored.collinear_faces_mended, kHostPrecision);
  if (stored.quality_snapped_for_host)
    Log("  curve points within %d %s steps or %g of the local edge length of a vertex or edge "
        "were merged into it (quality snapping: %zu vertices, %zu edges), as the %s result "
        "could not keep them apart otherwise",
        kHostSnapSteps, kHostPrecision, kQualitySnapTolerance, r.vertices_snapped, r.edges_snapped,
        kHostPrecision);
  else if (stored.snapped_for_host)
    Log("  curve points within %d %s steps of a vertex or edge were merged into it (%zu "
        "vertices, %zu edges), as the %s result could not keep them apart",
        kHostSnapSteps, kHostPrecision, r.vertices_snapped, r.edges_snapped, kHostPrecision);
  const std::string why = stored.explanation();
  if (!why.empty()) Log("  warning: %s", why.c_str());
}

// Intersecting pairs the check counts that the output stage does not: faces
// with the same three vertices, and the inputs' own self-intersections
// where those were not split.
void IntersectPlugin::explainRemaining(const SplitResult& r, std::size_t others, bool merge) {
  std::string parts;
  if (r.coincident_faces > r.coincident_faces_removed)
    parts += std::to_string(r.coincident_faces - r.coincident_faces_removed) +
             " faces lie twice where surfaces overlap in a plane (each layer keeps its copy, "
             "as the boolean filters need; 'Planar overlaps once' keeps each once)";
  if (!r.complete)
    parts += std::string(parts.empty() ? "" : "; ") +
             "the layers' own self-intersections were not split ('Also split "
             "self-intersections' splits them)";
  if (!merge)
    parts += std::string(parts.empty() ? "" : "; ") + "each layer is checked as written on its own";
  Log("  %zu of those pairs are no crossing the split left%s%s", others, parts.empty() ? "" : ": ",
      parts.c_str());
}

void IntersectPlugin::intersectAndSplit(MeshDocument& md, const RichParameterList& parameters,
                                        vcg::CallBackPos* cb) {
  const int mode = parameters.getEnum("mode");
  const Inputs in = inputsOf(md, parameters);
  const std::vector<MeshModel*>& layers = in.layers;
  SplitOptions options;
  options.between_meshes = mode != kWithinCurrent;
  options.self = mode == kWithinCurrent || parameters.getBool("split_self_intersections");
  options.weld_duplicates = parameters.getBool("weld_duplicate_vertices");
  options.remove_duplicate_faces = parameters.getBool("remove_duplicate_faces");
  // Only the merged layer keeps planar overlaps once: separate layers stay whole.
  options.overlaps_once = parameters.getEnum("output") == 1 && parameters.getBool("overlaps_once");
  options.snap_tolerance = parameters.getFloat("snap_tolerance");
  if (!(options.snap_tolerance >= 0 && options.snap_tolerance < 0.5))
    throw InvalidInputError("the snapping tolerance must be at least 0 (off) and below 0.5");
  options.progress = progressWithin(progressFrom(cb), 0, 94);
  const bool merge = parameters.getEnum("output") == 1;
  options.separate_meshes = !merge;
  const auto start = Clock::now();
  SplitResult r = splitAlongIntersections(in.meshes, options);
  // Welding and removing duplicate faces may be all there was to do (a
  // layer that met itself only through duplicate faces): that result is
  // kept. Layers that do not meet are still merged when asked (the boolean
  // filters take nested or separate parts from the merged layer);
  // otherwise nothing changed and nothing is written.
  const bool nothingMet =
      r.intersecting_pairs == 0 && r.vertices_welded == 0 && r.duplicate_faces_removed == 0;
  // Nothing to split is success (MeshLab's convention): logged, reported,
  // and the layers stay as they were.
  if (nothingMet && (mode == kWithinCurrent || !merge)) {
    if (mode == kWithinCurrent)
      Log("MeshMend: %s does not intersect itself: nothing to split; the layer is unchanged",
          layerName(*layers[0]).c_str());
    else
      Log("MeshMend: the chosen layers do not intersect: nothing to split; the layers are "
          "unchanged (to combine parts that do not meet, nested or apart, for the boolean "
          "filters, choose the merged output)");
    std::vector<std::string> names;
    for (MeshModel* m : layers) names.push_back(toStd(m->label()));
    publishReport(parameters, toJson(r).set("layers", names).set("unchanged", true));
    return;
  }
  // The output stage (output_stage.h): rounded to the host's scalar,
  // checked exactly on the stored values and repaired.
  OutputStageOptions stage;
  stage.scalar = kHostScalar;
  stage.progress = progressFrom(cb);
  const StoredOutput stored = storeForHost(r, in.meshes, options, stage);
  if (parameters.getBool("all_or_nothing") && !stored.explanation().empty())
    throw InvalidInputError(
        "the result is not exact once stored, so the layers were left "
        "unchanged ('All or nothing'): " +
        stored.explanation());
  const bool verify = parameters.getBool("verify");
  std::size_t remaining = 0;
  if (verify) {
    reportProgress(progressFrom(cb), 99, "Checking the result");
    remaining = storedIntersectingPairs(r, stored, !merge);
  }
  // The whole computation once (the core's time_ms adds up the splits it ran).
  r.time_ms = msSince(start);
  if (nothingMet) Log("  the layers do not intersect: the merged layer holds them as they are");
  const std::vector<std::string> precision = floatStorageNotes(in);
  for (const std::string& note : precision) Log("  warning: %s", note.c_str());
  logStored(stored, r);
  if (verify)
    Log("  check of the written %s result: %zu intersecting pairs remain%s", kHostPrecision,
        remaining, merge ? "" : " within the layers (each as written)");
  if (verify && remaining > stored.crossing)
    explainRemaining(r, remaining - stored.crossing, merge);
  JsonObject report = toJson(r);
  addToReport(stored, report);
  if (verify) report.set("remaining_intersecting_pairs", remaining);
  if (!precision.empty()) report.set("float_storage_notes", precision);
  std::vector<std::string> names;
  for (MeshModel* m : layers) names.push_back(toStd(m->label()));
  report.set("layers", names).set("output", merge ? "merged" : "separate");
  publishReport(parameters, report);

  // The document changes only from here on.
  std::vector<LayerAttributes> attributes;
  for (MeshModel* m : layers) attributes.push_back(snapshot(*m));
  if (merge) {
    MeshModel* out = md.addNewMesh("", "intersected", true);
    writeMesh(r.merged, attributes, *out);
    markCurveEdges(r.merged, r.merged_curve_edges, out->cm);
    markParts(r.merged, out->cm);
    out->cm.Tr.SetIdentity();
  } else {
    for (std::size_t i = 0; i < layers.size(); ++i) {
      writeMesh(r.meshes[i], {attributes[i]}, *layers[i]);  // in place
      markCurveEdges(r.meshes[i], r.curve_edges[i], layers[i]->cm);
      markParts(r.meshes[i], layers[i]->cm);
      layers[i]->cm.Tr.SetIdentity();  // the geometry is now in the common frame
    }
  }
  if (parameters.getBool("curves_layer")) {
    MeshModel* curves = md.addNewMesh("", "intersection curves", false);
    const Mesh& merged = r.merged;
    auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(curves->cm, merged.vert.size());
    for (std::size_t v = 0; v < merged.vert.size(); ++v, ++vi)
      vi->P() = HostPoint::Construct(merged.vert[v].cP());
    for (const auto& e : r.merged_curve_edges)
      vcg::tri::Allocator<CMeshO>::AddEdge(curves->cm, e[0], e[1]);
    vcg::tri::Clean<CMeshO>::RemoveUnreferencedVertex(curves->cm);
    vcg::tri::Allocator<CMeshO>::CompactEveryVector(curves->cm);
    vcg::tri::UpdateBounding<CMeshO>::Box(curves->cm);
  }
  Log("MeshMend: %zu intersecting pairs split: %zu curve edges in %zu closed loops and %zu open "
      "curves; %zu faces re-triangulated into %zu more faces, %zu new vertices (%.0f ms)",
      r.intersecting_pairs, r.curve_edges_welded, r.curve_loops, r.open_curves, r.faces_split,
      r.faces_added, r.new_vertices, r.time_ms);
  if (r.vertices_welded || r.duplicate_faces_removed)
    Log("  first %zu duplicate vertices were welded and %zu duplicate faces removed",
        r.vertices_welded, r.duplicate_faces_removed);
  if (r.coincident_faces_removed)
    Log("  %zu faces where the surfaces overlap in a plane were there twice: the merged layer "
        "keeps each once",
        r.coincident_faces_removed);
  else if (r.coincident_faces && merge)
    Log("  %zu faces lie twice where the surfaces overlap in a plane, each layer's own (for the "
        "boolean filters; the check above counts each as an intersecting pair, as every "
        "checker of self-intersections does): 'Planar overlaps once' keeps each once",
        r.coincident_faces);
  else if (r.coincident_faces)
    Log("  %zu faces lie in two layers where the surfaces overlap in a plane", r.coincident_faces);
  if (r.faces_split > 0 && options.snap_tolerance > 0)
    Log("  smallest angle of a new face: %.3g degrees (%.3g without snapping); %zu faces under 1 "
        "degree (%zu without); %zu curve points "
        "merged into vertices, %zu edges split at curve points",
        r.smallest_new_angle_deg, r.smallest_new_angle_deg_unsnapped, r.new_faces_below_1deg,
        r.new_faces_below_1deg_unsnapped, r.vertices_snapped, r.edges_snapped);
  else if (r.faces_split > 0)
    Log("  smallest angle of a new face: %.3g degrees; %zu faces under 1 degree",
        r.smallest_new_angle_deg, r.new_faces_below_1deg);
  if (r.degenerate_faces_kept)
    Log("  warning: %zu zero-area faces touched by a curve were kept unsplit",
        r.degenerate_faces_kept);
}

MESHLAB_PLUGIN_NAME_EXPORTER(IntersectPlugin)
