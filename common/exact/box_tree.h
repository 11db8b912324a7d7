// Candidate search for intersecting triangles: a bounding-volume hierarchy
// over axis-aligned boxes, with parallel self-join and box queries.
//
// Boxes are stored in float, rounded outward, so that they stay conservative
// (two triangles that touch always have overlapping boxes) at half the memory
// traffic of doubles; touching boxes count as overlapping.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "common/base/huge_pages.h"
#include "common/base/mesh.h"
#include "common/base/parallel.h"

namespace meshmend {

struct Box {
  float lo[3], hi[3];
};

// The smallest float box containing the three points (rounded outward).
Box boxOf(const Point3& a, const Point3& b, const Point3& c);
// The smallest float box containing the point. Rounding outward never
// reverses an order, so hull() of the corners' boxes is boxOf() of the
// corners, exactly: cheaper for faces that share corners.
Box boxOf(const Point3& p);
inline Box hull(const Box& a, const Box& b, const Box& c) {
  Box h;
  for (int k = 0; k < 3; ++k) {
    h.lo[k] = std::min({a.lo[k], b.lo[k], c.lo[k]});
    h.hi[k] = std::max({a.hi[k], b.hi[k], c.hi[k]});
  }
  return h;
}

// `b` grown to contain `x`.
inline void grow(Box& b, const Box& x) {
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = std::min(b.lo[k], x.lo[k]);
    b.hi[k] = std::max(b.hi[k], x.hi[k]);
  }
}

// `b` grown by `steps` floats on each side (as many std::nextafter steps,
// from the ordering of floats' bits: a loop of those was a tenth of a
// search around changed faces). Infinite and NaN bounds stay as they are.
Box widened(const Box& b, int steps);

// All six comparisons, then one branch on the result (in a tree descent
// each comparison's outcome is as good as random: a branch per comparison
// was mispredicted often).
inline bool overlap(const Box& x, const Box& y) {
  return (x.lo[0] <= y.hi[0]) & (y.lo[0] <= x.hi[0]) & (x.lo[1] <= y.hi[1]) & (y.lo[1] <= x.hi[1]) &
         (x.lo[2] <= y.hi[2]) & (y.lo[2] <= x.hi[2]);
}

// A coarse occupancy grid over the cells that some boxes touch: it turns
// away, cheaply, the boxes far from all of them (most of a large mesh), so
// that only the rest go into a tree or a search. Each occupied cell keeps
// the bounding box of the boxes that touch it: where they run through a
// cell as a thin band (faces along a curve), a box beside the band in the
// same cell is turned away too (a third of the faces a cell alone let
// through, on bunny + dragon).
class BoxGrid {
 public:
  explicit BoxGrid(const std::vector<Box>& boxes);
  // Does `b` touch a cell that one of the boxes touches, and overlap the
  // bounding box of those that touch it? (Never false for a box that
  // overlaps one of them: their overlap lies in a cell both touch.)
  bool touches(const Box& b) const;
  // Does every cell that `b` touches hold one of the boxes, b inside the
  // grid? Then every box that overlaps `b` touches an occupied cell.
  bool covers(const Box& b) const;

  // The faces of (points, triangles) whose boxes touch the grid's boxes
  // (touches(boxOf(corners)), exactly), but those marked in `skip`,
  // ascending, in parallel. Each point's cell is found once: a point is
  // shared by about six faces, and a box per face cost more than the test.
  std::vector<std::uint32_t> facesTouching(const std::vector<Point3>& points,
                                           const std::vector<Triangle>& triangles,
                                           const std::vector<char>& skip) const;

