#include "common/repair/holes/refine.h"

#include <algorithm>
#include <numeric>
#include <tuple>

namespace meshmend::holes {

namespace {

constexpr int kRefinePasses = 3;
constexpr int kFlipPasses = 4;

// The corner k of `t` whose edge to corner k + 1 has `key` (t has that edge).
int cornerBefore(const Triangle& t, std::uint64_t key) {
  int k = 0;
  while (edgeKey(t[k], t[(k + 1) % 3]) != key) ++k;
  return k;
}

// The patch's inner edges (local key) and the two triangles on each, in
// key order.
using EdgeSides = std::vector<std::pair<std::uint64_t, std::pair<int, int>>>;
EdgeSides innerEdgeSides(const Patch& patch) {
  // The half-edges bucketed by their lower vertex (a counting sort), each
  // bucket's few ordered by the higher one: pairs of equal ones are the
  // inner edges, found in key order.
  const std::vector<Triangle>& triangles = patch.triangles;
  std::vector<int> start(patch.size() + 1, 0);
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) ++start[std::size_t(std::min(t[k], t[(k + 1) % 3])) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::pair<int, int>> halves(std::size_t(start.back()));  // (higher vertex, triangle)
  std::vector<int> next(start.begin(), start.end() - 1);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      halves[std::size_t(next[std::size_t(std::min(a, b))]++)] = {std::max(a, b), int(t)};
    }
  EdgeSides sides;
  sides.reserve(halves.size() / 2);
  for (std::size_t v = 0; v + 1 < start.size(); ++v) {
    const auto first = halves.begin() + start[v], last = halves.begin() + start[v + 1];
    std::sort(first, last);
    for (auto it = first; it != last && it + 1 != last; ++it)
      if (it->first == (it + 1)->first) {
        sides.push_back({edgeKey(int(v), it->first), {it->second, (it + 1)->second}});
        ++it;
      }
  }
  return sides;
}

bool hasEdge(const EdgeSides& sides, std::uint64_t key) {
  const auto it =
      std::lower_bound(sides.begin(), sides.end(), key,
                       [](const auto& side, std::uint64_t k) { return side.first < k; });
  return it != sides.end() && it->first == key;
}

// Flips the patch's inner edges whose opposite angles at x add up to more
// than pi (Delaunay in space: rounder triangles, positive cotangent
// weights), where the flipped pair stays counter-clockwise in the domain
// and the new edge is not there yet. A few passes.
void flipToDelaunay(Patch& patch, const std::vector<Point3>& x,
                    const std::function<bool(int, int)>& forbidden) {
  // The sine and cosine of the angle at `apex`, both times the lengths of
  // its two sides: the angles at c and d add up to more than pi where the
  // sine of their sum is negative.
  auto angleAt = [&](int apex, int a, int b) {
    const Point3 u = x[std::size_t(a)] - x[std::size_t(apex)],
                 v = x[std::size_t(b)] - x[std::size_t(apex)];
    return std::pair<double, double>((u ^ v).Norm(), u * v);
  };
  const std::vector<Vec2>& uv = patch.uv;
  for (int pass = 0; pass < kFlipPasses; ++pass) {
    const EdgeSides sides = innerEdgeSides(patch);
    std::vector<char> touched(patch.triangles.size(), 0);
    std::size_t flips = 0;
    for (const auto& [key, side] : sides) {
      if (touched[std::size_t(side.first)] || touched[std::size_t(side.second)]) continue;
      Triangle& t1 = patch.triangles[std::size_t(side.first)];
      Triangle& t2 = patch.triangles[std::size_t(side.second)];
      const int k = cornerBefore(t1, key);
      const int a = t1[k], b = t1[(k + 1) % 3], c = t1[(k + 2) % 3];
      int j = 0;
      while (t2[j] == a || t2[j] == b) ++j;
      const int d = t2[j];
      if (c == d) continue;
      const auto [sinC, cosC] = angleAt(c, a, b);
      const auto [sinD, cosD] = angleAt(d, b, a);
      if (!(sinC * cosD + cosC * sinD < 0)) continue;
      if (hasEdge(sides, edgeKey(c, d)) || forbidden(c, d)) continue;
      // (a, b, c) + (b, a, d) -> (a, d, c) + (d, b, c).
      if (orient(uv[std::size_t(a)], uv[std::size_t(d)], uv[std::size_t(c)]) <= 0 ||
          orient(uv[std::size_t(d)], uv[std::size_t(b)], uv[std::size_t(c)]) <= 0)
        continue;
      t1 = {a, d, c};
      t2 = {d, b, c};
      touched[std::size_t(side.first)] = touched[std::size_t(side.second)] = 1;
      ++flips;
    }
    if (flips == 0) break;
  }
}

}  // namespace

