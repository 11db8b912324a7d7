// Enforcing a minimum clearance (Aycheh & Kyung): check that the surfaces
// do not meet, find the pairs closer than tau, take Gauss-Newton steps
// (step.cpp) through a line search that keeps them apart (line_search.cpp)
// until every pair is tau apart or the iterations, the locks or the cap stop
// it, then verify the result as it will be stored and write it back.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "common/base/errors.h"
#include "common/base/parallel.h"
#include "common/exact/intersections.h"
#include "common/repair/clearance/detail.h"
#include "common/repair/output_stage.h"

namespace meshmend {

using namespace clearance_detail;

namespace {

// A move by tau must be representable where the layers lie: below one step
// of the stored scalar at the largest coordinate, no vertex can move by that
// little, and the pairs short of tau cannot even be told from touching ones.
void requireRepresentableTau(const std::vector<Mesh*>& layers, const ClearanceOptions& options) {
  double largest = 0;
  for (const Mesh* m : layers)
    for (const Vertex& v : m->vert)
      if (!v.IsD())
        largest =
            std::max({largest, std::fabs(v.cP()[0]), std::fabs(v.cP()[1]), std::fabs(v.cP()[2])});
  const Scalar scalar = options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
  const double step = scalarStep(Point3(largest, 0, 0), scalar);
  if (options.tau > step) return;
  std::ostringstream m;
  m.precision(3);
  m << "tau (" << options.tau << ") is not more than one step of " << toString(scalar)
    << " at these coordinates (" << step << " at " << largest
    << "): no vertex can move by so little. Choose tau above " << step
    << ", or move the parts nearer the origin";
  throw InvalidInputError(m.str());
}

void checkOptions(const std::vector<Mesh*>& layers, const ClearanceOptions& options) {
  const double tau = options.tau;
  if (!(tau > 0) || !std::isfinite(tau))
    throw InvalidInputError("tau must be a finite distance > 0 (got " + std::to_string(tau) + ")");
  if (!(options.max_displacement >= 0) || !std::isfinite(options.max_displacement))
    throw InvalidInputError("max_displacement must be a finite distance >= 0 (0 = no cap)");
  if (!(options.active_margin >= 0)) throw InvalidInputError("active_margin must be >= 0");
  checkCommon(std::vector<const Mesh*>(layers.begin(), layers.end()), options.exclusion_rings,
              options.placements);
  requireRepresentableTau(layers, options);
  if (options.locked.empty()) return;
  if (options.locked.size() != layers.size())
    throw InvalidInputError("locked must hold one list per layer (" +
                            std::to_string(layers.size()) + "), not " +
                            std::to_string(options.locked.size()));
  for (std::size_t l = 0; l < layers.size(); ++l)
    if (!options.locked[l].empty() && options.locked[l].size() != std::size_t(layers[l]->vn))
      throw InvalidInputError("locked list of layer " + std::to_string(l) + " has " +
                              std::to_string(options.locked[l].size()) + " entries for " +
                              std::to_string(layers[l]->vn) + " vertices");
}

// The clearance is a distance between surfaces that do not meet: crossing
// faces would have to pass through each other, which no small move does.
void requireSeparateSurfaces(const Soup& soup, ClearanceScope scope) {
  const int nl = soup.layers();
  std::vector<MeshArrays> arrays(nl);
  for (int l = 0; l < nl; ++l) {
    const int first = soup.vertexOffset[l];
    arrays[l].points.assign(soup.points.begin() + first,
                            soup.points.begin() + soup.vertexOffset[l + 1]);
    for (int f = soup.faceOffset[l]; f < soup.faceOffset[l + 1]; ++f)
      arrays[l].triangles.push_back({soup.triangles[f][0] - first, soup.triangles[f][1] - first,
                                     soup.triangles[f][2] - first});
  }
  std::vector<const MeshArrays*> pointers;
  for (const MeshArrays& a : arrays) pointers.push_back(&a);
  FindIntersectionsOptions fo;
  fo.self = true;
  fo.cross = includesBetween(scope) && nl > 1;
  fo.layout = 1;  // Morton order: one pass of queries
  const FindIntersectionsResult found = findIntersectionsInArrays(pointers, fo);
  for (int l = 0; l < nl; ++l)
    if (found.self_pairs[l] > 0)
      throw TopologyError("layer " + std::to_string(l) + " intersects itself (" +
                          std::to_string(found.self_pairs[l]) +
                          " pairs of faces); a clearance can only be enforced between "
                          "surfaces that do not meet: run \"MeshMend: Remove "
                          "Self-Intersections\" on it first");
  for (const IntersectingPair& p : found.pairs)
    if (p.a.mesh != p.b.mesh)
      throw TopologyError("layers " + std::to_string(p.a.mesh) + " and " +
                          std::to_string(p.b.mesh) + " intersect (" +
                          std::to_string(found.cross_pairs) +
                          " pairs of faces between layers); a clearance can only be enforced "
                          "between surfaces that do not meet: run \"MeshMend: Intersect and "
                          "Split Layers\" and the patch filters (\"MeshMend: Remove Patches\") "
                          "first, or enforce the clearance within layers only");
}

std::vector<char> lockedVertices(const Soup& soup, const ClearanceOptions& options) {
  std::vector<char> locked(soup.points.size(), 0);
  for (std::size_t l = 0; l < options.locked.size(); ++l)
    for (std::size_t i = 0; i < options.locked[l].size(); ++i)
      locked[soup.vertexOffset[l] + i] = options.locked[l][i] != 0;
  return locked;
}

bool placed(const ClearanceOptions& options, int layer) {
  return !options.placements.empty() && !isIdentity(options.placements[layer]);
}

// The largest move storing can make in one axis: rounding to float moves a
// coordinate by at most 2^-24 of the largest in its layer's frame, which a
// placement carries to the common frame times its largest row sum; placing
// and back in double add a few steps of 2^-53. Two faces move by twice √3
// times that: the solve aims beyond tau by four times this, and the result
// is checked again.
double storingStep(const std::vector<Mesh*>& layers, const Soup& soup,
                   const ClearanceOptions& options) {
  double step = 0;
  for (int l = 0; l < soup.layers(); ++l) {
    double own = 0, there = 0, scale = 1;
    for (const Vertex& v : layers[l]->vert)
      for (int k = 0; k < 3; ++k) own = std::max(own, std::abs(v.cP()[k]));
    for (int v = soup.vertexOffset[l]; v < soup.vertexOffset[l + 1]; ++v)
      for (int k = 0; k < 3; ++k) there = std::max(there, std::abs(soup.points[v][k]));
    if (placed(options, l)) {
      const Placement& m = options.placements[l];
      scale = 0;
      for (int i = 0; i < 3; ++i)
        scale = std::max(scale, std::abs(m.ElementAt(i, 0)) + std::abs(m.ElementAt(i, 1)) +
                                    std::abs(m.ElementAt(i, 2)));
      step = std::max(step, std::ldexp(scale * own + there, -50));
    }
    if (options.round_to_float) step = std::max(step, std::ldexp(scale * own, -24));
  }
  return step;
}

Targets targetsFor(const std::vector<Mesh*>& layers, const Soup& soup,
                   const ClearanceOptions& options) {
  const double roundingMargin = 8 * std::sqrt(3.0) * storingStep(layers, soup, options);
  Targets t;
  t.reached = options.tau * (1 + 1e-9) + roundingMargin;  // "done" for the solve
  t.goal = t.reached + 1e-4 * options.tau;                // aimed at by each linearised step
  t.near = t.goal + options.active_margin * options.tau;  // pairs taking part in a step
  return t;
}

// The smallest distance of `pairs` and how many are below tau.
void minimumOf(const std::vector<NearPair>& pairs, double tau, double* minimum,
               std::size_t* below) {
  *minimum = kInf;
  *below = 0;
  for (const NearPair& p : pairs) {
    *minimum = std::min(*minimum, p.d);
    if (p.d < tau) ++*below;
  }
}

// Nothing close: the minimum comes from a growing search.
void minimumFromFarther(Separation& s, double* minimum) {
  if (!s.near.empty() || !anyPairInScope(s.soup)) return;
  double used = 0;
  const std::vector<NearPair> far =
      pairsFromRadius(s.soup, s.P, 4 * s.targets.near, &used, &s.candidates);
  std::size_t none = 0;
  minimumOf(far, s.options.tau, minimum, &none);
}

// The work bound on the input's short pairs (ClearanceOptions::max_short_pairs).
void boundShortPairs(std::size_t shortPairs, std::size_t bound, double tau, double closest) {
  if (bound == 0 || shortPairs <= bound) return;
  std::ostringstream message;
  message << shortPairs << " face pairs are closer than tau = " << tau
          << ", more than the work bound of " << bound
          << " (max_short_pairs): separating them all would take minutes, and so many mean a "
             "tau larger than the parts or than a few edge lengths, not gaps to open. Nothing "
             "was changed. Try a smaller tau (the closest pair is "
          << closest
          << " apart), more exclusion rings, or raise the bound if the parts really are that "
             "close everywhere";
  throw WorkLimitError(message.str());
}

// The active pairs of the input, the measures before, the work bound, and
// a lower bound of the displacement any solution needs: (tau - d) / 2 per
// short pair, tau - d when one side is locked.
void detectShortPairs(Separation& s) {
  const auto t0 = Clock::now();
  const double tau = s.options.tau;
  ClearanceResult& r = s.result;
  s.near = pairsWithin(s.soup, s.P, s.targets.near, &s.candidates);
  r.stage_ms.detect += msSince(t0);
  minimumOf(s.near, tau, &r.min_distance_before, &r.violating_pairs_before);
  boundShortPairs(r.violating_pairs_before, s.options.max_short_pairs, tau, r.min_distance_before);
  minimumFromFarther(s, &r.min_distance_before);
  auto allLocked = [&](std::uint32_t f) {
    const Triangle& t = s.soup.triangles[f];
    return s.locked[t[0]] && s.locked[t[1]] && s.locked[t[2]];
  };
  for (const NearPair& p : s.near) {
    if (!(p.d < tau)) continue;
    const double need = allLocked(p.f) || allLocked(p.g) ? tau - p.d : (tau - p.d) / 2;
    r.displacement_lower_bound = std::max(r.displacement_lower_bound, need);
  }
}

// Gauss-Newton steps until every active pair reaches tau, or the
// iterations, the locks, the cap or the line search stop them.
void separate(Separation& s) {
  ClearanceResult& r = s.result;
  r.stop_reason = "reached";
  const int maxIterations = std::max(0, s.options.max_iterations);
  for (int iteration = 0;; ++iteration) {
    double smallest = kInf;
    for (const NearPair& p : s.near) smallest = std::min(smallest, p.d);
    if (smallest >= s.targets.reached) return;
    if (iteration >= maxIterations) {
      r.stop_reason = "iterations";
      return;
    }
    reportProgress(s.options.progress, 5 + 90 * iteration / std::max(1, maxIterations),
                   "Separating");
    auto t0 = Clock::now();
    const Step step = linearisedStep(s);
    r.stage_ms.solve += msSince(t0);
    if (step.vertices.empty()) {
      if (r.stop_reason != "locked") r.stop_reason = "stalled";
      return;
    }
    t0 = Clock::now();
    const bool taken = takeStep(s, step);
    r.stage_ms.line_search += msSince(t0);
    if (!taken) {
      r.stop_reason = "stalled";
      return;
    }
    ++r.iterations;
  }
}

// With placements, each moved vertex as its layer will store it: its move
// taken back to the layer's frame (the move, not the position, so that the
// error scales with the move and axes it does not move along stay as they
// are), rounded there, and placed again (no re-rounding: the margin of
// targetsFor covers it, and verifyStored measures what is left).
void storeThroughPlacements(Separation& s, const std::vector<char>& movedVertex) {
  for (int l = 0; l < s.soup.layers(); ++l) {
    const Placement& m = s.options.placements[l];
    const Placement inverse = vcg::Inverse(m);
    for (int v = s.soup.vertexOffset[l]; v < s.soup.vertexOffset[l + 1]; ++v) {
      if (!movedVertex[v]) continue;
      const Point3 move = s.P[v] - s.P0[v];
      Point3 own = s.own[v];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) own[i] += inverse.ElementAt(i, j) * move[j];
      if (s.options.round_to_float) own = roundedToFloat(own);
      s.own[v] = own;
      s.P[v] = placed(s.options, l) ? Point3(m * own) : own;  // identity: no rounding
    }
  }
  s.result.stored.scalar = s.options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
}

// The output as it will be stored: the moved vertices through the output
// stage (output_stage.h; re-rounded where rounding would make a face around
// them cross another), then every pair with a face around a moved vertex
// measured again and tested exactly for intersection.
void verifyStored(Separation& s) {
  const Soup& soup = s.soup;
  std::vector<Point3>& P = s.P;
  const std::size_t nv = P.size(), nf = soup.faces();
  std::vector<char> movedVertex(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) movedVertex[v] = !(P[v] == s.P0[v]);
  std::vector<char> changed(nf, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    const Triangle& t = soup.triangles[f];
    changed[f] = movedVertex[t[0]] || movedVertex[t[1]] || movedVertex[t[2]];
  }
  if (s.options.placements.empty()) {
    OutputStageOptions stage;
    stage.scalar = s.options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
    s.result.stored = storeNewPoints(P, soup.triangles, movedVertex, changed, stage);
  } else {
    storeThroughPlacements(s, movedVertex);
  }
  s.result.rounded_to_float = s.options.round_to_float;

  std::vector<Box> boxes;
  for (std::size_t f = 0; f < nf; ++f) {
    const Triangle& t = soup.triangles[f];
    if (changed[f]) boxes.push_back(inflated(boxOf(P[t[0]], P[t[1]], P[t[2]]), s.targets.near));
  }
  std::vector<std::array<std::uint32_t, 2>> touched =
      pairsWithChangedBoxes(P, soup.triangles, changed, boxes);
  touched.erase(std::remove_if(touched.begin(), touched.end(),
                               [&](const std::array<std::uint32_t, 2>& p) {
                                 return !soup.checkedPair(p[0], p[1]);
                               }),
                touched.end());
  s.result.new_intersecting_pairs = intersectingOf(P, soup.triangles, touched).size();
  s.near.erase(std::remove_if(s.near.begin(), s.near.end(),
                              [&](const NearPair& p) { return changed[p.f] || changed[p.g]; }),
               s.near.end());
  std::vector<double> dist(touched.size(), kInf);
  parallelChunks(
      touched.size(),
      [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i)
          if (soup.clearancePair(touched[i][0], touched[i][1]))
            dist[i] = soup.distance(P, touched[i][0], touched[i][1]);
      },
      256);
  for (std::size_t i = 0; i < touched.size(); ++i)
    if (dist[i] < s.targets.near)
      s.near.push_back({std::min(touched[i][0], touched[i][1]),
                        std::max(touched[i][0], touched[i][1]), dist[i]});
}

