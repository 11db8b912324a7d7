// The contract of the filters that edit a mesh in place by adding, merging,
// flipping or removing faces (trim, stitch, close gaps), checked exactly at
// their end on the mesh as it will be stored, against the mesh as it was:
// no new edge with more than two faces, no new edge that two faces run the
// same way, no changed face without area, and no intersecting pair (the
// self-intersection rule) with a changed face. Faces the operation left as
// they were are the input's own: what they already had is not counted.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"

namespace meshmend {

struct EditContractOptions {
  // Check the coordinates rounded to float, as MeshLab 2020.09 stores them
  // (new vertices are computed in double).
  bool as_float = false;
  bool count_pairs = true;  // count the intersecting pairs with a changed face (exact)
  // Edges two faces run the same way may be new (a stitch asked to join
  // oppositely oriented sides: StitchOptions::allow_orientation_conflict).
  bool allow_orientation_conflicts = false;
  Progress progress;  // called once, before the pair count
  // A result that misses the contract (the filters' "Keep a partial result"):
  // off, requireEditContract throws ContractError and the caller changes
  // nothing; on, the result is returned with met false, for the caller to
  // store marked as partial. checkEditContract does not read it.
  bool keep_partial = false;
};

struct EditContract {
  bool met = true;
  std::vector<std::string> failures;  // what does not hold, one item each
  std::size_t changed_faces = 0;      // faces of `after` that are not an input face as it was
  std::size_t non_manifold_edges_before = 0, non_manifold_edges_after = 0;
  std::size_t inconsistent_edges_before = 0, inconsistent_edges_after = 0;
  std::size_t degenerate_changed_faces = 0;  // collinear or coincident corners, as stored
  std::size_t intersecting_pairs = 0;        // with a changed face, as stored (count_pairs)
};

// `before` and `after` are compact; `after`'s face provenance (mesh.h) names
// the faces of `before` (by their own provenance) it keeps: a face whose
// origin is not in `before`, or whose corners moved, is changed.
EditContract checkEditContract(const Mesh& before, const Mesh& after,
                               const EditContractOptions& options = {});

// The failures as one sentence ("a; b; c").
std::string describeFailures(const std::vector<std::string>& failures);
std::string describeFailures(const EditContract& contract);

// The end of an edit whose contract lists `failures` (what does not hold,
// one item each): none, or keepPartial, returns; else throws ContractError
// "<filter> could not make a valid result: a; b. Nothing was changed.
// <toTry>" (the caller has changed nothing yet).
void requireContract(const std::vector<std::string>& failures, const std::string& filter,
                     bool keepPartial, const std::string& toTry);

// checkEditContract, required as requireContract does (options.keep_partial).
EditContract requireEditContract(const Mesh& before, const Mesh& after, const std::string& filter,
                                 const EditContractOptions& options, const std::string& toTry);

// The report keys of a contract, as the filters' report_file and the
// module's report hold them: contract_met, contract_failures, partial (a
// result kept although it misses the contract) and, for an edit,
// changed_faces.
void reportContract(JsonObject& report, const std::vector<std::string>& failures);
void reportContract(JsonObject& report, const EditContract& contract);

}  // namespace meshmend