 private:
  static constexpr int kCellBits = 6;
  static constexpr int kCells = 1 << kCellBits;
  bool inside(const Box& b) const;
  // A multiplication, not a division: any map that never decreases with
  // the coordinate keeps overlapping boxes in overlapping cell ranges, as
  // marking and testing use this one. (Here, inlined: a call per axis was
  // a third of turning a large mesh's faces away.)
  // Clamped before converting (a huge or NaN offset, from coordinates near
  // the double range, has no int): a NaN start takes the first cell and a
  // NaN end the last, so that such a box is never turned away.
  void cellRange(const Box& b, int k, int& lo, int& hi) const {
    const double from = (b.lo[k] - bounds_.lo[k]) * cellsPerUnit_[k];
    const double to = (b.hi[k] - bounds_.lo[k]) * cellsPerUnit_[k];
    lo = !(from > 0) ? 0 : from < kCells - 1 ? int(from) : kCells - 1;
    hi = !(to < kCells - 1) ? kCells - 1 : to > 0 ? int(to) : 0;
  }
  static int index(int x, int y, int z) { return (x * kCells + y) * kCells + z; }
  bool occupied(int x, int y, int z) const { return cellBox_[index(x, y, z)] != kEmpty; }
  // Does `b` overlap the bounding box of a cell c of lo..hi (c's boxes)?
  bool overlapsCellBoxes(const Box& b, const int lo[3], const int hi[3]) const;
  bool overlapsCellBoxes(const Box& b, int cell) const {
    return cellBox_[cell] != kEmpty && overlap(b, cellBoxes_[cellBox_[cell]]);
  }
  // Of the cells lo..hi: a box that spans at most two cells along each axis
  // (most faces' boxes) is one look-up in blocks_.
  bool anyOccupied(const int lo[3], const int hi[3]) const {
    const int dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    if ((dx | dy | dz) > 1) return anyOccupiedIn(lo, hi);
    return blocks_[index(lo[0], lo[1], lo[2])] >> (dx | dy << 1 | dz << 2) & 1;
  }
  bool anyOccupiedIn(const int lo[3], const int hi[3]) const;  // cell by cell

  Box bounds_{{1, 1, 1}, {0, 0, 0}};
  float cellsPerUnit_[3] = {1, 1, 1};
  static constexpr std::uint32_t kEmpty = 0xffffffffu;
  std::vector<std::uint32_t>
      cellBox_;  // per cell: its boxes' bounding box in cellBoxes_, or kEmpty
  std::vector<Box> cellBoxes_;
  // Per cell, bit m (bit 0: x, 1: y, 2: z) set where a cell of the block
  // from this one to the next along each axis in m is occupied.
  std::vector<std::uint8_t> blocks_;
};

// A uniform grid over boxes whose non-empty cells are found by hashing:
// a query visits the cells its box touches and tests the boxes listed
// there. Built in two linear passes (no sorting: a tree's median splits,
// their comparisons as good as random, took a fifth to two fifths of a
// search between two small meshes), and a query far from every box
// touches only empty cells. The cells are about twice as large as the
// boxes on average, so that a box lists in a few; a query box that
// touches many cells tests every box instead.
class HashedBoxGrid {
 public:
  explicit HashedBoxGrid(std::vector<Box> boxes);

  // Whether the grid serves these queries (in number of box tests) about
  // as well as a tree would: false when one of its own boxes spans many
  // cells (it lists none then) or too many of the queries do (each of
  // those tests every box). Boxes of similar sizes, as the faces of a
  // mesh near a curve, suit it.
  bool suits(const std::vector<Box>& queries) const;

  // Calls visit(i) once for every box i that overlaps `query`. A pair is
  // reported in the first cell that both boxes touch (along each axis the
  // later of their first cells), so no set of pairs met is needed.
  template <class Visit>
  void query(const Box& query, Visit&& visit) const;

 private:
  static constexpr int kAxisBits = 10;  // at most 1024 cells along an axis
  static constexpr int kAxisCells = 1 << kAxisBits;
  static constexpr std::size_t kMostCells = 64;  // a box listed in, a query visiting, more: wide

  // Monotone in the coordinate (a subtraction and a multiplication, then
  // clamped before the conversion, which is undefined beyond int's range):
  // boxes that overlap have overlapping cell ranges.
  int cell(float v, int k) const {
    const float c = (v - bounds_.lo[k]) * cellsPerUnit_[k];
    const float last = float(kAxisCells - 1);
    return int(c > 0 ? (c < last ? c : last) : 0);  // NaN to 0
  }
  static std::uint32_t key(int x, int y, int z) {
    return std::uint32_t(x) | std::uint32_t(y) << kAxisBits | std::uint32_t(z) << 2 * kAxisBits;
  }
  std::uint32_t bucket(std::uint32_t key) const { return (key * 0x9E3779B1u) >> shift_; }
  std::size_t cellsOf(const Box& b) const {
    std::size_t cells = 1;
    for (int k = 0; k < 3; ++k) cells *= std::size_t(cell(b.hi[k], k) - cell(b.lo[k], k) + 1);
    return cells;
  }

