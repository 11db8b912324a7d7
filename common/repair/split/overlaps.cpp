// Coincident faces: twins in the merged output (overlapping surfaces cut
// alike) kept once, and repeated faces of an input removed before the split.
#include <algorithm>
#include <tuple>
#include <vector>

#include "common/repair/split/detail.h"

namespace meshmend::split_detail {

// Where meshes (or one mesh and itself) overlap in a plane, the contact
// inserts the edges of each side into the other, so both re-triangulate the
// overlap alike and, welded, their faces there coincide: the same three
// vertices twice (either orientation). This keeps each such face once in
// `merged` (McLaurin 2012's result is free of duplicate geometry)
// and returns how many it removed. Only faces whose corners are all curve
// vertices (`onCurve`) can have a twin: other vertices belong to one mesh.
// A curve edge inside an overlap (all its faces were twins) is then an
// ordinary edge of the one surface left there and leaves `curves` (sorted):
// the overlap's outline stays.
std::size_t keepOverlapsOnce(OutputArrays& merged, std::vector<char>& newFace,
                             const std::vector<char>& onCurve,
                             std::vector<std::array<int, 2>>& curves, bool remove) {
  std::vector<std::pair<Triangle, std::uint32_t>> corners;  // sorted corners, face
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    Triangle t = merged.triangles[f];
    if (!onCurve[t[0]] || !onCurve[t[1]] || !onCurve[t[2]]) continue;
    std::sort(t.begin(), t.end());
    corners.push_back({t, std::uint32_t(f)});
  }
  std::sort(corners.begin(), corners.end());
  enum : char { kSingle, kTwinKept, kTwinRemoved };
  std::vector<char> twin(merged.triangles.size(), kSingle);
  std::size_t removed = 0;
  for (std::size_t k = 1, first = 0; k < corners.size(); ++k) {
    if (corners[k].first != corners[first].first) {
      first = k;
      continue;
    }
    twin[corners[first].second] = kTwinKept;
    twin[corners[k].second] = kTwinRemoved;
    ++removed;
  }
  if (removed == 0 || !remove) return removed;  // (only counted)
  // A curve edge stays one where a face that had no twin uses it (the
  // overlap's outline), or where more than two faces are left on it (a
  // crossing inside the overlap: the parts' own self-intersections there).
  std::vector<char> outline(curves.size(), 0);
  std::vector<int> facesLeft(curves.size(), 0);
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    const Triangle& t = merged.triangles[f];
    if (twin[f] == kTwinRemoved || int(onCurve[t[0]]) + onCurve[t[1]] + onCurve[t[2]] < 2) continue;
    for (int i = 0; i < 3; ++i) {
      const std::array<int, 2> e = {std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])};
      const auto at = std::lower_bound(curves.begin(), curves.end(), e);
      if (at == curves.end() || *at != e) continue;
      ++facesLeft[at - curves.begin()];
      if (twin[f] == kSingle) outline[at - curves.begin()] = 1;
    }
  }
  std::size_t keptEdges = 0;
  for (std::size_t k = 0; k < curves.size(); ++k)
    if (outline[k] || facesLeft[k] > 2) curves[keptEdges++] = curves[k];
  curves.resize(keptEdges);
  std::size_t kept = 0;
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    if (twin[f] == kTwinRemoved) continue;
    merged.triangles[kept] = merged.triangles[f];
    merged.face_origin[kept] = merged.face_origin[f];
    newFace[kept] = newFace[f];
    ++kept;
  }
  merged.triangles.resize(kept);
  merged.face_origin.resize(kept);
  newFace.resize(kept);
  return removed;
}

// Removes faces with the same three vertices as an earlier face (in any
// order): the same surface twice, which would intersect itself everywhere.
std::size_t removeDuplicateFaces(WeldedArrays& in) {
  const std::vector<Triangle>& triangles = in.mesh.triangles;
  auto sorted = [&](std::uint32_t f) {
    Triangle t = triangles[f];
    std::sort(t.begin(), t.end());
    return t;
  };
  // Faces with the same vertices share their smallest: the faces are listed
  // by it (counting, in face order), and each is compared with the earlier
  // faces kept in its list, a few at most. (A table keyed by the vertex set
  // cost four times as much on a large mesh: every probe read another face
  // from anywhere in memory.)
  auto smallest = [&](const Triangle& t) { return std::size_t(std::min({t[0], t[1], t[2]})); };
  std::vector<std::uint32_t> first(in.mesh.points.size() + 1, 0);
  for (const Triangle& t : triangles) ++first[smallest(t) + 1];
  for (std::size_t v = 1; v < first.size(); ++v) first[v] += first[v - 1];
  std::vector<std::uint32_t> byCorner(triangles.size());
  {
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for (std::size_t f = 0; f < triangles.size(); ++f)
      byCorner[next[smallest(triangles[f])]++] = std::uint32_t(f);
  }
  std::vector<char> drop(triangles.size(), 0);
  for (std::size_t v = 0; v + 1 < first.size(); ++v)
    for (std::uint32_t i = first[v] + 1; i < first[v + 1]; ++i) {
      const Triangle key = sorted(byCorner[i]);
      for (std::uint32_t j = first[v]; j < i && !drop[byCorner[i]]; ++j)
        if (!drop[byCorner[j]] && sorted(byCorner[j]) == key) drop[byCorner[i]] = 1;
    }
  std::size_t kept = 0;
  for (std::size_t f = 0; f < drop.size(); ++f)
    if (!drop[f]) {
      in.mesh.triangles[kept] = in.mesh.triangles[f];
      in.face_origin[kept] = in.face_origin[f];
      ++kept;
    }
  const std::size_t removed = drop.size() - kept;
  in.mesh.triangles.resize(kept);
  in.face_origin.resize(kept);
  return removed;
}

}  // namespace meshmend::split_detail