std::size_t refineStretched(Patch& patch, std::vector<Point3>& x, std::vector<Point3>& flat,
                            double size, double maxStretch,
                            const std::function<bool(int, int)>& forbidden) {
  std::vector<Vec2>& uv = patch.uv;
  auto isStretched = [&](int a, int b, double& length) {
    length = (x[std::size_t(a)] - x[std::size_t(b)]).Norm();
    return length > size && length > maxStretch * norm(uv[std::size_t(a)] - uv[std::size_t(b)]);
  };
  // Most patches have no such edge: a plain scan finds that out.
  bool any = false;
  double length = 0;
  for (const Triangle& t : patch.triangles)
    for (int k = 0; k < 3 && !any; ++k) any = isStretched(t[k], t[(k + 1) % 3], length);
  if (!any) return 0;
  std::size_t splits = 0;
  for (int pass = 0; pass < kRefinePasses; ++pass) {
    struct Edge {
      double length;
      int first, second, a, b;
    };
    std::vector<Edge> stretched;
    for (const auto& [key, side] : innerEdgeSides(patch)) {
      const Triangle& t = patch.triangles[std::size_t(side.first)];
      const int k = cornerBefore(t, key);
      const int a = t[k], b = t[(k + 1) % 3];
      if (isStretched(a, b, length)) stretched.push_back({length, side.first, side.second, a, b});
    }
    if (stretched.empty()) break;
    std::sort(stretched.begin(), stretched.end(), [](const Edge& p, const Edge& q) {
      if (p.length != q.length) return p.length > q.length;
      return std::tie(p.first, p.a, p.b) < std::tie(q.first, q.a, q.b);
    });
    std::vector<char> touched(patch.triangles.size(), 0);
    for (const Edge& e : stretched) {
      if (touched[std::size_t(e.first)] || touched[std::size_t(e.second)]) continue;
      touched[std::size_t(e.first)] = touched[std::size_t(e.second)] = 1;
      const int m = int(uv.size());
      const std::size_t a = std::size_t(e.a), b = std::size_t(e.b);
      uv.push_back(0.5 * (uv[a] + uv[b]));
      patch.height.push_back((patch.height[a] + patch.height[b]) / 2);
      x.push_back((x[a] + x[b]) / 2);
      flat.push_back((flat[a] + flat[b]) / 2);
      // (from, to, apex) -> (from, m, apex) + (m, to, apex), in both triangles:
      // m lies on the edge in the domain, so both halves keep their orientation.
      for (const int t : {e.first, e.second}) {
        Triangle& tri = patch.triangles[std::size_t(t)];
        const int k = cornerBefore(tri, edgeKey(e.a, e.b));
        const int from = tri[k], to = tri[(k + 1) % 3], apex = tri[(k + 2) % 3];
        tri = {from, m, apex};
        patch.triangles.push_back({m, to, apex});
      }
      ++splits;
    }
  }
  flipToDelaunay(patch, x, forbidden);
  patch.around = TrianglesAround(patch.triangles, patch.size());
  return splits;
}

double meanShapeQuality(const Patch& patch, const std::vector<Point3>& x) {
  if (patch.triangles.empty()) return 0;
  double sum = 0;
  for (const Triangle& t : patch.triangles) {
    const Point3 &a = x[std::size_t(t[0])], &b = x[std::size_t(t[1])], &c = x[std::size_t(t[2])];
    const double squares = (b - a).SquaredNorm() + (c - b).SquaredNorm() + (a - c).SquaredNorm();
    if (squares > 0) sum += 2 * std::sqrt(3.0) * ((b - a) ^ (c - a)).Norm() / squares;
  }
  return sum / double(patch.triangles.size());
}

}  // namespace meshmend::holes