  struct Entry {
    std::uint32_t key;  // the cell (buckets hold the boxes of several)
    std::uint32_t box;
  };
  std::vector<Box> boxes_;
  std::vector<std::array<std::uint16_t, 3>> firstCell_;  // per box, along each axis
  std::vector<std::uint32_t> start_;                     // per bucket: its first entry
  std::vector<Entry> entries_;
  Box bounds_{{0, 0, 0}, {0, 0, 0}};
  float cellsPerUnit_[3] = {1, 1, 1};
  int shift_ = 31;
  bool usable_ = true;
};

class BoxTree {
 public:
  // How the hierarchy is built (both are measured in benchmarks/):
  enum class Layout {
    kMedianSplit,  // top-down: split at the median of the box centres along the widest axis
    // Sort the centres along a Morton (Z-order) curve, split each range where
    // its codes' highest differing bit changes (at the middle where the
    // codes are equal): a linear-time build (Karras 2012) whose nodes are
    // the curve's cells, as tight as the median split's on a surface.
    kMorton,
  };

  // Builds the hierarchy over `boxes` (primitive i = boxes[i]), using both cores.
  explicit BoxTree(std::vector<Box> boxes, Layout layout = Layout::kMedianSplit);

  std::size_t size() const { return order_.size(); }
  Box box(std::uint32_t i) const { return leafBox(place_[i]); }  // boxes[i], as given
  // The number of nodes on the longest path from the root to a leaf, less
  // one (0 for a single leaf): at most 61, for query()'s stack.
  int depth() const;
  const Box& bounds() const { return nodes_.empty() ? empty_ : nodes_[0].box; }

  // Calls visit(i, j, worker) once for every pair i < j of overlapping boxes,
  // from several threads (worker = 0..workerCount()-1).
  template <class Visit>
  void selfPairs(Visit&& visit) const;
  // The same pairs by their places in the tree's order (visit(x, y, worker),
  // boxes primitive(x) and primitive(y), in no particular order): for a
  // caller that keeps its own data per primitive in that order, side by side
  // for the pairs of two leaves.
  template <class Visit>
  void selfPairsByPlace(Visit&& visit) const;
  std::uint32_t primitive(std::uint32_t place) const { return order_[place]; }

  // Calls visit(i, worker) for every box of this tree that overlaps `query`.
  template <class Visit>
  void query(const Box& query, unsigned worker, Visit&& visit) const;

  // The leaves, in the tree's order, in groups of at most `most` boxes near
  // each other (whole subtrees, of at least one leaf each): a leaf's boxes
  // are first[0..count), a group's leaves leaves[firstLeaf..+leafCount);
  // each with its hull.
  struct Leaf {
    Box box;
    const std::uint32_t* first;
    std::uint32_t count;
  };
  struct Group {
    Box box;
    std::uint32_t firstLeaf, leafCount;
  };
  void groups(std::uint32_t most, std::vector<Leaf>& leaves, std::vector<Group>& groups) const;

 private:
  struct Node {
    Box box;
    std::uint32_t a;  // internal: left child; leaf: first index into order_
    std::uint32_t b;  // internal: right child; leaf: count | kLeaf
  };
  static constexpr std::uint32_t kLeaf = 0x80000000u;
  // At most this many boxes per leaf. Eight: on bunny + dragon the split
  // did 2.4 % fewer instructions than with four (its searches descend less
  // deep; the leaves' extra box tests cost less), with six 1 % fewer and
  // with twelve as many, while the output stage's search did more.
  static constexpr std::uint32_t kLeafSize = 8;
  static_assert(kLeafSize <= 8, "overlapMask() tests a leaf in two groups of four");
  // Below this depth a Morton-order hierarchy splits at its codes' bits, from
  // it on at the middle: leaves lie at most 32 + 29 deep (2^32 boxes, eight
  // a leaf), within query()'s stack of 64.
  static constexpr int kDeepestCodeSplit = 32;

  bool leaf(const Node& n) const { return n.b & kLeaf; }
  const float* bound(int k) const { return bounds_.data() + std::size_t(k) * stride_; }
  Box leafBox(std::uint32_t i) const {
    return {{bound(0)[i], bound(1)[i], bound(2)[i]}, {bound(3)[i], bound(4)[i], bound(5)[i]}};
  }
  // Bit j set where `q` overlaps box first + j, of the `count` (at most
  // kLeafSize) from `first`: overlap() on each, four at a time.
  unsigned overlapMask(const Box& q, std::uint32_t first, std::uint32_t count) const;
  std::uint32_t count(const Node& n) const { return n.b & ~kLeaf; }

