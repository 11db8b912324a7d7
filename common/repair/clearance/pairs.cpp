// The layers as one soup and the search for close face pairs: box trees
// over the faces grown by half the radius, a plane and edge-side test that
// discards neighbours on a smooth sheet before any distance is computed.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/base/errors.h"
#include "common/base/parallel.h"
#include "common/repair/clearance/detail.h"

namespace meshmend::clearance_detail {

namespace {

// Squared Euclidean gap between two boxes (0 when they overlap).
double gap2(const Box& x, const Box& y) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double g = std::max({0.0, double(y.lo[k]) - x.hi[k], double(x.lo[k]) - y.hi[k]});
    s += g * g;
  }
  return s;
}

}  // namespace

Soup::Soup(const std::vector<const Mesh*>& layers, ClearanceScope s, int exclusionRings,
           const std::vector<Placement>& placements)
    : scope(s), rings(exclusionRings) {
  for (std::size_t l = 0; l < layers.size(); ++l) {
    vertexOffset.push_back(int(points.size()));
    faceOffset.push_back(int(triangles.size()));
    const int offset = int(points.size());
    const bool placed = !placements.empty() && !isIdentity(placements[l]);
    for (const Point3& p : positionsOf(*layers[l]))
      points.push_back(placed ? Point3(placements[l] * p) : p);
    for (Triangle t : trianglesOf(*layers[l])) {
      for (int& v : t) v += offset;
      triangles.push_back(t);
      faceLayer.push_back(int(l));
    }
  }
  vertexOffset.push_back(int(points.size()));
  faceOffset.push_back(int(triangles.size()));
  Point3 lo = points.empty() ? Point3(0, 0, 0) : points[0], hi = lo;
  for (const Point3& p : points)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  diagonal = (hi - lo).Norm();
  // Faces around each vertex (a counting sort).
  starStart.assign(points.size() + 1, 0);
  for (const Triangle& t : triangles)
    for (int v : t) ++starStart[v + 1];
  std::partial_sum(starStart.begin(), starStart.end(), starStart.begin());
  star.resize(starStart.back());
  std::vector<int> fill(starStart.begin(), starStart.end() - 1);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int v : triangles[f]) star[fill[v]++] = int(f);
  if (rings == 2) {
    ringStart.assign(points.size() + 1, 0);
    for (std::size_t v = 0; v < points.size(); ++v) {
      std::vector<int> n;
      for (int i = starStart[v]; i < starStart[v + 1]; ++i)
        for (int u : triangles[star[i]])
          if (u != int(v)) n.push_back(u);
      std::sort(n.begin(), n.end());
      n.erase(std::unique(n.begin(), n.end()), n.end());
      ring.insert(ring.end(), n.begin(), n.end());
      ringStart[v + 1] = int(ring.size());
    }
  }
}

Box inflated(Box b, double by) {
  for (int k = 0; k < 3; ++k) {
    float lo = float(double(b.lo[k]) - by), hi = float(double(b.hi[k]) + by);
    b.lo[k] = std::nextafter(lo, -std::numeric_limits<float>::infinity());
    b.hi[k] = std::nextafter(hi, std::numeric_limits<float>::infinity());
  }
  return b;
}

