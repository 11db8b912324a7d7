#include "common/exact/box_tree.h"
#include "common/base/huge_pages.h"
#include "common/base/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <thread>

namespace meshmend {

namespace {

// x rounded to float toward -infinity (down) or +infinity (up): the
// conversion, or the float next to it, one step of its bits (toward zero
// or away from it by its sign, across zero from either zero, from an
// infinity to the largest finite float). The two are chosen by a mask, not
// a branch: whether a conversion rounded the wrong way is as good as
// random, and the mispredicted branches were a sixth of a search between
// two small meshes.
float down(double x) {
  const float f = float(x);
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  std::uint32_t stepped = bits + 2 * (bits >> 31) - 1;       // negative: away from zero
  if (bits == 0) stepped = 0x80000001u;                      // +0: the negative float next to it
  const std::uint32_t take = -std::uint32_t(double(f) > x);  // all ones or zero
  bits = (bits & ~take) | (stepped & take);
  float rounded;
  std::memcpy(&rounded, &bits, sizeof rounded);
  return rounded;
}

float up(double x) {
  const float f = float(x);
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  std::uint32_t stepped = bits + 1 - 2 * (bits >> 31);  // negative: toward zero
  if (bits == 0x80000000u) stepped = 1;                 // -0: the positive float next to it
  const std::uint32_t take = -std::uint32_t(double(f) < x);
  bits = (bits & ~take) | (stepped & take);
  float rounded;
  std::memcpy(&rounded, &bits, sizeof rounded);
  return rounded;
}

// x moved by `steps` floats (negative: down). Floats' bits ordered as
// integers: the magnitude's bits with the sign's (both zeros are 0).
float stepped(float x, std::int64_t steps) {
  if (!std::isfinite(x)) return x;
  std::uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const std::int64_t magnitude = bits & 0x7fffffffu;
  const std::int64_t infinity = 0x7f800000;
  const std::int64_t key =
      std::clamp((bits >> 31 ? -magnitude : magnitude) + steps, -infinity, infinity);
  bits = key < 0 ? 0x80000000u | std::uint32_t(-key) : std::uint32_t(key);
  float y;
  std::memcpy(&y, &bits, sizeof y);
  return y;
}

constexpr float kInf = std::numeric_limits<float>::infinity();

}  // namespace

Box boxOf(const Point3& a, const Point3& b, const Point3& c) {
  Box box;
  for (int k = 0; k < 3; ++k) {
    box.lo[k] = down(std::min({a[k], b[k], c[k]}));
    box.hi[k] = up(std::max({a[k], b[k], c[k]}));
  }
  return box;
}

Box boxOf(const Point3& p) {
  // A point stored as float (every point of a float host's mesh) is its own
  // box: one conversion per coordinate instead of two roundings.
  const float x = float(p[0]), y = float(p[1]), z = float(p[2]);
  if ((double(x) == p[0]) & (double(y) == p[1]) & (double(z) == p[2]))
    return {{x, y, z}, {x, y, z}};
  Box box;
  for (int k = 0; k < 3; ++k) {
    box.lo[k] = down(p[k]);
    box.hi[k] = up(p[k]);
  }
  return box;
}

Box widened(const Box& b, int steps) {
  Box w;
  for (int k = 0; k < 3; ++k) {
    w.lo[k] = stepped(b.lo[k], -steps);
    w.hi[k] = stepped(b.hi[k], steps);
  }
  return w;
}

BoxGrid::BoxGrid(const std::vector<Box>& boxes) : cellBox_(kCells * kCells * kCells, kEmpty) {
  if (boxes.empty()) return;
  bounds_ = boxes[0];
  for (const Box& b : boxes)
    for (int k = 0; k < 3; ++k) {
      bounds_.lo[k] = std::min(bounds_.lo[k], b.lo[k]);
      bounds_.hi[k] = std::max(bounds_.hi[k], b.hi[k]);
    }
  // Cubic cells, kCells along the longest axis: a box grown around a flat
  // band of faces (a shallow intersection curve) then spans a few cells
  // across the band, where with kCells along each axis it spanned dozens.
  float longest = 0;
  for (int k = 0; k < 3; ++k) longest = std::max(longest, bounds_.hi[k] - bounds_.lo[k]);
  for (int k = 0; k < 3; ++k) cellsPerUnit_[k] = 1 / std::max(longest / kCells, 1e-30f);
  std::vector<std::array<int, 3>> filled;  // each occupied cell once
  for (const Box& b : boxes) {
    int lo[3], hi[3];
    for (int k = 0; k < 3; ++k) cellRange(b, k, lo[k], hi[k]);
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z) {
          std::uint32_t& at = cellBox_[index(x, y, z)];
          if (at == kEmpty) {
            at = std::uint32_t(cellBoxes_.size());
            cellBoxes_.push_back(b);
            filled.push_back({x, y, z});
          } else {
            grow(cellBoxes_[at], b);
          }
        }
  }
  // Each occupied cell c sets, in the block of c - d (d in {0, 1}^3), the
  // bits m that contain d.
  std::uint8_t containing[8] = {};
  for (int d = 0; d < 8; ++d)
    for (int m = 0; m < 8; ++m) containing[d] |= std::uint8_t(((m & d) == d) << m);
  blocks_.assign(cellBox_.size(), 0);
  for (const auto& [x, y, z] : filled)
    for (int d = 0; d < 8; ++d) {
      const int bx = x - (d & 1), by = y - (d >> 1 & 1), bz = z - (d >> 2 & 1);
      if (bx >= 0 && by >= 0 && bz >= 0) blocks_[index(bx, by, bz)] |= containing[d];
    }
}

