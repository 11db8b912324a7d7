#include "filter_mend_inspect.h"

#include <QElapsedTimer>

#include "common/repair/inspect/inspect.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

// Values of the select_defects parameter.
enum Selection {
  kSelectNone,
  kSelectAll,
  kSelectNonManifold,
  kSelectBorder,
  kSelectDegenerate,
  kSelectOrientation,
  kSelectSelfIntersecting
};

struct SelectionBits {
  std::uint8_t face, vertex;
};

SelectionBits bitsFor(int selection) {
  switch (selection) {
    case kSelectAll:
      return {0xff, kVertexNonManifold | kVertexOnBorder | kVertexIsolated | kVertexDuplicate};
    case kSelectNonManifold:
      return {kFaceOnNonManifoldEdge, kVertexNonManifold};
    case kSelectBorder:
      return {kFaceOnBorder, kVertexOnBorder};
    case kSelectDegenerate:
      return {kFaceDegenerate | kFaceDuplicate, 0};
    case kSelectOrientation:
      return {kFaceOrientationFlip, 0};
    case kSelectSelfIntersecting:
      return {kFaceSelfIntersecting, 0};
    default:
      return {0, 0};
  }
}

}  // namespace

InspectPlugin::InspectPlugin() {
  addFilters(this, {INSPECT_DEFECTS});
}

QString InspectPlugin::filterName(FilterIDType) const {
  return "MeshMend: Inspect Mesh Defects";
}

QString InspectPlugin::pythonFilterName(FilterIDType) const {
  return "meshmend_inspect_defects";
}

QString InspectPlugin::filterInfo(FilterIDType) const {
  return "Reports the defects of the current layer: vertices, faces, connected components, "
         "border edges and border loops (holes), non-manifold edges and vertices, "
         "degenerate (zero-area, decided exactly) and duplicate faces, duplicate and "
         "unreferenced vertices, orientation consistency, closedness, the enclosed "
         "volume and genus of closed meshes, and the exact self-intersecting face pairs.<br>"
         "Vertex identity is the vertex index, as stored: two vertices at the same "
         "coordinates are different vertices (see <i>duplicate points</i>). Where MeshLab's "
         "importer changed the file's mesh (STL vertices, triangulated polygons, triangle "
         "strips, dropped faces) the report says so.<br>"
         "Optionally selects the faces and vertices involved in a kind of defect, and writes "
         "the report as JSON to <i>report_file</i> for scripts.";
}

int InspectPlugin::postconditions(QAction*) const {
  return MeshModel::MM_FACEFLAGSELECT | MeshModel::MM_VERTFLAGSELECT;
}

void InspectPlugin::initParameters(QAction*, MeshDocument&, RichParameterList& parameters) {
  parameters.addParam(RichEnum(
      "select_defects", kSelectNone,
      QStringList() << "None"
                    << "All defects"
                    << "Non-manifold edges and vertices"
                    << "Border edges and vertices"
                    << "Degenerate and duplicate faces"
                    << "Orientation flips"
                    << "Self-intersecting faces",
      "Select defects",
      "Replaces the face and vertex selection with the elements involved in the chosen kind of "
      "defect, so that MeshLab's selection tools and filters can act on them. 'None' leaves "
      "the selection unchanged."));
  parameters.addParam(RichBool(
      "self_intersections", true, "Count self-intersections",
      "Also finds the pairs of faces that intersect, exactly (faces sharing vertices count only "
      "when they meet beyond them, as in CGAL's self_intersections; vertices are shared by "
      "index). Takes about a second per million faces; turn it off for the topology counts "
      "alone."));
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      "When not empty, the report is also written to this path as one JSON object (keys: "
      "vertices, faces, connected_components, border_edges, border_loops, non_manifold_edges, "
      "non_manifold_vertices, degenerate_faces, duplicate_faces, isolated_vertices, "
      "duplicate_points, is_closed, consistently_oriented, volume, time_ms, ...)."));
}

void InspectPlugin::apply(QAction*, MeshDocument& md, const RichParameterList& parameters,
                          vcg::CallBackPos* cb) {
  MeshModel* model = md.mm();
  if (!model) throw InvalidInputError("there is no current layer: open a mesh first");
  const int selection = parameters.getEnum("select_defects");
  const Progress progress = progressFrom(cb);

  reportProgress(progress, 0, "MeshMend: reading the layer");
  const Mesh core = toCore(model->cm);
  reportProgress(progress, 30, "MeshMend: inspecting");
  InspectOptions options;
  options.mark_defects = selection != kSelectNone;
  options.self_intersections = parameters.getBool("self_intersections");
  const InspectResult r = inspect(core, options);
  const ImportNotes imported = importNotes(*model);

  JsonObject report = toJson(r);
  report.set("layer", toStd(model->label())).set("file", toStd(model->fullName()));
  if (imported.file_faces >= 0)
    report.set("file_vertices", imported.file_vertices).set("file_faces", imported.file_faces);
  report.set("importer_notes", imported.notes);
  publishReport(parameters, report);

  Log("MeshMend inspect of %s: %s", layerName(*model).c_str(), summarize(r).c_str());
  Log("  vertices %zu, faces %zu, edges %zu, connected components %zu", r.vertices, r.faces,
      r.edges, r.connected_components);
  Log("  border edges %zu in %zu border loops (longest %zu edges)", r.border_edges, r.border_loops,
      r.longest_border_loop);
  Log("  non-manifold edges %zu, non-manifold vertices %zu", r.non_manifold_edges,
      r.non_manifold_vertices);
  Log("  degenerate faces %zu, duplicate faces %zu", r.degenerate_faces, r.duplicate_faces);
  Log("  duplicate points %zu, unreferenced vertices %zu", r.duplicate_points, r.isolated_vertices);
  Log("  orientation: %s (%zu inconsistent edges); %s",
      r.consistently_oriented ? "consistent" : "inconsistent", r.orientation_inconsistent_edges,
      r.is_closed ? "closed" : "open");
  if (r.self_intersecting_pairs)
    Log("  self-intersecting pairs %zu (faces %zu)", *r.self_intersecting_pairs,
        *r.self_intersecting_faces);
  if (r.volume) Log("  volume %.10g", *r.volume);
  if (r.genus) Log("  genus %ld", *r.genus);
  for (const std::string& note : imported.notes) Log("  note: %s", note.c_str());
  Log("  time %.1f ms", r.time_ms);

  if (selection != kSelectNone) {  // the only change to the document, made last
    const SelectionBits bits = bitsFor(selection);
    Mesh& mesh = const_cast<Mesh&>(core);
    VertexOriginHandle vo = vertexOrigins(mesh);
    FaceOriginHandle fo = faceOrigins(mesh);
    CMeshO& cm = model->cm;
    for (CVertexO& v : cm.vert) v.ClearS();
    for (CFaceO& f : cm.face) f.ClearS();
    for (std::size_t i = 0; i < r.vertex_defects.size(); ++i)
      if (r.vertex_defects[i] & bits.vertex) cm.vert[vo[i].vertex].SetS();
    for (std::size_t f = 0; f < r.face_defects.size(); ++f)
      if (r.face_defects[f] & bits.face) cm.face[fo[f].face].SetS();
    Log("  selected %d faces and %d vertices",
        int(vcg::tri::UpdateSelection<CMeshO>::FaceCount(cm)),
        int(vcg::tri::UpdateSelection<CMeshO>::VertexCount(cm)));
  }
  reportProgress(progress, 100, "MeshMend: done");
}

MESHLAB_PLUGIN_NAME_EXPORTER(InspectPlugin)
