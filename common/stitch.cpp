#include "common/stitch.h"

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

#include "common/border_loops.h"
#include "common/box_tree.h"
#include "common/errors.h"
#include "common/intersections.h"
#include "common/predicates.h"

namespace meshmend {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

std::uint64_t edgeKey(int a, int b) {
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}
std::uint64_t undirectedKey(int a, int b) {
  return edgeKey(std::min(a, b), std::max(a, b));
}

// "vertex 123 (0.5, 1, -2)": where a user can find it in MeshLab.
std::string describeVertex(const Mesh& mesh, int v) {
  std::ostringstream s;
  s.precision(6);
  const Point3& p = mesh.vert[v].cP();
  s << "vertex " << v << " (" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return s.str();
}

void requireCompact(const Mesh& mesh) {
  if (std::size_t(mesh.vn) != mesh.vert.size() || std::size_t(mesh.fn) != mesh.face.size())
    throw InvalidInputError(
        "the mesh has deleted vertices or faces: compact it first (vcg::tri::Allocator::Compact)");
}

void requireVertex(const Mesh& mesh, int v, const std::string& what) {
  if (v < 0 || std::size_t(v) >= mesh.vert.size())
    throw InvalidInputError(what + " refers to vertex " + std::to_string(v) +
                            ", but the mesh has only " + std::to_string(mesh.vert.size()) +
                            " vertices");
}

// Edges used by exactly one face, from the sorted edge uses.
std::size_t borderEdgesOf(const std::vector<Triangle>& triangles) {
  const std::vector<EdgeUse> uses = edgeUses(triangles);
  std::size_t border = 0;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    if (j - i == 1) ++border;
    i = j;
  }
  return border;
}

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

// ================================================================ trimming

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

}  // namespace

TrimResult trimAlongLoop(Mesh& mesh, const TrimOptions& options) {
  const auto start = Clock::now();
  TrimResult result;
  requireFacesAndFiniteCoordinates(mesh, "the mesh");
  requireCompact(mesh);
  reportProgress(options.progress, 0, "Finding the loop");
  const std::vector<Point3> P = positionsOf(mesh);
  const std::vector<Triangle> T = trianglesOf(mesh);
  const int n = int(P.size());
  const std::vector<EdgeUse> uses = edgeUses(T);
  const Adjacency adj = adjacencyOf(uses, n);

  std::vector<int> loop;
  bool directed = true;
  if (!options.loop.empty()) {
    loop = options.loop;
    if (loop.size() > 1 && loop.front() == loop.back()) loop.pop_back();
    for (int v : loop) requireVertex(mesh, v, "the loop");
    if (loop.size() < 3) throw InvalidInputError("the loop needs at least three vertices");
    std::vector<char> seen(n, 0);
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
  } else if (!options.selected_vertices.empty()) {
    loop = loopFromSelection(mesh, adj, options.selected_vertices);
    directed = false;
  } else if (!options.picked_vertices.empty()) {
    loop = loopFromPicks(mesh, adj, options.picked_vertices);
  } else {
    throw InvalidInputError("no trim loop given: select a closed loop of vertices, or give it");
  }
  if (options.keep_face >= int(T.size()))
    throw InvalidInputError("keep_face " + std::to_string(options.keep_face) +
                            " is out of range (the mesh has " + std::to_string(T.size()) +
                            " faces)");
  if (options.keep_face < 0 && !directed)
    throw InvalidInputError(
        "a loop recovered from a selection has no direction: select a face on the side to keep");
  result.loop = loop;
  reportProgress(options.progress, 30, "Classifying faces");

  // Loop edges, keyed undirected, with the loop's direction.
  std::unordered_map<std::uint64_t, std::pair<int, int>> loopEdges;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const int a = loop[k], b = loop[(k + 1) % loop.size()];
    loopEdges[undirectedKey(a, b)] = {a, b};
  }
  // Faces joined across every edge that is not on the loop.
  std::vector<int> parent(T.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> root = [&](int f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  struct LoopUse {
    int face;
    bool along;  // runs the loop edge in the loop's direction
    int a, b;
  };
  std::vector<LoopUse> loopUses;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    const auto it = loopEdges.find(undirectedKey(uses[i].u, uses[i].v));
    if (it == loopEdges.end()) {
      for (std::size_t k = i + 1; k < j; ++k) parent[root(uses[k].face)] = root(uses[i].face);
    } else {
      for (std::size_t k = i; k < j; ++k)
        loopUses.push_back({uses[k].face, T[uses[k].face][uses[k].corner] == it->second.first,
                            it->second.first, it->second.second});
    }
    i = j;
  }
  // 0 unknown, 1 keep, 2 remove, per face-component root.
  std::vector<char> side(T.size(), 0);
  auto notSeparating = [&](int a, int b) {
    return TopologyError(
        "the loop does not separate the mesh: the faces on both sides of its "
        "edge from " +
        describeVertex(mesh, a) + " to " + describeVertex(mesh, b) +
        " are connected without crossing the loop (e.g. a loop around a handle "
        "or across a strip)");
  };
  // The same component on both sides of one loop edge: nothing separates.
  {
    std::unordered_map<std::uint64_t, std::pair<int, int>> sides;  // edge -> (along, against) root
    for (const LoopUse& u : loopUses) {
      auto& s = sides.try_emplace(undirectedKey(u.a, u.b), -1, -1).first->second;
      (u.along ? s.first : s.second) = root(u.face);
      if (s.first >= 0 && s.first == s.second) throw notSeparating(u.a, u.b);
    }
  }
  if (options.keep_face < 0) {
    for (const LoopUse& u : loopUses) {
      const int r = root(u.face);
      const char want = u.along ? 1 : 2;
      if (side[r] != 0 && side[r] != want)
        throw TopologyError(
            "the side to keep cannot be decided by the loop's direction near " +
            describeVertex(mesh, u.a) +
            ": the faces along the loop are inconsistently oriented, or the loop does not "
            "separate the mesh; select a face on the side to keep");
      side[r] = want;
    }
  } else {
    // Two-colour the components: across a loop edge the sides differ.
    std::unordered_map<int, std::vector<std::pair<int, bool>>> across;  // root -> (root, along)
    std::unordered_map<std::uint64_t, std::vector<std::pair<int, bool>>> byEdge;
    for (const LoopUse& u : loopUses)
      byEdge[undirectedKey(u.a, u.b)].push_back({root(u.face), u.along});
    for (const auto& [key, list] : byEdge)
      for (const auto& x : list)
        for (const auto& y : list)
          if (x.second != y.second) across[x.first].push_back({y.first, true});
    const int keepRoot = root(options.keep_face);
    if (!across.count(keepRoot) && std::none_of(loopUses.begin(), loopUses.end(),
                                                [&](auto& u) { return root(u.face) == keepRoot; }))
      throw InvalidInputError("face " + std::to_string(options.keep_face) +
                              " is not next to the loop on either side (it lies on a part of the "
                              "mesh the loop does not touch)");
    side[keepRoot] = 1;
    std::vector<int> stack{keepRoot};
    while (!stack.empty()) {
      const int r = stack.back();
      stack.pop_back();
      for (const auto& [other, unused] : across[r]) {
        (void)unused;
        const char want = side[r] == 1 ? 2 : 1;
        if (side[other] == 0) {
          side[other] = want;
          stack.push_back(other);
        } else if (side[other] != want) {
          for (const LoopUse& u : loopUses)
            if (root(u.face) == other) throw notSeparating(u.a, u.b);
        }
      }
    }
    // Components on the loop that no loop edge ties to the kept side (a
    // loop edge on a border has one face): the loop's direction relative to
    // the kept side decides.
    int keepAlong = 0;
    for (const LoopUse& u : loopUses)
      if (side[root(u.face)] != 0) keepAlong += (side[root(u.face)] == 1) == u.along ? 1 : -1;
    for (const LoopUse& u : loopUses) {
      const int r = root(u.face);
      if (side[r] == 0) side[r] = (u.along == (keepAlong >= 0)) ? 1 : 2;
    }
  }

  // Split the faces; provenance follows every element.
  reportProgress(options.progress, 70, "Writing");
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);
  std::vector<char> onLoop(n, 0);
  for (int v : loop) onLoop[v] = 1;
  std::vector<char> usedByKept(n, 0), usedByRemoved(n, 0), usedAtAll(n, 0);
  std::vector<char> removeFace(T.size(), 0);
  for (std::size_t f = 0; f < T.size(); ++f) {
    removeFace[f] = side[root(int(f))] == 2;
    for (int v : T[f]) (removeFace[f] ? usedByRemoved : usedByKept)[v] = 1;
    for (int v : T[f]) usedAtAll[v] = 1;
    if (onLoop[T[f][0]] && onLoop[T[f][1]] && onLoop[T[f][2]]) ++result.faces_on_loop;
  }
  auto part = [&](bool removed, std::vector<int>& index) {
    std::vector<Point3> points;
    std::vector<VertexOrigin> vorig;
    index.assign(n, -1);
    for (int v = 0; v < n; ++v) {
      const bool keep =
          removed ? usedByRemoved[v]
                  : (usedByKept[v] || !usedAtAll[v] || !options.remove_unreferenced_vertices);
      if (!keep) continue;
      index[v] = int(points.size());
      points.push_back(P[v]);
      vorig.push_back(vo[v]);
    }
    std::vector<Triangle> tris;
    std::vector<FaceOrigin> forig;
    for (std::size_t f = 0; f < T.size(); ++f)
      if (bool(removeFace[f]) == removed) {
        tris.push_back({index[T[f][0]], index[T[f][1]], index[T[f][2]]});
        forig.push_back(fo[f]);
      }
    return std::make_tuple(points, tris, vorig, forig);
  };
  std::vector<int> removedIndex;
  {
    const auto [points, tris, vorig, forig] = part(true, removedIndex);
    buildMesh(result.removed, points, tris, vorig, forig);
  }
  result.border_edges_before = borderEdgesOf(T);
  {
    const auto [points, tris, vorig, forig] = part(false, result.vertex_index);
    result.faces_kept = tris.size();
    result.faces_removed = T.size() - tris.size();
    result.border_edges_after = borderEdgesOf(tris);
    buildMesh(mesh, points, tris, vorig, forig);
  }
  reportProgress(options.progress, 100, "Done");
  result.time_ms = msSince(start);
  return result;
}

// ================================================================ stitching

namespace {

// For a few vertices of a mesh, every neighbour along an edge with the
// number of faces that run the edge each way: enough to tell border edges,
// their direction, and what a new face on an edge would do to it, in one
// pass over the faces and without sorting the whole mesh's edges.
class LocalEdges {
 public:
  struct Neighbour {
    int v;
    int opposite;      // the third corner of a face on the edge
    std::int16_t out;  // faces running (this -> v)
    std::int16_t in;   // faces running (v -> this)
  };

