// What trimming, stitching and gap closing (common/stitch/*.cpp) share:
// edge keys, checks that name what is wrong, the border edge count, the
// local edge table and the stitch plan. Not an interface of the core.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/base/timing.h"
#include "common/repair/output_stage.h"
#include "common/repair/stitch/stitch.h"

namespace meshmend::stitch_detail {

inline std::uint64_t edgeKey(int a, int b) {
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}
inline std::uint64_t undirectedKey(int a, int b) {
  return edgeKey(std::min(a, b), std::max(a, b));
}

// "vertex 123 (0.5, 1, -2)": where a user can find it in MeshLab.
std::string describeVertex(const Mesh& mesh, int v);

// InvalidInputError unless the mesh has no deleted vertices or faces.
void requireCompact(const Mesh& mesh);

// InvalidInputError unless v is a vertex of the mesh; `what` names the option.
void requireVertex(const Mesh& mesh, int v, const std::string& what);

// Edges used by exactly one face.
std::size_t borderEdgesOf(const std::vector<Triangle>& triangles);

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

// ---- the stitch of two border paths (stitch.cpp), reused by gap closing --------

// topologyRead is called once the mesh's faces are no longer read (from
// then on the plan reads the path vertices' coordinates and what it
// gathered).
StitchPlan planStitch(const Mesh& mesh, const StitchOptions& o,
                      const std::function<void()>& topologyRead = {});

// Exact count of the intersecting pairs that involve a planned face. Only
// the faces near the gap are looked at: the planned faces' boxes go into a
// tree, every face of the mesh whose box meets the tree's bounds is looked
// up in it, and the pairs found are decided on a small copy of the faces
// concerned.
std::size_t newIntersections(const Mesh& mesh, const StitchPlan& plan);

void applyPlan(Mesh& mesh, const StitchPlan& plan, StitchResult& r);

// The output stage (output_stage.h) on `mesh` once an operation added the
// vertices from `firstNew` on and changed the faces marked `changed` (new
// faces beyond its size): the positions as the host stores them, the new
// vertices re-rounded where rounding made a changed face cross. Nothing to
// store for a double host without new vertices.
StoredOutput storeStitched(Mesh& mesh, std::size_t firstNew, std::vector<char> changed,
                           bool roundToFloat);

}  // namespace meshmend::stitch_detail