bool BoxGrid::inside(const Box& b) const {
  for (int k = 0; k < 3; ++k)
    if (!(b.lo[k] >= bounds_.lo[k] && b.hi[k] <= bounds_.hi[k])) return false;
  return true;
}

bool BoxGrid::touches(const Box& b) const {
  if (!overlap(b, bounds_)) return false;
  int lo[3], hi[3];
  for (int k = 0; k < 3; ++k) cellRange(b, k, lo[k], hi[k]);
  return anyOccupied(lo, hi) && overlapsCellBoxes(b, lo, hi);
}

bool BoxGrid::overlapsCellBoxes(const Box& b, const int lo[3], const int hi[3]) const {
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z)
        if (overlapsCellBoxes(b, index(x, y, z))) return true;
  return false;
}

bool BoxGrid::anyOccupiedIn(const int lo[3], const int hi[3]) const {
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z)
        if (occupied(x, y, z)) return true;
  return false;
}

std::vector<std::uint32_t> BoxGrid::facesTouching(const std::vector<Point3>& P,
                                                  const std::vector<Triangle>& T,
                                                  const std::vector<char>& skip) const {
  // Per point: the one cell its box lies in, as (x * kCells + y) * kCells
  // + z; or, with kSpans set, that it spans cells or lies outside the grid,
  // and bit 2k (2k + 1) when its box ends below the grid (starts above it)
  // along axis k. A point stored as float (every point of a float host's
  // mesh, most of a double host's) is its own box: one cell where it is
  // inside, found once per axis (a box of each point was most of the work).
  constexpr std::uint32_t kSpans = 0x80000000u;
  auto code = [&](const Box& b) {
    int lo[3], hi[3];
    bool one = inside(b);
    std::uint32_t beyond = 0;
    for (int k = 0; k < 3; ++k) {
      cellRange(b, k, lo[k], hi[k]);
      one &= lo[k] == hi[k];
      beyond |= std::uint32_t(b.hi[k] < bounds_.lo[k]) << 2 * k |
                std::uint32_t(b.lo[k] > bounds_.hi[k]) << (2 * k + 1);
    }
    return one ? std::uint32_t((lo[0] * kCells + lo[1]) * kCells + lo[2]) : kSpans | beyond;
  };
  // A point stored as float inside the grid (most): its cell along each
  // axis as cellRange() finds it (the same float arithmetic), the clamp at
  // the low end needless inside; -1 where the product is NaN (an offset
  // past float times the zero cells per unit of an extent past float),
  // which cellRange() takes as spanning the axis.
  auto axisCell = [&](float x, int k) {
    const float c = (x - bounds_.lo[k]) * cellsPerUnit_[k];
    return c >= 0 ? int(std::min(c, float(kCells - 1))) : -1;
  };
  std::vector<std::uint32_t> cell(P.size());
  parallelChunks(P.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t v = begin; v < end; ++v) {
      const Point3& p = P[v];
      const float x = float(p[0]), y = float(p[1]), z = float(p[2]);
      const bool stored = (double(x) == p[0]) & (double(y) == p[1]) & (double(z) == p[2]);
      const bool in = (x >= bounds_.lo[0]) & (x <= bounds_.hi[0]) & (y >= bounds_.lo[1]) &
                      (y <= bounds_.hi[1]) & (z >= bounds_.lo[2]) & (z <= bounds_.hi[2]);
      if (stored & in) {
        const int cx = axisCell(x, 0), cy = axisCell(y, 1), cz = axisCell(z, 2);
        if ((cx | cy | cz) >= 0) {
          cell[v] = std::uint32_t(index(cx, cy, cz));
          continue;
        }
      }
      cell[v] = code(stored ? Box{{x, y, z}, {x, y, z}} : boxOf(p));
    }
  });
  // A face's box starts at its corners' lowest start and ends at their
  // highest end, and cellRange() never decreases with the coordinate: the
  // face's cells are the range of its corners' cells. Corners in one cell
  // (most faces) ask that cell; corners all beyond one side of the grid
  // (most of the rest of a large mesh) ask nothing; others, the box. The
  // face's box and the cells' boxes only where a cell it touches is
  // occupied (few faces), in a second step (as one step, on bunny + dragon
  // the search took 12 M instructions more).
  auto cellsOf = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, int lo[3], int hi[3]) {
    for (int k = 0, shift = 0; k < 3; ++k, shift += kCellBits) {
      const int ka = int(a >> shift) & (kCells - 1), kb = int(b >> shift) & (kCells - 1),
                kc = int(c >> shift) & (kCells - 1);
      lo[2 - k] = std::min({ka, kb, kc});
      hi[2 - k] = std::max({ka, kb, kc});
    }
  };
  auto mayTouch = [&](const Triangle& t) {
    const std::uint32_t a = cell[t[0]], b = cell[t[1]], c = cell[t[2]];
    if ((a | b | c) & kSpans) {
      const std::uint32_t all = a & b & c;  // with kSpans: beyond the same side, all three
      return !((all & kSpans) && (all & ~kSpans));
    }
    if (a == b && b == c) return cellBox_[a] != kEmpty;
    int lo[3], hi[3];
    cellsOf(a, b, c, lo, hi);
    return anyOccupied(lo, hi);
  };
  auto touchesFace = [&](const Triangle& t) {
    const Box box = boxOf(P[t[0]], P[t[1]], P[t[2]]);
    const std::uint32_t a = cell[t[0]], b = cell[t[1]], c = cell[t[2]];
    if ((a | b | c) & kSpans) return touches(box);
    if (a == b && b == c) return overlapsCellBoxes(box, int(a));
    int lo[3], hi[3];
    cellsOf(a, b, c, lo, hi);
    return overlapsCellBoxes(box, lo, hi);
  };
  std::vector<std::vector<std::uint32_t>> found(workerCount());
  parallelChunks(T.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
    for (std::size_t f = begin; f < end; ++f)
      if (!skip[f] && mayTouch(T[f]) && touchesFace(T[f]))
        found[worker].push_back(std::uint32_t(f));
  });
  return joined(found);  // ascending
}

