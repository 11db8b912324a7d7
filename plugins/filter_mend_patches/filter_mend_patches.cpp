#include "filter_mend_patches.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include "common/base/timing.h"
#include "common/exact/intersections.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/output_stage.h"
#include "common/repair/patches/patch_ops.h"
#include "common/repair/patches/patches.h"
#include "common/repair/split/split.h"
#include "plugins/bridge/filter_support.h"
#include "plugins/bridge/mesh_bridge.h"

using namespace meshmend;
using namespace meshmend::bridge;

namespace {

enum Layers { kCurrentLayer, kAllVisible };
// The "keep" choices: the unselected patches, then the boolean operations in their order.
enum Keep { kUnselected, kUnion, kIntersection, kDifference };
static_assert(kDifference - kUnion + 1 == kBooleanOperations);
BooleanOperation operationOf(int keep) {
  return BooleanOperation(keep - kUnion);
}

// The chosen layers as one core mesh (layer matrices applied) with the
// per-face labels the patch functions take.
struct Assembly {
  std::vector<MeshModel*> layers;
  std::vector<std::size_t> firstFace;  // per layer: its first face in `mesh`
  Mesh mesh;
  FaceLabels labels;
  std::vector<int> storedPatch;  // per face: the painted patch id, if every layer has them
};

template <class T>
bool hasFaceAttribute(CMeshO& cm, const char* name) {
  return vcg::tri::Allocator<CMeshO>::IsValidHandle(
      cm, vcg::tri::Allocator<CMeshO>::FindPerFaceAttribute<T>(cm, name));
}

// Calls fn(core face index, face) for the live faces of layer i of `a`.
template <class Fn>
void forEachFace(const Assembly& a, std::size_t i, Fn&& fn) {
  std::size_t index = a.firstFace[i];
  for (CFaceO& f : a.layers[i]->cm.face)
    if (!f.IsD()) fn(index++, f);
}

Assembly assemble(MeshDocument& md, int which) {
  Assembly a;
  if (which == kCurrentLayer) {
    if (!md.mm()) throw InvalidInputError("there is no current layer: open a mesh first");
    a.layers = {md.mm()};
  } else {
    for (MeshModel* m : layersOf(md))
      if (m->isVisible() && m->cm.fn > 0) a.layers.push_back(m);
    if (a.layers.empty()) throw InvalidInputError("no visible layer has faces");
  }
  bool allPainted = true;
  for (std::size_t i = 0; i < a.layers.size(); ++i) {
    CMeshO& cm = a.layers[i]->cm;
    a.firstFace.push_back(a.mesh.face.size());
    if (i == 0) {
      toCore(cm, a.mesh, {0, true});  // in place: a Mesh cannot move
      requireFacesAndFiniteCoordinates(a.mesh, layerName(*a.layers[i]));
    } else {
      const Mesh core = toCore(cm, {int(i), true});
      requireFacesAndFiniteCoordinates(core, layerName(*a.layers[i]));
      a.mesh = appended(a.mesh, core);
    }
    const bool parts = a.layers.size() == 1 && hasFaceAttribute<int>(cm, kPartAttribute);
    const bool curves = hasFaceAttribute<unsigned char>(cm, kCurveEdgesAttribute);
    const bool painted = hasFaceAttribute<int>(cm, kPatchAttribute);
    allPainted &= painted;
    auto part = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(cm, kPartAttribute);
    auto curve =
        vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<unsigned char>(cm, kCurveEdgesAttribute);
    auto patch = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(cm, kPatchAttribute);
    const bool colours = a.layers[i]->hasDataMask(MeshModel::MM_FACECOLOR);
    for (CFaceO& f : cm.face) {
      if (f.IsD()) continue;
      a.labels.part.push_back(parts ? std::max(0, part[f]) : int(i));
      a.labels.curve_edges.push_back(curves ? curve[f] : 0);
      a.labels.colour.push_back(colours ? f.C().V(0) | f.C().V(1) << 8 | f.C().V(2) << 16 : 0);
      a.storedPatch.push_back(painted ? patch[f] : -1);
    }
    // GetPerFaceAttribute added the attributes a layer did not have: undo.
    if (!parts) vcg::tri::Allocator<CMeshO>::DeletePerFaceAttribute(cm, kPartAttribute);
    if (!curves) vcg::tri::Allocator<CMeshO>::DeletePerFaceAttribute(cm, kCurveEdgesAttribute);
    if (!painted) vcg::tri::Allocator<CMeshO>::DeletePerFaceAttribute(cm, kPatchAttribute);
  }
  if (!allPainted) a.storedPatch.clear();
  return a;
}

// Patches as painted before (stored ids), or painted now with the defaults.
Patches patchesOf(const Assembly& a) {
  if (!a.storedPatch.empty()) return patchesFromIds(a.mesh, a.labels, a.storedPatch);
  return paintPatches(a.mesh, a.labels);
}

vcg::Color4b colourOf(int id) {
  const auto c = patchColour(id);
  return vcg::Color4b(c[0], c[1], c[2], 255);
}

std::string partsLegend(const Assembly& a) {
  if (a.layers.size() > 1) {
    std::string s;
    for (std::size_t i = 0; i < a.layers.size(); ++i)
      s += (i ? ", " : "") + std::to_string(i) + " = " + toStd(a.layers[i]->label());
    return "parts: " + s;
  }
  return "parts: the input layers of the intersection, in their order";
}

}  // namespace