  // With `among`, only the edges between two of the vertices are kept (what
  // a stitch asks about: path edges and rungs), a fraction of the entries.
  LocalEdges(const Mesh& mesh, const std::vector<int>& vertices, bool among = false)
      : slot_(mesh.vert.size(), -1) {
    int slots = 0;
    for (int v : vertices)
      if (slot_[v] < 0) slot_[v] = slots++;
    // One pass over every face notes the edges concerned (a test on the
    // slots of their ends, which the most edges fail) with the way the face
    // runs them and its third corner; the uses are counted per vertex on the
    // way, then placed.
    start_.assign(std::size_t(slots) + 1, 0);
    struct Use {
      int from, to, opposite;  // a face runs from -> to
    };
    std::vector<Use> found;
    found.reserve(std::size_t(slots) * (among ? 2 : 6));  // a border path vertex: two edges
    const Vertex* base = mesh.vert.data();
    auto note = [&](int from, int to, int opposite, int slotFrom, int slotTo) {
      // (s | t) >= 0: both are slots; (s & t) >= 0: one of them is.
      if ((among ? (slotFrom | slotTo) : (slotFrom & slotTo)) < 0) return;
      found.push_back({from, to, opposite});
      if (slotFrom >= 0) ++start_[slotFrom + 1];
      if (slotTo >= 0) ++start_[slotTo + 1];
    };
    for (const Face& f : mesh.face) {
      const int c0 = int(f.cV(0) - base), c1 = int(f.cV(1) - base), c2 = int(f.cV(2) - base);
      const int s0 = slot_[c0], s1 = slot_[c1], s2 = slot_[c2];
      note(c0, c1, c2, s0, s1);
      note(c1, c2, c0, s1, s2);
      note(c2, c0, c1, s2, s0);
    }
    for (int s = 0; s < slots; ++s) start_[s + 1] += start_[s];
    entries_.resize(start_.back());
    {
      std::vector<int> fill(start_.begin(), start_.end() - 1);
      for (const Use& u : found) {
        const int slotFrom = slot_[u.from], slotTo = slot_[u.to];
        if (slotFrom >= 0) entries_[fill[slotFrom]++] = Neighbour{u.to, u.opposite, 1, 0};
        if (slotTo >= 0) entries_[fill[slotTo]++] = Neighbour{u.from, u.opposite, 0, 1};
      }
    }
  }

  // Edge a-b (a must be one of the vertices): the faces that run it each
  // way and the third corner of one of them; no face: out = in = 0. The uses
  // of an edge are added up here, not merged beforehand (a vertex has few,
  // most edges are asked about once or twice).
  Neighbour find(int a, int b) const {
    Neighbour e{b, -1, 0, 0};
    const int s = a >= 0 && std::size_t(a) < slot_.size() ? slot_[a] : -1;
    if (s < 0) return e;
    for (int i = start_[s]; i < start_[s + 1]; ++i)
      if (entries_[i].v == b) {
        if (e.opposite < 0) e.opposite = entries_[i].opposite;
        e.out += entries_[i].out;
        e.in += entries_[i].in;
      }
    return e;
  }
  int uses(int a, int b) const {
    const Neighbour e = find(a, b);
    return e.out + e.in;
  }
  // On a border edge (with `among`: on one to another of the vertices).
  bool onBorder(int a) const {
    const int s = slot_[a];
    for (int i = start_[s]; i < start_[s + 1]; ++i) {
      int uses = 0;
      for (int j = start_[s]; j < start_[s + 1]; ++j)
        if (entries_[j].v == entries_[i].v) uses += entries_[j].out + entries_[j].in;
      if (uses == 1) return true;
    }
    return false;
  }

 private:
  std::vector<int> slot_, start_;
  std::vector<Neighbour> entries_;
};

// What a stitch will add, decided before the mesh changes.
struct StitchPlan {
  std::vector<Point3> newPoints;  // vertex n + k is newPoints[k]
  std::vector<Triangle> faces;
  std::array<int, 2> firstRung{-1, -1}, lastRung{-1, -1};
  bool closed = false, reversedB = false;
  std::size_t conflicts = 0;
  long borderDelta = 0;  // border edges after minus before
  double maxAspect = 0;
};

// The square of the aspect ratio, longest edge over shortest altitude
// (infinite for a degenerate triangle): no root per face, one for the largest.
double squaredAspectRatio(const Point3& a, const Point3& b, const Point3& c) {
  const double l = std::max({(b - a).SquaredNorm(), (c - b).SquaredNorm(), (a - c).SquaredNorm()});
  const double area2 = ((b - a) ^ (c - a)).SquaredNorm();
  return area2 > 0 ? l * l / area2 : INFINITY;
}

// Arc-length parametrised polyline (the rows of a subdivided strip).
class Polyline {
 public:
  explicit Polyline(std::vector<Point3> points) : p_(std::move(points)), s_(p_.size(), 0) {
    for (std::size_t i = 1; i < p_.size(); ++i) s_[i] = s_[i - 1] + (p_[i] - p_[i - 1]).Norm();
  }
  double length() const { return s_.back(); }
  // The point at arc length s (clamped; NaN, as 0 x an infinite length
  // gives, is the start).
  Point3 at(double s) const {
    if (p_.size() == 1 || !(s > 0)) return p_.front();
    if (s >= s_.back()) return p_.back();
    const std::size_t i = std::upper_bound(s_.begin(), s_.end(), s) - s_.begin() - 1;
    const double span = s_[i + 1] - s_[i];
    const double t = span > 0 ? (s - s_[i]) / span : 0;
    return p_[i] * (1 - t) + p_[i + 1] * t;
  }

 private:
  std::vector<Point3> p_;
  std::vector<double> s_;
};

// A path of mesh vertices (closed: back to its first vertex) as an
// arc-length parametrised polyline, its points read from the mesh.
class PathLine {
 public:
  PathLine(const Mesh& mesh, const std::vector<int>& path, bool closed)
      : mesh_(mesh), path_(path), s_(path.size() + (closed ? 1 : 0), 0) {
    for (std::size_t i = 1; i < s_.size(); ++i)
      s_[i] = s_[i - 1] + (point(i) - point(i - 1)).Norm();
  }
  double length() const { return s_.back(); }
  // The point at arc length s (clamped; NaN, as 0 x an infinite length
  // gives, is the start: past the search it read beyond the arrays).
  Point3 at(double s) const {
    if (s_.size() == 1 || !(s > 0)) return point(0);
    if (s >= s_.back()) return point(s_.size() - 1);
    const std::size_t i = std::upper_bound(s_.begin(), s_.end(), s) - s_.begin() - 1;
    const double span = s_[i + 1] - s_[i];
    const double t = span > 0 ? (s - s_[i]) / span : 0;
    return point(i) * (1 - t) + point(i + 1) * t;
  }

