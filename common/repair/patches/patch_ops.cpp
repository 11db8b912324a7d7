#include "common/repair/patches/patch_ops.h"
#include "common/base/timing.h"

#include <chrono>
#include <sstream>

#include "common/base/errors.h"
#include "common/repair/inspect/inspect.h"
#include "common/repair/output_stage.h"

namespace meshmend {

std::vector<int> parsePatchIds(const std::string& text, std::size_t patches) {
  std::vector<int> ids;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (item.empty()) continue;
    int lo = 0, hi = 0;
    char dash = 0;
    std::stringstream range(item);
    if (!(range >> lo)) throw InvalidInputError("'" + item + "' is not a patch id");
    hi = lo;
    if (range >> dash && !(dash == '-' && range >> hi))
      throw InvalidInputError("'" + item + "' is not a patch id or a range like 5-7");
    if (lo < 0 || hi < lo || std::size_t(hi) >= patches)
      throw InvalidInputError("patch id '" + item + "' does not exist: the ids run from 0 to " +
                              std::to_string(patches - 1));
    for (int id = lo; id <= hi; ++id) ids.push_back(id);
  }
  if (ids.empty()) throw InvalidInputError("no patch ids given: write them like 0, 3, 5-7");
  return ids;
}

FaceLabels mergedOutputLabels(SplitResult& split) {
  FaceLabels labels;
  labels.curve_edges = curveEdgeFlags(split.merged, split.merged_curve_edges);
  FaceOriginHandle fo = faceOrigins(split.merged);
  for (std::size_t f = 0; f < split.merged.face.size(); ++f) labels.part.push_back(fo[f].layer);
  return labels;
}

std::vector<std::string> partNotes(const Patches& p) {
  std::vector<std::string> notes;
  for (int part = 0; part < p.parts; ++part)
    if (part < int(p.part_inside_out.size()) && p.part_inside_out[part])
      notes.push_back("part " + std::to_string(part) +
                      " is inside out (its faces point inward: a negative volume): it is "
                      "classified as if turned outward, and the result faces outward");
    else if (part < int(p.part_closed.size()) && !p.part_closed[part])
      notes.push_back("part " + std::to_string(part) +
                      " is open (it has border edges): its winding number is fractional near "
                      "the holes, and a patch counts as inside it where the winding number "
                      "exceeds 0.5");
  return notes;
}

namespace {

// Whether a classified patch is chosen by `by` (a choice between parts).
bool chosenByClassification(const Patch& patch, PatchSelection by, int part) {
  switch (by) {
    case PatchSelection::kOutsideOthers:
      return patch.insideAllOthers(false);
    case PatchSelection::kInsideAllOthers:
      return patch.insideAllOthers(true);
    case PatchSelection::kInsidePart:
      return patch.part != part && patch.inside(part);
    default:
      return !patch.onUnionSurface();
  }
}

}  // namespace

SelectPatchesResult selectPatches(const Mesh& mesh, const FaceLabels& labels, Patches& p,
                                  const SelectPatchesOptions& options) {
  SelectPatchesResult r;
  r.chosen.assign(p.patches.size(), 0);
  if (options.by == PatchSelection::kByIds) {
    for (int id : parsePatchIds(options.ids, p.patches.size())) r.chosen[id] = 1;
  } else if (options.by == PatchSelection::kTouchingSelection) {
    bool any = false;
    for (std::size_t f = 0; f < options.selected_faces.size() && f < p.patch_of_face.size(); ++f)
      if (options.selected_faces[f]) r.chosen[p.patch_of_face[f]] = 1, any = true;
    if (!any)
      throw InvalidInputError(
          "no face is selected: select a face of each patch you want (e.g. with the selection "
          "tool), then run this again");
  } else {
    if (options.by == PatchSelection::kInsidePart && (options.part < 0 || options.part >= p.parts))
      throw InvalidInputError("there is no part " + std::to_string(options.part) +
                              ": the parts run from 0 to " + std::to_string(p.parts - 1));
    if (options.by != PatchSelection::kUnionInterior && p.parts < 2)
      throw InvalidInputError(
          "there is only one part: inside / outside other parts needs the merged output of "
          "'Intersect and Split Layers' (intersect_and_split's merged_part) or several layers");
    classifyPatches(mesh, labels, p);
    r.notes = partNotes(p);
    for (std::size_t id = 0; id < p.patches.size(); ++id)
      r.chosen[id] = chosenByClassification(p.patches[id], options.by, options.part);
  }
  for (std::size_t id = 0; id < r.chosen.size(); ++id)
    if (r.chosen[id]) ++r.patches_selected, r.faces_selected += p.patches[id].faces;
  return r;
}

