// The stages of self-intersection removal (selfintersect.h), shared by its
// source files: pretreat.cpp (input checks, cleaning and the
// pre-treatment of §2.1), growing.cpp (region growing and
// stitching, §2.3-2.4, and separating touching copies) and
// selfintersect.cpp (the stages in order, the contract, the report).
// Internal: nothing here is part of the core's interface.
#pragma once

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "common/base/mesh.h"
#include "common/base/progress.h"
#include "common/exact/triangle_intersection.h"

namespace meshmend::selfintersect {

inline int find(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

inline Point3 normalOf(const Point3& a, const Point3& b, const Point3& c) {
  return (b - a) ^ (c - a);
}

inline TrianglePoints pointsOf(const std::vector<Point3>& P, const Triangle& t) {
  return {P[t[0]], P[t[1]], P[t[2]]};
}

// ---- Edges ----------------------------------------------------------------

// The edge uses of the faces (mesh.h), grouped by edge:
// uses[first[e]..first[e+1]) are the uses of edge e.
struct Edges {
  std::vector<EdgeUse> uses;
  std::vector<int> first;        // per edge: its first use; one extra at the end
  std::vector<int> edge_of_use;  // per face corner (3f + i): its edge

  explicit Edges(const std::vector<Triangle>& T) {
    uses = edgeUses(T);
    edge_of_use.resize(uses.size());
    first.reserve(uses.size() / 2 + 2);
    for (std::size_t k = 0; k < uses.size(); ++k) {
      if (k == 0 || uses[k].u != uses[k - 1].u || uses[k].v != uses[k - 1].v)
        first.push_back(int(k));
      edge_of_use[3 * uses[k].face + uses[k].corner] = int(first.size()) - 1;
    }
    first.push_back(int(uses.size()));
  }
  std::size_t count() const { return first.size() - 1; }
  int size(int e) const { return first[e + 1] - first[e]; }
  // Does the use run from the smaller vertex to the larger?
  static bool forward(const EdgeUse& use, const std::vector<Triangle>& T) {
    return T[use.face][use.corner] == use.u;
  }
  // Uses in each direction.
  std::pair<int, int> directions(int e, const std::vector<Triangle>& T) const {
    int fwd = 0;
    for (int k = first[e]; k < first[e + 1]; ++k) fwd += forward(uses[k], T);
    return {fwd, size(e) - fwd};
  }
  // An edge the surface simply continues across: two faces, opposite directions.
  bool manifold(int e, const std::vector<Triangle>& T) const {
    return size(e) == 2 && directions(e, T) == std::make_pair(1, 1);
  }
};

struct TopologyCounts {
  std::size_t border_edges = 0, non_manifold_edges = 0;
  std::size_t fin_edges = 0;  // used more than once, unequally in the two directions
  int components = 0;
  int genus = -1;
};

TopologyCounts topologyOf(const Edges& edges, const std::vector<Triangle>& T,
                          std::size_t vertexCount);

// ---- Input checks and cleaning (pretreat.cpp) ---------------

// Throws TopologyError, naming the remedy, when two or more faces on an edge
// all run it the same way (some faces are turned over).
void requireConsistentOrientation(const Edges& edges, const std::vector<Triangle>& T);

double signedVolume(const std::vector<Point3>& P, const std::vector<Triangle>& T);

// Removes faces repeating another face's three vertices: of a group, one
// stays if they all run alike; two opposite copies bound nothing and both
// go. `origin` follows the faces. Returns the faces removed.
std::size_t removeDuplicateFaces(std::vector<Triangle>& T, std::vector<int>& origin);

// §2.1: faces with zero area or a smallest angle under `angleDeg` are
// removed by collapsing their shortest edge or flipping their longest one,
// each change kept only if no face turns over or gets thinner and nothing
// new crosses (exact). With `apply` false, only counts.
struct PretreatmentCounts {
  std::size_t degenerate_before = 0, collapses = 0, flips = 0, degenerate_left = 0;
};
PretreatmentCounts pretreat(std::vector<Point3>& P, std::vector<Triangle>& T,
                            std::vector<int>& faceOrigin, double angleDeg, bool apply,
                            const Progress& progress);

// ---- Region growing and stitching (growing.cpp) -------------

// The valid region (§2.3) of the cut mesh (P, T) and its stitching (§2.4).
// `newFace`: per face, 1 when the split made it; `births`: per face, the
// input triangle whose plane it lies in.
struct Stitched {
  std::vector<int> vertex_of_corner;  // per valid face corner (3f + i): output vertex
  std::vector<int> source_vertex;     // per output vertex: its vertex in the input arrays
  std::size_t edges_duplicated = 0;   // edges with more than two valid faces
};
struct Grown {
  std::vector<char> valid;  // per face of T: kept
  Stitched stitched;
  std::size_t seeds = 0, rays = 0, conflicts = 0;
};
Grown growAndStitch(const std::vector<Point3>& P, const std::vector<Triangle>& T,
                    const std::vector<char>& newFace, std::vector<TrianglePoints> births,
                    const Progress& progress);

// Moves the coincident copies that stitching made apart (see the .cpp);
// returns the copies left moved. Its exact tests have a work bound: past it
// the copies not yet placed stay home and `boundReached` is set.
std::size_t separateCopies(std::vector<Point3>& P, const std::vector<Triangle>& T,
                           const std::vector<int>& source, bool asFloat, const Progress& progress,
                           bool* boundReached);

}  // namespace meshmend::selfintersect
