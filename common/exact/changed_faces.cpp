#include "common/exact/changed_faces.h"

#include <algorithm>
#include <cstring>

namespace meshmend {

namespace {

// The faces marked, ascending. Eight flags at a time: most faces of a
// large mesh are not marked.
std::vector<std::uint32_t> marked(const std::vector<char>& changed) {
  std::vector<std::vector<std::uint32_t>> found(workerCount());
  parallelChunks(changed.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
    std::size_t f = begin;
    for (; f + 8 <= end; f += 8) {
      std::uint64_t eight;
      std::memcpy(&eight, changed.data() + f, 8);
      if (eight == 0) continue;
      for (std::size_t g = f; g < f + 8; ++g)
        if (changed[g]) found[worker].push_back(std::uint32_t(g));
    }
    for (; f < end; ++f)
      if (changed[f]) found[worker].push_back(std::uint32_t(f));
  });
  return joined(found);
}

}  // namespace

ChangedFaceSearch::ChangedFaceSearch(const std::vector<Point3>& points,
                                     const std::vector<Triangle>& triangles,
                                     const std::vector<char>& changed, int widenSteps,
                                     const NearFaceFinder& near)
    : faces_(marked(changed)), boxes_(faces_.size()) {
  parallelChunks(faces_.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      const Triangle& t = triangles[faces_[i]];
      boxes_[i] = widened(boxOf(points[t[0]], points[t[1]], points[t[2]]), widenSteps);
    }
  });
  search(points, triangles, changed, near);
}

ChangedFaceSearch::ChangedFaceSearch(const std::vector<Point3>& points,
                                     const std::vector<Triangle>& triangles,
                                     const std::vector<char>& changed,
                                     std::vector<Box> changedBoxes)
    : faces_(marked(changed)), boxes_(std::move(changedBoxes)) {
  search(points, triangles, changed);
}

// With faces_ and boxes_ holding the changed faces: their tree, and the
// unchanged faces near them.
void ChangedFaceSearch::search(const std::vector<Point3>& points,
                               const std::vector<Triangle>& triangles,
                               const std::vector<char>& changed, const NearFaceFinder& near) {
  changedCount_ = faces_.size();
  if (changedCount_ == 0) return;
  changedTree_ = std::make_unique<BoxTree>(boxes_);
  findNearFaces(points, triangles, changed, near);
}

// The unchanged faces near the changed boxes, with their boxes: from `near`
// or else those that touch the boxes' grid cells (most of the rest of a
// large mesh is turned away by its corners' cells).
void ChangedFaceSearch::findNearFaces(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                                      const std::vector<char>& changed,
                                      const NearFaceFinder& near) {
  const std::vector<std::uint32_t> found =
      near ? near(*changedTree_, changed) : BoxGrid(boxes_).facesTouching(P, T, changed);
  faces_.insert(faces_.end(), found.begin(), found.end());
  boxes_.resize(faces_.size());
  parallelChunks(faces_.size() - changedCount_, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t k = changedCount_ + begin; k < changedCount_ + end; ++k) {
      const Triangle& t = T[faces_[k]];
      boxes_[k] = boxOf(P[t[0]], P[t[1]], P[t[2]]);
    }
  });
}

std::vector<std::array<std::uint32_t, 2>> ChangedFaceSearch::pairs() const {
  std::vector<std::vector<std::array<std::uint32_t, 2>>> found(workerCount());
  forEachPair([&](std::uint32_t a, std::uint32_t b, unsigned worker) {
    found[worker].push_back({faces_[a], faces_[b]});
  });
  return joined(found);
}

std::vector<std::vector<std::uint32_t>> ChangedFaceSearch::candidatesOf(
    const std::vector<std::uint32_t>& faces) const {
  std::vector<std::vector<std::uint32_t>> rows(faces.size());
  std::vector<Box> boxes;          // of the changed faces asked for
  std::vector<std::size_t> rowOf;  // their rows
  const auto changedEnd = faces_.begin() + std::ptrdiff_t(changedCount_);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto at = std::lower_bound(faces_.begin(), changedEnd, faces[i]);
    if (at == changedEnd || *at != faces[i]) continue;  // unchanged: no pairs of its own
    const Box& box = boxes_[std::size_t(at - faces_.begin())];
    changedTree_->query(box, 0, [&](std::uint32_t j, unsigned) {
      if (faces_[j] != faces[i]) rows[i].push_back(faces_[j]);
    });
    boxes.push_back(box);
    rowOf.push_back(i);
  }
  // The near faces: one pass over them serves every face asked for (asked
  // for a few at a time, as re-rounding does, that costs less than a
  // hierarchy of them).
  const BoxTree asked(boxes);
  for (std::size_t k = changedCount_; k < faces_.size(); ++k)
    asked.query(boxes_[k], 0,
                [&](std::uint32_t j, unsigned) { rows[rowOf[j]].push_back(faces_[k]); });
  return rows;
}

std::vector<std::array<std::uint32_t, 2>> pairsWithChangedFaces(const std::vector<Point3>& P,
                                                                const std::vector<Triangle>& T,
                                                                const std::vector<char>& changed,
                                                                int widenSteps) {
  return ChangedFaceSearch(P, T, changed, widenSteps).pairs();
}

std::vector<std::array<std::uint32_t, 2>> pairsWithChangedBoxes(
    const std::vector<Point3>& P, const std::vector<Triangle>& T, const std::vector<char>& changed,
    const std::vector<Box>& changedBoxes) {
  return ChangedFaceSearch(P, T, changed, changedBoxes).pairs();
}

}  // namespace meshmend
