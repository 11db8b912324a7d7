#include "filter_mend_intersect.h"

#include "common/intersections.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

enum Mode { kWithinCurrent, kBetweenTwo, kAllVisible };

}  // namespace

IntersectPlugin::IntersectPlugin() {
  typeList << SELECT_INTERSECTING;
  for (FilterIDType id : types()) actionList << new QAction(filterName(id), this);
}

QString IntersectPlugin::filterName(FilterIDType) const {
  return "MeshMend: Select Intersecting Faces";
}

QString IntersectPlugin::filterInfo(FilterIDType) const {
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

void IntersectPlugin::initParameterSet(QAction*, MeshDocument& md, RichParameterList& parameters) {
  MeshModel* current = md.mm();
  MeshModel* other = current;
  for (MeshModel* m : md.meshList)
    if (m != current) {
      other = m;
      break;
    }
  parameters.addParam(RichEnum(
      "mode", kWithinCurrent,
      QStringList() << "Within the current layer"
                    << "Between two chosen layers"
                    << "Among all visible layers",
      "Mode",
      "Within the current layer: its self-intersections. Between two chosen layers: faces of "
      "the first that meet faces of the second (layer matrices applied). Among all visible "
      "layers: both, for every visible layer and every two of them."));
  parameters.addParam(RichMesh("first_layer", current, &md, "First layer",
                               "First layer of the 'between two chosen layers' mode."));
  parameters.addParam(RichMesh("second_layer", other, &md, "Second layer",
                               "Second layer of the 'between two chosen layers' mode."));
  parameters.addParam(
      RichBool("segments_layer", false, "Create a layer with the segments",
               "Adds a layer named 'intersection segments' holding the exact intersection segments "
               "(rounded to float) as edges, so that the curves can be seen and saved."));
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      "When not empty, the result is also written to this path as one JSON object: "
      "self_intersecting_pairs, self_intersecting_faces, cross_intersecting_pairs, per-layer "
      "counts, candidate_pairs and time_ms (detection time, file I/O excluded)."));
}

bool IntersectPlugin::applyFilter(QAction*, MeshDocument& md, const RichParameterList& parameters,
                                  vcg::CallBackPos* cb) {
  return guarded(*this, errorMessage, [&] {
    const int mode = parameters.getEnum("mode");
    std::vector<MeshModel*> layers;
    if (mode == kWithinCurrent) {
      if (!md.mm()) throw InvalidInputError("there is no current layer: open a mesh first");
      layers = {md.mm()};
    } else if (mode == kBetweenTwo) {
      MeshModel* a = parameters.getMesh("first_layer");
      MeshModel* b = parameters.getMesh("second_layer");
      if (!a || !b) throw InvalidInputError("choose the two layers to intersect");
      if (a == b)
        throw InvalidInputError("the same layer (" + layerName(*a) +
                                ") was chosen twice: choose two different layers, or use the "
                                "mode 'Within the current layer'");
      layers = {a, b};
    } else {
      for (MeshModel* m : md.meshList)
        if (m->isVisible() && m->cm.fn > 0) layers.push_back(m);
      if (layers.empty()) throw InvalidInputError("no visible layer has faces");
    }

    std::vector<Mesh> cores;
    for (std::size_t i = 0; i < layers.size(); ++i) {
      cores.push_back(toCore(layers[i]->cm, {int(i), true}));
      requireFacesAndFiniteCoordinates(cores.back(), layerName(*layers[i]));
    }
    std::vector<const Mesh*> inputs;
    for (const Mesh& m : cores) inputs.push_back(&m);
    FindIntersectionsOptions options;
    options.self = mode != kBetweenTwo;
    options.cross = mode != kWithinCurrent;
    options.contacts = parameters.getBool("segments_layer");
    options.progress = progressFrom(cb);
    const FindIntersectionsResult r = findIntersections(inputs, options);

    JsonObject report = toJson(r);
    std::vector<std::string> names;
    for (MeshModel* m : layers) names.push_back(toStd(m->label()));
    report.set("layers", names);
    writeReport(parameters.getString("report_file"), report);

    // The document changes only from here on.
    std::size_t selected = 0;
    for (std::size_t i = 0; i < layers.size(); ++i) {
      CMeshO& cm = layers[i]->cm;
      for (CFaceO& f : cm.face) f.ClearS();
      FaceOriginHandle fo = faceOrigins(cores[i]);
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
        vi->P() = vcg::Point3f::Construct(soup.points[i]);
      for (const auto& e : soup.edges) vcg::tri::Allocator<CMeshO>::AddEdge(seg->cm, e[0], e[1]);
      vcg::tri::UpdateBounding<CMeshO>::Box(seg->cm);
      Log("  created layer 'intersection segments': %zu segments", soup.edges.size());
    }

    for (std::size_t i = 0; i < layers.size(); ++i)
      if (options.self)
        Log("MeshMend: %s has %zu self-intersecting pairs (%zu faces)",
            layerName(*layers[i]).c_str(), r.self_pairs[i], r.self_faces[i]);
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
  });
}

MESHLAB_PLUGIN_NAME_EXPORTER(IntersectPlugin)
