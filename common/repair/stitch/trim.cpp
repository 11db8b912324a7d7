// Trimming along a closed loop of vertices: the loop from a selection or
// a list, the faces on each side by a flood fill that does not cross it,
// and the chosen side removed (Widing & Ekeberg 2015, §2.1).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <future>
#include <memory>
#include <numeric>
#include <queue>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "common/base/border_loops.h"
#include "common/base/errors.h"
#include "common/exact/box_tree.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"
#include "common/repair/stitch/detail.h"

namespace meshmend {

using namespace stitch_detail;

namespace {

// Vertex adjacency (each undirected edge once per end), sorted per vertex.
struct Adjacency {
  std::vector<int> start, next;
  const int* begin(int v) const { return next.data() + start[v]; }
  const int* end(int v) const { return next.data() + start[v + 1]; }
  int degree(int v) const { return start[v + 1] - start[v]; }
  bool joined(int a, int b) const { return std::binary_search(begin(a), end(a), b); }
};

Adjacency adjacencyOf(const std::vector<EdgeUse>& uses, int vertexCount) {
  Adjacency adj;
  adj.start.assign(std::size_t(vertexCount) + 1, 0);
  for (std::size_t i = 0; i < uses.size(); ++i)
    if (i == 0 || uses[i].u != uses[i - 1].u || uses[i].v != uses[i - 1].v) {
      ++adj.start[uses[i].u + 1];
      ++adj.start[uses[i].v + 1];
    }
  for (int v = 0; v < vertexCount; ++v) adj.start[v + 1] += adj.start[v];
  adj.next.resize(adj.start.back());
  std::vector<int> fill(adj.start.begin(), adj.start.end() - 1);
  for (std::size_t i = 0; i < uses.size(); ++i)
    if (i == 0 || uses[i].u != uses[i - 1].u || uses[i].v != uses[i - 1].v) {
      adj.next[fill[uses[i].u]++] = uses[i].v;
      adj.next[fill[uses[i].v]++] = uses[i].u;
    }
  for (int v = 0; v < vertexCount; ++v)
    std::sort(adj.next.begin() + adj.start[v], adj.next.begin() + adj.start[v + 1]);
  return adj;
}

// The loop through selected vertices. A sharp turn of the path makes a
// triangle of three selected vertices; its third edge (the short cut) is
// dropped when the middle vertex has no other selected neighbour, so that
// such a turn is not mistaken for a branch.
std::vector<int> loopFromSelection(const Mesh& mesh, const Adjacency& adj,
                                   const std::vector<bool>& selected) {
  const int n = int(mesh.vert.size());
  if (selected.size() != std::size_t(n))
    throw InvalidInputError("selected_vertices has " + std::to_string(selected.size()) +
                            " flags for " + std::to_string(n) + " vertices");
  std::vector<int> chosen;
  for (int v = 0; v < n; ++v)
    if (selected[v]) chosen.push_back(v);
  if (chosen.empty()) throw InvalidInputError("no vertex is selected: select a closed loop");
  std::unordered_map<int, std::vector<int>> nb;
  for (int v : chosen) {
    std::vector<int>& list = nb[v];
    for (const int* w = adj.begin(v); w != adj.end(v); ++w)
      if (selected[*w]) list.push_back(*w);
  }
  auto drop = [&](int a, int b) {
    std::vector<int>& la = nb[a];
    la.erase(std::find(la.begin(), la.end(), b));
    std::vector<int>& lb = nb[b];
    lb.erase(std::find(lb.begin(), lb.end(), a));
  };
  for (bool changed = true; changed;) {
    changed = false;
    for (int v : chosen) {
      const std::vector<int>& lv = nb[v];
      if (lv.size() != 2) continue;
      const int a = lv[0], b = lv[1];
      if (nb[a].size() > 2 && nb[b].size() > 2 &&
          std::find(nb[a].begin(), nb[a].end(), b) != nb[a].end()) {
        drop(a, b);
        changed = true;
      }
    }
  }
  for (int v : chosen) {
    const std::size_t d = nb[v].size();
    if (d == 0)
      throw InvalidInputError("the selection is not a closed loop: " + describeVertex(mesh, v) +
                              " is selected but no selected vertex shares an edge with it");
    if (d == 1)
      throw InvalidInputError("the selection is not a closed loop: the path ends at " +
                              describeVertex(mesh, v) +
                              " (one selected neighbour along edges); select the vertices that "
                              "close it");
    if (d > 2)
      throw InvalidInputError("the selection is not a single loop: " + describeVertex(mesh, v) +
                              " has " + std::to_string(d) +
                              " selected neighbours along edges (the path branches there)");
  }
  std::vector<int> loop{chosen.front()};
  int prev = -1, cur = chosen.front();
  while (true) {
    const std::vector<int>& l = nb[cur];
    const int next = l[0] != prev ? l[0] : l[1];
    if (next == chosen.front()) break;
    loop.push_back(next);
    prev = cur;
    cur = next;
  }
  if (loop.size() != chosen.size()) {
    std::unordered_set<int> on(loop.begin(), loop.end());
    for (int v : chosen)
      if (!on.count(v))
        throw InvalidInputError(
            "the selection forms more than one loop: " + describeVertex(mesh, v) +
            " is not on the loop through " + describeVertex(mesh, loop.front()));
  }
  if (loop.size() < 3) throw InvalidInputError("the selected loop has fewer than three vertices");
  return loop;
}

// Picked vertices joined by shortest edge paths; each leg avoids the
// vertices of the loop so far and the other picks, so the loop is simple.
std::vector<int> loopFromPicks(const Mesh& mesh, const Adjacency& adj,
                               const std::vector<int>& picks) {
  const int n = int(mesh.vert.size());
  for (int v : picks) requireVertex(mesh, v, "picked_vertices");
  if (picks.size() < 3)
    throw InvalidInputError("pick at least three vertices: two picks do not define a loop");
  std::vector<char> used(n, 0);
  for (int v : picks) {
    if (used[v]) throw InvalidInputError(describeVertex(mesh, v) + " is picked twice");
    used[v] = 1;
  }
  std::vector<double> dist(n, INFINITY);
  std::vector<int> from(n, -1);
  std::vector<int> touched;
  std::vector<int> loop;
  for (std::size_t k = 0; k < picks.size(); ++k) {
    const int s = picks[k], t = picks[(k + 1) % picks.size()];
    for (int v : touched) dist[v] = INFINITY, from[v] = -1;
    touched.clear();
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    dist[s] = 0;
    touched.push_back(s);
    queue.push({0, s});
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > dist[v]) continue;
      if (v == t) break;
      for (const int* w = adj.begin(v); w != adj.end(v); ++w) {
        if (used[*w] && *w != t) continue;
        const double nd = d + (mesh.vert[*w].cP() - mesh.vert[v].cP()).Norm();
        if (nd < dist[*w]) {
          if (std::isinf(dist[*w])) touched.push_back(*w);
          dist[*w] = nd;
          from[*w] = v;
          queue.push({nd, *w});
        }
      }
    }
    if (std::isinf(dist[t]))
      throw InvalidInputError("no edge path from picked " + describeVertex(mesh, s) + " to " +
                              describeVertex(mesh, t) +
                              " avoids the rest of the loop: pick vertices on one connected "
                              "part, or more of them");
    std::vector<int> leg;
    for (int v = from[t]; v != s; v = from[v]) leg.push_back(v);
    loop.push_back(s);
    for (auto it = leg.rbegin(); it != leg.rend(); ++it) {
      loop.push_back(*it);
      used[*it] = 1;
    }
  }
  return loop;
}