  void build(std::uint32_t begin, std::uint32_t end, std::vector<Node>& out);
  void buildInOrder(std::uint32_t begin, std::uint32_t end, std::vector<Node>& out, int depth);
  void sortByMorton(std::uint32_t begin, std::uint32_t end);
  std::uint32_t mortonSplit(std::uint32_t begin, std::uint32_t end) const;
  void buildParallel(bool splitByMedian);
  void orderBoxes();

  template <class Visit>
  void within(std::uint32_t n, unsigned worker, Visit& visit) const;
  template <class Visit>
  void between(std::uint32_t x, std::uint32_t y, unsigned worker, Visit& visit) const;
  // Appends the leaves and groups of subtree n (groups()); returns its
  // number of boxes.
  std::uint32_t groups(std::uint32_t n, std::uint32_t most, std::vector<Leaf>& leaves,
                       std::vector<Group>& groups) const;
  void tasks(std::uint32_t n, int depth,
             std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const;
  void pairTasks(std::uint32_t x, std::uint32_t y, int depth,
                 std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const;

  std::vector<Box> boxes_;  // as given, while the hierarchy is built
  // The arrays below are each written whole before they are read: new
  // elements are left uninitialized (no pass zeroing them first).
  template <class T>
  using Array = std::vector<T, DefaultInitAllocator<T>>;
  Array<std::uint32_t> order_;  // primitive indices, leaves own contiguous ranges
  // boxes_[order_[i]], one array per bound (lo x, y, z, hi x, y, z; each
  // `stride_` floats, kLeafSize - 1 of them room after the last box): a box
  // is tested against four of a leaf's in one SSE comparison per bound.
  Array<float> bounds_;
  std::size_t stride_ = 0;
  Array<std::uint32_t> place_;  // where primitive i is in order_
  // While a median-split hierarchy is built: per primitive in the current
  // order, lo + hi of its box on each axis and its index. Selecting medians
  // on these, next to each other in memory, does the same as on order_ with
  // the boxes looked up, at a fraction of the cost on a large mesh.
  struct Centre {
    float sum[3];
    std::uint32_t index;
  };
  std::vector<Centre> centres_;
  // While a Morton-order hierarchy is built: the primitives' codes, in order.
  Array<std::uint32_t> codes_;
  std::vector<Node> nodes_;
  Box empty_{{1, 1, 1}, {0, 0, 0}};
};

// ---- inline and templates ------------------------------------------------------

inline unsigned BoxTree::overlapMask(const Box& q, std::uint32_t first, std::uint32_t count) const {
#if defined(__SSE2__)
  const __m128 loX = _mm_set1_ps(q.lo[0]), loY = _mm_set1_ps(q.lo[1]), loZ = _mm_set1_ps(q.lo[2]);
  const __m128 hiX = _mm_set1_ps(q.hi[0]), hiY = _mm_set1_ps(q.hi[1]), hiZ = _mm_set1_ps(q.hi[2]);
  auto axis = [&](int k, std::uint32_t at, __m128 lo, __m128 hi) {  // as overlap(): NaN is false
    return _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(bound(k) + at), hi),
                      _mm_cmple_ps(lo, _mm_loadu_ps(bound(3 + k) + at)));
  };
  auto four = [&](std::uint32_t at) {
    const __m128 x = axis(0, at, loX, hiX), y = axis(1, at, loY, hiY), z = axis(2, at, loZ, hiZ);
    return unsigned(_mm_movemask_ps(_mm_and_ps(x, _mm_and_ps(y, z))));
  };
  unsigned mask = four(first);
  if (count > 4) mask |= four(first + 4) << 4;
  return mask & ((1u << count) - 1);
#else
  unsigned mask = 0;
  for (std::uint32_t j = 0; j < count; ++j) mask |= unsigned(overlap(q, leafBox(first + j))) << j;
  return mask;
#endif
}

template <class Visit>
void BoxTree::within(std::uint32_t n, unsigned worker, Visit& visit) const {
  const Node& node = nodes_[n];
  if (leaf(node)) {
    const std::uint32_t first = node.a, size = count(node);
    for (std::uint32_t i = 0; i + 1 < size; ++i) {
      std::uint32_t later = overlapMask(leafBox(first + i), first, size) & ~((2u << i) - 1);
      for (; later; later &= later - 1)
        visit(first + i, first + std::uint32_t(__builtin_ctz(later)), worker);
    }
    return;
  }
  within(node.a, worker, visit);
  within(node.b, worker, visit);
  between(node.a, node.b, worker, visit);
}