namespace {

// The choice of Remove Patches: which patches stay, which turn over.
PatchChoice choiceOf(const Mesh& mesh, const FaceLabels& labels, Patches& p,
                     const RemovePatchesOptions& options, RemovePatchesResult& r) {
  PatchChoice choice;
  if (!options.keep) {
    if (options.remove.empty())
      throw InvalidInputError(
          "no face is selected and no patch id given: select the patches to remove first (e.g. "
          "with 'Select Patches'), or choose a boolean result");
    choice.keep.assign(p.patches.size(), 1);
    for (int id : options.remove) {
      if (id < 0 || std::size_t(id) >= p.patches.size())
        throw InvalidInputError("patch id " + std::to_string(id) +
                                " does not exist: the ids run from 0 to " +
                                std::to_string(p.patches.size() - 1));
      choice.keep[std::size_t(id)] = 0;
    }
    r.keep = "unselected";
    return choice;
  }
  if (*options.keep != BooleanOperation::kUnion && p.parts < 2)
    throw InvalidInputError(
        "intersection and difference need two parts: the merged output of 'Intersect and Split "
        "Layers' of two layers (intersect_and_split's merged_part), or two visible layers");
  reportProgress(options.progress, 20, "Classifying patches");
  classifyPatches(mesh, labels, p);
  r.notes = partNotes(p);
  r.keep = toString(*options.keep);
  return choosePatches(p, *options.keep);
}

// The checks of the result, on its coordinates as the host stores them.
void check(RemovePatchesResult& r, Scalar scalar) {
  Mesh stored = r.mesh;
  for (Vertex& v : stored.vert) v.P() = storedAs(v.cP(), scalar);
  const InspectResult i = inspect(stored);
  r.non_manifold_edges = i.non_manifold_edges;
  r.border_edges = i.border_edges;
  r.is_closed = i.is_closed;
  r.volume = i.volume;
  r.remaining_intersecting_pairs = storedIntersectingPairs(r.mesh, scalar);
  r.verified = true;
}

}  // namespace

RemovePatchesResult removePatches(const Mesh& mesh, const FaceLabels& labels, Patches p,
                                  const RemovePatchesOptions& options) {
  const auto start = Clock::now();
  RemovePatchesResult r;
  reportProgress(options.progress, 0, "Choosing patches");
  const PatchChoice choice = choiceOf(mesh, labels, p, options, r);
  std::size_t kept = 0;
  for (char k : choice.keep) kept += k != 0;
  if (kept == 0)
    throw InvalidInputError(
        "nothing would be left: every patch would be removed. The result is empty when the "
        "parts' interiors do not overlap (an intersection), or the first part lies inside the "
        "others (a difference); if the meshes cross, intersect and split them first");
  r.patches = p.patches.size();
  r.patches_removed = p.patches.size() - kept;
  reportProgress(options.progress, 60, "Extracting the kept patches");
  r.mesh = extractPatches(mesh, p, choice.keep, choice.flip);
  if (options.removed_mesh && kept < p.patches.size()) {
    std::vector<char> removed(choice.keep.size());
    for (std::size_t id = 0; id < removed.size(); ++id) removed[id] = !choice.keep[id];
    r.removed = extractPatches(mesh, p, removed);
  }
  if (options.verify) {
    reportProgress(options.progress, 80, "Checking the result");
    check(r, options.scalar);
  }
  r.time_ms = msSince(start);
  return r;
}

JsonObject toJson(const RemovePatchesResult& r) {
  JsonObject j;
  j.set("patches", r.patches)
      .set("patches_removed", r.patches_removed)
      .set("faces_out", std::size_t(r.mesh.fn))
      .set("keep", r.keep);
  if (r.verified) {
    j.set("non_manifold_edges", r.non_manifold_edges)
        .set("border_edges", r.border_edges)
        .set("is_closed", r.is_closed)
        .set("volume", r.volume)
        .set("remaining_intersecting_pairs", r.remaining_intersecting_pairs);
  }
  j.set("time_ms", r.time_ms);
  return j;
}

}  // namespace meshmend
