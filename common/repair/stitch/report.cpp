// The contracts and report keys of trimming, stitching and gap closing.
#include "common/repair/stitch/stitch.h"

namespace meshmend {

JsonObject toJson(const TrimResult& r) {
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", 0)
      .set("vertices_merged", 0)
      .set("loop_vertices", r.loop.size())
      .set("faces_kept", r.faces_kept)
      .set("faces_removed", r.faces_removed)
      .set("faces_on_loop", r.faces_on_loop)
      .set("time_ms", r.time_ms);
  return j;
}

JsonObject toJson(const StitchResult& r) {
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", r.faces_added)
      .set("vertices_merged", 0)
      .set("vertices_added", r.vertices_added)
      .set("closed", r.closed)
      .set("reversed_b", r.reversed_b)
      .set("orientation_conflicts", r.orientation_conflicts)
      .set("max_aspect_ratio", r.max_aspect_ratio);
  if (r.checked) j.set("new_intersecting_pairs", r.new_intersecting_pairs);
  j.set("time_ms", r.time_ms);
  return j;
}

JsonObject toJson(const StitchSequenceResult& r) {
  std::vector<JsonObject> steps;
  for (const StitchResult& s : r.steps) steps.push_back(toJson(s));
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", r.faces_added)
      .set("vertices_merged", 0)
      .set("vertices_added", r.vertices_added)
      .set("new_intersecting_pairs", r.new_intersecting_pairs)
      .set("steps", steps)
      .set("time_ms", r.time_ms);
  return j;
}

EditContractOptions editContractOptions(const TrimOptions& options, bool keepPartial) {
  EditContractOptions c;
  c.count_pairs = false;  // trimming only removes faces: none is new
  c.keep_partial = keepPartial;
  c.progress = options.progress;
  return c;
}

EditContractOptions editContractOptions(const StitchOptions& options, bool keepPartial) {
  EditContractOptions c;
  c.as_float = options.round_to_float;
  c.count_pairs = options.check_intersections;
  c.allow_orientation_conflicts = options.allow_orientation_conflict;
  c.keep_partial = keepPartial;
  c.progress = options.progress;
  return c;
}

EditContractOptions editContractOptions(const CloseGapsOptions& options, bool keepPartial) {
  EditContractOptions c;
  c.as_float = options.round_to_float;
  c.count_pairs = true;
  c.keep_partial = keepPartial;
  c.progress = options.progress;
  return c;
}

bool changedAnything(const CloseGapsResult& r) {
  return r.vertices_merged > 0 || r.faces_added > 0 || r.faces_flipped > 0 ||
         r.degenerate_faces_removed > 0;
}

JsonObject toJson(const CloseGapsResult& r) {
  std::vector<JsonObject> gaps;
  for (const GapReport& g : r.gaps) {
    JsonObject o;
    o.set("path_a_vertices", g.path_a.size())
        .set("path_b_vertices", g.path_b.size())
        .set("closed", g.closed)
        .set("gap", g.gap)
        .set("stitched", g.stitched)
        .set("faces_added", g.faces_added);
    if (!g.reason.empty()) o.set("reason", g.reason);
    gaps.push_back(o);
  }
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", r.faces_added)
      .set("vertices_merged", r.vertices_merged)
      .set("merge_tolerance", r.merge_tolerance)
      .set("max_gap", r.max_gap)
      .set("faces_flipped", r.faces_flipped)
      .set("orientation_conflicts", r.orientation_conflicts)
      .set("border_edges_after_merge", r.border_edges_after_merge)
      .set("edges_merged", r.edges_merged)
      .set("merges_skipped", r.merges_skipped)
      .set("degenerate_faces_removed", r.degenerate_faces_removed)
      .set("vertices_added", r.vertices_added)
      .set("gaps_found", r.gaps_found)
      .set("gaps_stitched", r.gaps_stitched);
  if (r.verified)
    j.set("new_intersecting_pairs", r.new_intersecting_pairs)
        .set("remaining_intersecting_pairs", r.remaining_intersecting_pairs);
  j.set("gaps", gaps).set("time_ms", r.time_ms);
  return j;
}

}  // namespace meshmend
