#include "common/box_tree.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <thread>

namespace meshmend {

namespace {

float down(double x) {
  float f = float(x);
  if (double(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

float up(double x) {
  float f = float(x);
  if (double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

void grow(Box& b, const Box& x) {
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = std::min(b.lo[k], x.lo[k]);
    b.hi[k] = std::max(b.hi[k], x.hi[k]);
  }
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

BoxTree::BoxTree(std::vector<Box> boxes) : boxes_(std::move(boxes)), order_(boxes_.size()) {
  std::iota(order_.begin(), order_.end(), 0u);
  if (boxes_.empty()) return;
  const std::uint32_t n = std::uint32_t(boxes_.size());
  if (n < 20000) {
    build(0, n, nodes_);
    return;
  }
  // Two halves in parallel, then joined under a common root.
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
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (centers.hi[k] - centers.lo[k] > centers.hi[axis] - centers.lo[axis]) axis = k;
  const std::uint32_t mid = n / 2;
  std::nth_element(order_.begin(), order_.begin() + mid, order_.end(),
                   [&](std::uint32_t x, std::uint32_t y) {
                     return boxes_[x].lo[axis] + boxes_[x].hi[axis] <
                            boxes_[y].lo[axis] + boxes_[y].hi[axis];
                   });
  std::vector<Node> left, right;
  std::thread worker([&] { build(0, mid, left); });
  build(mid, n, right);
  worker.join();
  nodes_.reserve(1 + left.size() + right.size());
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

// Median split along the longest axis of the box centres; children indices
// are relative to `out`.
void BoxTree::build(std::uint32_t begin, std::uint32_t end, std::vector<Node>& out) {
  const std::uint32_t self = std::uint32_t(out.size());
  out.push_back({});
  Box box{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
  Box centers = box;
  for (std::uint32_t i = begin; i < end; ++i) {
    const Box& b = boxes_[order_[i]];
    grow(box, b);
    for (int k = 0; k < 3; ++k) {
      const float c = 0.5f * (b.lo[k] + b.hi[k]);
      centers.lo[k] = std::min(centers.lo[k], c);
      centers.hi[k] = std::max(centers.hi[k], c);
    }
  }
  out[self].box = box;
  if (end - begin <= kLeafSize) {
    out[self].a = begin;
    out[self].b = (end - begin) | kLeaf;
    return;
  }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (centers.hi[k] - centers.lo[k] > centers.hi[axis] - centers.lo[axis]) axis = k;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](std::uint32_t x, std::uint32_t y) {
                     return boxes_[x].lo[axis] + boxes_[x].hi[axis] <
                            boxes_[y].lo[axis] + boxes_[y].hi[axis];
                   });
  const std::uint32_t left = std::uint32_t(out.size());
  build(begin, mid, out);
  const std::uint32_t right = std::uint32_t(out.size());
  build(mid, end, out);
  out[self].a = left;
  out[self].b = right;
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