PatchesPlugin::PatchesPlugin() {
  addFilters(this, {PAINT_PATCHES, SELECT_PATCHES, REMOVE_PATCHES});
}

QString PatchesPlugin::filterName(FilterIDType id) const {
  switch (id) {
    case PAINT_PATCHES:
      return "MeshMend: Paint Surface Patches";
    case SELECT_PATCHES:
      return "MeshMend: Select Patches";
    default:
      return "MeshMend: Remove Patches";
  }
}

QString PatchesPlugin::pythonFilterName(FilterIDType filter) const {
  switch (filter) {
    case PAINT_PATCHES:
      return "meshmend_paint_patches";
    case SELECT_PATCHES:
      return "meshmend_select_patches";
    default:
      return "meshmend_remove_patches";
  }
}

QString PatchesPlugin::filterInfo(FilterIDType id) const {
  switch (id) {
    case PAINT_PATCHES:
      return "Flood-fills the faces into surface patches bounded by the curves that "
             "'Intersect and Split Layers' inserted, by border (free) edges and non-manifold "
             "edges, and optionally by changes of face colour or creases sharper than an angle. "
             "Each patch gets an id (stored per face in the attribute 'meshmend_patch' and in "
             "the face quality) and a colour. Each patch is also classified with generalized "
             "winding numbers: inside or outside each other part (input layer), and whether it "
             "lies on the outer surface of all parts together (robust to holes: a scan with "
             "holes is still 'inside' where its winding number exceeds 0.5; a layer's own folds "
             "count like overlaps between layers). The log lists id, part, faces, area and "
             "status.<br>Method: surface painting of <i>McLaurin et al.</i>, IJNME 2013 §2.6; "
             "winding numbers of <i>Jacobson et al.</i>, SIGGRAPH 2013, evaluated through a "
             "hierarchy as in <i>Barill et al.</i>, SIGGRAPH 2018.";
    case SELECT_PATCHES:
      return "Selects whole patches (as painted by 'Paint Surface Patches', or painted now with "
             "its defaults): by id, those touching the faces already selected (click one face "
             "with the selection tool, then run this), or by classification: outside all other "
             "parts, inside all other parts, inside one part, or inside the union (the patches "
             "'keep outer surface' removes).";
    default:
      return "Removes patches and joins what is left into one mesh: either the patches that "
             "have a selected face, or by a boolean preset computed from the classification: "
             "keep the outer surface (union), keep the common interior (intersection), or keep "
             "the first part minus the others (difference; the other parts' patches that bound "
             "it are turned over). Removed patches can be moved to a new layer, so nothing is "
             "lost. Vertices that coincide exactly (where the layers met along a curve) are "
             "welded. The result is checked (non-manifold and border edges, intersecting pairs) "
             "and logged.";
  }
}