// Every pair in scope closer than `radius` (boxes grown by radius / 2, so
// that a pair at distance < radius always has overlapping boxes): one tree
// per layer for pairs within layers, the smaller layer's tree queried by the
// larger one's faces for pairs between layers, one tree of all faces for both.
std::vector<NearPair> pairsWithin(const Soup& soup, const std::vector<Point3>& P, double radius,
                                  std::size_t* candidates) {
  const std::size_t nf = soup.faces();
  std::vector<Box> boxes(nf), grown(nf);
  // Unit normal and offset of each face's plane: a face whose corners all
  // lie `radius` or more to one side of the other's plane is that far away.
  std::vector<Point3> normal(nf);
  std::vector<double> offset(nf);
  // And the outward normals of its edges in its plane: neighbours on a
  // smooth sheet are not beside each other's planes but beside an edge.
  std::vector<std::array<Point3, 3>> side(nf);
  parallelChunks(nf, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t f = b; f < e; ++f) {
      const Triangle& t = soup.triangles[f];
      boxes[f] = boxOf(P[t[0]], P[t[1]], P[t[2]]);
      grown[f] = inflated(boxes[f], radius / 2);
      Point3 n = (P[t[1]] - P[t[0]]) ^ (P[t[2]] - P[t[0]]);
      const double len = n.Norm();
      n = len > 0 ? n / len : Point3(0, 0, 0);
      normal[f] = n;
      offset[f] = n * P[t[0]];
      for (int i = 0; i < 3; ++i) {
        Point3 a = (P[t[(i + 1) % 3]] - P[t[i]]) ^ n;  // outward for a counter-clockwise face
        const double l = a.Norm();
        side[f][i] = l > 0 ? a / l : Point3(0, 0, 0);
      }
    }
  });
  // Rounding in the plane test is far below `radius`; a margin of a
  // millionth keeps it conservative.
  const double planeRadius = radius * (1 + 1e-6);
  auto beside = [&](std::uint32_t f, std::uint32_t g) {
    if (normal[f] == Point3(0, 0, 0)) return false;
    double lo = kInf, hi = -kInf;
    for (int v : soup.triangles[g]) {
      const double s = normal[f] * P[v] - offset[f];
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    if (lo >= planeRadius || hi <= -planeRadius) return true;
    for (int i = 0; i < 3; ++i) {
      const Point3& a = side[f][i];
      const double from = a * P[soup.triangles[f][i]];
      double nearest = kInf;
      for (int v : soup.triangles[g]) nearest = std::min(nearest, a * P[v] - from);
      if (nearest >= planeRadius) return true;
    }
    return false;
  };
  struct alignas(64) Found {
    std::vector<NearPair> pairs;
    std::size_t candidates = 0;
  };
  std::vector<Found> found(workerCount());
  const double r2 = radius * radius;
  auto visit = [&](std::uint32_t f, std::uint32_t g, unsigned w) {
    if (g < f) std::swap(f, g);
    if (!soup.clearancePair(f, g) || gap2(boxes[f], boxes[g]) >= r2) return;
    if (beside(f, g) || beside(g, f)) return;
    ++found[w].candidates;
    const double d = soup.distance(P, f, g);
    if (d < radius) found[w].pairs.push_back({f, g, d});
  };
  // Trees answer one self-join or one pass of queries: Morton order builds
  // three times faster than median splits.
  auto treeOf = [&](int first, int last) {
    return BoxTree(std::vector<Box>(grown.begin() + first, grown.begin() + last),
                   BoxTree::Layout::kMorton);
  };
  const int nl = soup.layers();
  if (soup.scope == ClearanceScope::kBoth || nl == 1) {
    if (soup.scope != ClearanceScope::kBetweenLayers) treeOf(0, int(nf)).selfPairs(visit);
  } else if (soup.scope == ClearanceScope::kWithinLayers) {
    for (int l = 0; l < nl; ++l) {
      const std::uint32_t first = std::uint32_t(soup.faceOffset[l]);
      treeOf(soup.faceOffset[l], soup.faceOffset[l + 1])
          .selfPairs([&](std::uint32_t f, std::uint32_t g, unsigned w) {
            visit(first + f, first + g, w);
          });
    }
  } else {
    for (int a = 0; a < nl; ++a)
      for (int b = a + 1; b < nl; ++b) {
        const int sizeA = soup.faceOffset[a + 1] - soup.faceOffset[a];
        const int sizeB = soup.faceOffset[b + 1] - soup.faceOffset[b];
        const int small = sizeA <= sizeB ? a : b, large = sizeA <= sizeB ? b : a;
        const BoxTree tree = treeOf(soup.faceOffset[small], soup.faceOffset[small + 1]);
        const std::uint32_t firstSmall = std::uint32_t(soup.faceOffset[small]);
        const int firstLarge = soup.faceOffset[large];
        parallelChunks(
            std::size_t(soup.faceOffset[large + 1] - firstLarge),
            [&](std::size_t begin, std::size_t end, unsigned worker) {
              for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t g = std::uint32_t(firstLarge + i);
                if (!overlap(grown[g], tree.bounds())) continue;
                tree.query(grown[g], worker,
                           [&](std::uint32_t f, unsigned w) { visit(firstSmall + f, g, w); });
              }
            },
            1024);
      }
  }
  std::vector<NearPair> all;
  std::size_t count = 0;
  for (const Found& x : found) {
    all.insert(all.end(), x.pairs.begin(), x.pairs.end());
    count += x.candidates;
  }
  if (candidates) *candidates += count;
  // Deterministic order whatever the threads did.
  std::sort(all.begin(), all.end(), [](const NearPair& x, const NearPair& y) {
    return x.f != y.f ? x.f < y.f : x.g < y.g;
  });
  return all;
}

