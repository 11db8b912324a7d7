#include "filter_mend_render.h"

#include <QElapsedTimer>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "common/repair/patches/patches.h"
#include "common/render/render_channels.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

// Values of the "values" parameter.
enum Values { kClearanceValues, kPatchValues, kFaceChangeValues };

template <class T>
bool hasFaceAttribute(CMeshO& cm, const char* name) {
  return vcg::tri::Allocator<CMeshO>::IsValidHandle<T>(
      cm, vcg::tri::Allocator<CMeshO>::FindPerFaceAttribute<T>(cm, name));
}

// True when rewriting the layer's texture coordinates loses nothing of the
// user's: it has none, or only the values this filter wrote before.
bool holdsNoTextureOfItsOwn(const MeshModel& model) {
  const CMeshO& cm = model.cm;
  if (model.hasDataMask(MeshModel::MM_VERTTEXCOORD) || !cm.textures.empty()) return false;
  if (!model.hasDataMask(MeshModel::MM_WEDGTEXCOORD)) return true;
  for (const CFaceO& f : cm.face)
    if (!f.IsD())
      for (int k = 0; k < 3; ++k)
        if (decodeChannel(f.cWT(k).U(), f.cWT(k).V()).channel == RenderChannel::kNone) return false;
  return true;
}

// The patch ids of the live faces: the attribute Paint Surface Patches
// writes, else the face quality it also writes (what a saved file keeps).
std::vector<int> patchIds(MeshModel& model, const std::vector<CFaceO*>& faces, bool& fromQuality) {
  CMeshO& cm = model.cm;
  std::vector<int> ids;
  ids.reserve(faces.size());
  fromQuality = false;
  if (hasFaceAttribute<int>(cm, kPatchAttribute)) {
    auto id = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(cm, kPatchAttribute);
    for (CFaceO* f : faces) ids.push_back(id[f]);
    return ids;
  }
  if (!model.hasDataMask(MeshModel::MM_FACEQUALITY))
    throw InvalidInputError(layerName(model) +
                            " has no patch ids: run MeshMend: Paint Surface Patches first");
  fromQuality = true;
  for (CFaceO* f : faces) {
    const double q = f->cQ();
    if (!(q >= 0) || q != std::floor(q) || q > 1e9)
      throw InvalidInputError(layerName(model) + " has no patch ids (face " +
                              std::to_string(vcg::tri::Index(cm, f)) + " has the face quality " +
                              std::to_string(q) +
                              ", not an id): run MeshMend: Paint Surface Patches first");
    ids.push_back(int(q));
  }
  return ids;
}

}  // namespace

RenderValuesPlugin::RenderValuesPlugin() {
  addFilters(this, {PREPARE_SHADER_VIEW});
}

QString RenderValuesPlugin::filterName(FilterIDType) const {
  return "MeshMend: Prepare Shader View";
}

QString RenderValuesPlugin::pythonFilterName(FilterIDType) const {
  return "meshmend_prepare_shader_view";
}

QString RenderValuesPlugin::filterInfo(FilterIDType) const {
  return "Puts MeshMend's values where MeshLab's shaders can read them, for the shaders "
         "Render > Shaders > meshmend_clearance.gdp, meshmend_patches.gdp and "
         "meshmend_new_faces.gdp. MeshLab hands a shader only positions, normals, colours and "
         "texture coordinates (no quality, no per-face attributes), so the values go into the "
         "layer's per-wedge texture coordinates, which nothing else of MeshMend uses: the "
         "clearance (vertex quality of MeshMend: Measure Clearance, or any vertex quality), the "
         "patch ids of MeshMend: Paint Surface Patches with their boundaries, or which faces the "
         "last MeshMend filter that rebuilt the layer made (new, cut from an input face, kept). "
         "A layer with texture coordinates of its own is refused: prepare a duplicate. Untick "
         "texture coordinates when saving the layer if the file should not keep them.";
}

void RenderValuesPlugin::initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) {
  // The values the current layer holds, most specific first.
  int values = kClearanceValues;
  if (md.mm() && hasFaceAttribute<int>(md.mm()->cm, kPatchAttribute))
    values = kPatchValues;
  else if (md.mm() && hasFaceAttribute<unsigned char>(md.mm()->cm, kFaceChangeAttribute))
    values = kFaceChangeValues;
  parameters.addParam(RichEnum(
      "values", values,
      QStringList() << "Clearance (vertex quality)"
                    << "Patches (patch ids)"
                    << "Faces the last filter made (new, cut, kept)",
      "Values",
      "Clearance: each vertex's quality (MeshMend: Measure Clearance sets it to the local "
      "clearance), for meshmend_clearance.gdp. Patches: the patch ids of MeshMend: Paint Surface "
      "Patches (or the face quality of a saved painted mesh) and the edges between patches, for "
      "meshmend_patches.gdp. Faces the last filter made: what the last MeshMend filter that "
      "rebuilt this layer did to each face (new, cut from an input face, kept), for "
      "meshmend_new_faces.gdp."));
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      "When not empty, the outcome is also written to this path as one JSON object (keys: "
      "values, faces, and value_min and value_max, patches, or kept_faces, cut_faces and "
      "new_faces; time_ms)."));
}