PatchesPlugin::FilterClass PatchesPlugin::filterClass(QAction* a) const {
  switch (ID(a)) {
    case PAINT_PATCHES:
      return FaceColoring;
    case SELECT_PATCHES:
      return Selection;
    default:
      return Cleaning;
  }
}

int PatchesPlugin::postconditions(QAction* a) const {
  switch (ID(a)) {
    case PAINT_PATCHES:
      return MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY;
    case SELECT_PATCHES:
      return MeshModel::MM_FACEFLAGSELECT;
    default:
      return MeshModel::MM_ALL;
  }
}

void PatchesPlugin::initParameters(QAction* a, MeshDocument&, RichParameterList& parameters) {
  const PaintOptions paint;
  const SelectPatchesOptions select;
  const RemovePatchesOptions remove;
  parameters.addParam(RichEnum(
      "layers", kCurrentLayer,
      QStringList() << "The current layer"
                    << "All visible layers",
      "Layers",
      "The current layer (e.g. the merged output of 'Intersect and Split Layers', whose faces "
      "remember their input layer), or all visible layers together (each one a part)."));
  switch (ID(a)) {
    case PAINT_PATCHES:
      parameters.addParam(RichBool("at_curves", paint.at_curves, "Stop at intersection curves",
                                   "Curve edges marked by 'Intersect and Split Layers' bound "
                                   "patches."));
      parameters.addParam(RichBool("at_non_manifold", paint.at_non_manifold,
                                   "Stop at non-manifold edges",
                                   "Edges shared by three or more faces bound patches (the "
                                   "curves of a merged layer are such edges)."));
      parameters.addParam(RichBool("at_colour_changes", paint.at_colour_changes,
                                   "Stop at colour changes",
                                   "An edge between faces of different colour bounds patches "
                                   "(surface groups of a CAD export)."));
      parameters.addParam(RichFloat("crease_angle", float(paint.crease_angle_deg),
                                    "Stop at creases sharper than (degrees)",
                                    "An edge whose faces' normals differ by more than this "
                                    "angle bounds patches; 0 = off."));
      parameters.addParam(RichBool("classify", true, "Classify inside / outside",
                                   "Computes each patch's winding numbers (inside or outside "
                                   "each other part; on the outer surface or not)."));
      break;
    case SELECT_PATCHES:
      parameters.addParam(RichEnum("by", int(select.by),  // the choices in PatchSelection's order
                                   QStringList() << "Patch ids"
                                                 << "Patches touching the selected faces"
                                                 << "Outside all other parts"
                                                 << "Inside all other parts"
                                                 << "Inside one part"
                                                 << "Inside the union (not on the outer surface)",
                                   "Select", "Which patches to select."));
      parameters.addParam(RichString("ids", "", "Patch ids",
                                     "For 'Patch ids': ids as listed by 'Paint Surface Patches', "
                                     "like 0, 3, 5-7."));
      parameters.addParam(RichInt("part", select.part, "Part",
                                  "For 'Inside one part': the part (input layer number, from "
                                  "0) the patches must lie inside."));
      break;
    default:
      parameters.addParam(RichEnum(
          "keep", remove.keep ? kUnion + int(*remove.keep) : kUnselected,
          QStringList() << "All but the patches with a selected face"
                        << "Outer surface (union)"
                        << "Common interior (intersection)"
                        << "First part minus the others (difference)",
          "Keep", "What to keep: everything except the selected patches, or a boolean result."));
      parameters.addParam(RichBool("removed_to_layer", remove.removed_mesh,
                                   "Move removed patches to a layer",
                                   "Puts the removed patches into a new layer named 'removed "
                                   "patches' instead of deleting them."));
      parameters.addParam(RichBool("verify", remove.verify, "Check the result",
                                   "Counts intersecting pairs (exact), non-manifold and border "
                                   "edges of the result and logs them."));
      break;
  }
  parameters.addParam(RichString(
      "report_file", "", "Report file (JSON)",
      ID(a) == REMOVE_PATCHES
          ? "When not empty, the result is also written to this path as one JSON object: "
            "patches, patches_removed, faces_out, non_manifold_edges, border_edges, "
            "remaining_intersecting_pairs, is_closed, volume and time_ms."
      : ID(a) == SELECT_PATCHES
          ? "When not empty, the result is also written to this path as one JSON object: "
            "patches, patches_selected, faces_selected, selected_ids and time_ms."
          : "When not empty, the result is also written to this path as one JSON object: "
            "patches (count), parts, patch_list (id, part, faces, area, status, winding "
            "numbers) and time_ms."));
}