 private:
  Point3 point(std::size_t i) const {  // i == path_.size(): back at the first vertex
    return mesh_.vert[path_[i < path_.size() ? i : 0]].cP();
  }
  const Mesh& mesh_;
  const std::vector<int>& path_;
  std::vector<double> s_;
};

// Sum of distances between points at the same arc-length fraction (of b
// run backwards when reversedB): small when the two paths run side by side
// in the same direction. A closed path run backwards from its first vertex
// is its forward run reversed, so one parametrisation serves both ways.
double correspondenceCost(const PathLine& a, const PathLine& b, bool reversedB) {
  constexpr int kSamples = 32;
  double cost = 0;
  for (int k = 0; k <= kSamples; ++k) {
    const double t = double(k) / kSamples;
    cost += (a.at(t * a.length()) - b.at((reversedB ? 1 - t : t) * b.length())).Norm();
  }
  return cost;
}

// The merge-like triangulation (§2.2) of the strip between lists a and b
// (indices into `points`), from rung (a[0], b[0]) to (a.back(), b.back()):
// each step advances along the list whose next diagonal is shorter, any
// number of steps along one list. A step that would make a triangle with
// exactly collinear corners takes the other list when it can, and so does a
// step whose triangle would fold back over the face on its path edge
// (valid(false, i, x): x lies beyond edge a[i]-a[i+1], away from that face;
// valid(true, j, x): beyond edge b[j]-b[j+1]). Faces are
// `forward` = (a[i], a[i+1], b[j]) and (b[j], a[i], b[j+1]), else reversed.
// Returns, per step, whether it advanced along a; raises maxSquaredAspect to
// the faces' squared aspect ratios (their corners are at hand).
template <class PointOf, class Valid>
std::vector<char> zipper(const std::vector<int>& a, const std::vector<int>& b, PointOf&& point,
                         Valid&& valid, bool forward, std::vector<Triangle>& faces,
                         double& maxSquaredAspect) {
  std::vector<char> steps;
  steps.reserve(a.size() + b.size());
  faces.reserve(faces.size() + a.size() + b.size());
  std::size_t i = 0, j = 0;
  while (i + 1 < a.size() || j + 1 < b.size()) {
    bool alongA;
    if (i + 1 == a.size()) {
      alongA = false;
    } else if (j + 1 == b.size()) {
      alongA = true;
    } else {
      const Point3 &ai = point(a[i]), &ai1 = point(a[i + 1]), &bj = point(b[j]),
                   &bj1 = point(b[j + 1]);
      alongA = (ai1 - bj).SquaredNorm() <= (ai - bj1).SquaredNorm();
      const bool validA = valid(false, i, b[j]), validB = valid(true, j, a[i]);
      if (validA != validB) alongA = validA;
      const bool flat = alongA ? collinear(ai, ai1, bj) : collinear(bj, ai, bj1);
      if (flat && !(alongA ? collinear(bj, ai, bj1) : collinear(ai, ai1, bj))) alongA = !alongA;
    }
    if (alongA) {
      faces.push_back(forward ? Triangle{a[i], a[i + 1], b[j]} : Triangle{a[i + 1], a[i], b[j]});
      maxSquaredAspect =
          std::max(maxSquaredAspect, squaredAspectRatio(point(a[i]), point(a[i + 1]), point(b[j])));
      ++i;
    } else {
      faces.push_back(forward ? Triangle{b[j], a[i], b[j + 1]} : Triangle{a[i], b[j], b[j + 1]});
      maxSquaredAspect =
          std::max(maxSquaredAspect, squaredAspectRatio(point(b[j]), point(a[i]), point(b[j + 1])));
      ++j;
    }
    steps.push_back(alongA);
  }
  return steps;
}

struct PreparedPath {
  std::vector<int> v;
  bool closed = false;
  int sign = 0;  // +1: the path runs along its border edges' direction, -1 against, 0 unknown
  std::size_t against = 0;  // border edges against the majority
};

PreparedPath preparePath(const Mesh& mesh, const BorderPath& path, const char* name) {
  PreparedPath p;
  p.v = path.vertices;
  const std::string what = std::string("path ") + name;
  for (int v : p.v)
    if (v < 0 || std::size_t(v) >= mesh.vert.size()) requireVertex(mesh, v, what);
  bool repeated = false;
  if (p.v.size() > 2 && p.v.front() == p.v.back()) {
    p.v.pop_back();
    repeated = true;
  }
  if (p.v.size() < 2 && !(p.v.size() == 1 && path.shape != BorderPath::Shape::Closed))
    throw InvalidInputError(what + " has fewer than two vertices");
  p.closed = path.shape == BorderPath::Shape::Closed ||
             (path.shape == BorderPath::Shape::Auto && repeated);
  if (path.shape == BorderPath::Shape::Closed && p.v.size() < 3)
    throw InvalidInputError(what + " is a closed loop of fewer than three vertices");
  return p;
}

// Marks the path's vertices with `bit` in `on`, and refuses a repeated one.
void checkDistinct(const Mesh& mesh, const PreparedPath& p, std::vector<char>& on, char bit,
                   const char* name) {
  for (int v : p.v) {
    if (on[v] & bit)
      throw InvalidInputError(describeVertex(mesh, v) + " appears twice in path " + name);
    on[v] |= bit;
  }
}

// Direction of a path relative to its border edges, by majority.
void orientPath(PreparedPath& p, const LocalEdges& edges) {
  long along = 0, against = 0;
  const std::size_t count = p.closed ? p.v.size() : p.v.size() - 1;
  for (std::size_t k = 0; k < count; ++k) {
    const LocalEdges::Neighbour e = edges.find(p.v[k], p.v[k + 1 < p.v.size() ? k + 1 : 0]);
    if (e.out + e.in != 1) continue;
    (e.out ? along : against)++;
  }
  p.sign = along > against ? 1 : against > along ? -1 : 0;
  p.against = std::size_t(std::min(along, against));
}

template <class T>
void rotate(std::vector<T>& v, std::size_t first) {
  std::rotate(v.begin(), v.begin() + first, v.end());
}

// topologyRead is called once the mesh's faces are no longer read (from
// then on the plan reads the path vertices' coordinates and what it
// gathered).
StitchPlan planStitch(const Mesh& mesh, const StitchOptions& o,
                      const std::function<void()>& topologyRead = {}) {
  StitchPlan plan;
  PreparedPath A = preparePath(mesh, o.a, "a"), B = preparePath(mesh, o.b, "b");
  constexpr char kOnA = 1, kOnB = 2;
  std::vector<char> on(mesh.vert.size(), 0);
  checkDistinct(mesh, A, on, kOnA, "a");
  checkDistinct(mesh, B, on, kOnB, "b");
  std::vector<int> all = A.v;
  all.insert(all.end(), B.v.begin(), B.v.end());
  const LocalEdges edges(mesh, all, true);
  // Most path vertices are on a border edge of their path; the others are
  // checked against all their edges.
  {
    std::vector<int> unsure;
    for (int v : all)
      if (!edges.onBorder(v)) unsure.push_back(v);
    if (!unsure.empty()) {
      const LocalEdges full(mesh, unsure);
      for (const auto* p : {&A, &B})
        for (int v : p->v)
          if (!edges.onBorder(v) && !full.onBorder(v))
            throw InvalidInputError(describeVertex(mesh, v) + " of path " + (p == &A ? "a" : "b") +
                                    " is not on a border edge: stitch paths must follow borders");
    }
  }
  if (topologyRead) topologyRead();
  // Auto shape: a path whose ends share a border edge goes all around.
  for (auto [p, path] : {std::make_pair(&A, &o.a), std::make_pair(&B, &o.b)})
    if (path->shape == BorderPath::Shape::Auto && !p->closed && p->v.size() >= 3 &&
        edges.uses(p->v.front(), p->v.back()) == 1)
      p->closed = true;
  if (A.closed != B.closed)
    throw InvalidInputError(
        "one path is a closed loop and the other is open: stitch a loop to a loop, or give two "
        "open paths");
  plan.closed = A.closed;
  // Shared vertices: only the ends of open paths (a crack closing at a point).
  {
    for (std::size_t k = 0; k < B.v.size(); ++k)
      if (on[B.v[k]] & kOnA) {
        const bool endOfB = k == 0 || k + 1 == B.v.size();
        const bool endOfA = B.v[k] == A.v.front() || B.v[k] == A.v.back();
        if (A.closed || !endOfA || !endOfB)
          throw InvalidInputError(describeVertex(mesh, B.v[k]) +
                                  " is on both paths (only open paths may share an end)");
      }
  }
  orientPath(A, edges);
  orientPath(B, edges);

  // Closed loops start at their nearest pair of vertices (nearest to a
  // sample of a's vertices: linear, and good enough to start the zipper).
  if (A.closed) {
    const std::size_t samples = std::min<std::size_t>(A.v.size(), 32);
    double best = INFINITY;
    std::size_t bi = 0, bj = 0;
    for (std::size_t s = 0; s < samples; ++s) {
      const std::size_t i = s * A.v.size() / samples;
      const Point3& p = mesh.vert[A.v[i]].cP();
      for (std::size_t j = 0; j < B.v.size(); ++j) {
        const double d = (mesh.vert[B.v[j]].cP() - p).SquaredNorm();
        if (d < best) best = d, bi = i, bj = j;
      }
    }
    rotate(A.v, bi);
    rotate(B.v, bj);
  }
  // Which way b runs beside a: by geometry, and by orientation (a side
  // that runs along its border must meet one that runs against it).
  const PathLine lineA(mesh, A.v, A.closed), lineB(mesh, B.v, B.closed);
  const double costSame = correspondenceCost(lineA, lineB, false);
  const double costReversed = correspondenceCost(lineA, lineB, true);
  const bool geometrySame = costSame <= costReversed;
  bool same = geometrySame;
  if (A.sign != 0 && B.sign != 0) {
    const bool orientationSame = A.sign == -B.sign;
    const double chosen = orientationSame ? costSame : costReversed;
    const double other = orientationSame ? costReversed : costSame;
    if (orientationSame != geometrySame && chosen > 2 * other) {
      if (!o.allow_orientation_conflict)
        throw TopologyError(
            "the two sides are oppositely oriented: following the borders' directions would "
            "twist the stitch across the gap (path a runs " +
            std::string(A.sign > 0 ? "along" : "against") + " its border, path b " +
            (B.sign > 0 ? "along" : "against") +
            " its own, side by side); invert the faces of one side first");
      plan.conflicts += B.v.size();
    } else {
      same = orientationSame;
    }
  }
  plan.reversedB = !same;
  if (!same) {
    std::reverse(B.v.begin() + (B.closed ? 1 : 0), B.v.end());
    B.sign = -B.sign;
  }
  // forward faces run a against a[i] -> a[i+1] and b along b[j+1] -> b[j]:
  // right when a runs against its border and b along its own.
  const bool forward = A.sign != 0 ? A.sign < 0 : B.sign != 0 ? B.sign > 0 : true;
  plan.conflicts += A.against + B.against;

  std::vector<int> a = A.v, b = B.v;
  if (A.closed) {
    a.push_back(a.front());
    b.push_back(b.front());
  } else {
    if (b.front() == a.front()) b.erase(b.begin());
    if (!b.empty() && b.back() == a.back()) b.pop_back();
    if (b.empty()) throw InvalidInputError("path b has no vertex that path a does not share");
  }

  // Every edge of a path gets one new face: it must be a border edge run
  // the other way, or no edge yet. Noted per edge: the third corner of the
  // face on it (-1: no face), for the zipper's fold test.
  auto checkPathEdges = [&](const std::vector<int>& p, bool newFaceRunsForward, const char* name) {
    std::vector<int> opposite(p.size() > 1 ? p.size() - 1 : 0, -1);
    for (std::size_t k = 0; k + 1 < p.size(); ++k) {
      const LocalEdges::Neighbour e = edges.find(p[k], p[k + 1]);
      const int used = e.out + e.in;
      if (used == 0) {
        ++plan.borderDelta;
      } else if (used == 1) {
        opposite[k] = e.opposite;
        const bool existingForward = e.out == 1;
        if (existingForward == newFaceRunsForward && !o.allow_orientation_conflict)
          throw TopologyError("the border along path " + std::string(name) +
                              " changes direction between " + describeVertex(mesh, p[k]) + " and " +
                              describeVertex(mesh, p[k + 1]) +
                              ": the faces there are inconsistently oriented");
        --plan.borderDelta;
      } else {
        throw TopologyError("the edge from " + describeVertex(mesh, p[k]) + " to " +
                            describeVertex(mesh, p[k + 1]) + " on path " + name +
                            " already has two faces: the path leaves the border there");
      }
    }
    return opposite;
  };
  const std::vector<int> oppositeA = checkPathEdges(a, forward, "a");
  const std::vector<int> oppositeB = checkPathEdges(b, !forward, "b");

  const int n = int(mesh.vert.size());
  auto existingPoint = [&](int v) -> Point3 { return mesh.vert[v].cP(); };
  // Beyond edge k of path a (onB: of path b): on the other side of it than
  // the face already on it, measured in that face's plane (any point is
  // beyond an edge with no face).
  // The zipper asks about one edge of each path until it moves past it: the
  // edge's frame is kept for the next question.
  struct EdgeFrame {
    std::size_t k = SIZE_MAX;
    Point3 P, d, normal;
  } frames[2];
  auto beyond = [&](bool onB, std::size_t k, int x) {
    const int opposite = (onB ? oppositeB : oppositeA)[k];
    if (opposite < 0) return true;
    EdgeFrame& f = frames[onB];
    if (f.k != k) {
      const std::vector<int>& p = onB ? b : a;
      f.k = k;
      f.P = existingPoint(p[k]);
      f.d = existingPoint(p[k + 1]) - f.P;
      f.normal = f.d ^ (existingPoint(opposite) - f.P);
    }
    return ((f.d ^ (existingPoint(x) - f.P)) * f.normal) < 0;
  };
  double maxSquaredAspect = 0;
  std::vector<char> steps =
      zipper(a, b, existingPoint, beyond, forward, plan.faces, maxSquaredAspect);

  // Rungs: an end rung may close an existing border edge; an inner rung
  // gets two new faces, so it must not exist yet.
  {
    std::size_t i = 0, j = 0;
    for (std::size_t s = 0; s <= steps.size(); ++s) {
      const bool end = !A.closed && (s == 0 || s == steps.size());
      const LocalEdges::Neighbour e =
          a[i] != b[j] ? edges.find(a[i], b[j]) : LocalEdges::Neighbour{b[j], -1, 0, 0};
      const int used = e.out + e.in;
      if (end) {
        // The first face runs b[0] -> a[0] (forward), the last a -> b.
        const bool newRunsAToB = (s == 0) != forward;
        if (used == 0) {
          ++plan.borderDelta;
        } else if (used == 1 && (e.out == 1) != newRunsAToB) {
          --plan.borderDelta;
        } else {
          throw TopologyError("the stitch would add a face to the edge from " +
                              describeVertex(mesh, a[i]) + " to " + describeVertex(mesh, b[j]) +
                              ", which " +
                              (used == 1 ? "runs the same way" : "already has two faces"));
        }
      } else if (used > 0) {
        throw TopologyError("the stitch would add two faces to the existing edge from " +
                            describeVertex(mesh, a[i]) + " to " + describeVertex(mesh, b[j]) +
                            ": the paths touch there; stitch shorter paths");
      }
      if (s < steps.size()) (steps[s] ? i : j)++;
    }
  }
  if (!A.closed) {
    plan.firstRung = {a.front(), b.front()};
    plan.lastRung = {a.back(), b.back()};
  }

  // Subdivision: rows of new vertices across a wide strip.
  if (o.max_aspect_ratio > 0) {
    auto meanEdge = [&](const std::vector<int>& p) {
      double sum = 0;
      for (std::size_t k = 0; k + 1 < p.size(); ++k)
        sum += (existingPoint(p[k + 1]) - existingPoint(p[k])).Norm();
      return p.size() > 1 ? sum / double(p.size() - 1) : 0.0;
    };
    const double ha = meanEdge(a), hb = meanEdge(b.size() > 1 ? b : a);
    const double h = 0.5 * (ha + hb);
    std::vector<std::array<int, 2>> rungs{{a[0], b[0]}};
    {
      std::size_t i = 0, j = 0;
      for (char s : steps) {
        (s ? i : j)++;
        rungs.push_back({a[i], b[j]});
      }
    }
    double longest = 0, shortest = INFINITY;
    for (const auto& r : rungs) {
      const double l = (existingPoint(r[0]) - existingPoint(r[1])).Norm();
      longest = std::max(longest, l);
      shortest = std::min(shortest, l);
    }
    // One row count for the whole strip: enough for the widest rung, but
    // never so many that rows crowd closer than h / max_aspect_ratio where
    // the gap is narrowest (that would trade long slivers for flat ones).
    int strips = 1;
    if (h > 0) {
      strips = int(std::ceil(longest / (o.max_aspect_ratio * h)));
      strips = std::min(strips, int(std::floor(shortest * o.max_aspect_ratio / h)));
      strips = std::max(1, std::min(strips, o.max_rows + 1));
    }
    if (strips > 1) {
      plan.faces.clear();
      maxSquaredAspect = 0;
      std::vector<std::vector<int>> rows{a};
      for (int k = 1; k < strips; ++k) {
        const double t = double(k) / strips;
        std::vector<Point3> curve;
        for (const auto& r : rungs)
          curve.push_back(existingPoint(r[0]) * (1 - t) + existingPoint(r[1]) * t);
        const Polyline line(curve);
        const double spacing = (1 - t) * ha + t * hb;
        const int segments =
            std::max(1, int(std::lround(line.length() / std::max(spacing, 1e-300))));
        std::vector<int> row;
        for (int s = 0; s <= segments; ++s) {
          if (A.closed && s == segments) {
            row.push_back(row.front());
            break;
          }
          row.push_back(n + int(plan.newPoints.size()));
          plan.newPoints.push_back(line.at(line.length() * s / segments));
        }
        rows.push_back(row);
      }
      rows.push_back(b);
      auto anyPoint = [&](int v) -> Point3 {
        return v < n ? mesh.vert[v].cP() : plan.newPoints[v - n];
      };
      // One of the two rows of every strip is new vertices: the fold test,
      // made between an existing edge and an existing vertex, never applies.
      auto anyIsValid = [](bool, std::size_t, int) { return true; };
      for (std::size_t k = 0; k + 1 < rows.size(); ++k)
        zipper(rows[k], rows[k + 1], anyPoint, anyIsValid, forward, plan.faces, maxSquaredAspect);
      // End rungs are now chains of strips edges (new border edges).
      if (!A.closed) {
        const bool closesFirst = edges.uses(a.front(), b.front()) == 1;
        const bool closesLast = edges.uses(a.back(), b.back()) == 1;
        if (closesFirst || closesLast)
          throw TopologyError(
              "a wide stitch cannot be subdivided where its end rung is an existing edge");
        plan.borderDelta += 2 * (strips - 1);
      }
    }
  }
  plan.maxAspect = std::sqrt(maxSquaredAspect);
  return plan;
}

// Exact count of the intersecting pairs that involve a planned face. Only
// the faces near the gap are looked at: the planned faces' boxes go into a
// tree, every face of the mesh whose box meets the tree's bounds is looked
// up in it, and the pairs found are decided on a small copy of the faces
// concerned.
std::size_t newIntersections(const Mesh& mesh, const StitchPlan& plan) {
  if (plan.faces.empty()) return 0;
  const int n = int(mesh.vert.size());
  const Vertex* base = mesh.vert.data();
  auto point = [&](int v) -> Point3 { return v < n ? mesh.vert[v].cP() : plan.newPoints[v - n]; };
  std::vector<Box> boxes;
  boxes.reserve(plan.faces.size());
  for (const Triangle& t : plan.faces)
    boxes.push_back(boxOf(point(t[0]), point(t[1]), point(t[2])));
  const BoxTree tree(boxes);
  const Box bounds = tree.bounds();
  // Mesh faces whose boxes overlap a planned face's: (planned, mesh face).
  std::vector<std::vector<std::array<std::uint32_t, 2>>> found(workerCount());
  parallelChunks(mesh.face.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
    for (std::size_t g = begin; g < end; ++g) {
      const Face& f = mesh.face[g];
      const Box b = boxOf(f.cV(0)->cP(), f.cV(1)->cP(), f.cV(2)->cP());
      if (!overlap(b, bounds)) continue;
      tree.query(b, worker, [&](std::uint32_t i, unsigned) {
        found[worker].push_back({i, std::uint32_t(g)});
      });
    }
  });
  // The faces concerned, renumbered: the planned ones first.
  std::vector<Point3> P;
  std::vector<Triangle> T;
  std::vector<int> localVertex(n + plan.newPoints.size(), -1);
  auto local = [&](int v) {
    if (localVertex[v] < 0) {
      localVertex[v] = int(P.size());
      P.push_back(point(v));
    }
    return localVertex[v];
  };
  T.reserve(plan.faces.size());
  for (const Triangle& t : plan.faces) T.push_back({local(t[0]), local(t[1]), local(t[2])});
  std::vector<std::uint32_t> localFace(mesh.face.size(), 0);  // 0: not copied yet
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (const auto& list : found)
    for (const auto& [i, g] : list) {
      if (localFace[g] == 0) {
        const Face& f = mesh.face[g];
        localFace[g] = std::uint32_t(T.size());
        T.push_back(
            {local(int(f.cV(0) - base)), local(int(f.cV(1) - base)), local(int(f.cV(2) - base))});
      }
      pairs.push_back({i, localFace[g]});
    }
  // Planned faces among themselves (their local indices are their own).
  for (auto& list : found) list.clear();
  tree.selfPairs([&](std::uint32_t i, std::uint32_t j, unsigned worker) {
    found[worker].push_back({i, j});
  });
  for (const auto& list : found) pairs.insert(pairs.end(), list.begin(), list.end());
  return intersectingOf(P, T, pairs).size();
}

