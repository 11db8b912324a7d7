#include "common/base/border_loops.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

namespace meshmend {

std::pair<const int*, const int*> BorderEdges::facesAt(int v) const {
  const auto it = std::lower_bound(vertices.begin(), vertices.end(), v);
  if (it == vertices.end() || *it != v) return {nullptr, nullptr};
  const std::size_t i = std::size_t(it - vertices.begin());
  return {faces.data() + start[i], faces.data() + start[i + 1]};
}

namespace {

// ---- Finding the border edges ---------------------------------------------------

// Per vertex, two sums over the corners of its faces: the index of the next
// corner less the index of the previous one, and the same of their squares
// (in 64-bit arithmetic modulo 2^64). Each edge run once each way around a
// vertex adds and takes away the same terms. What is left is the sums over
// the unpaired uses: with one or two unpaired uses in each direction the
// true values are below 2^63 in magnitude, and they are zero only if the
// indices pair up (a + b = c + d and a^2 + b^2 = c^2 + d^2 give {a, b} =
// {c, d}), so a vertex with such a use is never missed.
template <class Corners>
std::vector<std::uint64_t> cornerSums(std::size_t faceCount, std::size_t vertexCount,
                                      const Corners& corners) {
  std::vector<std::uint64_t> sums(2 * vertexCount, 0);
  std::uint64_t* s = sums.data();
  for (std::size_t f = 0; f < faceCount; ++f) {
    const Triangle t = corners(f);
    const std::uint64_t a = std::uint32_t(t[0]), b = std::uint32_t(t[1]), c = std::uint32_t(t[2]);
    s[2 * a] += b - c;
    s[2 * a + 1] += b * b - c * c;
    s[2 * b] += c - a;
    s[2 * b + 1] += c * c - a * a;
    s[2 * c] += a - b;
    s[2 * c + 1] += a * a - b * b;
  }
  return sums;
}

// Collects, in one pass over the faces, the faces at the vertices whose
// slot (slots[v], nonzero: the index in `vertices`, plus one) says so; each
// face once per vertex, grouped by vertex in `out` (vertices ascending).
// Most faces have no such corner: one test of the three slots skips them.
template <class Corners>
void gatherFaces(std::size_t faceCount, const Corners& corners, const std::vector<int>& vertices,
                 const int* slots, BorderEdges& out) {
  std::vector<std::pair<int, int>> found;  // (slot, face)
  for (std::size_t f = 0; f < faceCount; ++f) {
    const Triangle t = corners(f);
    const int s0 = slots[t[0]], s1 = slots[t[1]], s2 = slots[t[2]];
    if ((s0 | s1 | s2) == 0) continue;
    if (s0 != 0) found.push_back({s0 - 1, int(f)});
    if (s1 != 0 && t[1] != t[0]) found.push_back({s1 - 1, int(f)});
    if (s2 != 0 && t[2] != t[0] && t[2] != t[1]) found.push_back({s2 - 1, int(f)});
  }
  out.vertices = vertices;
  out.start.assign(vertices.size() + 1, 0);
  for (const auto& [slot, face] : found) ++out.start[std::size_t(slot) + 1];
  std::partial_sum(out.start.begin(), out.start.end(), out.start.begin());
  out.faces.resize(found.size());
  out.corners.resize(found.size());
  std::vector<int> next(out.start.begin(), out.start.end() - 1);
  for (const auto& [slot, face] : found) {
    const int at = next[std::size_t(slot)]++;
    out.faces[std::size_t(at)] = face;
    out.corners[std::size_t(at)] = corners(std::size_t(face));
  }
}

// The border edges leaving vertex v, from the faces at it: an edge v -> b
// of one face is a border edge when no other use of the edge {v, b} is
// among them (every use of an edge at v is in a face at v).
void bordersLeaving(int v, const int* faces, const Triangle* corners, std::size_t count,
                    std::vector<BorderEdge>& out) {
  struct Use {
    int after, before, face;
  };
  std::vector<Use> uses;
  for (std::size_t i = 0; i < count; ++i)
    for (int k = 0; k < 3; ++k)
      if (corners[i][k] == v)
        uses.push_back({corners[i][(k + 1) % 3], corners[i][(k + 2) % 3], faces[i]});
  for (const Use& u : uses) {
    if (u.after == v) continue;
    int times = 0;
    for (const Use& w : uses) times += (w.after == u.after) + (w.before == u.after);
    if (times == 1) out.push_back({v, u.after, u.face});
  }
}

template <class Corners>
BorderEdges borderEdges(std::size_t faceCount, std::size_t vertexCount, const Corners& corners) {
  BorderEdges out;
  std::vector<int> vertices, slots(vertexCount, 0);
  {
    const std::vector<std::uint64_t> sums = cornerSums(faceCount, vertexCount, corners);
    for (std::size_t v = 0; v < vertexCount; ++v)
      if ((sums[2 * v] | sums[2 * v + 1]) != 0) {
        vertices.push_back(int(v));
        slots[v] = int(vertices.size());
      }
  }
  if (vertices.empty()) return out;
  gatherFaces(faceCount, corners, vertices, slots.data(), out);
  std::vector<int> missed;  // ends of border edges whose sums cancelled (see the header)
  for (std::size_t i = 0; i < out.vertices.size(); ++i)
    bordersLeaving(out.vertices[i], out.faces.data() + out.start[i],
                   out.corners.data() + out.start[i], std::size_t(out.start[i + 1] - out.start[i]),
                   out.edges);
  for (const BorderEdge& e : out.edges)
    if (slots[std::size_t(e.to)] == 0) missed.push_back(e.to);
  while (!missed.empty()) {
    std::sort(missed.begin(), missed.end());
    missed.erase(std::unique(missed.begin(), missed.end()), missed.end());
    for (int v : missed) vertices.push_back(v);
    std::sort(vertices.begin(), vertices.end());
    for (std::size_t i = 0; i < vertices.size(); ++i) slots[std::size_t(vertices[i])] = int(i + 1);
    BorderEdges again;
    gatherFaces(faceCount, corners, vertices, slots.data(), again);
    std::vector<BorderEdge> more;
    for (int v : missed) {
      const std::size_t i =
          std::size_t(std::lower_bound(vertices.begin(), vertices.end(), v) - vertices.begin());
      bordersLeaving(v, again.faces.data() + again.start[i], again.corners.data() + again.start[i],
                     std::size_t(again.start[i + 1] - again.start[i]), more);
    }
    again.edges = std::move(out.edges);
    out = std::move(again);
    missed.clear();
    for (const BorderEdge& e : more) {
      out.edges.push_back(e);
      if (slots[std::size_t(e.to)] == 0) missed.push_back(e.to);
    }
  }
  return out;
}

// ---- Following the border edges into loops ------------------------------------------

// At vertex v, where several borders pass, decides which outgoing border
// edge follows each incoming one. The faces at v fall into fans (faces
// joined through edges at v that exactly two of them use); each fan must be
// a plain open fan, with one border edge in and one out. Seen along the
// faces' mean normal, the border arriving from u continues along the first
// fan met turning counter-clockwise from u: the gap between the two fans is
// the hole. Returns false when the fans are not plain.
bool pairAtPinch(int v, const BorderEdges& found, const std::function<Point3(int)>& point,
                 const std::vector<int>& ins, const std::vector<int>& outs,
                 std::unordered_map<int, int>& next) {
  const auto range = std::lower_bound(found.vertices.begin(), found.vertices.end(), v);
  const std::size_t slot = std::size_t(range - found.vertices.begin());
  const int first = found.start[slot], count = found.start[slot + 1] - first;
  const std::vector<BorderEdge>& edges = found.edges;
  auto corners = [&](int i) -> const Triangle& { return found.corners[std::size_t(first + i)]; };
  std::vector<int> parent(static_cast<std::size_t>(count));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::unordered_map<int, std::vector<int>> byNeighbour;
  for (int i = 0; i < count; ++i)
    for (int c : corners(i))
      if (c != v) byNeighbour[c].push_back(i);
  for (const auto& [neighbour, list] : byNeighbour)
    if (list.size() == 2) parent[root(list[0])] = root(list[1]);
  auto fanOf = [&](int face) {
    for (int i = 0; i < count; ++i)
      if (found.faces[std::size_t(first + i)] == face) return root(i);
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
  for (int i = 0; i < count; ++i) {
    const Triangle& t = corners(i);
    const Point3 a = point(t[0]);
    n += (point(t[1]) - a) ^ (point(t[2]) - a);
  }
  if (n.Norm() == 0) n = Point3(0, 0, 1);
  n.Normalize();
  Point3 u = std::abs(n[0]) < 0.9 ? Point3(1, 0, 0) ^ n : Point3(0, 1, 0) ^ n;
  u.Normalize();
  const Point3 w = n ^ u;
  const Point3 at = point(v);
  auto angle = [&](int other) {
    const Point3 d = point(other) - at;
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
std::vector<BorderLoop> simpleLoops(const BorderLoop& walk) {
  std::vector<BorderLoop> out;
  BorderLoop stack;
  std::unordered_map<int, std::size_t> at;
  for (std::size_t i = 0; i < walk.vertices.size(); ++i) {
    const int v = walk.vertices[i];
    const auto it = at.find(v);
    if (it != at.end()) {
      const std::size_t k = it->second;
      BorderLoop part;
      part.vertices.assign(stack.vertices.begin() + std::ptrdiff_t(k), stack.vertices.end());
      part.faces.assign(stack.faces.begin() + std::ptrdiff_t(k), stack.faces.end());
      out.push_back(std::move(part));
      for (std::size_t j = k + 1; j < stack.vertices.size(); ++j) at.erase(stack.vertices[j]);
      stack.vertices.resize(k + 1);
      stack.faces.resize(k + 1);
      stack.faces[k] = walk.faces[i];  // the walk goes on from v along this edge
      continue;
    }
    at[v] = stack.vertices.size();
    stack.vertices.push_back(v);
    stack.faces.push_back(walk.faces[i]);
  }
  out.push_back(std::move(stack));
  return out;
}

}  // namespace

BorderEdges findBorderEdges(const std::vector<Triangle>& triangles, std::size_t vertexCount) {
  const Triangle* t = triangles.data();
  return borderEdges(triangles.size(), vertexCount, [t](std::size_t f) { return t[f]; });
}

BorderEdges findBorderEdges(const Mesh& mesh) {
  const Vertex* base = mesh.vert.data();
  const Face* faces = mesh.face.data();
  return borderEdges(mesh.face.size(), mesh.vert.size(), [base, faces](std::size_t f) {
    const Face& face = faces[f];
    return Triangle{int(face.cV(0) - base), int(face.cV(1) - base), int(face.cV(2) - base)};
  });
}

BorderLoops findBorderLoops(const BorderEdges& found, const std::function<Point3(int)>& point) {
  BorderLoops result;
  const std::vector<BorderEdge>& edges = found.edges;
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
  std::unordered_map<int, int> pinchNext;
  std::unordered_set<int> broken;
  for (int v : special) {
    const auto out = outOf.find(v);
    const auto in = inTo.find(v);
    if (out != outOf.end() && in != inTo.end() && out->second.size() == in->second.size() &&
        pairAtPinch(v, found, point, in->second, out->second, pinchNext)) {
      result.pinched.push_back(v);
      continue;
    }
    broken.insert(v);
  }
  std::vector<int> next(edges.size(), -1), previous(edges.size(), -1);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const int to = edges[e].to;
    if (broken.count(to)) continue;
    if (const auto it = pinchNext.find(int(e)); it != pinchNext.end())
      next[e] = it->second;
    else if (!std::binary_search(result.pinched.begin(), result.pinched.end(), to))
      next[e] = outOf[to][0];
    if (next[e] >= 0) previous[std::size_t(next[e])] = int(e);
  }
  // Open borders first, from their start, so that each is followed whole.
  std::vector<int> starts;
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (previous[e] < 0) starts.push_back(int(e));
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (previous[e] >= 0) starts.push_back(int(e));
  std::vector<char> visited(edges.size(), 0);
  for (int start : starts) {
    if (visited[std::size_t(start)]) continue;
    BorderLoop loop;
    for (int e = start;;) {
      visited[std::size_t(e)] = 1;
      loop.vertices.push_back(edges[std::size_t(e)].from);
      loop.faces.push_back(edges[std::size_t(e)].face);
      const int n = next[std::size_t(e)];
      if (n == start) break;
      if (n < 0 || visited[std::size_t(n)]) {
        loop.closed = false;
        loop.vertices.push_back(edges[std::size_t(e)].to);
        loop.broken_at = edges[std::size_t(e)].to;
        break;
      }
      e = n;
    }
    if (!loop.closed) {
      result.loops.push_back(std::move(loop));
      continue;
    }
    for (BorderLoop& part : simpleLoops(loop)) result.loops.push_back(std::move(part));
  }
  return result;
}

BorderLoops findBorderLoops(const std::vector<Point3>& P, const std::vector<Triangle>& T) {
  return findBorderLoops(findBorderEdges(T, P.size()), [&P](int v) { return P[std::size_t(v)]; });
}

}  // namespace meshmend
