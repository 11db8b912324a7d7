#include "common/repair/edit_contract.h"

#include <algorithm>
#include <map>

#include "common/base/errors.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"
#include "common/repair/inspect/inspect.h"

namespace meshmend {

namespace {

// The corners of each face as a sorted triple of positions (orientation
// and rotation do not change what a face covers).
using Corners = std::array<Point3, 3>;
Corners cornersOf(const std::vector<Point3>& P, const Triangle& t) {
  Corners c{P[t[0]], P[t[1]], P[t[2]]};
  std::sort(c.begin(), c.end());
  return c;
}

// Per face of `after`: 1 unless it is a face of `before` with the same corners.
std::vector<char> changedFaces(const Mesh& before, const Mesh& after,
                               const std::vector<Point3>& afterPoints,
                               const std::vector<Triangle>& afterTriangles) {
  const std::vector<Point3> P = positionsOf(before);
  const std::vector<Triangle> T = trianglesOf(before);
  std::map<std::pair<int, int>, int> faceOf;  // (layer, face) origin -> face of `before`
  {
    FaceOriginHandle fo = faceOrigins(const_cast<Mesh&>(before));
    for (std::size_t f = 0; f < T.size(); ++f) faceOf[{fo[f].layer, fo[f].face}] = int(f);
  }
  FaceOriginHandle fo = faceOrigins(const_cast<Mesh&>(after));
  std::vector<char> changed(afterTriangles.size(), 1);
  for (std::size_t f = 0; f < afterTriangles.size(); ++f) {
    const auto it = faceOf.find({fo[f].layer, fo[f].face});
    if (fo[f].face < 0 || it == faceOf.end()) continue;
    changed[f] = cornersOf(afterPoints, afterTriangles[f]) != cornersOf(P, T[it->second]);
  }
  return changed;
}

std::size_t degenerate(const std::vector<Point3>& P, const Triangle& t) {
  return t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || collinear(P[t[0]], P[t[1]], P[t[2]]);
}

}  // namespace

EditContract checkEditContract(const Mesh& before, const Mesh& after,
                               const EditContractOptions& options) {
  EditContract c;
  std::vector<Point3> P = positionsOf(after);
  const std::vector<Triangle> T = trianglesOf(after);
  const std::vector<char> changed = changedFaces(before, after, P, T);
  if (options.as_float)
    for (Point3& p : P) p = roundedToFloat(p);
  InspectOptions counts;
  counts.measures = false;  // the counts below, no measures
  const InspectResult was = inspect(before, counts), is = inspect(after, counts);
  c.non_manifold_edges_before = was.non_manifold_edges;
  c.non_manifold_edges_after = is.non_manifold_edges;
  c.inconsistent_edges_before = was.orientation_inconsistent_edges;
  c.inconsistent_edges_after = is.orientation_inconsistent_edges;
  for (std::size_t f = 0; f < T.size(); ++f)
    if (changed[f]) ++c.changed_faces, c.degenerate_changed_faces += degenerate(P, T[f]);
  auto fail = [&](std::size_t n, const std::string& what) {
    if (n > 0) c.failures.push_back(std::to_string(n) + " " + what);
  };
  if (c.non_manifold_edges_after > c.non_manifold_edges_before)
    fail(c.non_manifold_edges_after - c.non_manifold_edges_before,
         "new edges with more than two faces");
  if (!options.allow_orientation_conflicts &&
      c.inconsistent_edges_after > c.inconsistent_edges_before)
    fail(c.inconsistent_edges_after - c.inconsistent_edges_before,
         "new edges run the same way by both their faces");
  fail(c.degenerate_changed_faces, "new or changed faces without area as stored");
  if (options.count_pairs && c.changed_faces > 0) {
    reportProgress(options.progress, 95, "Checking the result");
    c.intersecting_pairs = intersectingOf(P, T, pairsWithChangedFaces(P, T, changed)).size();
    fail(c.intersecting_pairs, "intersecting face pairs with a new or changed face");
  }
  c.met = c.failures.empty();
  return c;
}

std::string describeFailures(const std::vector<std::string>& failures) {
  std::string s;
  for (const std::string& f : failures) s += (s.empty() ? "" : "; ") + f;
  return s;
}

std::string describeFailures(const EditContract& contract) {
  return describeFailures(contract.failures);
}

void requireContract(const std::vector<std::string>& failures, const std::string& filter,
                     bool keepPartial, const std::string& toTry) {
  if (failures.empty() || keepPartial) return;
  throw ContractError(filter + " could not make a valid result: " + describeFailures(failures) +
                      ". Nothing was changed. " + toTry);
}

EditContract requireEditContract(const Mesh& before, const Mesh& after, const std::string& filter,
                                 const EditContractOptions& options, const std::string& toTry) {
  EditContract c = checkEditContract(before, after, options);
  requireContract(c.failures, filter, options.keep_partial, toTry);
  return c;
}

void reportContract(JsonObject& report, const std::vector<std::string>& failures) {
  report.set("contract_met", failures.empty())
      .set("contract_failures", failures)
      .set("partial", !failures.empty());
}

void reportContract(JsonObject& report, const EditContract& contract) {
  reportContract(report, contract.failures);
  report.set("changed_faces", contract.changed_faces);
}

}  // namespace meshmend
