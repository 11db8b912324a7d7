// A sequence of stitches between border paths that meet end to end, and
// the border paths of a selection.
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

}  // namespace meshmend