void RenderValuesPlugin::apply(QAction*, MeshDocument& md, const RichParameterList& parameters,
                               vcg::CallBackPos*) {
  MeshModel* model = md.mm();
  if (!model) throw InvalidInputError("there is no current layer: open a mesh first");
  QElapsedTimer timer;
  timer.start();
  CMeshO& cm = model->cm;
  if (cm.fn == 0) throw InvalidInputError(layerName(*model) + " has no faces to show");
  if (!holdsNoTextureOfItsOwn(*model))
    throw InvalidInputError(
        layerName(*model) +
        " has texture coordinates of its own, which this would overwrite: duplicate the layer "
        "(Filters > Layer and Attribute Management > Duplicate Current Layer) and prepare the "
        "copy");
  const int values = parameters.getEnum("values");
  if (values < kClearanceValues || values > kFaceChangeValues)
    throw InvalidInputError("unknown values " + std::to_string(values) +
                            ": use 0 (clearance), 1 (patches) or 2 (faces the last filter made)");

  Triangles triangles;
  std::vector<CFaceO*> faces;
  triangles.reserve(cm.fn);
  faces.reserve(cm.fn);
  for (CFaceO& f : cm.face)
    if (!f.IsD()) {
      triangles.push_back({int(vcg::tri::Index(cm, f.V(0))), int(vcg::tri::Index(cm, f.V(1))),
                           int(vcg::tri::Index(cm, f.V(2)))});
      faces.push_back(&f);
    }

  JsonObject report;
  report.set("layer", toStd(model->label())).set("faces", faces.size());
  std::vector<WedgeCoords> coords;
  std::string summary, shader;
  if (values == kClearanceValues) {
    if (!model->hasDataMask(MeshModel::MM_VERTQUALITY))
      throw InvalidInputError(layerName(*model) +
                              " has no vertex quality: run MeshMend: Measure Clearance first");
    std::vector<double> quality(cm.vert.size(), 0);
    double low = HUGE_VAL, high = -HUGE_VAL;
    for (const auto& t : triangles)
      for (int v : t) {
        quality[v] = cm.vert[v].cQ();
        low = std::min(low, quality[v]);
        high = std::max(high, quality[v]);
      }
    coords = encodeVertexValues(triangles, quality);
    report.set("values", "clearance").set("value_min", low).set("value_max", high);
    char text[160];
    std::snprintf(text, sizeof text, "vertex quality from %.6g to %.6g", low, high);
    summary = text;
    shader = "meshmend_clearance.gdp (set tau and colour_range in its dialog)";
  } else if (values == kPatchValues) {
    bool fromQuality = false;
    const std::vector<int> ids = patchIds(*model, faces, fromQuality);
    coords = encodeFaceLabels(triangles, ids, RenderChannel::kPatches, true);
    const std::size_t patches = std::set<int>(ids.begin(), ids.end()).size();
    report.set("values", "patches").set("patches", patches);
    summary =
        std::to_string(patches) + " patches" + (fromQuality ? " (ids from the face quality)" : "");
    shader = "meshmend_patches.gdp";
  } else {
    if (!hasFaceAttribute<unsigned char>(cm, kFaceChangeAttribute))
      throw InvalidInputError(
          layerName(*model) +
          " has no record of the faces a MeshMend filter made: run a filter that rebuilds the "
          "layer first (Fill Holes, Stitch Boundaries, Close Gaps Between Borders, Intersect "
          "and Split Layers, Remove Self-Intersections, Remove Patches); the record lives in "
          "memory only, saved files do not keep it");
    auto change =
        vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<unsigned char>(cm, kFaceChangeAttribute);
    std::vector<int> labels;
    std::size_t count[3] = {0, 0, 0};
    for (CFaceO* f : faces) {
      const int c = std::min<int>(change[f], kFaceNew);
      labels.push_back(c);
      ++count[c];
    }
    coords = encodeFaceLabels(triangles, labels, RenderChannel::kFaceChanges, false);
    report.set("values", "face_changes")
        .set("kept_faces", count[kFaceKept])
        .set("cut_faces", count[kFaceCut])
        .set("new_faces", count[kFaceNew]);
    summary = std::to_string(count[kFaceNew]) + " new faces, " + std::to_string(count[kFaceCut]) +
              " cut from input faces, " + std::to_string(count[kFaceKept]) + " kept";
    shader = "meshmend_new_faces.gdp";
  }
  report.set("time_ms", double(timer.nsecsElapsed()) / 1e6);
  publishReport(parameters, report);

  // The only change to the document, made last.
  model->updateDataMask(MeshModel::MM_WEDGTEXCOORD);
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      faces[i]->WT(k).U() = coords[i][k][0];
      faces[i]->WT(k).V() = coords[i][k][1];
      faces[i]->WT(k).N() = 0;
    }
  Log("MeshMend: %s of %s in its texture coordinates (%s); show them with Render > Shaders > %s",
      values == kClearanceValues ? "clearance"
      : values == kPatchValues   ? "patch ids"
                                 : "faces made",
      layerName(*model).c_str(), summary.c_str(), shader.c_str());
}

MESHLAB_PLUGIN_NAME_EXPORTER(RenderValuesPlugin)
