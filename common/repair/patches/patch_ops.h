// What the patch filters do with painted patches, written once for the
// MeshLab filters and the Python module: choosing patches (Select Patches)
// and removing them or keeping a boolean result (Remove Patches).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/repair/patches/patches.h"
#include "common/repair/split/split.h"

namespace meshmend {

// Patch ids from text such as "0, 3, 5-7" (the filters' `ids` parameter).
// Throws InvalidInputError for text that is no id or range, an id out of
// [0, patches), or no id at all.
std::vector<int> parsePatchIds(const std::string& text, std::size_t patches);

// What a user needs to know about how parts were classified: open parts
// (a fractional winding number near their holes) and parts taken turned
// (closed, pointing inward).
std::vector<std::string> partNotes(const Patches& patches);

// The labels of intersect-and-split's merged output: its curve edges, and
// as each face's part the input mesh it came from (the split's merged mesh
// is not changed; its provenance handle is not const).
FaceLabels mergedOutputLabels(SplitResult& split);

// How Select Patches chooses (the filter's `by`, in its order).
enum class PatchSelection {
  kByIds,              // the ids in SelectPatchesOptions::ids
  kTouchingSelection,  // patches with a selected face
  kOutsideOthers,      // outside every other part
  kInsideAllOthers,    // inside every other part
  kInsidePart,         // inside part SelectPatchesOptions::part (not its own)
  kUnionInterior,      // not on the outer surface of the union
};

struct SelectPatchesOptions {
  PatchSelection by = PatchSelection::kTouchingSelection;  // the filter's default
  std::string ids;                                         // for kByIds: "0, 3, 5-7"
  std::vector<char> selected_faces;                        // for kTouchingSelection: per face
  int part = 1;                                            // for kInsidePart
};

struct SelectPatchesResult {
  std::vector<char> chosen;  // per patch id
  std::size_t patches_selected = 0, faces_selected = 0;
  std::vector<std::string> notes;  // partNotes, where the choice classified the patches
};

// Chooses patches of `patches` (painted on `mesh` with `labels`),
// classifying them first where the choice needs it. Throws
// InvalidInputError for a choice the input cannot make (no selected face,
// no such part, a single part where the choice is between parts).
SelectPatchesResult selectPatches(const Mesh& mesh, const FaceLabels& labels, Patches& patches,
                                  const SelectPatchesOptions& options);

struct RemovePatchesOptions {
  // What to keep: every patch but those in `remove` (unset keep), or the
  // boolean result `keep` (the filter's default: the union).
  std::optional<BooleanOperation> keep = BooleanOperation::kUnion;
  std::vector<int> remove;          // patch ids, when keep is unset
  bool removed_mesh = false;        // also return the removed patches (removed_to_layer)
  bool verify = true;               // check the result (below)
  Scalar scalar = Scalar::kDouble;  // how the host stores it (the check counts on that)
  Progress progress;                // between stages
};

struct RemovePatchesResult {
  Mesh mesh;     // the kept patches, welded (extractPatches)
  Mesh removed;  // the removed ones (RemovePatchesOptions::removed_mesh)
  std::size_t patches = 0, patches_removed = 0;
  std::string keep;                // "unselected", or the boolean operation's name
  std::vector<std::string> notes;  // partNotes of a boolean's classification
  // With verify: the result's intersecting pairs (the checker's rule, as
  // stored), non-manifold and border edges, closedness and volume (when
  // closed and oriented).
  bool verified = false;
  std::size_t remaining_intersecting_pairs = 0, non_manifold_edges = 0, border_edges = 0;
  bool is_closed = false;
  std::optional<double> volume;
  double time_ms = 0;
};

// Remove Patches. Throws InvalidInputError where nothing would be left, no
// id is given, or an intersection or difference has a single part.
RemovePatchesResult removePatches(const Mesh& mesh, const FaceLabels& labels, Patches patches,
                                  const RemovePatchesOptions& options);

// The report_file keys: patches, patches_removed, faces_out, keep, and with
// verify non_manifold_edges, border_edges, is_closed, volume,
// remaining_intersecting_pairs; time_ms.
JsonObject toJson(const RemovePatchesResult& result);

}  // namespace meshmend