void applyPlan(Mesh& mesh, const StitchPlan& plan, StitchResult& r) {
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);
  const int layer = mesh.vert.empty() ? 0 : std::max(0, vo[0].layer);
  const std::size_t n = mesh.vert.size(), m = mesh.face.size();
  if (!plan.newPoints.empty()) {
    auto vi = vcg::tri::Allocator<Mesh>::AddVertices(mesh, plan.newPoints.size());
    for (std::size_t k = 0; k < plan.newPoints.size(); ++k, ++vi) {
      vi->P() = plan.newPoints[k];
      vo[n + k] = VertexOrigin{layer, -1, -1, {0, 0, 0}};
      r.new_vertices.push_back(int(n + k));
    }
  }
  r.new_faces.reserve(plan.faces.size());
  if (!plan.faces.empty()) {
    auto fi = vcg::tri::Allocator<Mesh>::AddFaces(mesh, plan.faces.size());
    for (std::size_t k = 0; k < plan.faces.size(); ++k, ++fi) {
      for (int c = 0; c < 3; ++c) fi->V(c) = &mesh.vert[plan.faces[k][c]];
      fo[m + k] = FaceOrigin{layer, -1};
      r.new_faces.push_back(int(m + k));
    }
  }
  r.faces_added = plan.faces.size();
  r.vertices_added = plan.newPoints.size();
  r.closed = plan.closed;
  r.reversed_b = plan.reversedB;
  r.orientation_conflicts = plan.conflicts;
  r.first_rung = plan.firstRung;
  r.last_rung = plan.lastRung;
  r.max_aspect_ratio = plan.maxAspect;
}

// Border edges (edges used by exactly one face) counted in two passes over
// the faces: tally() for every face, which lets a caller count while it
// reads the faces for its own purpose, then count(). Each edge's other end
// is listed at its smaller end (a counting sort: the tallies size the
// lists). While placing, the few ends already listed at that vertex are
// searched: an end listed once is turned into its complement (a second
// use), and a third use changes nothing. The count follows as the edges are
// placed: no sort, no pass over the lists.
class BorderEdgeCounter {
 public:
  explicit BorderEdgeCounter(const Mesh& mesh)
      : mesh_(mesh), base_(mesh.vert.data()), fill_(mesh.vert.size() + 1, 0) {}

  void tally(const Face& f) {
    const std::array<int, 3> c = cornersOf(f);
    ++fill_[std::min(c[0], c[1]) + 1];
    ++fill_[std::min(c[1], c[2]) + 1];
    ++fill_[std::min(c[2], c[0]) + 1];
  }

  std::size_t count() {
    // fill_[v]: where v's list starts, then where its next end goes.
    const std::size_t n = mesh_.vert.size();
    for (std::size_t v = 0; v < n; ++v) fill_[v + 1] += fill_[v];
    const std::vector<int> start(fill_.begin(), fill_.end() - 1);
    const std::unique_ptr<int[]> other(new int[std::size_t(fill_[n])]);  // written before read
    std::size_t border = 0;
    auto place = [&](int a, int b) {
      const int low = std::min(a, b), high = std::max(a, b);  // ~high < 0 <= high
      int* const first = other.get() + start[low];
      int* const last = other.get() + fill_[low];
      for (int* e = first; e != last; ++e) {
        if (*e == high) {  // the second use: no longer a border edge
          *e = ~high;
          --border;
          return;
        }
        if (*e == ~high) return;  // a third or later use
      }
      *last = high;
      ++fill_[low];
      ++border;
    };
    for (const Face& f : mesh_.face) {
      const std::array<int, 3> c = cornersOf(f);
      place(c[0], c[1]);
      place(c[1], c[2]);
      place(c[2], c[0]);
    }
    return border;
  }

 private:
  std::array<int, 3> cornersOf(const Face& f) const {
    return {int(f.cV(0) - base_), int(f.cV(1) - base_), int(f.cV(2) - base_)};
  }
  const Mesh& mesh_;
  const Vertex* base_;
  std::vector<int> fill_;
};

}  // namespace

std::size_t countBorderEdges(const Mesh& mesh) {
  BorderEdgeCounter counter(mesh);
  for (const Face& f : mesh.face) counter.tally(f);
  return counter.count();
}

namespace {

// The output stage (output_stage.h) on `mesh` once an operation added the
// vertices from `firstNew` on and changed the faces marked `changed` (new
// faces beyond its size): the positions as the host stores them, the new
// vertices re-rounded where rounding made a changed face cross. Nothing to
// store for a double host without new vertices.
StoredOutput storeStitched(Mesh& mesh, std::size_t firstNew, std::vector<char> changed,
                           bool roundToFloat) {
  StoredOutput stored;
  stored.scalar = roundToFloat ? Scalar::kFloat : Scalar::kDouble;
  if (!roundToFloat && firstNew >= mesh.vert.size()) return stored;
  std::vector<Point3> P = positionsOf(mesh);
  const std::vector<Triangle> T = trianglesOf(mesh);
  std::vector<char> movable(P.size(), 0);
  for (std::size_t v = firstNew; v < P.size(); ++v) movable[v] = 1;
  changed.resize(T.size(), 1);
  OutputStageOptions stage;
  stage.scalar = stored.scalar;
  stored = storeNewPoints(P, T, movable, changed, stage);
  for (std::size_t v = 0; v < P.size(); ++v) mesh.vert[v].P() = P[v];
  return stored;
}

}  // namespace

