#include "common/border_loops.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace meshmend {

namespace {

struct DirectedBorderEdge {
  int from, to, face;
};

// Border edges in their faces' direction, from the sorted edge uses.
std::vector<DirectedBorderEdge> directedBorderEdges(const std::vector<Triangle>& T) {
  const std::vector<EdgeUse> uses = edgeUses(T);
  std::vector<DirectedBorderEdge> out;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    if (j - i == 1) {
      const Triangle& t = T[uses[i].face];
      out.push_back({t[uses[i].corner], t[(uses[i].corner + 1) % 3], uses[i].face});
    }
    i = j;
  }
  return out;
}

// At vertex v, where several borders pass, decides which outgoing border
// edge follows each incoming one. The faces at v fall into fans (faces
// joined through edges at v that exactly two of them use); each fan must be
// a plain open fan, with one border edge in and one out. Seen along the
// faces' mean normal, the border arriving from u continues along the first
// fan met turning counter-clockwise from u: the gap between the two fans is
// the hole. Returns false when the fans are not plain.
bool pairAtPinch(int v, const std::vector<Point3>& P, const std::vector<Triangle>& T,
                 const std::vector<int>& faces, const std::vector<int>& ins,
                 const std::vector<int>& outs, const std::vector<DirectedBorderEdge>& edges,
                 std::unordered_map<int, int>& next) {
  std::vector<int> parent(faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::unordered_map<int, std::vector<int>> byNeighbour;
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (int c : T[faces[i]])
      if (c != v) byNeighbour[c].push_back(int(i));
  for (const auto& [neighbour, list] : byNeighbour)
    if (list.size() == 2) parent[root(list[0])] = root(list[1]);
  auto fanOf = [&](int face) {
    for (std::size_t i = 0; i < faces.size(); ++i)
      if (faces[i] == face) return root(int(i));
    return -1;
  };
  std::unordered_map<int, int> fanIn, fanOut;  // fan -> its border edge in / out
  for (int e : ins) {
    const int fan = fanOf(edges[e].face);
    if (fan < 0 || !fanIn.emplace(fan, e).second) return false;
  }
  for (int e : outs) {
    const int fan = fanOf(edges[e].face);
    if (fan < 0 || !fanOut.emplace(fan, e).second) return false;
  }
  if (fanIn.size() != fanOut.size()) return false;
  for (const auto& [fan, e] : fanIn)
    if (!fanOut.count(fan)) return false;
  Point3 n(0, 0, 0);
  for (int f : faces) {
    const Triangle& t = T[f];
    n += (P[t[1]] - P[t[0]]) ^ (P[t[2]] - P[t[0]]);
  }
  if (n.Norm() == 0) n = Point3(0, 0, 1);
  n.Normalize();
  Point3 u = std::abs(n[0]) < 0.9 ? Point3(1, 0, 0) ^ n : Point3(0, 1, 0) ^ n;
  u.Normalize();
  const Point3 w = n ^ u;
  auto angle = [&](int other) {
    const Point3 d = P[other] - P[v];
    return std::atan2(d * w, d * u);
  };
  for (const auto& [fan, in] : fanIn) {
    const double from = angle(edges[in].from);
    int best = -1;
    double bestTurn = INFINITY;
    for (const auto& [otherFan, out] : fanOut) {
      if (otherFan == fan) continue;
      double turn = angle(edges[out].to) - from;
      while (turn <= 0) turn += 2 * M_PI;
      if (turn < bestTurn) bestTurn = turn, best = out;
    }
    next[in] = best;
  }
  return true;
}

// A closed walk that passes a vertex twice is cut there into simple loops.
std::vector<std::vector<int>> simpleLoops(const std::vector<int>& walk) {
  std::vector<std::vector<int>> out;
  std::vector<int> stack;
  std::unordered_map<int, std::size_t> at;
  for (int v : walk) {
    const auto it = at.find(v);
    if (it != at.end()) {
      const std::size_t k = it->second;
      out.emplace_back(stack.begin() + std::ptrdiff_t(k), stack.end());
      for (std::size_t j = k + 1; j < stack.size(); ++j) at.erase(stack[j]);
      stack.resize(k + 1);
      continue;
    }
    at[v] = stack.size();
    stack.push_back(v);
  }
  out.push_back(stack);
  return out;
}

}  // namespace

BorderLoops findBorderLoops(const std::vector<Point3>& P, const std::vector<Triangle>& T) {
  BorderLoops result;
  const std::vector<DirectedBorderEdge> edges = directedBorderEdges(T);
  if (edges.empty()) return result;
  // Border edges out of and into each vertex, for the vertices on a border.
  std::unordered_map<int, std::vector<int>> outOf, inTo;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    outOf[edges[e].from].push_back(int(e));
    inTo[edges[e].to].push_back(int(e));
  }
  std::vector<int> special;  // not one border edge in and one out
  for (const auto& [v, outs] : outOf) {
    const auto in = inTo.find(v);
    if (outs.size() != 1 || in == inTo.end() || in->second.size() != 1) special.push_back(v);
  }
  for (const auto& [v, ins] : inTo)
    if (!outOf.count(v)) special.push_back(v);
  std::sort(special.begin(), special.end());
  // Faces at the special vertices (one pass over the faces).
  std::unordered_map<int, std::vector<int>> facesAt;
  for (int v : special) facesAt[v];
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int c : T[f]) {
      const auto it = facesAt.find(c);
      if (it != facesAt.end()) it->second.push_back(int(f));
    }
  std::unordered_map<int, int> pinchNext;
  std::unordered_map<int, char> broken;  // vertex -> 1
  for (int v : special) {
    const auto out = outOf.find(v);
    const auto in = inTo.find(v);
    if (out != outOf.end() && in != inTo.end() && out->second.size() == in->second.size() &&
        pairAtPinch(v, P, T, facesAt[v], in->second, out->second, edges, pinchNext)) {
      result.pinched.push_back(v);
      continue;
    }
    broken[v] = 1;
  }
  std::vector<int> next(edges.size(), -1), previous(edges.size(), -1);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const int to = edges[e].to;
    if (broken.count(to)) continue;
    if (const auto it = pinchNext.find(int(e)); it != pinchNext.end())
      next[e] = it->second;
    else if (!std::binary_search(result.pinched.begin(), result.pinched.end(), to))
      next[e] = outOf[to][0];
    if (next[e] >= 0) previous[next[e]] = int(e);
  }
  // Open borders first, from their start, so that each is followed whole.
  std::vector<int> starts;
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (previous[e] < 0) starts.push_back(int(e));
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (previous[e] >= 0) starts.push_back(int(e));
  std::vector<char> visited(edges.size(), 0);
  for (int start : starts) {
    if (visited[start]) continue;
    BorderLoop loop;
    for (int e = start;;) {
      visited[e] = 1;
      loop.vertices.push_back(edges[e].from);
      const int n = next[e];
      if (n == start) break;
      if (n < 0 || visited[n]) {
        loop.closed = false;
        loop.vertices.push_back(edges[e].to);
        loop.broken_at = edges[e].to;
        break;
      }
      e = n;
    }
    if (!loop.closed) {
      result.loops.push_back(std::move(loop));
      continue;
    }
    for (std::vector<int>& part : simpleLoops(loop.vertices)) {
      BorderLoop simple;
      simple.vertices = std::move(part);
      result.loops.push_back(std::move(simple));
    }
  }
  return result;
}

}  // namespace meshmend