bool anyPairInScope(const Soup& soup) {
  if (includesBetween(soup.scope) && soup.layers() > 1) return true;
  return includesWithin(soup.scope) && soup.faces() > 1;
}

std::vector<NearPair> pairsFromRadius(const Soup& soup, const std::vector<Point3>& P, double start,
                                      double* used, std::size_t* candidates) {
  double radius = start;
  while (true) {
    std::vector<NearPair> pairs = pairsWithin(soup, P, radius, candidates);
    // (A diagonal beyond double's range is infinite: the radius stops once
    // it is too.)
    if (!pairs.empty() || radius > 2 * soup.diagonal || std::isinf(radius) ||
        !anyPairInScope(soup)) {
      *used = radius;
      return pairs;
    }
    radius *= 4;
  }
}

std::vector<ClearancePair> listShortest(const Soup& soup, const std::vector<Point3>& P,
                                        std::vector<NearPair> pairs, double below,
                                        std::size_t count) {
  pairs.erase(
      std::remove_if(pairs.begin(), pairs.end(), [&](const NearPair& p) { return !(p.d < below); }),
      pairs.end());
  auto closer = [](const NearPair& x, const NearPair& y) {
    return x.d != y.d ? x.d < y.d : (x.f != y.f ? x.f < y.f : x.g < y.g);
  };
  const std::size_t n = std::min(count, pairs.size());
  std::partial_sort(pairs.begin(), pairs.begin() + n, pairs.end(), closer);
  std::vector<ClearancePair> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(soup.describe(P, pairs[i].f, pairs[i].g));
  return out;
}

bool isIdentity(const Placement& m) {
  return m == Placement::Identity();
}

void checkCommon(const std::vector<const Mesh*>& layers, int rings,
                 const std::vector<Placement>& placements) {
  if (layers.empty()) throw InvalidInputError("no layer given");
  for (std::size_t l = 0; l < layers.size(); ++l)
    requireFacesAndFiniteCoordinates(*layers[l], "layer " + std::to_string(l));
  if (rings != 1 && rings != 2)
    throw InvalidInputError("exclusion_rings must be 1 or 2, not " + std::to_string(rings));
  if (!placements.empty() && placements.size() != layers.size())
    throw InvalidInputError("placements must hold one matrix per layer (" +
                            std::to_string(layers.size()) + "), not " +
                            std::to_string(placements.size()));
  for (std::size_t l = 0; l < placements.size(); ++l) {
    const Placement& m = placements[l];
    bool finite = true;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) finite &= std::isfinite(m.ElementAt(i, j));
    const bool affine = m.ElementAt(3, 0) == 0 && m.ElementAt(3, 1) == 0 &&
                        m.ElementAt(3, 2) == 0 && m.ElementAt(3, 3) == 1;
    const double det = finite ? m.Determinant() : 0;
    if (!finite || !affine || !(std::fabs(det) > 0) || !std::isfinite(det))
      throw InvalidInputError("the placement of layer " + std::to_string(l) +
                              " is not an invertible affine matrix (finite, last row 0 0 0 1)");
  }
}

}  // namespace meshmend::clearance_detail