// The loop to trim along, from the options: a list of vertices, a
// selection (which gives no direction: `directed` false) or picked vertices.
std::vector<int> loopOf(const Mesh& mesh, const Adjacency& adj, const TrimOptions& options,
                        bool& directed) {
  directed = true;
  if (!options.selected_vertices.empty() && options.loop.empty()) {
    directed = false;
    return loopFromSelection(mesh, adj, options.selected_vertices);
  }
  if (options.loop.empty() && !options.picked_vertices.empty())
    return loopFromPicks(mesh, adj, options.picked_vertices);
  if (options.loop.empty())
    throw InvalidInputError("no trim loop given: select a closed loop of vertices, or give it");
  std::vector<int> loop = options.loop;
  if (loop.size() > 1 && loop.front() == loop.back()) loop.pop_back();
  for (int v : loop) requireVertex(mesh, v, "the loop");
  if (loop.size() < 3) throw InvalidInputError("the loop needs at least three vertices");
  std::vector<char> seen(mesh.vert.size(), 0);
  for (int v : loop) {
    if (seen[v])
      throw InvalidInputError("the loop passes " + describeVertex(mesh, v) +
                              " twice: a trim loop must be simple");
    seen[v] = 1;
  }
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const int a = loop[k], b = loop[(k + 1) % loop.size()];
    if (!adj.joined(a, b))
      throw InvalidInputError("the loop is broken between " + describeVertex(mesh, a) + " and " +
                              describeVertex(mesh, b) + ": they share no edge");
  }
  return loop;
}

// A face on a loop edge: whether it runs the edge in the loop's direction.
struct LoopUse {
  int face;
  bool along;
  int a, b;  // the loop edge, in the loop's direction
};