StitchResult stitchPaths(Mesh& mesh, const StitchOptions& options) {
  const auto start = Clock::now();
  requireFacesAndFiniteCoordinates(mesh, "the mesh");
  requireCompact(mesh);
  if (options.max_aspect_ratio < 0 || options.max_rows < 0)
    throw InvalidInputError("max_aspect_ratio and max_rows must not be negative");
  reportProgress(options.progress, 0, "Planning the stitch");
  StitchResult r;
  // Room for the new faces (at most one per path vertex) and their
  // provenance, its memory touched by a resize up and back, so that writing
  // them does not stop at every fresh page: the provenance here, the faces
  // on the second core while the plan reads the faces around the paths. A
  // larger copy of the faces is made there (the mesh's border edges counted
  // in the same reading, for the report) and swapped in once the plan no
  // longer reads the faces: copying into a larger array is most of the cost
  // of adding faces.
  const std::size_t faces = mesh.face.size();
  const std::size_t room = faces + options.a.vertices.size() + options.b.vertices.size();
  {
    auto& origins = faceOrigins(mesh)._handle->data;
    origins.reserve(room);
    origins.resize(room);
    origins.resize(faces);
  }
  std::promise<void> facesFree;
  bool freed = false;
  auto release = [&] {
    if (!freed) facesFree.set_value();
    freed = true;
  };
  auto secondCore = [&mesh, free = facesFree.get_future(), faces, room] {
    const auto t = Clock::now();
    BorderEdgeCounter counter(mesh);
    std::vector<Face> larger;
    larger.reserve(room);
    for (const Face& f : mesh.face) {
      larger.push_back(f);
      counter.tally(f);
    }
    const std::size_t count = counter.count();
    const double ms = msSince(t);
    larger.resize(room);
    larger.resize(faces);
    free.wait();
    mesh.face.swap(larger);
    return std::make_pair(count, ms);
  };
  auto background = std::async(std::launch::async, std::move(secondCore));
  StitchPlan plan;
  try {
    auto clock = Clock::now();
    plan = planStitch(mesh, options, [&] {
      if (!options.check_intersections) release();
    });
    r.stage_ms.plan = msSince(clock);
    if (options.check_intersections) {
      reportProgress(options.progress, 50, "Checking intersections");
      clock = Clock::now();
      r.new_intersecting_pairs = newIntersections(mesh, plan);
      r.checked = true;
      r.stage_ms.check = msSince(clock);
    }
  } catch (...) {
    release();  // the second thread finishes before the error leaves
    throw;
  }
  release();
  reportProgress(options.progress, 90, "Writing");
  std::tie(r.border_edges_before, r.stage_ms.count) = background.get();
  const auto clock = Clock::now();
  const std::size_t verticesBefore = mesh.vert.size(), facesBefore = mesh.face.size();
  applyPlan(mesh, plan, r);
  r.stored = storeStitched(mesh, verticesBefore, std::vector<char>(facesBefore, 0),
                           options.round_to_float);
  if (r.checked && (r.stored.vertices_rerounded > 0 || options.round_to_float))
    r.new_intersecting_pairs = r.stored.crossing;  // as stored
  r.stage_ms.write = msSince(clock);
  r.border_edges_after = std::size_t(long(r.border_edges_before) + plan.borderDelta);
  reportProgress(options.progress, 100, "Done");
  r.time_ms = msSince(start);
  return r;
}

namespace {

// Path p oriented to end at vertex x (an end of p, or one border edge
// beyond it): the path, or empty when p does not reach x.
std::vector<int> endingAt(const std::vector<int>& p, int x, const LocalEdges& edges) {
  std::vector<int> v = p;
  if (v.back() == x) return v;
  if (v.front() == x) {
    std::reverse(v.begin(), v.end());
    return v;
  }
  if (edges.uses(x, v.back()) == 1) {
    v.push_back(x);
    return v;
  }
  if (edges.uses(x, v.front()) == 1) {
    std::reverse(v.begin(), v.end());
    v.push_back(x);
    return v;
  }
  return {};
}

}  // namespace

StitchSequenceResult stitchPathsSequence(Mesh& mesh, const StitchSequenceOptions& options) {
  const auto start = Clock::now();
  requireFacesAndFiniteCoordinates(mesh, "the mesh");
  requireCompact(mesh);
  StitchSequenceResult result;
  const int count = int(options.paths.size());
  // Working copy: the mesh is unchanged when a step throws.
  Mesh work = mesh;
  std::vector<std::vector<int>> paths;
  std::vector<BorderPath::Shape> shapes;
  for (const BorderPath& p : options.paths) {
    paths.push_back(p.vertices);
    shapes.push_back(p.shape);
  }
  std::vector<int> owner(count);  // original index -> current path (union-find)
  std::iota(owner.begin(), owner.end(), 0);
  auto current = [&](int i) {
    while (owner[i] != i) i = owner[i] = owner[owner[i]];
    return i;
  };
  std::vector<char> used(count, 0);
  result.border_edges_before = countBorderEdges(work);
  for (std::size_t step = 0; step < options.pairs.size(); ++step) {
    const std::string where = "step " + std::to_string(step + 1) + ": ";
    const auto [ia, ib] = options.pairs[step];
    if (ia < 0 || ib < 0 || ia >= count || ib >= count)
      throw InvalidInputError(where + "path index out of range");
    const int ca = current(ia), cb = current(ib);
    if (ca == cb)
      throw InvalidInputError(where + "paths " + std::to_string(ia) + " and " + std::to_string(ib) +
                              " were concatenated into one path");
    if (used[ca] || used[cb])
      throw InvalidInputError(where + "a path was already stitched in an earlier step");
    StitchOptions so = options.stitch;
    so.a = BorderPath{paths[ca], shapes[ca]};
    so.b = BorderPath{paths[cb], shapes[cb]};
    so.progress = nullptr;
    reportProgress(options.stitch.progress, int(100 * step / options.pairs.size()), "Stitching");
    StitchResult r;
    try {
      r = stitchPaths(work, so);
    } catch (const TopologyError& e) {
      throw TopologyError(where + e.what());
    } catch (const InvalidInputError& e) {
      throw InvalidInputError(where + e.what());
    }
    used[ca] = used[cb] = 1;
    result.concatenated.emplace_back();
    if (options.concatenate && !r.closed) {
      // A remaining path ending at one end of the stitch on a's side and
      // another at the same end on b's side are joined through the rung.
      for (const auto& rung : {r.first_rung, r.last_rung}) {
        std::vector<int> candidates;
        for (int i = 0; i < count; ++i)
          if (current(i) == i && !used[i]) candidates.push_back(i);
        std::vector<int> probe;
        for (int i : candidates) probe.insert(probe.end(), paths[i].begin(), paths[i].end());
        probe.push_back(rung[0]);
        probe.push_back(rung[1]);
        const LocalEdges edges(work, probe);
        int u = -1, v = -1;
        std::vector<int> pu, pv;
        for (int i : candidates) {
          if (u < 0) {
            pu = endingAt(paths[i], rung[0], edges);
            if (!pu.empty()) {
              u = i;
              continue;
            }
          }
          if (v < 0) {
            pv = endingAt(paths[i], rung[1], edges);
            if (!pv.empty()) v = i;
          }
        }
        if (u < 0 || v < 0) continue;
        std::reverse(pv.begin(), pv.end());  // now starts at rung[1]
        pu.insert(pu.end(), pv.begin(), pv.end());
        paths[u] = pu;
        shapes[u] = BorderPath::Shape::Open;
        owner[v] = u;
        result.concatenated.back().push_back({u, v});
      }
    }
    result.faces_added += r.faces_added;
    result.vertices_added += r.vertices_added;
    result.new_intersecting_pairs += r.new_intersecting_pairs;
    result.steps.push_back(r);
  }
  result.border_edges_after = countBorderEdges(work);
  mesh = work;
  result.time_ms = msSince(start);
  return result;
}

std::vector<BorderPath> borderPathsFromSelection(const Mesh& mesh,
                                                 const std::vector<bool>& selected) {
  if (selected.size() != mesh.vert.size())
    throw InvalidInputError("the selection has " + std::to_string(selected.size()) + " flags for " +
                            std::to_string(mesh.vert.size()) + " vertices");
  const std::vector<Triangle> T = trianglesOf(mesh);
  const std::vector<EdgeUse> uses = edgeUses(T);
  // Directed border edges between selected vertices: next / previous.
  std::unordered_map<int, int> next, prev;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    if (j - i == 1 && selected[uses[i].u] && selected[uses[i].v]) {
      const int a = T[uses[i].face][uses[i].corner], b = T[uses[i].face][(uses[i].corner + 1) % 3];
      // At a bow-tie vertex keep the first border edge out and in.
      if (!next.count(a) && !prev.count(b)) {
        next[a] = b;
        prev[b] = a;
      }
    }
    i = j;
  }
  std::vector<BorderPath> out;
  std::unordered_set<int> done;
  std::vector<int> starts;
  for (const auto& [a, b] : next) starts.push_back(a);
  std::sort(starts.begin(), starts.end());
  // Open runs start where no border edge comes in; then the loops.
  for (int pass = 0; pass < 2; ++pass)
    for (int s : starts) {
      if (done.count(s) || (pass == 0 && prev.count(s))) continue;
      BorderPath p;
      int v = s;
      while (true) {
        p.vertices.push_back(v);
        done.insert(v);
        const auto it = next.find(v);
        if (it == next.end()) break;
        v = it->second;
        if (v == s) {
          p.shape = BorderPath::Shape::Closed;
          break;
        }
        if (done.count(v)) {
          p.vertices.push_back(v);
          break;
        }
      }
      if (p.shape != BorderPath::Shape::Closed) p.shape = BorderPath::Shape::Open;
      out.push_back(p);
    }
  return out;
}

// ================================================================ gap closing