bool BoxGrid::covers(const Box& b) const {
  if (!inside(b)) return false;
  int lo[3], hi[3];
  for (int k = 0; k < 3; ++k) cellRange(b, k, lo[k], hi[k]);
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z)
        if (!occupied(x, y, z)) return false;
  return true;
}

HashedBoxGrid::HashedBoxGrid(std::vector<Box> boxes) : boxes_(std::move(boxes)) {
  if (boxes_.empty()) return;
  bounds_ = boxes_[0];
  double extent[3] = {0, 0, 0};
  for (const Box& b : boxes_) {
    grow(bounds_, b);
    for (int k = 0; k < 3; ++k) extent[k] += double(b.hi[k]) - b.lo[k];
  }
  // Cells twice as large as the boxes along each axis on average (a box
  // lists in about three; as large as them, eight, and the search took
  // longer), at most kAxisCells along one.
  for (int k = 0; k < 3; ++k) {
    const double size = std::max(2 * extent[k] / double(boxes_.size()),
                                 (double(bounds_.hi[k]) - bounds_.lo[k]) / kAxisCells);
    cellsPerUnit_[k] = size > 0 ? float(1 / size) : 0;  // flat along k: one cell
  }
  firstCell_.resize(boxes_.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    for (int k = 0; k < 3; ++k) firstCell_[i][k] = std::uint16_t(cell(boxes_[i].lo[k], k));
    const std::size_t cells = cellsOf(boxes_[i]);
    if (cells > kMostCells) {  // boxes of very different sizes: a tree's case
      usable_ = false;
      firstCell_ = {};
      return;
    }
    total += cells;
  }
  // About one bucket per entry (a power of two, the hash's top bits).
  int bits = 1;
  while ((std::size_t(1) << bits) < total && bits < 30) ++bits;
  shift_ = 32 - bits;
  start_.assign((std::size_t(1) << bits) + 1, 0);
  auto forEachCell = [&](std::uint32_t i, auto&& f) {
    const Box& b = boxes_[i];
    const int hx = cell(b.hi[0], 0), hy = cell(b.hi[1], 1), hz = cell(b.hi[2], 2);
    for (int x = firstCell_[i][0]; x <= hx; ++x)
      for (int y = firstCell_[i][1]; y <= hy; ++y)
        for (int z = firstCell_[i][2]; z <= hz; ++z) f(key(x, y, z));
  };
  for (std::uint32_t i = 0; i < boxes_.size(); ++i)
    forEachCell(i, [&](std::uint32_t k) { ++start_[bucket(k) + 1]; });
  for (std::size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
  entries_.resize(total);
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::uint32_t i = 0; i < boxes_.size(); ++i)
    forEachCell(i, [&](std::uint32_t k) { entries_[fill[bucket(k)]++] = {k, i}; });
}

