// The curve points of a split (McLaurin 2012, §2): every distinct point
// where faces cross, named by the input elements that define it. Used by
// the split's stages only (split.cpp, mesh_splitter.h).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>

#include "common/base/errors.h"
#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "common/exact/box_tree.h"
#include "common/exact/exact_point.h"
#include "common/exact/predicates.h"
#include "common/exact/retriangulate.h"
#include "common/repair/split/detail.h"

namespace meshmend::split_detail {

// An input edge: mesh and its two vertices, smaller first.
struct EdgeRef {
  std::uint32_t mesh, u, v;
  bool operator==(const EdgeRef& o) const { return mesh == o.mesh && u == o.u && v == o.v; }
};
inline EdgeRef edgeRef(std::uint32_t mesh, int a, int b) {
  return {mesh, std::uint32_t(std::min(a, b)), std::uint32_t(std::max(a, b))};
}

// Every distinct curve point of all pairs, named by its defining input
// elements (an input vertex; an input edge crossing an input face; two
// coplanar input edges crossing), so that the pairs sharing a point find it
// without comparing coordinates. Points of different names that coincide
// exactly (degenerate inputs) are merged afterwards.
class CurvePoints {
 public:
  explicit CurvePoints(std::size_t expected) {
    points_.reserve(expected);
    names_.reserve(expected);
    std::size_t slots = 64;  // a power of two, at least twice the points
    while (slots < 2 * expected) slots *= 2;
    slots_.assign(slots, -1);
  }

  // The id of the point `tag` of the pair's contact (its ExactPoint `point`).
  int add(const ContactPoint& tag, const ExactPoint& point, const FaceRef faces[2],
          const std::vector<const std::vector<Triangle>*>& triangles) {
    const FaceRef& own = faces[tag.triangle];
    const Triangle& t = (*triangles[own.mesh])[own.face];
    Name name;
    switch (tag.kind) {
      case ContactPoint::Kind::kVertex:
        name.key = {0, own.mesh, std::uint32_t(t[tag.index]), 0, 0, 0, 0};
        name.vertex_mesh = own.mesh;
        name.vertex = t[tag.index];
        break;
      case ContactPoint::Kind::kEdgeFace: {
        const FaceRef& other = faces[1 - tag.triangle];
        const EdgeRef e = edgeRef(own.mesh, t[tag.index], t[(tag.index + 1) % 3]);
        name.key = {1, e.mesh, e.u, e.v, other.mesh, other.face, 0};
        name.edges[name.edge_count++] = e;
        break;
      }
      case ContactPoint::Kind::kEdgeEdge: {
        const Triangle& tb = (*triangles[faces[1].mesh])[faces[1].face];
        EdgeRef e = edgeRef(faces[0].mesh, t[tag.index], t[(tag.index + 1) % 3]);
        EdgeRef g = edgeRef(faces[1].mesh, tb[tag.other_index], tb[(tag.other_index + 1) % 3]);
        if (std::tie(g.mesh, g.u, g.v) < std::tie(e.mesh, e.u, e.v)) std::swap(e, g);
        name.key = {2, e.mesh, e.u, e.v, g.mesh, g.u, g.v};
        name.edges[name.edge_count++] = e;
        name.edges[name.edge_count++] = g;
        break;
      }
    }
    // Open addressing (linear probing): one lookup per contact point, no
    // allocation per point.
    std::size_t slot = hash(name.key) & (slots_.size() - 1);
    for (; slots_[slot] >= 0; slot = (slot + 1) & (slots_.size() - 1))
      if (names_[slots_[slot]].key == name.key) return slots_[slot];
    slots_[slot] = int(points_.size());
    points_.push_back(point);
    names_.push_back(name);
    if (2 * points_.size() > slots_.size()) rehash();
    return int(points_.size()) - 1;
  }

  // Merges exactly coincident points; afterwards representative(id) names
  // each, and each representative lists its group (next_).
  void mergeCoincident() {
    std::vector<const ExactPoint*> all;
    all.reserve(points_.size());
    for (const ExactPoint& p : points_) all.push_back(&p);
    representative_ = coincidentGroups(all);
    next_.assign(points_.size(), -1);
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const int r = representative_[i];
      if (r == int(i)) continue;
      next_[i] = next_[r];  // the group after r: the later points first
      next_[r] = int(i);
    }
  }

  int representative(int id) const { return representative_[id]; }
  const ExactPoint& point(int id) const { return points_[id]; }
  std::size_t size() const { return points_.size(); }
  // Is the point (a representative) known to lie on input edge e (from the
  // names of its group)?
  bool knownOnEdge(int id, const EdgeRef& e) const {
    for (int q = id; q >= 0; q = next_[q])
      for (int k = 0; k < names_[q].edge_count; ++k)
        if (names_[q].edges[k] == e) return true;
    return false;
  }
  // The input vertex of `mesh` at this point (a representative), or -1;
  // of two coincident ones (duplicates left unwelded), the later.
  int inputVertex(std::uint32_t mesh, int id) const {
    for (int q = next_[id]; q >= 0; q = next_[q])
      if (names_[q].vertex >= 0 && names_[q].vertex_mesh == mesh) return names_[q].vertex;
    return names_[id].vertex >= 0 && names_[id].vertex_mesh == mesh ? names_[id].vertex : -1;
  }

 private:
  using Key = std::array<std::uint32_t, 7>;
  struct Name {
    Key key{};
    std::array<EdgeRef, 2> edges{};  // input edges the point lies on
    int edge_count = 0;
    std::uint32_t vertex_mesh = 0;
    int vertex = -1;  // the input vertex it is, or -1
  };
  static std::size_t hash(const Key& k) {
    std::size_t h = 0;
    for (std::uint32_t x : k) h = h * 0x9E3779B97F4A7C15ull + x;
    return h ^ (h >> 29);
  }
  void rehash() {
    slots_.assign(2 * slots_.size(), -1);
    for (std::size_t i = 0; i < names_.size(); ++i) {
      std::size_t slot = hash(names_[i].key) & (slots_.size() - 1);
      while (slots_[slot] >= 0) slot = (slot + 1) & (slots_.size() - 1);
      slots_[slot] = int(i);
    }
  }

  std::vector<ExactPoint> points_;
  std::vector<Name> names_;
  std::vector<int> slots_;  // hash table: point index or -1
  std::vector<int> representative_;
  std::vector<int> next_;  // the next point of the same group, or -1
};

}  // namespace meshmend::split_detail
