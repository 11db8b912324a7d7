// Candidate pairs around the faces a local edit changed (moved or new).
// After such an edit only pairs with a changed face can intersect anew, when
// every pair of two unchanged faces is known: the search looks only there.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "common/base/mesh.h"
#include "common/base/parallel.h"
#include "common/exact/box_tree.h"

namespace meshmend {

// The unchanged faces (not marked in `changed`) whose boxes overlap a box
// of `boxes`, ascending, each once (a superset will do): for a caller who
// knows where the faces lie, instead of a pass over all of them.
using NearFaceFinder = std::function<std::vector<std::uint32_t>(const BoxTree& boxes,
                                                                const std::vector<char>& changed)>;

// The candidate pairs (box overlap) of faces of (points, triangles) with at
// least one face `changed`, found once and then visited all at once in
// parallel (forEachPair, each pair once) or per changed face
// (candidatesOf).
//
// The boxes of the changed faces may be widened (room for moving their
// vertices, as re-rounding does): the pairs are those of the boxes, and
// stay a superset of the overlapping faces' pairs while every vertex of a
// changed face stays inside the boxes it was given and no vertex of an
// unchanged face moves (a face with a moved corner is a changed one).
class ChangedFaceSearch {
 public:
  // The changed faces' boxes are theirs widened by `widenSteps` float steps
  // on each side (room for moving a vertex by as many float steps, or by
  // more double steps).
  // The unchanged faces near them from `near` when given.
  ChangedFaceSearch(const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
                    const std::vector<char>& changed, int widenSteps = 0,
                    const NearFaceFinder& near = {});
  // The same with the caller's boxes for the changed faces (in face order),
  // e.g. covering every position their vertices may take.
  ChangedFaceSearch(const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
                    const std::vector<char>& changed, std::vector<Box> changedBoxes);

  // The faces of the search: the changed ones, ascending, then the
  // unchanged ones near a changed face, ascending. Every candidate pair's
  // unchanged face is one of these, and most faces of a large mesh, far
  // from the edit, are not.
  const std::vector<std::uint32_t>& faces() const { return faces_; }
  std::size_t changedCount() const { return changedCount_; }

  // Calls visit(a, b, worker) once for every candidate pair, a < b given
  // as positions in faces() (a is changed), from several threads (worker =
  // 0..workerCount()-1): per-face data in that order stays close together.
  template <class Visit>
  void forEachPair(Visit&& visit) const;
  // Every candidate pair, as faces: two changed ones as (smaller, larger),
  // else (changed, unchanged).
  std::vector<std::array<std::uint32_t, 2>> pairs() const;
  // Per face of `faces`, the other face of each of its candidate pairs
  // (none for an unchanged face).
  std::vector<std::vector<std::uint32_t>> candidatesOf(
      const std::vector<std::uint32_t>& faces) const;

 private:
  void search(const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
              const std::vector<char>& changed, const NearFaceFinder& near = {});
  void findNearFaces(const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
                     const std::vector<char>& changed, const NearFaceFinder& near);

  std::vector<std::uint32_t> faces_;
  std::size_t changedCount_ = 0;
  std::vector<Box> boxes_;  // per face of faces_: a changed one's as given, a near one's own
  std::unique_ptr<BoxTree> changedTree_;
};

// Candidate pairs of faces of (points, triangles) where at least one face
// is `changed` (ChangedFaceSearch(...).pairs()).
std::vector<std::array<std::uint32_t, 2>> pairsWithChangedFaces(
    const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
    const std::vector<char>& changed, int widenSteps = 0);
// The same with the caller's boxes for the changed faces (in face order).
std::vector<std::array<std::uint32_t, 2>> pairsWithChangedBoxes(
    const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
    const std::vector<char>& changed, const std::vector<Box>& changedBoxes);

// ---- templates -----------------------------------------------------------------

template <class Visit>
void ChangedFaceSearch::forEachPair(Visit&& visit) const {
  if (changedCount_ == 0) return;
  // Two changed faces: one traversal of the tree against itself (a descent
  // per changed face cost twice as much).
  changedTree_->selfPairs(visit);
  // A changed face and a near one: the near one descends the tree.
  parallelChunks(
      faces_.size() - changedCount_,
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t k = changedCount_ + begin; k < changedCount_ + end; ++k)
          changedTree_->query(boxes_[k], worker,
                              [&](std::uint32_t i, unsigned w) { visit(i, std::uint32_t(k), w); });
      },
      1024);
}

}  // namespace meshmend