bool HashedBoxGrid::suits(const std::vector<Box>& queries) const {
  if (!usable_) return false;
  std::size_t wide = 0;
  for (const Box& q : queries) wide += cellsOf(q) > kMostCells;
  // A wide query tests every box: worth it while those tests cost no more
  // than the cell visits of all the queries, a few dozen tests each.
  return wide * boxes_.size() <= 64 * queries.size();
}

BoxTree::BoxTree(std::vector<Box> boxes, Layout layout) : boxes_(std::move(boxes)) {
  resizeInHugePages(order_, boxes_.size());
  std::iota(order_.begin(), order_.end(), 0u);
  if (boxes_.empty()) return;
  if (layout == Layout::kMorton) {
    resizeInHugePages(codes_, boxes_.size());
    sortByMorton(0, std::uint32_t(boxes_.size()));
    buildParallel(false);
    codes_ = {};
    orderBoxes();
    return;
  }
  resizeInHugePages(centres_, boxes_.size());
  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    const Box& b = boxes_[i];
    centres_[i] = {{b.lo[0] + b.hi[0], b.lo[1] + b.hi[1], b.lo[2] + b.hi[2]}, std::uint32_t(i)};
  }
  buildParallel(true);
  for (std::size_t i = 0; i < centres_.size(); ++i) order_[i] = centres_[i].index;
  centres_ = {};
  orderBoxes();
}

// The boxes in leaf order, and where each one went; the boxes as given are
// no longer needed.
void BoxTree::orderBoxes() {
  stride_ = boxes_.size() + kLeafSize - 1;
  resizeInHugePages(bounds_, 6 * stride_);
  resizeInHugePages(place_, boxes_.size());
  float* lo[3] = {&bounds_[0], &bounds_[stride_], &bounds_[2 * stride_]};
  float* hi[3] = {&bounds_[3 * stride_], &bounds_[4 * stride_], &bounds_[5 * stride_]};
  for (std::size_t i = 0; i < order_.size(); ++i) {
    const Box& b = boxes_[order_[i]];
    for (int k = 0; k < 3; ++k) {
      lo[k][i] = b.lo[k];
      hi[k][i] = b.hi[k];
    }
    place_[order_[i]] = std::uint32_t(i);
  }
  for (int k = 0; k < 6; ++k)  // the room after the last box, read by overlapMask() and masked
    std::fill_n(bounds_.begin() + std::ptrdiff_t(k * stride_ + boxes_.size()), kLeafSize - 1, 0.f);
  boxes_ = {};
}