namespace {

// Points within a distance of a query: a uniform grid (cell = the
// distance), or exact coordinate buckets for distance 0.
class NearPoints {
 public:
  NearPoints(const std::vector<Point3>& points, const std::vector<int>& ids, double radius)
      : points_(points), radius_(radius) {
    for (int id : ids) cells_[keyOf(points[id])].push_back(id);
  }
  template <class Visit>
  void near(const Point3& q, Visit&& visit) const {
    if (radius_ <= 0) {
      const auto it = cells_.find(keyOf(q));
      if (it != cells_.end())
        for (int id : it->second)
          if (points_[id] == q) visit(id);
      return;
    }
    const auto c = cellOf(q);
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(hash({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (int id : it->second)
            if ((points_[id] - q).SquaredNorm() <= radius_ * radius_) visit(id);
        }
  }
  // Points within `radius` of q, which may exceed the cell (a few cells
  // further; a cell may be visited twice where two hash alike).
  template <class Visit>
  void near(const Point3& q, double radius, Visit&& visit) const {
    const long reach = std::max(1L, cellIndex(std::ceil(radius / radius_)));
    const auto c = cellOf(q);
    for (long dx = -reach; dx <= reach; ++dx)
      for (long dy = -reach; dy <= reach; ++dy)
        for (long dz = -reach; dz <= reach; ++dz) {
          const auto it = cells_.find(hash({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (int id : it->second)
            if ((points_[id] - q).SquaredNorm() <= radius * radius) visit(id);
        }
  }

 private:
  // A coordinate's cell, clamped to what a long holds (a coordinate over
  // the radius may overflow to infinity, and converting that is undefined).
  static long cellIndex(double x) {
    return x == x ? long(std::clamp(std::floor(x), -4e18, 4e18)) : 0;
  }
  std::array<long, 3> cellOf(const Point3& p) const {
    return {cellIndex(p[0] / radius_), cellIndex(p[1] / radius_), cellIndex(p[2] / radius_)};
  }
  static std::uint64_t hash(const std::array<long, 3>& c) {
    std::uint64_t h = 0;
    for (long x : c) h = (h ^ std::uint64_t(x)) * 0x9E3779B97F4A7C15ull, h ^= h >> 29;
    return h;
  }
  std::uint64_t keyOf(const Point3& p) const {
    if (radius_ > 0) return hash(cellOf(p));
    std::uint64_t h = 0;
    for (int k = 0; k < 3; ++k) {
      const double x = p[k] == 0 ? 0.0 : p[k];
      std::uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      h = (h ^ bits) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 32;
    }
    return h;
  }
  const std::vector<Point3>& points_;
  double radius_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

struct BorderEdge {
  int from, to, face;
};

std::vector<BorderEdge> borderEdgesDirected(const std::vector<Triangle>& T) {
  const std::vector<EdgeUse> uses = edgeUses(T);
  std::vector<BorderEdge> out;
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

// Union-find over indices, with path halving.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int root(int v) {
    while (parent_[v] != v) v = parent_[v] = parent_[parent_[v]];
    return v;
  }
  void join(int from, int into) { parent_[root(from)] = root(into); }

 private:
  std::vector<int> parent_;
};

// Border vertices that coincide (exactly, or within the tolerance, through
// chains of such pairs) share a class: classOf[v] is its representative,
// v itself for a vertex on no border edge.
std::vector<int> coincidenceClasses(const std::vector<Point3>& P,
                                    const std::vector<BorderEdge>& border, double tolerance) {
  const int n = int(P.size());
  std::vector<int> borderVertices;
  {
    std::vector<char> on(n, 0);
    for (const BorderEdge& e : border) on[e.from] = on[e.to] = 1;
    for (int v = 0; v < n; ++v)
      if (on[v]) borderVertices.push_back(v);
  }
  DisjointSets sets(P.size());
  const NearPoints near(P, borderVertices, tolerance);
  for (int v : borderVertices) near.near(P[v], [&](int w) { sets.join(w, v); });
  std::vector<int> classOf(n);
  for (int v = 0; v < n; ++v) classOf[v] = sets.root(v);
  return classOf;
}

// Faces flipped so that faces meeting at an edge run it opposite ways,
// where "meeting" counts coincident border vertices as one: the facets of a
// soup whose neighbours face the other way (some CAD exports) can then be
// merged. Only edges with exactly two faces propagate the orientation. A
// connected part that needed no flip is left as it is; one that did keeps,
// if it is closed (every edge has a second face), the orientation whose
// signed volume is positive (outward), else the orientation of most of its
// area as given.
void orientConsistently(const std::vector<Point3>& P, std::vector<Triangle>& T,
                        const std::vector<int>& classOf, CloseGapsResult& r) {
  const std::size_t m = T.size();
  std::vector<Triangle> G(m);
  for (std::size_t f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) G[f][k] = classOf[T[f][k]];
  const std::vector<EdgeUse> uses = edgeUses(G);
  // Neighbours across two-face edges: (face, same direction?).
  std::vector<int> start(m + 1, 0);
  std::vector<char> open(m, 0);  // has an edge with one face
  auto forEachPair = [&](auto&& visit) {
    for (std::size_t i = 0; i < uses.size();) {
      std::size_t j = i + 1;
      while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
      if (uses[i].u != uses[i].v) {
        if (j - i == 1) open[uses[i].face] = 1;
        if (j - i == 2 && uses[i].face != uses[i + 1].face) {
          const bool same = (G[uses[i].face][uses[i].corner] == uses[i].u) ==
                            (G[uses[i + 1].face][uses[i + 1].corner] == uses[i + 1].u);
          visit(uses[i].face, uses[i + 1].face, same);
        }
      }
      i = j;
    }
  };
  forEachPair([&](int f, int g, bool) { ++start[f + 1], ++start[g + 1]; });
  for (std::size_t f = 0; f < m; ++f) start[f + 1] += start[f];
  std::vector<std::pair<int, bool>> next(start.back());
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    forEachPair([&](int f, int g, bool same) {
      next[fill[f]++] = {g, same};
      next[fill[g]++] = {f, same};
    });
  }
  std::vector<char> flip(m, 0), seen(m, 0);
  std::vector<int> part;
  for (std::size_t seed = 0; seed < m; ++seed) {
    if (seen[seed]) continue;
    part.assign(1, int(seed));
    seen[seed] = 1;
    for (std::size_t k = 0; k < part.size(); ++k) {
      const int f = part[k];
      for (int i = start[f]; i < start[f + 1]; ++i) {
        const auto [g, same] = next[i];
        const char want = char(flip[f] ^ char(same));
        if (!seen[g]) {
          seen[g] = 1;
          flip[g] = want;
          part.push_back(g);
        } else if (flip[g] != want && f < g) {
          ++r.orientation_conflicts;
        }
      }
    }
    if (std::none_of(part.begin(), part.end(), [&](int f) { return flip[f]; })) continue;
    bool closed = true;
    double keptArea = 0, flippedArea = 0, volume = 0;
    const Point3 centre = P[T[part[0]][0]];
    for (int f : part) {
      const Point3 a = P[T[f][0]] - centre, b = P[T[f][1]] - centre, c = P[T[f][2]] - centre;
      const double area = ((b - a) ^ (c - a)).Norm();
      (flip[f] ? flippedArea : keptArea) += area;
      const double v = a * (b ^ c);
      volume += flip[f] ? -v : v;
      closed = closed && !open[f];
    }
    const bool turn = closed ? volume < 0 : flippedArea > keptArea;
    for (int f : part) flip[f] ^= char(turn);
  }
  for (std::size_t f = 0; f < m; ++f)
    if (flip[f]) {
      std::swap(T[f][1], T[f][2]);
      ++r.faces_flipped;
    }
}

// Step 1: border edges that coincide (within the tolerance) and run
// opposite ways become one edge, and border edges whose ends coincide
// collapse (their face, of zero area within the tolerance, goes). Where
// more than two border edges coincide (solids that touch along an edge),
// each is paired with the next one around the edge behind its face, so
// that each solid closes on its own. Merge by merge, each is kept only if
// it leaves every edge it touches with at most two faces running it
// opposite ways. Vertices merge only through these edges: coincident
// vertices whose faces do not join stay apart (a vertex split).
void mergeCoincidentBorders(const std::vector<Point3>& P, std::vector<Triangle>& T,
                            const std::vector<int>& classOf, std::vector<char>& removedFace,
                            std::vector<int>& target, CloseGapsResult& r) {
  const int n = int(P.size());
  target.resize(n);
  std::iota(target.begin(), target.end(), 0);
  removedFace.assign(T.size(), 0);
  const std::vector<BorderEdge> border = borderEdgesDirected(T);
  // Requested merges: pairs of border edges, or one edge to collapse (e2 < 0).
  std::vector<std::array<int, 2>> requests;
  for (std::size_t e = 0; e < border.size(); ++e)
    if (classOf[border[e].from] == classOf[border[e].to]) requests.push_back({int(e), -1});
  {
    std::vector<std::pair<std::uint64_t, int>> byKey;
    for (std::size_t e = 0; e < border.size(); ++e) {
      const int a = classOf[border[e].from], b = classOf[border[e].to];
      if (a != b) byKey.push_back({undirectedKey(a, b), int(e)});
    }
    std::sort(byKey.begin(), byKey.end());
    for (std::size_t i = 0; i < byKey.size();) {
      std::size_t j = i + 1;
      while (j < byKey.size() && byKey[j].first == byKey[i].first) ++j;
      const std::size_t count = j - i;
      if (count == 2) {
        const BorderEdge &x = border[byKey[i].second], &y = border[byKey[i + 1].second];
        if (classOf[x.from] == classOf[y.to])
          requests.push_back({byKey[i].second, byKey[i + 1].second});
      } else if (count > 2) {
        // Around the edge from class lo to class hi: each use's face apex at
        // an angle; a face running lo -> hi faces towards larger angles,
        // so its inside is its predecessor, which must run hi -> lo.
        const int lo = int(byKey[i].first >> 32);
        const BorderEdge& first = border[byKey[i].second];
        const Point3 origin = P[classOf[first.from] == lo ? first.from : first.to];
        Point3 axis = P[classOf[first.from] == lo ? first.to : first.from] - origin;
        axis.Normalize();
        Point3 u = std::abs(axis[0]) < 0.9 ? Point3(1, 0, 0) ^ axis : Point3(0, 1, 0) ^ axis;
        u.Normalize();
        const Point3 w = axis ^ u;
        struct Around {
          double angle;
          int edge;
          bool forward;
        };
        std::vector<Around> around;
        for (std::size_t k = i; k < j; ++k) {
          const BorderEdge& e = border[byKey[k].second];
          const Triangle& t = T[e.face];
          const int apex = t[0] != e.from && t[0] != e.to   ? t[0]
                           : t[1] != e.from && t[1] != e.to ? t[1]
                                                            : t[2];
          const Point3 d = P[apex] - origin;
          around.push_back({std::atan2(d * w, d * u), byKey[k].second, classOf[e.from] == lo});
        }
        std::sort(around.begin(), around.end(),
                  [](const Around& x, const Around& y) { return x.angle < y.angle; });
        for (std::size_t k = 0; k < around.size(); ++k) {
          const Around& behind = around[(k + around.size() - 1) % around.size()];
          if (around[k].forward && !behind.forward)
            requests.push_back({around[k].edge, behind.edge});
        }
      }
      i = j;
    }
  }
  if (requests.empty()) return;

  // Faces per vertex (a merged vertex's go to the vertex it joins).
  std::vector<std::vector<int>> facesOf(n);
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int v : T[f]) facesOf[v].push_back(int(f));
  DisjointSets sets(P.size());
  std::vector<int> affected;
  std::vector<Triangle> changed;
  std::vector<char> collapses;
  for (const auto& [e1, e2] : requests) {
    // e1 = a -> b, e2 = c -> d: d joins a, c joins b; a collapse: b joins a.
    const int a = sets.root(border[e1].from), b = sets.root(border[e1].to);
    int from[2], to[2], joins = 0;
    auto join = [&](int x, int y) {
      if (x != y) from[joins] = x, to[joins++] = y;
    };
    if (e2 < 0) {
      join(b, a);
    } else {
      join(sets.root(border[e2].to), a);
      join(sets.root(border[e2].from), b);
      if (joins == 2 && from[0] == to[1] && from[1] == to[0]) continue;  // crossed: a <-> b
    }
    if (joins == 0) {  // done by the merges before
      if (e2 >= 0) ++r.edges_merged;
      continue;
    }
    auto mapped = [&](int v) {  // at most two steps (c -> b -> a)
      for (int step = 0; step < 2; ++step)
        for (int k = 0; k < joins; ++k)
          if (v == from[k]) {
            v = to[k];
            break;
          }
      return v;
    };
    affected.clear();
    for (int k = 0; k < joins; ++k)
      for (int f : facesOf[from[k]])
        if (!removedFace[f]) affected.push_back(f);
    std::sort(affected.begin(), affected.end());
    affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
    changed.clear();
    collapses.clear();
    for (int f : affected) {
      const Triangle t{mapped(T[f][0]), mapped(T[f][1]), mapped(T[f][2])};
      changed.push_back(t);
      collapses.push_back(t[0] == t[1] || t[1] == t[2] || t[2] == t[0]);
    }
    // Every edge of a changed face, with the faces it has after the merge:
    // those of its first end and of the vertices joining that end.
    auto faceAfter = [&](int f, const Triangle*& t) {
      const auto it = std::lower_bound(affected.begin(), affected.end(), f);
      if (it == affected.end() || *it != f) {
        t = &T[f];
        return true;
      }
      const std::size_t k = std::size_t(it - affected.begin());
      t = &changed[k];
      return !collapses[k];
    };
    auto usesOf = [&](int u, int v, int& forward, int& backward) {
      forward = backward = 0;
      auto visit = [&](const std::vector<int>& faces) {
        for (int f : faces) {
          const Triangle* t = nullptr;
          if (removedFace[f] || !faceAfter(f, t)) continue;
          for (int i = 0; i < 3; ++i) {
            if ((*t)[i] == u && (*t)[(i + 1) % 3] == v) ++forward;
            if ((*t)[i] == v && (*t)[(i + 1) % 3] == u) ++backward;
          }
        }
      };
      visit(facesOf[u]);
      for (int k = 0; k < joins; ++k)
        if (mapped(from[k]) == u) visit(facesOf[from[k]]);
    };
    bool ok = true;
    for (std::size_t k = 0; k < changed.size() && ok; ++k) {
      if (collapses[k]) continue;
      for (int i = 0; i < 3 && ok; ++i) {
        int forward, backward;
        usesOf(changed[k][i], changed[k][(i + 1) % 3], forward, backward);
        ok = forward <= 1 && forward + backward <= 2;
      }
    }
    if (!ok) {
      ++r.merges_skipped;
      continue;
    }
    for (std::size_t k = 0; k < affected.size(); ++k) {
      T[affected[k]] = changed[k];
      if (collapses[k]) {
        removedFace[affected[k]] = 1;
        ++r.degenerate_faces_removed;
      }
    }
    for (int k = 0; k < joins; ++k) {
      const int into = mapped(from[k]);
      sets.join(from[k], into);
      facesOf[into].insert(facesOf[into].end(), facesOf[from[k]].begin(), facesOf[from[k]].end());
      facesOf[from[k]].clear();
      ++r.vertices_merged;
    }
    if (e2 >= 0) ++r.edges_merged;
  }
  for (int v = 0; v < n; ++v) target[v] = sets.root(v);
}

// Step 2: runs of border vertices facing another run within the bound. A
// border vertex's partner is its nearest border vertex within the bound
// that lies in front of it (away from its faces, within about 100 degrees
// of the direction across its border) and is on another border loop, or
// far along its own loop (the two sides of a crack: at least twice as far
// along the loop as straight across, more than between any two points of a
// convex hole's border, where it is at most pi/2). Runs of consecutive vertices
// of one loop whose partners are on one loop face the run there holding
// most of those partners. On one loop, two runs whose ends meet at a crack's
// tip (the same vertex, or the two ends of one border edge) are extended
// to it, so that stitching them closes the crack. Pairs with a path of
// fewer than minPathVertices vertices are left out.
// The bound: `bound`, or, between two vertices of one part (joined by
// faces: a slit or crack, not a gap between separate parts), localFactor x
// the mean length of the border edges at either vertex, whichever is
// smaller (at most four times the typical local bound: a few long border
// edges do not widen the search everywhere).
std::vector<GapReport> facingBorders(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                                     double bound, double localFactor, int minPathVertices) {
  const BorderLoops found = findBorderLoops(P, T);
  const std::vector<BorderLoop>& loops = found.loops;
  const std::size_t n = P.size();
  std::vector<int> loopOf(n, -1), positionOf(n, -1);
  std::vector<int> ids;
  std::vector<std::vector<double>> arc(loops.size());  // arc length from the loop's start
  for (std::size_t l = 0; l < loops.size(); ++l) {
    const std::vector<int>& loop = loops[l].vertices;
    arc[l].assign(loop.size() + 1, 0);
    for (std::size_t k = 0; k < loop.size(); ++k) {
      if (loopOf[loop[k]] < 0) {
        loopOf[loop[k]] = int(l);
        positionOf[loop[k]] = int(k);
        ids.push_back(loop[k]);
      }
      const int next = loop[(k + 1) % loop.size()];
      const bool wraps = k + 1 == loop.size();
      arc[l][k + 1] = arc[l][k] + (wraps && !loops[l].closed ? 0.0 : (P[next] - P[loop[k]]).Norm());
    }
  }
  // Across each border edge, away from its face, in the face's plane; and
  // the lengths of the border edges at each vertex.
  std::vector<Point3> outward(n, Point3(0, 0, 0));
  std::vector<double> borderLength(n, 0);
  std::vector<int> borderEdges(n, 0);
  for (const BorderEdge& e : borderEdgesDirected(T)) {
    const double edgeLength = (P[e.to] - P[e.from]).Norm();
    for (const int v : {e.from, e.to}) {
      borderLength[v] += edgeLength;
      ++borderEdges[v];
    }
    const Triangle& t = T[e.face];
    const Point3 normal = (P[t[1]] - P[t[0]]) ^ (P[t[2]] - P[t[0]]);
    Point3 across = (P[e.to] - P[e.from]) ^ normal;
    const double length = across.Norm();
    if (length > 0) {
      across /= length;
      outward[e.from] += across;
      outward[e.to] += across;
    }
  }
  auto alongLoop = [&](int l, int i, int j) {
    const double d = std::abs(arc[l][i] - arc[l][j]);
    return loops[l].closed ? std::min(d, arc[l].back() - d) : d;
  };
  auto localBound = [&](int v) {
    return borderEdges[v] > 0 ? localFactor * borderLength[v] / borderEdges[v] : 0.0;
  };
  // Parts: vertices joined through faces.
  std::vector<int> part(n);
  std::iota(part.begin(), part.end(), 0);
  auto partOf = [&](int v) {
    while (part[v] != v) v = part[v] = part[part[v]];
    return v;
  };
  for (const Triangle& t : T)
    for (int k = 1; k < 3; ++k) part[partOf(t[k])] = partOf(t[0]);
  // The grid's cell: the bound, or the typical (median) local bound if larger.
  double cell = bound;
  if (localFactor > 0 && !ids.empty()) {
    std::vector<double> locals;
    for (int v : ids) locals.push_back(localBound(v));
    std::nth_element(locals.begin(), locals.begin() + locals.size() / 2, locals.end());
    cell = std::max(cell, locals[locals.size() / 2]);
  }
  if (!(cell > 0)) return {};
  const NearPoints near(P, ids, cell);
  std::vector<int> partnerOf(n, -1);
  for (int v : ids) {
    double best = INFINITY;
    const int l = loopOf[v];
    const double radius = std::min(std::max(bound, localBound(v)), 4 * cell);
    near.near(P[v], radius, [&](int w) {
      if (w == v) return;
      const Point3 d = P[w] - P[v];
      const double distance = d.Norm();
      if (distance > bound &&
          (partOf(v) != partOf(w) || distance > std::min(localBound(v), localBound(w))))
        return;
      if (loopOf[w] == l) {
        const double along = alongLoop(l, positionOf[v], positionOf[w]);
        if (along <= 0 || along < 2 * distance) return;
      }
      const double facing = d * outward[v];
      if (facing < -0.2 * distance * outward[v].Norm()) return;
      if (distance < best) best = distance, partnerOf[v] = w;
    });
  }
  // Runs of loop l whose partners are on loop `other`, in the loop's order.
  auto runsOf = [&](int l, int other) {
    std::vector<std::vector<int>> runs;
    const std::vector<int>& loop = loops[l].vertices;
    const std::size_t m = loop.size();
    auto facing = [&](std::size_t k) {
      const int w = partnerOf[loop[k % m]];
      return w >= 0 && loopOf[w] == other;
    };
    std::size_t first = 0;
    if (loops[l].closed) {
      while (first < m && facing(first)) ++first;
      if (first == m) return std::vector<std::vector<int>>{loop};  // the whole loop
    }
    const std::size_t end = loops[l].closed ? first + m : m;
    for (std::size_t k = first; k < end; ++k) {
      if (!facing(k)) continue;
      std::vector<int> run;
      while (k < end && facing(k)) run.push_back(loop[k++ % m]);
      runs.push_back(run);
    }
    return runs;
  };
  std::vector<std::array<int, 2>> loopPairs;
  {
    std::set<std::array<int, 2>> seen;
    for (int v : ids)
      if (const int w = partnerOf[v]; w >= 0) {
        const std::array<int, 2> key{std::min(loopOf[v], loopOf[w]),
                                     std::max(loopOf[v], loopOf[w])};
        if (seen.insert(key).second) loopPairs.push_back(key);
      }
  }
  std::vector<GapReport> gaps;
  for (const auto& [l1, l2] : loopPairs) {
    const auto runs1 = runsOf(l1, l2);
    const auto runs2 = l1 == l2 ? runs1 : runsOf(l2, l1);
    const bool whole1 = runs1.size() == 1 && runs1[0].size() == loops[l1].vertices.size();
    const bool whole2 = runs2.size() == 1 && runs2[0].size() == loops[l2].vertices.size();
    std::unordered_map<int, int> runOf2;
    for (std::size_t k = 0; k < runs2.size(); ++k)
      for (int v : runs2[k]) runOf2[v] = int(k);
    std::vector<char> taken(runs2.size(), 0);
    for (std::size_t k1 = 0; k1 < runs1.size(); ++k1) {
      if (l1 == l2 && taken[k1]) continue;
      const std::vector<int>& run = runs1[k1];
      std::vector<int> votes(runs2.size(), 0);
      for (int v : run) {
        const auto it = runOf2.find(partnerOf[v]);
        if (it != runOf2.end()) ++votes[it->second];
      }
      if (l1 == l2) votes[k1] = 0;  // a run does not face itself
      if (votes.empty()) continue;
      const int k2 = int(std::max_element(votes.begin(), votes.end()) - votes.begin());
      if (votes[k2] == 0 || taken[k2]) continue;
      taken[k2] = 1;
      if (l1 == l2) taken[k1] = 1;
      GapReport g;
      g.closed = l1 != l2 && whole1 && whole2;
      g.path_a = run;
      g.path_b = runs2[k2];
      for (int v : g.path_a)
        if (partnerOf[v] >= 0) g.gap = std::max(g.gap, (P[partnerOf[v]] - P[v]).Norm());
      if (l1 != l2 && (whole1 || whole2) && !g.closed)
        g.reason = "a whole border loop faces only part of another loop";
      auto onLoop = [&](int v) { return loopOf[v] == l1; };
      if (l1 == l2 && loops[l1].closed && onLoop(g.path_a.front()) && onLoop(g.path_a.back()) &&
          onLoop(g.path_b.front()) && onLoop(g.path_b.back())) {
        // a runs forward along the loop beside b running backward: a's
        // start meets b's end, a's end meets b's start.
        const std::vector<int>& loop = loops[l1].vertices;
        const int m = int(loop.size());
        auto at = [&](int k) { return loop[((k % m) + m) % m]; };
        std::unordered_set<int> used(g.path_a.begin(), g.path_a.end());
        used.insert(g.path_b.begin(), g.path_b.end());
        const int p = at(positionOf[g.path_a.front()] - 1), q = at(positionOf[g.path_b.back()] + 1);
        if (!used.count(p) && !used.count(q) && (p == q || at(positionOf[q] + 1) == p)) {
          g.path_a.insert(g.path_a.begin(), p);
          g.path_b.push_back(q);
          used.insert(p);
          used.insert(q);
        }
        const int s = at(positionOf[g.path_a.back()] + 1), t = at(positionOf[g.path_b.front()] - 1);
        if (!used.count(s) && !used.count(t) && (s == t || at(positionOf[s] + 1) == t)) {
          g.path_a.push_back(s);
          g.path_b.insert(g.path_b.begin(), t);
        }
      }
      if (int(std::min(g.path_a.size(), g.path_b.size())) < minPathVertices) continue;
      gaps.push_back(g);
    }
  }
  return gaps;
}

}  // namespace

CloseGapsResult closeGaps(Mesh& mesh, const CloseGapsOptions& options) {
  const auto start = Clock::now();
  requireFacesAndFiniteCoordinates(mesh, "the mesh");
  requireCompact(mesh);
  if (!(options.merge_tolerance >= 0) || !(options.max_gap >= 0) ||
      !(options.local_gap_factor >= 0) || !(options.max_aspect_ratio >= 0))
    throw InvalidInputError(
        "merge_tolerance, max_gap, local_gap_factor and max_aspect_ratio must not be negative");
  CloseGapsResult r;
  std::vector<Point3> P = positionsOf(mesh);
  std::vector<Triangle> T = trianglesOf(mesh);
  r.border_edges_before = borderEdgesOf(T);
  double scale = 1;
  if (!options.absolute_distances) {
    vcg::Box3d box;
    for (const Point3& p : P) box.Add(p);
    scale = box.Diag();
  }
  r.merge_tolerance = options.merge_tolerance * scale;
  r.max_gap = options.max_gap * scale;

  // ---- Step 1: orient, merge coincident borders.
  reportProgress(options.progress, 0, "Merging coincident borders");
  const std::vector<int> classOf = coincidenceClasses(P, borderEdgesDirected(T), r.merge_tolerance);
  if (options.orient_faces) orientConsistently(P, T, classOf, r);
  std::vector<char> removedFace;
  std::vector<int> target;
  mergeCoincidentBorders(P, T, classOf, removedFace, target, r);
  const int n = int(P.size());
  r.vertex_index.assign(n, -1);
  std::vector<char> changedFace(T.size(), 0);  // corners merged (for the check)
  if (r.vertices_merged > 0 || r.faces_flipped > 0) {
    VertexOriginHandle vo = vertexOrigins(mesh);
    FaceOriginHandle fo = faceOrigins(mesh);
    std::vector<Point3> points;
    std::vector<VertexOrigin> vorig;
    for (int v = 0; v < n; ++v)
      if (target[v] == v) {
        r.vertex_index[v] = int(points.size());
        points.push_back(P[v]);
        vorig.push_back(vo[v]);
      }
    for (int v = 0; v < n; ++v) r.vertex_index[v] = r.vertex_index[target[v]];
    std::vector<Triangle> kept;
    std::vector<FaceOrigin> forig;
    std::vector<char> keptChanged;
    const std::vector<Triangle> input = trianglesOf(mesh);
    for (std::size_t f = 0; f < T.size(); ++f) {
      if (removedFace[f]) continue;
      bool merged = false;
      for (int k = 0; k < 3; ++k) merged = merged || target[input[f][k]] != input[f][k];
      kept.push_back({r.vertex_index[T[f][0]], r.vertex_index[T[f][1]], r.vertex_index[T[f][2]]});
      forig.push_back(fo[f]);
      keptChanged.push_back(merged);
    }
    buildMesh(mesh, points, kept, vorig, forig);
    P = points;
    T = kept;
    changedFace = keptChanged;
  } else {
    std::iota(r.vertex_index.begin(), r.vertex_index.end(), 0);
  }
  r.border_edges_after_merge = borderEdgesOf(T);
  r.border_edges_after = r.border_edges_after_merge;
  const std::size_t verticesAfterMerge = mesh.vert.size();

  // ---- Step 2: facing borders, in rounds: a stitch can leave borders that
  // face each other anew (the rest of an L-shaped slit), so they are looked
  // for again until a round stitches nothing.
  if (r.max_gap > 0) {
    constexpr int kRounds = 8;
    std::set<std::pair<std::vector<int>, std::vector<int>>> reported;
    for (int round = 0; round < kRounds; ++round) {
      reportProgress(options.progress, 30 + 60 * round / kRounds, "Finding facing borders");
      std::vector<GapReport> gaps =
          facingBorders(positionsOf(mesh), trianglesOf(mesh), r.max_gap, options.local_gap_factor,
                        options.min_path_vertices);
      std::size_t stitched = 0;
      // Stitch each pair on the current mesh (earlier stitches change borders).
      for (GapReport& g : gaps) {
        if (!reported.insert({g.path_a, g.path_b}).second) continue;  // left open before
        ++r.gaps_found;
        if (g.reason.empty()) {
          StitchOptions so;
          so.a = {g.path_a, g.closed ? BorderPath::Shape::Closed : BorderPath::Shape::Open};
          so.b = {g.path_b, g.closed ? BorderPath::Shape::Closed : BorderPath::Shape::Open};
          so.max_aspect_ratio = options.max_aspect_ratio;
          so.round_to_float = options.round_to_float;
          try {
            const StitchPlan plan = planStitch(mesh, so);
            if (plan.conflicts > 0) {
              g.reason = "the two sides are inconsistently oriented";
            } else if (options.check_intersections && newIntersections(mesh, plan) > 0) {
              g.reason = "the stitch would intersect the mesh";
            } else {
              StitchResult sr;
              applyPlan(mesh, plan, sr);
              g.stitched = true;
              g.faces_added = sr.faces_added;
              r.faces_added += sr.faces_added;
              r.vertices_added += sr.vertices_added;
              r.border_edges_after = std::size_t(long(r.border_edges_after) + plan.borderDelta);
              ++r.gaps_stitched;
              ++stitched;
            }
          } catch (const Error& e) {
            g.reason = e.what();
          }
        }
        r.gaps.push_back(std::move(g));
      }
      if (stitched == 0) break;
    }
  }
  // ---- The output stage: new vertices (subdivided strips) as stored.
  r.stored = storeStitched(mesh, verticesAfterMerge, changedFace, options.round_to_float);
  // ---- The output's intersecting pairs: those that involve a merged or new
  // face, and all of them by the checker's rule.
  if (options.verify) {
    reportProgress(options.progress, 90, "Checking the result");
    changedFace.resize(mesh.face.size(), 1);
    const std::vector<Point3> points = positionsOf(mesh);
    const std::vector<Triangle> triangles = trianglesOf(mesh);
    r.new_intersecting_pairs =
        intersectingOf(points, triangles, pairsWithChangedFaces(points, triangles, changedFace))
            .size();
    r.remaining_intersecting_pairs =
        storedIntersectingPairs(MeshArrays{points, triangles}, r.stored.scalar);
    r.verified = true;
  }
  reportProgress(options.progress, 100, "Done");
  r.time_ms = msSince(start);
  return r;
}

// ================================================================ reports

JsonObject toJson(const TrimResult& r) {
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", 0)
      .set("vertices_merged", 0)
      .set("loop_vertices", r.loop.size())
      .set("faces_kept", r.faces_kept)
      .set("faces_removed", r.faces_removed)
      .set("faces_on_loop", r.faces_on_loop)
      .set("time_ms", r.time_ms);
  return j;
}

JsonObject toJson(const StitchResult& r) {
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", r.faces_added)
      .set("vertices_merged", 0)
      .set("vertices_added", r.vertices_added)
      .set("closed", r.closed)
      .set("reversed_b", r.reversed_b)
      .set("orientation_conflicts", r.orientation_conflicts)
      .set("max_aspect_ratio", r.max_aspect_ratio);
  if (r.checked) j.set("new_intersecting_pairs", r.new_intersecting_pairs);
  j.set("time_ms", r.time_ms);
  return j;
}

JsonObject toJson(const StitchSequenceResult& r) {
  std::vector<JsonObject> steps;
  for (const StitchResult& s : r.steps) steps.push_back(toJson(s));
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", r.faces_added)
      .set("vertices_merged", 0)
      .set("vertices_added", r.vertices_added)
      .set("new_intersecting_pairs", r.new_intersecting_pairs)
      .set("steps", steps)
      .set("time_ms", r.time_ms);
  return j;
}

EditContractOptions editContractOptions(const TrimOptions& options, bool keepPartial) {
  EditContractOptions c;
  c.count_pairs = false;  // trimming only removes faces: none is new
  c.keep_partial = keepPartial;
  c.progress = options.progress;
  return c;
}

EditContractOptions editContractOptions(const StitchOptions& options, bool keepPartial) {
  EditContractOptions c;
  c.as_float = options.round_to_float;
  c.count_pairs = options.check_intersections;
  c.allow_orientation_conflicts = options.allow_orientation_conflict;
  c.keep_partial = keepPartial;
  c.progress = options.progress;
  return c;
}

EditContractOptions editContractOptions(const CloseGapsOptions& options, bool keepPartial) {
  EditContractOptions c;
  c.as_float = options.round_to_float;
  c.count_pairs = true;
  c.keep_partial = keepPartial;
  c.progress = options.progress;
  return c;
}

bool changedAnything(const CloseGapsResult& r) {
  return r.vertices_merged > 0 || r.faces_added > 0 || r.faces_flipped > 0 ||
         r.degenerate_faces_removed > 0;
}

JsonObject toJson(const CloseGapsResult& r) {
  std::vector<JsonObject> gaps;
  for (const GapReport& g : r.gaps) {
    JsonObject o;
    o.set("path_a_vertices", g.path_a.size())
        .set("path_b_vertices", g.path_b.size())
        .set("closed", g.closed)
        .set("gap", g.gap)
        .set("stitched", g.stitched)
        .set("faces_added", g.faces_added);
    if (!g.reason.empty()) o.set("reason", g.reason);
    gaps.push_back(o);
  }
  JsonObject j;
  j.set("border_edges_before", r.border_edges_before)
      .set("border_edges_after", r.border_edges_after)
      .set("faces_added", r.faces_added)
      .set("vertices_merged", r.vertices_merged)
      .set("merge_tolerance", r.merge_tolerance)
      .set("max_gap", r.max_gap)
      .set("faces_flipped", r.faces_flipped)
      .set("orientation_conflicts", r.orientation_conflicts)
      .set("border_edges_after_merge", r.border_edges_after_merge)
      .set("edges_merged", r.edges_merged)
      .set("merges_skipped", r.merges_skipped)
      .set("degenerate_faces_removed", r.degenerate_faces_removed)
      .set("vertices_added", r.vertices_added)
      .set("gaps_found", r.gaps_found)
      .set("gaps_stitched", r.gaps_stitched);
  if (r.verified)
    j.set("new_intersecting_pairs", r.new_intersecting_pairs)
        .set("remaining_intersecting_pairs", r.remaining_intersecting_pairs);
  j.set("gaps", gaps).set("time_ms", r.time_ms);
  return j;
}

}  // namespace meshmend