// The measures after, the outcome and what the log must say about it.
void concludeOutcome(Separation& s) {
  ClearanceResult& r = s.result;
  const double tau = s.options.tau;
  minimumOf(s.near, tau, &r.min_distance_after, &r.violating_pairs_after);
  minimumFromFarther(s, &r.min_distance_after);
  r.reached = r.violating_pairs_after == 0 && r.new_intersecting_pairs == 0;
  if (r.reached) {
    r.stop_reason = "reached";
  } else if (r.stop_reason == "reached") {
    // Only storing (rounding, placements) can get here.
    r.stop_reason = "rounding";
    const std::string how = s.options.placements.empty()
                                ? "rounding to float"
                                : "storing the moved vertices in their layers' own frames";
    r.warnings.push_back(how + " left " + std::to_string(r.violating_pairs_after) +
                         " pairs short of tau and " + std::to_string(r.new_intersecting_pairs) +
                         " intersecting pairs" +
                         (s.options.placements.empty()
                              ? std::string()
                              : ": apply the placements to the layers first and run again"));
  }
  r.short_pairs = listShortest(s.soup, s.P, s.near, tau, s.options.max_listed_pairs);
  if (!r.reached && r.stop_reason == "stalled")
    r.warnings.push_back("no step keeping the surfaces apart improved the " +
                         std::to_string(r.violating_pairs_after) +
                         " pairs still short: tau may be more than the shape allows "
                         "there (a part thinner than tau, faces a few rings apart), or "
                         "locked vertices and the cap hold them");
  if (!r.reached && r.stop_reason == "locked")
    r.warnings.push_back("the pairs still short have only locked or capped vertices");
}