void PatchesPlugin::apply(QAction* a, MeshDocument& md, const RichParameterList& parameters,
                          vcg::CallBackPos* cb) {
  switch (ID(a)) {
    case PAINT_PATCHES:
      paint(md, parameters, cb);
      break;
    case SELECT_PATCHES:
      select(md, parameters, cb);
      break;
    default:
      remove(md, parameters, cb);
      break;
  }
}

void PatchesPlugin::paint(MeshDocument& md, const RichParameterList& parameters,
                          vcg::CallBackPos* cb) {
  const auto start = Clock::now();
  reportProgress(progressFrom(cb), 0, "Painting patches");
  const Assembly a = assemble(md, parameters.getEnum("layers"));
  PaintOptions options;
  options.at_curves = parameters.getBool("at_curves");
  options.at_non_manifold = parameters.getBool("at_non_manifold");
  options.at_colour_changes = parameters.getBool("at_colour_changes");
  options.crease_angle_deg = parameters.getFloat("crease_angle");
  if (!(options.crease_angle_deg >= 0 && options.crease_angle_deg < 180))
    throw InvalidInputError("the crease angle must be between 0 (off) and 180 degrees");
  Patches p = paintPatches(a.mesh, a.labels, options);
  const bool classify = parameters.getBool("classify");
  if (classify) {
    reportProgress(progressFrom(cb), 50, "Classifying patches");
    classifyPatches(a.mesh, a.labels, p);
  }
  const double ms = msSince(start);
  JsonObject report = toJson(p);
  report.set("time_ms", ms);
  publishReport(parameters, report);

  // The document changes only from here on.
  for (std::size_t i = 0; i < a.layers.size(); ++i) {
    MeshModel* m = a.layers[i];
    m->updateDataMask(MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY);
    auto id = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(m->cm, kPatchAttribute);
    forEachFace(a, i, [&](std::size_t f, CFaceO& face) {
      const int patch = p.patch_of_face[f];
      id[face] = patch;
      face.Q() = float(patch);
      face.C() = colourOf(patch);
    });
  }
  Log("MeshMend: %zu patches (%zu bounding edges) in %.0f ms; %s", p.patches.size(),
      p.boundary_edges, ms, partsLegend(a).c_str());
  if (p.patches_split_at_open_parts)
    Log("  %zu patches lay on both sides of an open part: split where its winding number "
        "crosses 0.5",
        p.patches_split_at_open_parts);
  Log("  id   part   faces   area   status");
  constexpr std::size_t kListed = 200;
  for (std::size_t id = 0; id < p.patches.size() && id < kListed; ++id) {
    const Patch& patch = p.patches[id];
    Log("  %zu   %d   %zu   %.6g   %s", id, patch.part, patch.faces, patch.area,
        classify ? statusOf(patch, p.parts).c_str() : "-");
  }
  if (p.patches.size() > kListed)
    Log("  ... %zu more patches (all of them are in the report file)", p.patches.size() - kListed);
  if (classify)
    for (const std::string& note : partNotes(p)) Log("  note: %s", note.c_str());
}

