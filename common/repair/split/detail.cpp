// The split's small shared helpers (split/detail.h).
#include <algorithm>
#include <numeric>

#include "common/repair/split/detail.h"

namespace meshmend::split_detail {

// Sorts `pairs` (of values in [0, bound)) and removes the repeats, as
// std::sort and std::unique would. A split's curve edges are a few hundred
// to a hundred thousand pairs on as many vertices, and comparison sorting
// them took a tenth of a small split: when `bound` is not much larger than
// their number, a counting sort on the first value (each has the two or
// three curve edges of one curve vertex, ordered in place) takes linear time.
void sortUnique(std::vector<std::array<int, 2>>& pairs, std::size_t bound) {
  if (bound > 16 * pairs.size() + 4096) {  // sparse: the counts would cost more
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    return;
  }
  std::vector<int> start(bound + 1, 0);
  for (const auto& e : pairs) ++start[e[0] + 1];
  for (std::size_t v = 0; v < bound; ++v) start[v + 1] += start[v];
  std::vector<std::array<int, 2>> sorted(pairs.size());
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (const auto& e : pairs) sorted[next[e[0]]++] = e;
  }
  pairs.clear();
  for (std::size_t v = 0; v < bound; ++v) {
    const auto first = sorted.begin() + start[v], last = sorted.begin() + start[v + 1];
    for (auto i = first; i != last; ++i)  // insertion sort: a few per value
      for (auto j = i; j != first && (*j)[1] < (*(j - 1))[1]; --j) std::iter_swap(j, j - 1);
    for (auto i = first; i != last; ++i)
      if (i == first || (*i)[1] != (*(i - 1))[1]) pairs.push_back(*i);
  }
}

// Barycentric coordinates of p in triangle (a, b, c), from the rounded values.
Point3 barycentric(const Point3& p, const Point3& a, const Point3& b, const Point3& c) {
  const Point3 n = (b - a) ^ (c - a);
  const double n2 = n.SquaredNorm();
  if (!(n2 > 0)) return {1, 0, 0};
  const double wa = (((c - b) ^ (p - b)) * n) / n2, wb = (((a - c) ^ (p - c)) * n) / n2;
  return {wa, wb, 1 - wa - wb};
}

// Closed and open components of a curve graph.
void countCurves(std::size_t vertices, const std::vector<std::array<int, 2>>& edges,
                 std::size_t& loops, std::size_t& open) {
  // Components of the curve graph (union-find with path halving); one is
  // open when it has an end point (a vertex of one curve edge). Curves may
  // branch without ending (three surfaces through one point, the outline of
  // a planar overlap meeting a crossing): a component is closed when none
  // of its vertices ends a curve.
  std::vector<int> parent(vertices), degree(vertices, 0);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& e : edges) {
    ++degree[e[0]], ++degree[e[1]];
    parent[find(e[0])] = find(e[1]);
  }
  enum : std::uint8_t { kNone, kClosed, kOpen };  // per component root
  std::vector<std::uint8_t> component(vertices, kNone);
  for (std::size_t v = 0; v < vertices; ++v) {
    if (degree[v] == 0) continue;
    std::uint8_t& c = component[find(int(v))];
    if (degree[v] == 1)
      c = kOpen;
    else if (c == kNone)
      c = kClosed;
  }
  loops = std::size_t(std::count(component.begin(), component.end(), kClosed));
  open = std::size_t(std::count(component.begin(), component.end(), kOpen));
}

}  // namespace meshmend::split_detail