// Displacements from the input positions.
void measureDisplacements(Separation& s) {
  ClearanceResult& r = s.result;
  const std::size_t nv = s.P.size();
  double sum = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    const double len = (s.P[v] - s.P0[v]).Norm();
    if (len > 0) ++r.vertices_moved;
    sum += len;
    r.max_displacement = std::max(r.max_displacement, len);
    if (s.capped[v]) ++r.vertices_capped;
  }
  r.mean_displacement_all = nv ? sum / double(nv) : 0;
  r.mean_displacement_moved = r.vertices_moved ? sum / double(r.vertices_moved) : 0;
}

}  // namespace

ClearanceResult enforceClearance(std::vector<Mesh*>& layers, const ClearanceOptions& options) {
  const auto start = Clock::now();
  checkOptions(layers, options);
  reportProgress(options.progress, 0, "Checking intersections");
  Separation s(std::vector<const Mesh*>(layers.begin(), layers.end()), options);
  s.result.tau = options.tau;
  // With round_to_float everything works on the input as MeshLab stores it
  // (a no-op for a mesh that comes from MeshLab), so that only the moved
  // vertices are rounded at the end, within the margin the solve keeps. A
  // placed layer is stored in its own frame: it is read as it is.
  for (int l = 0; l < s.soup.layers(); ++l)
    for (int v = s.soup.vertexOffset[l]; v < s.soup.vertexOffset[l + 1]; ++v) {
      if (options.round_to_float && !placed(options, l)) s.P[v] = roundedToFloat(s.P[v]);
      if (!options.placements.empty())
        s.own.push_back(layers[l]->vert[v - s.soup.vertexOffset[l]].cP());
    }
  auto t0 = Clock::now();
  requireSeparateSurfaces(s.soup, options.scope);
  s.result.stage_ms.check = msSince(t0);

  s.locked = lockedVertices(s.soup, options);
  s.capped.assign(s.P.size(), 0);
  s.targets = targetsFor(layers, s.soup, options);
  s.P0 = s.P;
  detectShortPairs(s);
  separate(s);

  t0 = Clock::now();
  verifyStored(s);
  concludeOutcome(s);
  s.result.stage_ms.verify = msSince(t0);
  measureDisplacements(s);

  // The last chance to cancel comes before the layers change.
  reportProgress(options.progress, 100, "Done");
  const std::vector<Point3>& stored = options.placements.empty() ? s.P : s.own;
  for (int l = 0; l < s.soup.layers(); ++l) {
    Mesh& mesh = *layers[l];
    for (int i = 0; i < s.soup.vertexOffset[l + 1] - s.soup.vertexOffset[l]; ++i)
      mesh.vert[i].P() = stored[s.soup.vertexOffset[l] + i];
  }
  s.result.time_ms = msSince(start);
  return s.result;
}

}  // namespace meshmend