// Builds the two halves of the root in parallel (for large inputs), then joins
// them under the root. With `splitByMedian`, the halves are the two sides of
// the median along the widest axis; otherwise the current (Morton) order is
// kept and split by mortonSplit.
void BoxTree::buildParallel(bool splitByMedian) {
  const std::uint32_t n = std::uint32_t(boxes_.size());
  auto one = [&](std::uint32_t b, std::uint32_t e, std::vector<Node>& out) {
    if (splitByMedian)
      build(b, e, out);
    else
      buildInOrder(b, e, out, n < 20000 ? 0 : 1);  // the large root's split is made below
  };
  // Room for m nodes over m boxes, made once: a median split's leaves hold
  // four to eight boxes, a Morton-order one's about five on average (the
  // dragon: 343,655 nodes over 871,414 boxes); only a tree of mostly
  // one-box leaves outgrows it, and its vector grows then.
  if (n < 20000) {
    reserveInHugePages(nodes_, n);
    one(0, n, nodes_);
    return;
  }
  Box all{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
  Box centers = all;
  for (const Box& b : boxes_) {
    grow(all, b);
    for (int k = 0; k < 3; ++k) {
      const float c = 0.5f * (b.lo[k] + b.hi[k]);
      centers.lo[k] = std::min(centers.lo[k], c);
      centers.hi[k] = std::max(centers.hi[k], c);
    }
  }
  const std::uint32_t mid = splitByMedian ? n / 2 : mortonSplit(0, n);
  if (splitByMedian) {
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (centers.hi[k] - centers.lo[k] > centers.hi[axis] - centers.lo[axis]) axis = k;
    std::nth_element(
        centres_.begin(), centres_.begin() + mid, centres_.end(),
        [axis](const Centre& x, const Centre& y) { return x.sum[axis] < y.sum[axis]; });
  }
  std::vector<Node> left, right;
  reserveInHugePages(left, mid);
  reserveInHugePages(right, n - mid);
  TaskAlongside worker([&] { one(0, mid, left); });
  one(mid, n, right);
  worker.wait();
  reserveInHugePages(nodes_, 1 + left.size() + right.size());
  nodes_.push_back({all, 1, std::uint32_t(1 + left.size())});
  auto append = [&](const std::vector<Node>& part) {
    const std::uint32_t offset = std::uint32_t(nodes_.size());
    for (Node node : part) {
      if (!leaf(node)) {
        node.a += offset;
        node.b += offset;
      }
      nodes_.push_back(node);
    }
  };
  append(left);
  append(right);
}

namespace {

// Bit k of i moved to bit 3k, for every 10-bit i: a look-up per axis
// instead of five shifts and masks.
constexpr std::array<std::uint32_t, 1024> kSpread = [] {
  std::array<std::uint32_t, 1024> t{};
  for (std::uint32_t i = 0; i < 1024; ++i)
    for (int k = 0; k < 10; ++k) t[i] |= (i >> k & 1u) << 3 * k;
  return t;
}();

}  // namespace

// Orders the primitives order_[begin..end) along a Morton curve through their
// box centres, within those centres' bounds (10 bits per axis,
// least-significant-digit radix sort), and sets their codes_.
void BoxTree::sortByMorton(std::uint32_t begin, std::uint32_t end) {
  Box centers{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
  for (std::uint32_t i = begin; i < end; ++i)
    for (int k = 0; k < 3; ++k) {
      const Box& b = boxes_[order_[i]];
      const float c = 0.5f * (b.lo[k] + b.hi[k]);
      centers.lo[k] = std::min(centers.lo[k], c);
      centers.hi[k] = std::max(centers.hi[k], c);
    }
  const std::size_t n = end - begin;
  std::uint32_t* code = codes_.data() + begin;
  std::uint32_t* order = order_.data() + begin;
  float scale[3];  // any map that keeps the centres' order will do
  for (int k = 0; k < 3; ++k) {
    const float extent = centers.hi[k] - centers.lo[k];
    scale[k] = extent > 0 ? 1023.f / extent : 0.f;
  }
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t q[3];
    for (int k = 0; k < 3; ++k) {
      const float c = 0.5f * (boxes_[order[i]].lo[k] + boxes_[order[i]].hi[k]);
      q[k] = std::uint32_t(std::min(1023.f, std::max(0.f, (c - centers.lo[k]) * scale[k])));
    }
    code[i] = kSpread[q[0]] | kSpread[q[1]] << 1 | kSpread[q[2]] << 2;
  }
  // Three passes of 10 bits, back and forth between the arrays and a copy;
  // the three digits' counts in one reading (a pass does not change them).
  Array<std::uint32_t> otherCode(n), otherOrder(n);
  std::uint32_t *fromCode = code, *fromOrder = order, *toCode = otherCode.data(),
                *toOrder = otherOrder.data();
  std::uint32_t counts[3][1025] = {};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t c = code[i];
    ++counts[0][(c & 1023) + 1];
    ++counts[1][(c >> 10 & 1023) + 1];
    ++counts[2][(c >> 20 & 1023) + 1];
  }
  for (int shift = 0; shift < 30; shift += 10) {
    std::uint32_t* count = counts[shift / 10];
    for (int b = 0; b < 1024; ++b) count[b + 1] += count[b];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t slot = count[(fromCode[i] >> shift) & 1023]++;
      toCode[slot] = fromCode[i];
      toOrder[slot] = fromOrder[i];
    }
    std::swap(fromCode, toCode);
    std::swap(fromOrder, toOrder);
  }
  std::copy(fromCode, fromCode + n, code);  // an odd number of passes: from the copy
  std::copy(fromOrder, fromOrder + n, order);
}