template <class Visit>
void BoxTree::between(std::uint32_t x, std::uint32_t y, unsigned worker, Visit& visit) const {
  const Node &nx = nodes_[x], &ny = nodes_[y];
  if (!overlap(nx.box, ny.box)) return;
  if (leaf(nx) && leaf(ny)) {
    for (std::uint32_t near = overlapMask(ny.box, nx.a, count(nx)); near; near &= near - 1) {
      const std::uint32_t i = nx.a + std::uint32_t(__builtin_ctz(near));
      for (std::uint32_t hit = overlapMask(leafBox(i), ny.a, count(ny)); hit; hit &= hit - 1)
        visit(i, ny.a + std::uint32_t(__builtin_ctz(hit)), worker);
    }
    return;
  }
  // Descend the larger node (by box extent sum), or the one that is not a leaf.
  auto extent = [](const Box& b) {
    return (b.hi[0] - b.lo[0]) + (b.hi[1] - b.lo[1]) + (b.hi[2] - b.lo[2]);
  };
  if (leaf(ny) || (!leaf(nx) && extent(nx.box) >= extent(ny.box))) {
    between(nx.a, y, worker, visit);
    between(nx.b, y, worker, visit);
  } else {
    between(x, ny.a, worker, visit);
    between(x, ny.b, worker, visit);
  }
}

template <class Visit>
void BoxTree::selfPairs(Visit&& visit) const {
  selfPairsByPlace([&](std::uint32_t x, std::uint32_t y, unsigned worker) {
    const std::uint32_t p = order_[x], q = order_[y];
    visit(std::min(p, q), std::max(p, q), worker);
  });
}

template <class Visit>
void BoxTree::selfPairsByPlace(Visit&& visit) const {
  if (nodes_.empty()) return;
  // Split the traversal into independent tasks: (n, n) = all pairs within
  // node n, (x, y) = pairs between two nodes; workers take them in turn.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> work;
  tasks(0, 8, work);
  std::atomic<std::size_t> next{0};
  parallelChunks(
      workerCount(),
      [&](std::size_t, std::size_t, unsigned worker) {
        for (std::size_t t; (t = next.fetch_add(1)) < work.size();) {
          const auto [x, y] = work[t];
          if (x == y)
            within(x, worker, visit);
          else
            between(x, y, worker, visit);
        }
      },
      1);
}

template <class Visit>
void HashedBoxGrid::query(const Box& q, Visit&& visit) const {
  if (boxes_.empty() || !overlap(q, bounds_)) return;
  int lo[3], hi[3];
  std::size_t cells = 1;
  for (int k = 0; k < 3; ++k) {
    lo[k] = cell(q.lo[k], k);
    hi[k] = cell(q.hi[k], k);
    cells *= std::size_t(hi[k] - lo[k] + 1);
  }
  if (cells > kMostCells || !usable_) {
    for (std::uint32_t i = 0; i < boxes_.size(); ++i)
      if (overlap(boxes_[i], q)) visit(i);
    return;
  }
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z) {
        const std::uint32_t k = key(x, y, z), b = bucket(k);
        for (std::uint32_t e = start_[b]; e < start_[b + 1]; ++e) {
          const Entry& entry = entries_[e];
          if (entry.key != k || !overlap(boxes_[entry.box], q)) continue;
          const auto& first = firstCell_[entry.box];
          if (x == std::max(lo[0], int(first[0])) && y == std::max(lo[1], int(first[1])) &&
              z == std::max(lo[2], int(first[2])))
            visit(entry.box);
        }
      }
}

template <class Visit>
void BoxTree::query(const Box& q, unsigned worker, Visit&& visit) const {
  if (nodes_.empty()) return;
  std::uint32_t stack[64];  // the depth stays under 63 (kDeepestCodeSplit)
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (!overlap(n.box, q)) continue;
    if (leaf(n)) {
      for (std::uint32_t hit = overlapMask(q, n.a, count(n)); hit; hit &= hit - 1)
        visit(order_[n.a + std::uint32_t(__builtin_ctz(hit))], worker);
    } else {
      stack[top++] = n.a;
      stack[top++] = n.b;
    }
  }
}

}  // namespace meshmend