// The faces joined across every edge that is not on the loop (union-find),
// and the faces on loop edges.
struct LoopComponents {
  std::vector<int> parent;
  std::vector<LoopUse> uses;
  int root(int f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  }
};

LoopComponents componentsAcross(const std::vector<Triangle>& T, const std::vector<EdgeUse>& uses,
                                const std::vector<int>& loop) {
  std::unordered_map<std::uint64_t, std::pair<int, int>> loopEdges;  // undirected -> directed
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const int a = loop[k], b = loop[(k + 1) % loop.size()];
    loopEdges[undirectedKey(a, b)] = {a, b};
  }
  LoopComponents c;
  c.parent.resize(T.size());
  std::iota(c.parent.begin(), c.parent.end(), 0);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    const auto it = loopEdges.find(undirectedKey(uses[i].u, uses[i].v));
    if (it == loopEdges.end()) {
      for (std::size_t k = i + 1; k < j; ++k) c.parent[c.root(uses[k].face)] = c.root(uses[i].face);
    } else {
      for (std::size_t k = i; k < j; ++k)
        c.uses.push_back({uses[k].face, T[uses[k].face][uses[k].corner] == it->second.first,
                          it->second.first, it->second.second});
    }
    i = j;
  }
  return c;
}

TopologyError notSeparating(const Mesh& mesh, int a, int b) {
  return TopologyError(
      "the loop does not separate the mesh: the faces on both sides of its edge from " +
      describeVertex(mesh, a) + " to " + describeVertex(mesh, b) +
      " are connected without crossing the loop (e.g. a loop around a handle or across a strip)");
}

// The same component on both sides of one loop edge: nothing separates.
void requireSeparating(const Mesh& mesh, LoopComponents& c) {
  std::unordered_map<std::uint64_t, std::pair<int, int>> sides;  // edge -> (along, against) root
  for (const LoopUse& u : c.uses) {
    auto& s = sides.try_emplace(undirectedKey(u.a, u.b), -1, -1).first->second;
    (u.along ? s.first : s.second) = c.root(u.face);
    if (s.first >= 0 && s.first == s.second) throw notSeparating(mesh, u.a, u.b);
  }
}

// Per component root: 1 keep, 2 remove (0 unknown). By the loop's
// direction: the faces running a loop edge its way are kept.
std::vector<char> sidesByDirection(const Mesh& mesh, LoopComponents& c, std::size_t faces) {
  std::vector<char> side(faces, 0);
  for (const LoopUse& u : c.uses) {
    const int r = c.root(u.face);
    const char want = u.along ? 1 : 2;
    if (side[r] != 0 && side[r] != want)
      throw TopologyError(
          "the side to keep cannot be decided by the loop's direction near " +
          describeVertex(mesh, u.a) +
          ": the faces along the loop are inconsistently oriented, or the loop does not "
          "separate the mesh; select a face on the side to keep");
    side[r] = want;
  }
  return side;
}

// The same from a face on the side to keep: the components two-coloured,
// the sides differing across every loop edge.
std::vector<char> sidesFromKeptFace(const Mesh& mesh, LoopComponents& c, std::size_t faces,
                                    int keepFace) {
  std::vector<char> side(faces, 0);
  std::unordered_map<int, std::vector<int>> across;  // root -> roots across a loop edge
  std::unordered_map<std::uint64_t, std::vector<std::pair<int, bool>>> byEdge;
  for (const LoopUse& u : c.uses)
    byEdge[undirectedKey(u.a, u.b)].push_back({c.root(u.face), u.along});
  for (const auto& [key, list] : byEdge)
    for (const auto& x : list)
      for (const auto& y : list)
        if (x.second != y.second) across[x.first].push_back(y.first);
  const int keepRoot = c.root(keepFace);
  if (!across.count(keepRoot) && std::none_of(c.uses.begin(), c.uses.end(),
                                              [&](auto& u) { return c.root(u.face) == keepRoot; }))
    throw InvalidInputError("face " + std::to_string(keepFace) +
                            " is not next to the loop on either side (it lies on a part of the "
                            "mesh the loop does not touch)");
  side[keepRoot] = 1;
  std::vector<int> stack{keepRoot};
  while (!stack.empty()) {
    const int r = stack.back();
    stack.pop_back();
    for (int other : across[r]) {
      const char want = side[r] == 1 ? 2 : 1;
      if (side[other] == 0) {
        side[other] = want;
        stack.push_back(other);
      } else if (side[other] != want) {
        for (const LoopUse& u : c.uses)
          if (c.root(u.face) == other) throw notSeparating(mesh, u.a, u.b);
      }
    }
  }
  // Components on the loop that no loop edge ties to the kept side (a loop
  // edge on a border has one face): the loop's direction relative to the
  // kept side decides.
  int keepAlong = 0;
  for (const LoopUse& u : c.uses)
    if (side[c.root(u.face)] != 0) keepAlong += (side[c.root(u.face)] == 1) == u.along ? 1 : -1;
  for (const LoopUse& u : c.uses) {
    const int r = c.root(u.face);
    if (side[r] == 0) side[r] = (u.along == (keepAlong >= 0)) ? 1 : 2;
  }
  return side;
}