int BoxTree::depth() const {
  int deepest = 0;
  std::vector<std::pair<std::uint32_t, int>> open;
  if (!nodes_.empty()) open.push_back({0, 0});
  while (!open.empty()) {
    const auto [n, d] = open.back();
    open.pop_back();
    deepest = std::max(deepest, d);
    if (!leaf(nodes_[n])) {
      open.push_back({nodes_[n].a, d + 1});
      open.push_back({nodes_[n].b, d + 1});
    }
  }
  return deepest;
}

void BoxTree::groups(std::uint32_t most, std::vector<Leaf>& leaves,
                     std::vector<Group>& groups) const {
  leaves.clear();
  groups.clear();
  if (!nodes_.empty()) this->groups(0, most, leaves, groups);
}

std::uint32_t BoxTree::groups(std::uint32_t n, std::uint32_t most, std::vector<Leaf>& leaves,
                              std::vector<Group>& groups) const {
  const Node& node = nodes_[n];
  if (leaf(node)) {
    groups.push_back({node.box, std::uint32_t(leaves.size()), 1});
    leaves.push_back({node.box, order_.data() + node.a, count(node)});
    return count(node);
  }
  const std::size_t mark = groups.size();
  const std::uint32_t firstLeaf = std::uint32_t(leaves.size());
  const std::uint32_t size =
      this->groups(node.a, most, leaves, groups) + this->groups(node.b, most, leaves, groups);
  if (size <= most) {  // one group for both children's
    groups.resize(mark);
    groups.push_back({node.box, firstLeaf, std::uint32_t(leaves.size()) - firstLeaf});
  }
  return size;
}

// Where the sorted codes of begin..end first have their highest differing
// bit set (the middle where all are equal): the two sides are the halves of
// the curve's cell that holds the range.
std::uint32_t BoxTree::mortonSplit(std::uint32_t begin, std::uint32_t end) const {
  const std::uint32_t first = codes_[begin], last = codes_[end - 1];
  if (first == last) return begin + (end - begin) / 2;
  const std::uint32_t bit = std::uint32_t(1) << (31 - __builtin_clz(first ^ last));
  return std::uint32_t(std::partition_point(codes_.begin() + begin, codes_.begin() + end,
                                            [bit](std::uint32_t code) { return !(code & bit); }) -
                       codes_.begin());
}

