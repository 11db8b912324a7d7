// The line search of the enforcement: the step is taken only as far as
// every intermediate configuration stays free of intersections
// (conservative advancement for faces sharing no vertex, the exact test at
// the end for neighbours) and the shortfall Σ (goal - d)² goes down.
#include <algorithm>
#include <atomic>
#include <cmath>

#include "common/base/parallel.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"
#include "common/repair/clearance/detail.h"

namespace meshmend::clearance_detail {

namespace {

// The face pairs a step can change: a moved face against any face its swept
// box (grown by targets.near) reaches, each pair (f < g) with its rules and
// its distance before the step.
struct Touched {
  std::vector<char> changed;       // per face: a corner moves
  std::vector<double> faceMotion;  // per face: its largest corner move
  std::vector<std::array<std::uint32_t, 2>> pairs;
  std::vector<char> shares, counts;  // per pair: shares a vertex, is a clearance pair
  std::vector<double> before;        // per pair: distance (not for neighbours)
};

Touched touchedBy(const Separation& s, const Step& step) {
  const Soup& soup = s.soup;
  const std::vector<Point3>& P = s.P;
  const std::size_t nf = soup.faces();
  Touched t;
  t.changed.assign(nf, 0);
  t.faceMotion.assign(nf, 0);
  for (int v : step.vertices)
    for (int i = soup.starStart[v]; i < soup.starStart[v + 1]; ++i) {
      const int f = soup.star[i];
      t.changed[f] = 1;
      t.faceMotion[f] = std::max(t.faceMotion[f], step.by[v].Norm());
    }
  std::vector<Box> swept;
  for (std::size_t f = 0; f < nf; ++f) {
    if (!t.changed[f]) continue;
    const Triangle& c = soup.triangles[f];
    Box a = boxOf(P[c[0]], P[c[1]], P[c[2]]);
    const Box b = boxOf(P[c[0]] + step.by[c[0]], P[c[1]] + step.by[c[1]], P[c[2]] + step.by[c[2]]);
    for (int k = 0; k < 3; ++k) {
      a.lo[k] = std::min(a.lo[k], b.lo[k]);
      a.hi[k] = std::max(a.hi[k], b.hi[k]);
    }
    swept.push_back(inflated(a, s.targets.near));
  }
  t.pairs = pairsWithChangedBoxes(P, soup.triangles, t.changed, swept);
  t.pairs.erase(std::remove_if(t.pairs.begin(), t.pairs.end(),
                               [&](const std::array<std::uint32_t, 2>& p) {
                                 return !soup.checkedPair(p[0], p[1]);
                               }),
                t.pairs.end());
  for (auto& p : t.pairs)
    if (p[1] < p[0]) std::swap(p[0], p[1]);
  const std::size_t nt = t.pairs.size();
  t.shares.assign(nt, 0);
  t.counts.assign(nt, 0);
  t.before.assign(nt, kInf);
  parallelChunks(
      nt,
      [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) {
          const auto [f, g] = t.pairs[i];
          t.shares[i] = soup.sharesVertex(f, g);
          t.counts[i] = soup.clearancePair(f, g);
          if (!t.shares[i]) t.before[i] = soup.distance(P, f, g);
        }
      },
      256);
  return t;
}

// Σ (goal - d)² over the clearance pairs short of the goal.
double shortfall(const Touched& t, const std::vector<double>& distance, double goal) {
  double sum = 0;
  for (std::size_t i = 0; i < t.pairs.size(); ++i)
    if (t.counts[i] && distance[i] < goal) sum += (goal - distance[i]) * (goal - distance[i]);
  return sum;
}

// Do faces f and g (sharing no vertex, `before` apart) stay apart all along
// the fraction alpha of the step? Conservative advancement: every point of
// a face moves at most its largest corner move, so the pair cannot meet
// before their distance has been used up by both faces' motion. `after`
// receives the distance at the end.
bool staysApart(const Separation& s, const Step& step, const Touched& t, std::uint32_t f,
                std::uint32_t g, double before, double alpha, double& after) {
  const Soup& soup = s.soup;
  const double motion = alpha * (t.faceMotion[f] + t.faceMotion[g]);
  double dist = before, at = 0;
  Point3 a[3], c[3];
  auto distanceAt = [&](double fraction) {
    for (int k = 0; k < 3; ++k) {
      const int u = soup.triangles[f][k], w = soup.triangles[g][k];
      a[k] = s.P[u] + step.by[u] * (alpha * fraction);
      c[k] = s.P[w] + step.by[w] * (alpha * fraction);
    }
    return triangleDistance(a, c).distance;
  };
  bool safe = false;
  for (int round = 0; round < 200; ++round) {
    if (dist > motion * (1 - at)) {
      safe = true;
      break;
    }
    if (!(dist > 1e-14 * soup.diagonal)) break;
    at = std::min(1.0, at + 0.9 * dist / motion);
    dist = distanceAt(at);
    if (at == 1.0) {
      safe = dist > 0;
      break;
    }
  }
  if (!safe) return false;
  after = motion > 0 && at < 1.0 ? distanceAt(1.0) : dist;
  return true;
}

// Does the fraction alpha of the step (positions in `trial`) keep every
// touched pair apart? Fills `after` for the pairs sharing no vertex.
bool keepsApart(const Separation& s, const Step& step, const Touched& t, double alpha,
                const std::vector<Point3>& trial, std::vector<double>& after) {
  const Soup& soup = s.soup;
  const std::vector<Point3>& P = s.P;
  std::atomic<bool> collides{false};
  parallelChunks(
      t.pairs.size(),
      [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e && !collides.load(std::memory_order_relaxed); ++i) {
          const auto [f, g] = t.pairs[i];
          if (t.shares[i]) {
            // Neighbours: the exact test at the end of the step (a face
            // turned into a segment counts as a collision).
            for (std::uint32_t h : {f, g}) {
              const Triangle& c = soup.triangles[h];
              if (t.changed[h] && collinear(trial[c[0]], trial[c[1]], trial[c[2]]) &&
                  !collinear(P[c[0]], P[c[1]], P[c[2]]))
                collides = true;
            }
            if (!collides && facesIntersect(trial, soup.triangles, f, g)) collides = true;
            continue;
          }
          if (!staysApart(s, step, t, f, g, t.before[i], alpha, after[i])) {
            collides = true;
            continue;
          }
          // The distance is a float computation: below a thousandth of
          // tau, the exact test decides.
          if (after[i] < 1e-3 * s.options.tau && facesIntersect(trial, soup.triangles, f, g))
            collides = true;
        }
      },
      256);
  return !collides;
}

}  // namespace