// The faces of `remove`d or kept side as a mesh, with provenance; `index`
// maps the mesh's vertices to the part's (-1: not in it).
struct Part {
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  std::vector<VertexOrigin> vertexOrigin;
  std::vector<FaceOrigin> faceOrigin;
};

Part partOf(Mesh& mesh, const std::vector<char>& removeFace, bool removed, bool removeUnreferenced,
            std::vector<int>& index) {
  const std::vector<Point3> P = positionsOf(mesh);
  const std::vector<Triangle> T = trianglesOf(mesh);
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);
  const std::size_t n = P.size();
  std::vector<char> used(n, 0), usedAtAll(n, 0);
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int v : T[f]) {
      usedAtAll[v] = 1;
      if (bool(removeFace[f]) == removed) used[v] = 1;
    }
  Part part;
  index.assign(n, -1);
  for (std::size_t v = 0; v < n; ++v) {
    const bool keep = removed ? used[v] : (used[v] || !usedAtAll[v] || !removeUnreferenced);
    if (!keep) continue;
    index[v] = int(part.points.size());
    part.points.push_back(P[v]);
    part.vertexOrigin.push_back(vo[v]);
  }
  for (std::size_t f = 0; f < T.size(); ++f)
    if (bool(removeFace[f]) == removed) {
      part.triangles.push_back({index[T[f][0]], index[T[f][1]], index[T[f][2]]});
      part.faceOrigin.push_back(fo[f]);
    }
  return part;
}

}  // namespace

TrimResult trimAlongLoop(Mesh& mesh, const TrimOptions& options) {
  const auto start = Clock::now();
  TrimResult result;
  requireFacesAndFiniteCoordinates(mesh, "the mesh");
  requireCompact(mesh);
  reportProgress(options.progress, 0, "Finding the loop");
  const std::vector<Triangle> T = trianglesOf(mesh);
  const std::vector<EdgeUse> uses = edgeUses(T);
  const Adjacency adj = adjacencyOf(uses, int(mesh.vert.size()));
  bool directed = true;
  result.loop = loopOf(mesh, adj, options, directed);
  if (options.keep_face >= int(T.size()))
    throw InvalidInputError("keep_face " + std::to_string(options.keep_face) +
                            " is out of range (the mesh has " + std::to_string(T.size()) +
                            " faces)");
  if (options.keep_face < 0 && !directed)
    throw InvalidInputError(
        "a loop recovered from a selection has no direction: select a face on the side to keep");

  reportProgress(options.progress, 30, "Classifying faces");
  LoopComponents components = componentsAcross(T, uses, result.loop);
  requireSeparating(mesh, components);
  const std::vector<char> side =
      options.keep_face < 0 ? sidesByDirection(mesh, components, T.size())
                            : sidesFromKeptFace(mesh, components, T.size(), options.keep_face);

  // Split the faces; provenance follows every element.
  reportProgress(options.progress, 70, "Writing");
  std::vector<char> onLoop(mesh.vert.size(), 0), removeFace(T.size(), 0);
  for (int v : result.loop) onLoop[v] = 1;
  for (std::size_t f = 0; f < T.size(); ++f) {
    removeFace[f] = side[components.root(int(f))] == 2;
    if (onLoop[T[f][0]] && onLoop[T[f][1]] && onLoop[T[f][2]]) ++result.faces_on_loop;
  }
  std::vector<int> removedIndex;
  const Part removed = partOf(mesh, removeFace, true, true, removedIndex);
  const Part kept =
      partOf(mesh, removeFace, false, options.remove_unreferenced_vertices, result.vertex_index);
  buildMesh(result.removed, removed.points, removed.triangles, removed.vertexOrigin,
            removed.faceOrigin);
  result.border_edges_before = borderEdgesOf(T);
  result.faces_kept = kept.triangles.size();
  result.faces_removed = T.size() - kept.triangles.size();
  result.border_edges_after = borderEdgesOf(kept.triangles);
  buildMesh(mesh, kept.points, kept.triangles, kept.vertexOrigin, kept.faceOrigin);
  reportProgress(options.progress, 100, "Done");
  result.time_ms = msSince(start);
  return result;
}

}  // namespace meshmend
