// Measuring the clearance (Aycheh & Kyung's distances of non-adjacent
// triangles): the closest pairs, the pairs below tau, a histogram and each
// vertex's local clearance; and the report keys of both filters.
#include <algorithm>
#include <cmath>
#include <optional>

#include "common/base/errors.h"
#include "common/repair/clearance/detail.h"

namespace meshmend {

using namespace clearance_detail;

const char* toString(ClearanceScope scope) {
  switch (scope) {
    case ClearanceScope::kWithinLayers:
      return "within_layers";
    case ClearanceScope::kBetweenLayers:
      return "between_layers";
    default:
      return "both";
  }
}

ClearanceMeasure measureClearance(const std::vector<const Mesh*>& layers,
                                  const ClearanceMeasureOptions& options) {
  const auto start = Clock::now();
  if (!(options.tau >= 0) || !std::isfinite(options.tau))
    throw InvalidInputError("tau must be a finite distance >= 0");
  if (!(options.local_max >= 0) || !std::isfinite(options.local_max))
    throw InvalidInputError("local_max must be a finite distance >= 0");
  if (options.histogram_bins < 1) throw InvalidInputError("histogram_bins must be at least 1");
  checkCommon(layers, options.exclusion_rings, options.placements);
  reportProgress(options.progress, 0, "Preparing");
  const Soup soup(layers, options.scope, options.exclusion_rings, options.placements);
  const std::vector<Point3>& P = soup.points;

  ClearanceMeasure m;
  m.tau = options.tau;
  // Without tau or cap, the search starts at a quarter of the mean edge
  // length and grows until the closest pair is found.
  // Pairs up to tau must all be found (counted, selected), whatever the
  // local clearance cap.
  double startRadius = std::max(options.local_max, 2 * options.tau);
  if (!(startRadius > 0)) {
    double sum = 0;
    for (const Triangle& t : soup.triangles) sum += (P[t[0]] - P[t[1]]).Norm();
    startRadius = std::max(0.25 * sum / double(soup.faces()), 1e-12 * soup.diagonal);
    if (!(startRadius > 0)) startRadius = 1e-300;
  }
  reportProgress(options.progress, 10, "Closest pairs");
  double used = 0;
  std::vector<NearPair> pairs = pairsFromRadius(soup, P, startRadius, &used, &m.candidate_pairs);
  for (const NearPair& p : pairs)
    if (!m.found || p.d < m.min_distance) {
      m.found = true;
      m.min_distance = p.d;
    }
  m.local_max = options.local_max > 0 ? options.local_max
                : options.tau > 0     ? 2 * options.tau
                : m.found             ? 2 * m.min_distance
                                      : 0;
  if (m.local_max > used) {
    reportProgress(options.progress, 50, "Local clearances");
    pairs = pairsWithin(soup, P, m.local_max, &m.candidate_pairs);
  }

  const int n = soup.layers();
  m.faces_below_tau.resize(n);
  m.vertex_clearance.resize(n);
  for (int l = 0; l < n; ++l) {
    m.faces_below_tau[l].assign(soup.faceOffset[l + 1] - soup.faceOffset[l], 0);
    m.vertex_clearance[l].assign(soup.vertexOffset[l + 1] - soup.vertexOffset[l], m.local_max);
  }
  m.histogram.assign(options.histogram_bins, 0);
  for (const NearPair& p : pairs) {
    if (p.d < options.tau) {
      ++m.violating_pairs;
      for (std::uint32_t f : {p.f, p.g})
        m.faces_below_tau[soup.faceLayer[f]][f - soup.faceOffset[soup.faceLayer[f]]] = 1;
    }
    if (p.d < m.local_max) {
      const int bin =
          std::min(options.histogram_bins - 1, int(p.d / m.local_max * options.histogram_bins));
      ++m.histogram[bin];
      for (std::uint32_t f : {p.f, p.g}) {
        const int l = soup.faceLayer[f];
        for (int v : soup.triangles[f]) {
          double& c = m.vertex_clearance[l][v - soup.vertexOffset[l]];
          c = std::min(c, p.d);
        }
      }
    }
  }
  for (const auto& faces : m.faces_below_tau)
    m.faces_below_tau_count += std::size_t(std::count(faces.begin(), faces.end(), 1));
  if (m.found) {
    m.shortest = listShortest(soup, P, pairs, kInf, options.max_listed_pairs);
    m.closest = m.shortest.front();
  }
  reportProgress(options.progress, 100, "Done");
  m.time_ms = msSince(start);
  return m;
}

namespace {

JsonObject toJson(const ClearancePair& p) {
  return JsonObject()
      .set("layer_a", p.layer_a)
      .set("face_a", p.face_a)
      .set("layer_b", p.layer_b)
      .set("face_b", p.face_b)
      .set("kind", p.kind)
      .set("distance", p.distance)
      .set("point_a", std::vector<double>{p.point_a[0], p.point_a[1], p.point_a[2]})
      .set("point_b", std::vector<double>{p.point_b[0], p.point_b[1], p.point_b[2]});
}

std::vector<JsonObject> toJson(const std::vector<ClearancePair>& pairs) {
  std::vector<JsonObject> out;
  for (const ClearancePair& p : pairs) out.push_back(toJson(p));
  return out;
}

}  // namespace

JsonObject toJson(const ClearanceMeasure& m) {
  JsonObject j;
  const std::optional<double> minimum =
      m.found ? std::optional<double>(m.min_distance) : std::nullopt;
  std::vector<double> histogram(m.histogram.begin(), m.histogram.end());
  j.set("tau", m.tau)
      .set("min_distance", minimum)
      .set("min_distance_before", minimum)
      .set("min_distance_after", minimum)
      .set("violating_pairs", m.violating_pairs)
      .set("violating_pairs_before", m.violating_pairs)
      .set("violating_pairs_after", m.violating_pairs)
      .set("faces_below_tau", m.faces_below_tau_count)
      .set("max_displacement", 0.0)
      .set("mean_displacement", 0.0)
      .set("local_max", m.local_max)
      .set("histogram", histogram)
      .set("candidate_pairs", m.candidate_pairs);
  if (m.found) j.set("closest", toJson(m.closest));
  j.set("shortest", toJson(m.shortest)).set("time_ms", m.time_ms);
  return j;
}

std::vector<std::string> clearanceContractFailures(double minDistanceBefore,
                                                   double minDistanceAfter,
                                                   std::size_t intersectingPairs) {
  std::vector<std::string> failures;
  if (intersectingPairs > 0)
    failures.push_back(std::to_string(intersectingPairs) + " intersecting face pairs as stored");
  if (minDistanceAfter < minDistanceBefore)
    failures.push_back("the smallest distance fell from " + std::to_string(minDistanceBefore) +
                       " to " + std::to_string(minDistanceAfter));
  return failures;
}

std::vector<std::string> clearanceContractFailures(const ClearanceResult& r) {
  return clearanceContractFailures(r.min_distance_before, r.min_distance_after,
                                   r.new_intersecting_pairs);
}

JsonObject toJson(const ClearanceResult& r) {
  auto finite = [](double x) { return std::isfinite(x) ? std::optional<double>(x) : std::nullopt; };
  JsonObject j;
  j.set("tau", r.tau)
      .set("reached", r.reached)
      .set("stop_reason", r.stop_reason)
      .set("min_distance_before", finite(r.min_distance_before))
      .set("min_distance_after", finite(r.min_distance_after))
      .set("violating_pairs_before", r.violating_pairs_before)
      .set("violating_pairs_after", r.violating_pairs_after)
      .set("max_displacement", r.max_displacement)
      .set("mean_displacement", r.mean_displacement_moved)
      .set("mean_displacement_moved", r.mean_displacement_moved)
      .set("mean_displacement_all", r.mean_displacement_all)
      .set("vertices_moved", r.vertices_moved)
      .set("displacement_lower_bound", r.displacement_lower_bound)
      .set("vertices_capped", r.vertices_capped)
      .set("iterations", r.iterations)
      .set("step_halvings", r.step_halvings)
      .set("constraints_last", r.constraints_last)
      .set("new_intersecting_pairs", r.new_intersecting_pairs)
      .set("rounded_to_float", r.rounded_to_float)
      .set("short_pairs", toJson(r.short_pairs))
      .set("warnings", r.warnings)
      .set("time_ms", r.time_ms);
  const auto& t = r.stage_ms;
  j.set("stage_ms", JsonObject()
                        .set("check", t.check)
                        .set("detect", t.detect)
                        .set("solve", t.solve)
                        .set("line_search", t.line_search)
                        .set("verify", t.verify));
  return j;
}

}  // namespace meshmend