void PatchesPlugin::select(MeshDocument& md, const RichParameterList& parameters,
                           vcg::CallBackPos* cb) {
  const auto start = Clock::now();
  reportProgress(progressFrom(cb), 0, "Selecting patches");
  const Assembly a = assemble(md, parameters.getEnum("layers"));
  Patches p = patchesOf(a);
  SelectPatchesOptions options;
  options.by = PatchSelection(parameters.getEnum("by"));
  options.ids = toStd(parameters.getString("ids"));
  options.part = parameters.getInt("part");
  if (options.by == PatchSelection::kTouchingSelection) {
    options.selected_faces.assign(a.mesh.face.size(), 0);
    for (std::size_t i = 0; i < a.layers.size(); ++i)
      forEachFace(a, i,
                  [&](std::size_t f, CFaceO& face) { options.selected_faces[f] = face.IsS(); });
  }
  const SelectPatchesResult r = selectPatches(a.mesh, a.labels, p, options);
  for (const std::string& note : r.notes) Log("  note: %s", note.c_str());
  const std::vector<char>& chosen = r.chosen;
  std::size_t faces = 0, patches = r.patches_selected;
  for (std::size_t i = 0; i < a.layers.size(); ++i)
    forEachFace(a, i, [&](std::size_t f, CFaceO& face) {
      if (chosen[p.patch_of_face[f]]) {
        face.SetS();
        ++faces;
      } else {
        face.ClearS();
      }
    });
  Log("MeshMend: selected %zu of %zu patches (%zu faces)", patches, p.patches.size(), faces);
  std::vector<double> ids;  // JSON numbers
  for (std::size_t id = 0; id < chosen.size(); ++id)
    if (chosen[id]) ids.push_back(double(id));
  JsonObject report;
  report.set("patches", p.patches.size())
      .set("patches_selected", patches)
      .set("faces_selected", faces)
      .set("selected_ids", ids)
      .set("time_ms", msSince(start));
  publishReport(parameters, report);
}

void PatchesPlugin::remove(MeshDocument& md, const RichParameterList& parameters,
                           vcg::CallBackPos* cb) {
  const int which = parameters.getEnum("layers");
  const Assembly a = assemble(md, which);
  Patches p = patchesOf(a);
  const int keepMode = parameters.getEnum("keep");
  RemovePatchesOptions options;
  if (keepMode == kUnselected) {
    options.keep.reset();  // the patches with a selected face go
    std::vector<char> removed(p.patches.size(), 0);
    for (std::size_t i = 0; i < a.layers.size(); ++i)
      forEachFace(a, i, [&](std::size_t f, CFaceO& face) {
        if (face.IsS()) removed[p.patch_of_face[f]] = 1;
      });
    for (std::size_t id = 0; id < removed.size(); ++id)
      if (removed[id]) options.remove.push_back(int(id));
  } else {
    options.keep = operationOf(keepMode);
  }
  const bool toLayer = parameters.getBool("removed_to_layer");
  options.removed_mesh = toLayer;
  options.verify = parameters.getBool("verify");
  options.scalar = kHostStoresFloat ? Scalar::kFloat : Scalar::kDouble;
  options.progress = progressFrom(cb);
  const RemovePatchesResult r = removePatches(a.mesh, a.labels, std::move(p), options);
  for (const std::string& note : r.notes) Log("  note: %s", note.c_str());
  const Mesh& result = r.mesh;
  const Mesh& removed = r.removed;
  const std::size_t kept = r.patches - r.patches_removed;
  publishReport(parameters, toJson(r));

  // The document changes only from here on.
  std::vector<LayerAttributes> attributes;
  for (MeshModel* m : a.layers) attributes.push_back(snapshot(*m));
  MeshModel* out = which == kCurrentLayer ? a.layers[0] : md.addNewMesh("", "kept patches", true);
  writeMesh(result, attributes, *out);
  out->cm.Tr.SetIdentity();
  for (const char* name : {kPatchAttribute, kPartAttribute, kCurveEdgesAttribute})
    vcg::tri::Allocator<CMeshO>::DeletePerFaceAttribute(out->cm, name);
  if (toLayer && removed.fn > 0) {
    MeshModel* rest = md.addNewMesh("", "removed patches", false);
    writeMesh(removed, attributes, *rest);
    rest->cm.Tr.SetIdentity();
  }
  if (which == kAllVisible)
    for (MeshModel* m : a.layers) setLayerVisible(*m, false);
  Log("MeshMend: kept %zu of %zu patches: %d faces (%.0f ms)%s", kept, r.patches, out->cm.fn,
      r.time_ms, toLayer ? "; the removed ones are in layer 'removed patches'" : "");
  if (r.verified)
    Log("  check: %zu intersecting pairs, %zu non-manifold edges, %zu border edges%s",
        r.remaining_intersecting_pairs, r.non_manifold_edges, r.border_edges,
        r.is_closed ? ", closed" : "");
}

MESHLAB_PLUGIN_NAME_EXPORTER(PatchesPlugin)