bool takeStep(Separation& s, const Step& step) {
  const Touched t = touchedBy(s, step);
  const double goal = s.targets.goal;
  const double before = shortfall(t, t.before, goal);
  std::vector<Point3> trial = s.P;
  std::vector<double> after(t.pairs.size(), kInf);
  bool accepted = false;
  for (double alpha = 1; alpha >= 1.0 / 1024; alpha /= 2) {
    for (int v : step.vertices) trial[v] = s.P[v] + step.by[v] * alpha;
    std::fill(after.begin(), after.end(), kInf);
    if (keepsApart(s, step, t, alpha, trial, after) && shortfall(t, after, goal) < before) {
      accepted = true;
      break;
    }
    ++s.result.step_halvings;
  }
  if (!accepted) return false;

  const double cap = s.options.max_displacement;
  for (int v : step.vertices) {
    s.P[v] = trial[v];
    if (cap > 0 && (s.P[v] - s.P0[v]).Norm() >= cap * (1 - 1e-9)) s.capped[v] = 1;
  }
  // The active pairs again: pairs of unchanged faces keep their distance,
  // the others come from the touched pairs.
  s.near.erase(std::remove_if(s.near.begin(), s.near.end(),
                              [&](const NearPair& p) { return t.changed[p.f] || t.changed[p.g]; }),
               s.near.end());
  for (std::size_t i = 0; i < t.pairs.size(); ++i)
    if (t.counts[i] && after[i] < s.targets.near)
      s.near.push_back({t.pairs[i][0], t.pairs[i][1], after[i]});
  return true;
}

}  // namespace meshmend::clearance_detail