// A hierarchy over the Morton order: each range split by mortonSplit, and
// at its middle from kDeepestCodeSplit on. Splits at the codes' bits can be
// as uneven as the boxes are (a part graded towards a point, coded again
// within each cluster, would split off a few boxes per level); the middle
// bounds the depth by kDeepestCodeSplit + log2(size), which query()'s stack
// and the traversals' recursion rely on.
void BoxTree::buildInOrder(std::uint32_t begin, std::uint32_t end, std::vector<Node>& out,
                           int depth) {
  const std::uint32_t self = std::uint32_t(out.size());
  out.push_back({});
  if (end - begin <= kLeafSize) {
    Box box{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
    for (std::uint32_t i = begin; i < end; ++i) grow(box, boxes_[order_[i]]);
    out[self] = {box, begin, (end - begin) | kLeaf};
    return;
  }
  // A cluster finer than the codes' cells (a small, detailed part far from
  // the rest) is coded again within its own bounds: otherwise it would be
  // split in an arbitrary order, into children that all overlap.
  const bool byCode = depth < kDeepestCodeSplit;
  if (byCode && codes_[begin] == codes_[end - 1]) sortByMorton(begin, end);
  const std::uint32_t mid = byCode ? mortonSplit(begin, end) : begin + (end - begin) / 2;
  const std::uint32_t left = std::uint32_t(out.size());
  buildInOrder(begin, mid, out, depth + 1);
  const std::uint32_t right = std::uint32_t(out.size());
  buildInOrder(mid, end, out, depth + 1);
  Box box = out[left].box;
  grow(box, out[right].box);
  out[self] = {box, left, right};
}

// Median split along the longest axis of the box centres; children indices
// are relative to `out`.
void BoxTree::build(std::uint32_t begin, std::uint32_t end, std::vector<Node>& out) {
  const std::uint32_t self = std::uint32_t(out.size());
  out.push_back({});
  if (end - begin <= kLeafSize) {
    Box box{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
    for (std::uint32_t i = begin; i < end; ++i) grow(box, boxes_[centres_[i].index]);
    out[self] = {box, begin, (end - begin) | kLeaf};
    return;
  }
  // The centres' extent, in locals: kept in a Box, every step stored its
  // bounds and loaded them again (a third of the build).
  float lo0 = kInf, lo1 = kInf, lo2 = kInf, hi0 = -kInf, hi1 = -kInf, hi2 = -kInf;
  for (std::uint32_t i = begin; i < end; ++i) {
    const float* sum = centres_[i].sum;
    const float c0 = 0.5f * sum[0], c1 = 0.5f * sum[1], c2 = 0.5f * sum[2];
    lo0 = std::min(lo0, c0), lo1 = std::min(lo1, c1), lo2 = std::min(lo2, c2);
    hi0 = std::max(hi0, c0), hi1 = std::max(hi1, c1), hi2 = std::max(hi2, c2);
  }
  const float extent[3] = {hi0 - lo0, hi1 - lo1, hi2 - lo2};
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (extent[k] > extent[axis]) axis = k;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(centres_.begin() + begin, centres_.begin() + mid, centres_.begin() + end,
                   [axis](const Centre& x, const Centre& y) { return x.sum[axis] < y.sum[axis]; });
  const std::uint32_t left = std::uint32_t(out.size());
  build(begin, mid, out);
  const std::uint32_t right = std::uint32_t(out.size());
  build(mid, end, out);
  // A node's box is its children's together (the same as over its boxes).
  Box box = out[left].box;
  grow(box, out[right].box);
  out[self] = {box, left, right};
}

void BoxTree::tasks(std::uint32_t n, int depth,
                    std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const {
  const Node& node = nodes_[n];
  if (depth == 0 || leaf(node)) {
    out.emplace_back(n, n);
    return;
  }
  tasks(node.a, depth - 1, out);
  tasks(node.b, depth - 1, out);
  pairTasks(node.a, node.b, depth - 1, out);
}

void BoxTree::pairTasks(std::uint32_t x, std::uint32_t y, int depth,
                        std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const {
  const Node &nx = nodes_[x], &ny = nodes_[y];
  if (!overlap(nx.box, ny.box)) return;
  if (depth <= 0 || leaf(nx) || leaf(ny)) {
    out.emplace_back(x, y);
    return;
  }
  pairTasks(nx.a, ny.a, depth - 1, out);
  pairTasks(nx.a, ny.b, depth - 1, out);
  pairTasks(nx.b, ny.a, depth - 1, out);
  pairTasks(nx.b, ny.b, depth - 1, out);
}

}  // namespace meshmend
